//! Numerical stability of compositing, opacity correction and ray/triangle tests,
//! against f64 references with explicit tolerances.

use billow_core::compositing::{correct_premultiplied, corrected_alpha, over, under};
use billow_core::ray_triangle::WatertightRay;
use glam::{DVec4, Vec3, Vec4};
use proptest::prelude::*;

fn corrected_f64(a: f64, r: f64) -> f64 {
    -(r * (-a).ln_1p()).exp_m1()
}

#[test]
fn opacity_correction_relative_accuracy() {
    // Relative error ≤ 1e-5 for every α, including tiny ones where 1 − (1−α)^r cancels.
    for &a in &[
        1e-30f32,
        1e-12,
        1e-7,
        3e-5,
        1e-3,
        0.1,
        0.5,
        0.9,
        0.999,
        1.0 - 1e-6,
    ] {
        for &r in &[1e-3f32, 0.25, 0.5, 1.0, 2.0, 7.5, 1000.0] {
            let got = f64::from(corrected_alpha(a, r));
            let want = corrected_f64(f64::from(a), f64::from(r)).min(1.0);
            assert!(
                (got - want).abs() <= 1e-5 * want + 1e-38,
                "a={a} r={r}: {got} vs {want}"
            );
        }
    }
    // The naive f32 formula loses tiny alphas entirely; ours does not.
    let naive = 1.0 - (1.0 - 1e-9f32).powf(0.5);
    assert_eq!(naive, 0.0);
    assert!((corrected_alpha(1e-9, 0.5) - 5e-10).abs() < 1e-15);
    // Exact end points and guards.
    assert_eq!(corrected_alpha(0.0, 3.0), 0.0);
    assert_eq!(corrected_alpha(1.0, 0.01), 1.0);
    assert_eq!(corrected_alpha(0.5, 0.0), 0.0);
    assert_eq!(corrected_alpha(0.5, f32::NAN), 0.0);
    assert!((corrected_alpha(0.5, 1.0) - 0.5).abs() < 1e-7);
    // Colour scaling: limit r for α → 0, no NaN.
    let c = correct_premultiplied(Vec4::new(1e-20, 0.0, 0.0, 0.0), 2.0);
    assert!(c.is_finite() && c.w == 0.0 && (c.x - 2e-20).abs() < 1e-26);
    let c = correct_premultiplied(Vec4::new(0.25, 0.5, 0.0, 0.5), 2.0);
    assert!(
        (c.w - 0.75).abs() < 1e-6 && (c.y - 0.75).abs() < 1e-6,
        "{c}"
    );
}

/// Composites `n` identical slices back to front in f32 and f64.
fn composite_n(src: Vec4, n: usize) -> (Vec4, DVec4) {
    let mut a = Vec4::ZERO;
    let mut b = DVec4::ZERO;
    for _ in 0..n {
        a = over(src, a);
        b = src.as_dvec4() + b * (1.0 - f64::from(src.w));
    }
    (a, b)
}

#[test]
fn thousands_of_slices_no_drift() {
    // α near 0: 10 000 slices of α = 1e-4 (→ 1 − e^{−1}); α near 1; mid.
    for (alpha, n) in [
        (1e-4f32, 10_000),
        (1e-6, 20_000),
        (0.5, 5_000),
        (1.0 - 1e-6, 5_000),
        (0.999, 3_000),
    ] {
        let src = Vec4::new(0.3 * alpha, 0.6 * alpha, 0.9 * alpha, alpha);
        let (f, d) = composite_n(src, n);
        assert!(f.is_finite(), "NaN/inf for α={alpha}");
        let err = (f.as_dvec4() - d).abs().max_element();
        assert!(err < 2e-4, "α={alpha} n={n}: drift {err}");
        assert!(f.w <= 1.0 + 1e-6 && f.x <= f.w + 1e-6);
    }
    // Opacity correction is consistent with subdivision: n slices of the corrected α
    // reproduce the original opacity.
    for (alpha, n) in [(0.3f32, 1000usize), (0.999, 4000), (1e-3, 2000)] {
        let a = corrected_alpha(alpha, 1.0 / n as f32);
        let src = correct_premultiplied(Vec4::new(0.5 * alpha, 0.0, 0.0, alpha), 1.0 / n as f32);
        let (f, _) = composite_n(src, n);
        assert!(
            (f.w - alpha).abs() < 2e-4,
            "α={alpha}: {} (per-slice {a})",
            f.w
        );
        assert!((f.x - 0.5 * alpha).abs() < 2e-4, "colour {}", f.x);
    }
    // Front-to-back equals back-to-front.
    let layers: Vec<Vec4> = (0..500)
        .map(|i| Vec4::new(0.1, 0.2, 0.05, 0.01 + (i % 7) as f32 * 0.01))
        .collect();
    let mut btf = Vec4::ZERO;
    for l in layers.iter().rev() {
        btf = over(*l, btf);
    }
    let mut ftb = Vec4::ZERO;
    for l in &layers {
        ftb = under(ftb, *l);
    }
    assert!((btf - ftb).abs().max_element() < 1e-5);
}

