//! The opacity of a particle along one pixel's ray: the CPU reference of the particle
//! shader (`shaders/particles.wgsl`) and of the tests (Umenhoffer et al., *Spherical
//! billboards*, §2).
//!
//! A particle is a sphere (view-space centre `P`, radius `r`) whose density falls off
//! linearly from the centre. Along a ray with distance `d` from the centre the paper's
//! opacity is `α = 1 − exp(−τ (1 − d/r) Δs)`, `Δs` the length of the ray inside the
//! sphere after clipping by the near plane (nothing in front of it counts: no popping
//! when the camera enters a particle) and by the opaque scene's depth (nothing behind a
//! surface counts: no hard line where a surface cuts a particle).
//!
//! - [`spherical`]: the exact perspective ray from the eye (view-space origin) through
//!   the pixel — the viewer's mode.
//! - [`spherical_parallel`]: the paper's approximation, rays parallel to the view axis
//!   (`d = |P.xy − Q.xy|`, interval `P.z ± w` in depth), kept to measure the difference.
//! - [`planar`]: a classic billboard: a flat quad at the particle's centre depth, depth
//!   tested against the scene and clipped by the near plane as a whole, with the sphere's
//!   full chord `2w` — the clipping and popping artefacts the paper fixes.
//!
//! Depths are positive view distances along −z; `near` is the near-plane distance and
//! `scene` the opaque depth at the pixel (`f32::INFINITY` for none).

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec3;

/// `1 − exp(−x)` accurate for small `x` (`x ≥ 0`).
pub fn one_minus_exp_neg(x: f32) -> f32 {
    -(-x).exp_m1()
}

/// Length of the ray `t·dir` (`|dir| = 1`, `t ≥ 0`) inside the sphere `(p, r)` between the
/// near plane and the scene depth, and the ray's distance to the centre.
/// `None` when the ray misses the sphere.
pub fn chord(p: Vec3, r: f32, dir: Vec3, near: f32, scene: f32) -> Option<(f32, f32)> {
    let b = dir.dot(p);
    let d2 = (p.length_squared() - b * b).max(0.0);
    let r2 = r * r;
    if !(d2 < r2) {
        return None;
    }
    let w = (r2 - d2).sqrt();
    // Depth of a point t·dir is t·(−dir.z): convert the clip planes to ray parameters.
    let dz = -dir.z;
    let (t_near, t_scene) = if dz > 1e-12 {
        (near / dz, scene / dz)
    } else {
        (0.0, f32::INFINITY)
    };
    let enter = (b - w).max(t_near).max(0.0);
    let exit = (b + w).min(t_scene);
    Some(((exit - enter).max(0.0), d2.sqrt()))
}

/// Opacity along the exact perspective ray through view-space direction `dir` (unit).
pub fn spherical(p: Vec3, r: f32, tau: f32, dir: Vec3, near: f32, scene: f32) -> f32 {
    match chord(p, r, dir, near, scene) {
        Some((ds, d)) => one_minus_exp_neg(tau * (1.0 - d / r).max(0.0) * ds),
        None => 0.0,
    }
}

/// The paper's version: the ray through the quad point `q` is parallel to the view axis.
pub fn spherical_parallel(p: Vec3, r: f32, tau: f32, q: Vec3, near: f32, scene: f32) -> f32 {
    let d = (p.truncate() - q.truncate()).length();
    if !(d < r) {
        return 0.0;
    }
    let w = (r * r - d * d).sqrt();
    let depth = -p.z;
    let ds = ((depth + w).min(scene) - (depth - w).max(near)).max(0.0);
    one_minus_exp_neg(tau * (1.0 - d / r) * ds)
}