#[test]
fn shared_edge_hit_exactly_once() {
    // A quad split along its diagonal; rays exactly through the diagonal and the corners.
    let q = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
    for &(x, y) in &[
        (0.0f32, 0.0f32),
        (0.5, 0.5),
        (-0.25, -0.25),
        (0.3, 0.1),
        (0.999, 0.999),
    ] {
        for dir in [Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)] {
            let r = WatertightRay::new(Vec3::new(x, y, -dir.z * 2.0), dir);
            let hits = tris
                .iter()
                .filter(|t| r.intersect(t[0], t[1], t[2], 0.0, 10.0).is_some())
                .count();
            assert_eq!(hits, 1, "ray at ({x},{y}) dir {dir}");
        }
    }
    // A fan around a shared vertex: exactly one triangle owns the centre.
    let c = Vec3::ZERO;
    let ring: Vec<Vec3> = (0..6)
        .map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 6.0;
            Vec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    let r = WatertightRay::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let hits = (0..6)
        .filter(|&i| {
            r.intersect(c, ring[i], ring[(i + 1) % 6], 0.0, 10.0)
                .is_some()
        })
        .count();
    assert_eq!(hits, 1);
}

#[test]
fn near_degenerate_triangles() {
    let r = WatertightRay::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    // Edge-on (contains the ray direction): miss, no NaN.
    assert!(r
        .intersect(
            Vec3::new(0.0, -1.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
            Vec3::new(0.0, 0.0, 2.0),
            0.0,
            10.0
        )
        .is_none());
    // Zero area (collinear): miss.
    assert!(r
        .intersect(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            0.0,
            10.0
        )
        .is_none());
    // Sliver 1e-7 wide covering the ray: a finite hit with valid barycentrics.
    let h = r.intersect(
        Vec3::new(-1.0, -1e-7, 0.0),
        Vec3::new(1.0, -1e-7, 0.0),
        Vec3::new(0.0, 1e-7, 0.0),
        0.0,
        10.0,
    );
    let h = h.expect("sliver hit");
    assert!((h.t - 1.0).abs() < 1e-6 && h.front);
    assert!((h.bary.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    // Huge and tiny coordinates.
    for s in [1e-6f32, 1e6] {
        let r = WatertightRay::new(
            Vec3::new(0.1 * s, 0.1 * s, 3.0 * s),
            Vec3::new(0.0, 0.0, -1.0),
        );
        let h = r
            .intersect(
                Vec3::new(-s, -s, s),
                Vec3::new(s, -s, s),
                Vec3::new(0.0, s, s),
                0.0,
                f32::INFINITY,
            )
            .unwrap();
        assert!(((h.t / s) - 2.0).abs() < 1e-5, "{}", h.t);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Random triangles and rays: hits agree with an f64 Möller–Trumbore away from edges,
    /// barycentrics reproduce the hit point, never NaN.
    #[test]
    fn ray_triangle_matches_f64(v in prop::array::uniform3(prop::array::uniform3(-1.0f32..1.0)),
                                o in prop::array::uniform3(-3.0f32..3.0), d in prop::array::uniform3(-1.0f32..1.0)) {
        let (v0, v1, v2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
        let dir = Vec3::from(d);
        prop_assume!(dir.length() > 1e-3);
        let org = Vec3::from(o);
        let r = WatertightRay::new(org, dir);
        let got = r.intersect(v0, v1, v2, 0.0, f32::INFINITY);
        // f64 reference
        let (a, b, c, od, dd) = (v0.as_dvec3(), v1.as_dvec3(), v2.as_dvec3(), org.as_dvec3(), dir.as_dvec3());
        let e1 = b - a; let e2 = c - a;
        let p = dd.cross(e2); let det = e1.dot(p);
        prop_assume!(det.abs() > 1e-6);
        let tv = od - a; let u = tv.dot(p) / det;
        let q = tv.cross(e1); let w = dd.dot(q) / det; let t = e2.dot(q) / det;
        let margin = 1e-4;
        let inside = u > margin && w > margin && u + w < 1.0 - margin && t > margin;
        let outside = u < -margin || w < -margin || u + w > 1.0 + margin || t < -margin;
        if inside {
            let h = got.expect("should hit");
            prop_assert!((f64::from(h.t) - t).abs() < 1e-4 * (1.0 + t.abs()));
            let hp = v0 * h.bary[0] + v1 * h.bary[1] + v2 * h.bary[2];
            prop_assert!((hp - (org + dir * h.t)).length() < 1e-3);
            prop_assert_eq!(h.front, e1.cross(e2).dot(dd) < 0.0);
        } else if outside {
            prop_assert!(got.is_none());
        }
        if let Some(h) = got {
            prop_assert!(h.t.is_finite() && h.bary.iter().all(|b| b.is_finite()));
        }
    }
}