/// A classic flat billboard at the centre depth, its ray through the quad point `q`.
pub fn planar(p: Vec3, r: f32, tau: f32, q: Vec3, near: f32, scene: f32) -> f32 {
    let d = (p.truncate() - q.truncate()).length();
    let depth = -p.z;
    // The quad is depth-tested and clipped as a whole: all or nothing.
    if !(d < r) || depth < near || depth > scene {
        return 0.0;
    }
    let w = (r * r - d * d).sqrt();
    one_minus_exp_neg(tau * (1.0 - d / r) * 2.0 * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    const INF: f32 = f32::INFINITY;

    #[test]
    fn path_lengths_are_analytic() {
        let p = Vec3::new(0.0, 0.0, -10.0);
        let r = 2.0;
        // Through the centre: 2r.
        let (ds, d) = chord(p, r, Vec3::NEG_Z, 0.1, INF).unwrap();
        assert!((ds - 4.0).abs() < 1e-5 && d < 1e-6, "{ds} {d}");
        // Tangent (at the angle asin(r/|P|) from the centre's direction): 0 or a miss.
        let th = (r / 10.0f32).asin();
        let dir = Vec3::new(th.sin(), 0.0, -th.cos());
        assert!(chord(p, r, dir, 0.1, INF).is_none_or(|(ds, _)| ds < 1e-2));
        let inside = Vec3::new((0.99 * th).sin(), 0.0, -(0.99 * th).cos());
        assert!(chord(p, r, inside, 0.1, INF).is_some_and(|(ds, _)| ds > 0.0));
        // A depth plane through the centre halves it.
        let (half, _) = chord(p, r, Vec3::NEG_Z, 0.1, 10.0).unwrap();
        assert!((half - 2.0).abs() < 1e-5, "{half}");
        // The near plane through the centre halves it too.
        let (half, _) = chord(p, r, Vec3::NEG_Z, 10.0, INF).unwrap();
        assert!((half - 2.0).abs() < 1e-5, "{half}");
        // Behind the eye: nothing.
        assert_eq!(chord(-p, r, Vec3::NEG_Z, 0.1, INF).map(|c| c.0), Some(0.0));
    }

    #[test]
    fn opacity_of_a_ray_through_the_centre() {
        let p = Vec3::new(0.0, 0.0, -5.0);
        let a = spherical(p, 1.0, 0.4, Vec3::NEG_Z, 0.1, INF);
        assert!((a - (1.0 - (-0.8f32).exp())).abs() < 1e-6, "{a}");
        assert_eq!(spherical(p, 1.0, 0.4, Vec3::X, 0.1, INF), 0.0);
        assert!(
            one_minus_exp_neg(1e-9) > 0.0,
            "tiny densities keep their opacity"
        );
    }

    /// The camera moving through a particle in small steps: spherical billboards change
    /// α smoothly (no step above a small bound), planar ones jump to 0.
    #[test]
    fn no_popping_as_the_near_plane_crosses_a_particle() {
        let (r, tau, near) = (1.0, 2.0, 0.05);
        let q = |p: Vec3| Vec3::new(p.x, p.y, p.z); // ray through the centre
        let mut prev_s: Option<f32> = None;
        let mut prev_p: Option<f32> = None;
        let (mut max_step_s, mut max_step_p) = (0.0f32, 0.0f32);
        for i in 0..=400 {
            let z = -1.5 + i as f32 * 3.0 / 400.0; // particle centre from 1.5 ahead to 1.5 behind
            let p = Vec3::new(0.0, 0.0, z);
            let s = spherical(p, r, tau, Vec3::NEG_Z, near, INF);
            let pl = planar(p, r, tau, q(p), near, INF);
            if let Some(a) = prev_s {
                max_step_s = max_step_s.max((s - a).abs());
            }
            if let Some(a) = prev_p {
                max_step_p = max_step_p.max((pl - a).abs());
            }
            prev_s = Some(s);
            prev_p = Some(pl);
        }
        assert!(
            max_step_s < 0.03,
            "spherical: largest per-step change {max_step_s}"
        );
        assert!(
            max_step_p > 0.5,
            "planar pops: largest per-step change {max_step_p}"
        );
    }

    /// An opaque plane through the particle (the paper's Figure 1): across the pixels
    /// where the surface passes the particle's centre depth, spherical billboards fade
    /// smoothly, planar ones cut hard.
    #[test]
    fn no_hard_line_where_an_opaque_surface_cuts_a_particle() {
        let p = Vec3::new(0.0, 0.0, -10.0);
        let (r, tau) = (1.0, 3.0);
        // The scene depth varies linearly across x: a tilted wall through the centre.
        let jump = |f: &dyn Fn(f32) -> f32| {
            let mut m = 0.0f32;
            let mut prev: Option<f32> = None;
            for i in 0..=200 {
                let scene = 9.0 + i as f32 * 2.0 / 200.0;
                let a = f(scene);
                if let Some(b) = prev {
                    m = m.max((a - b).abs());
                }
                prev = Some(a);
            }
            m
        };
        let s = jump(&|scene| spherical(p, r, tau, Vec3::NEG_Z, 0.1, scene));
        let pl = jump(&|scene| planar(p, r, tau, p, 0.1, scene));
        assert!(s < 0.05, "spherical: largest step {s}");
        assert!(pl > 0.9, "planar: hard line of {pl}");
    }

    /// The paper's parallel-ray approximation against the exact perspective ray, for a
    /// particle off the view axis: equal on the axis, different near the image border.
    #[test]
    fn the_parallel_approximation_errs_off_axis() {
        let (r, tau) = (1.0, 1.0);
        let on_axis = Vec3::new(0.0, 0.0, -6.0);
        let exact = spherical(on_axis, r, tau, Vec3::NEG_Z, 0.1, INF);
        let approx = spherical_parallel(on_axis, r, tau, on_axis, 0.1, INF);
        assert!((exact - approx).abs() < 1e-6);
        // 30° off axis, the ray through the centre direction: exact sees d = 0.
        let off = Vec3::new(6.0 * 0.5773503, 0.0, -6.0);
        let e = spherical(off, r, tau, off.normalize(), 0.1, INF);
        // The paper's shader takes the quad point on the ray at the centre's depth.
        let q = off.normalize() * (6.0 / off.normalize().z.abs());
        let a = spherical_parallel(off, r, tau, q, 0.1, INF);
        assert!(
            (e - a).abs() < 1e-3,
            "through the centre both see the centre"
        );
        // Near the silhouette the approximation misplaces the edge.
        let dir = (off + Vec3::new(0.0, 0.93, 0.0)).normalize();
        let e = spherical(off, r, tau, dir, 0.1, INF);
        let q = dir * (6.0 / dir.z.abs());
        let a = spherical_parallel(off, r, tau, q, 0.1, INF);
        assert!(e > 0.0 && (e - a).abs() > 1e-3, "exact {e}, parallel {a}");
        // Sweeps of rays across a particle (r = 1, 6 away) off the view axis: the largest
        // opacity difference, quoted in docs/particles.md. It grows with the angle and
        // the density; on the axis it is 0.
        for (deg, tau) in [(30.0f32, 1.0), (30.0, 4.0), (45.0, 1.0), (45.0, 4.0)] {
            let c = Vec3::new(6.0 * deg.to_radians().tan(), 0.0, -6.0);
            let mut worst = 0.0f32;
            for i in -300..=300 {
                let dir = (c + Vec3::new(0.0, i as f32 * 0.005, 0.0)).normalize();
                let q = dir * (6.0 / dir.z.abs());
                let e = spherical(c, r, tau, dir, 0.1, INF);
                let a = spherical_parallel(c, r, tau, q, 0.1, INF);
                worst = worst.max((e - a).abs());
            }
            println!("{deg}° off axis, τ = {tau}: max |exact − parallel| = {worst:.4}");
            assert!(worst > 0.005 && worst < 0.5, "{worst}");
        }
    }
}
