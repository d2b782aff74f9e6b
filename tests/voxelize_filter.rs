//! MIP filtering (composite along, average across, odd sizes), the composite operator,
//! combine presets and expressions, Toksvig helpers, quantization and cells.

use std::str::FromStr;

use billow::voxelize::grid3::Grid3;
use billow::voxelize::mip::{downsample, taps};
use billow::voxelize::quantize::{decode_rgba8, encode_normal, encode_rgba8, srgb_eotf, srgb_oetf};
use billow::voxelize::toksvig::{average_normal, toksvig_factor};
use billow::voxelize::{
    clamp_premultiplied, Combine, CombineFn, CombineParseError, Dir, Expr, Preset,
};
use billow_core::cells::box_prisms;
use billow_core::compositing::over;
use glam::{Vec3, Vec4};
use proptest::prelude::*;

fn grid(dims: [usize; 3], mut f: impl FnMut([usize; 3]) -> [f32; 4]) -> Grid3<[f32; 4]> {
    let mut g = Grid3::new(dims);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let i = g.index([x, y, z]);
                g.data[i] = f([x, y, z]);
            }
        }
    }
    g
}

#[test]
fn composite_along_view_axis_average_across() {
    // Two voxels along x, both α = 0.5.
    let g = grid([2, 1, 1], |_| [0.25, 0.0, 0.0, 0.5]);
    for dir in Dir::ALL {
        let d = downsample(&g, dir);
        assert_eq!(d.dims, [1, 1, 1]);
        let a = d.data[0][3];
        let want = if dir.axis() == 0 { 0.75 } else { 0.5 };
        assert!((a - want).abs() < 1e-6, "{dir:?}: {a}");
    }
}

#[test]
fn composite_respects_the_viewing_side() {
    // Front (high x) red opaque-ish, back green: from +X red wins, from −X green.
    let g = grid([2, 1, 1], |p| {
        if p[0] == 1 {
            [0.8, 0.0, 0.0, 0.8]
        } else {
            [0.0, 0.8, 0.0, 0.8]
        }
    });
    let px = downsample(&g, Dir::PosX).data[0];
    let nx = downsample(&g, Dir::NegX).data[0];
    assert!(
        (Vec4::from(px) - Vec4::new(0.8, 0.16, 0.0, 0.96))
            .abs()
            .max_element()
            < 1e-6,
        "{px:?}"
    );
    assert!(
        (Vec4::from(nx) - Vec4::new(0.16, 0.8, 0.0, 0.96))
            .abs()
            .max_element()
            < 1e-6,
        "{nx:?}"
    );
}

#[test]
fn odd_taps_cover_every_child_exactly_once() {
    for d in 1..40usize {
        let t = taps(d);
        assert_eq!(t.len(), (d >> 1).max(1));
        let mut cover = vec![0.0f32; d];
        for parent in &t {
            for &(c, w) in parent {
                cover[c] += w;
            }
        }
        assert!(
            cover.iter().all(|&c| (c - 1.0).abs() < 1e-6),
            "d={d}: {cover:?}"
        );
    }
    assert_eq!(
        taps(5),
        vec![
            vec![(0, 1.0), (1, 1.0), (2, 0.5)],
            vec![(2, 0.5), (3, 1.0), (4, 1.0)]
        ]
    );
}

/// Composite of a whole column along `axis` (front first for `dir`).
fn column_alpha(g: &Grid3<[f32; 4]>, dir: Dir, mut p: [usize; 3]) -> f64 {
    let a = dir.axis();
    let n = g.dims[a];
    let mut t = 1.0f64;
    for i in 0..n {
        p[a] = if dir.positive() { n - 1 - i } else { i };
        t *= 1.0 - g.get(p)[3] as f64;
    }
    1.0 - t
}

#[test]
fn odd_sizes_preserve_column_opacity_and_coverage_at_every_level() {
    for dir in Dir::ALL {
        let a = dir.axis();
        // Uniform across the view axis, varying along it: each column's opacity is kept.
        let mut g = grid([5, 3, 7], |p| {
            let al = 0.1 + 0.12 * p[a] as f32;
            [al * 0.5, al * 0.25, 0.0, al]
        });
        let want = column_alpha(&g, dir, [0, 0, 0]);
        let mut levels = 1;
        while g.dims != [1, 1, 1] {
            g = downsample(&g, dir);
            levels += 1;
            for v in &g.data {
                assert!(
                    v[0] <= v[3] + 1e-6
                        && v[3] <= 1.0
                        && v.iter().all(|c| c.is_finite() && *c >= 0.0)
                );
            }
            let got = column_alpha(&g, dir, [0, 0, 0]);
            assert!(
                (got - want).abs() < 1e-5,
                "{dir:?} {:?}: {got} vs {want}",
                g.dims
            );
        }
        assert_eq!(levels, 3); // 5x3x7 → 2x1x3 → 1x1x1
                               // One voxel thick along the view axis: the average coverage is kept.
        let mut dims = [5, 3, 7];
        dims[a] = 1;
        let g = grid(dims, |p| {
            [
                0.0,
                0.0,
                0.0,
                ((p[0] * 7 + p[1] * 3 + p[2]) % 5) as f32 / 4.0,
            ]
        });
        let mean = |g: &Grid3<[f32; 4]>| {
            g.data.iter().map(|v| v[3] as f64).sum::<f64>() / g.data.len() as f64
        };
        let d = downsample(&g, dir);
        assert!((mean(&d) - mean(&g)).abs() < 1e-5, "{dir:?}");
    }
}

#[test]
fn single_voxel_volume_is_its_own_mip() {
    let g = grid([1, 1, 1], |_| [0.1, 0.2, 0.3, 0.4]);
    for dir in Dir::ALL {
        assert_eq!(downsample(&g, dir), g);
    }
}

#[test]
fn presets_mean_max_min_opaque() {
    // Seen only from +Z (a single-sided quad facing +Z).
    let mut s = [Vec4::ZERO; 6];
    s[4] = Vec4::new(0.6, 0.3, 0.0, 1.0);
    let mean = Preset::Mean.combine(&s);
    let max = Preset::Max.combine(&s);
    assert!((mean - s[4] / 6.0).abs().max_element() < 1e-6);
    assert_eq!(max, s[4]);
    assert_eq!(Preset::Min.combine(&s), Vec4::ZERO);
    assert_eq!(Preset::Opaque.combine(&s), s[4]);
    // opaque: α = max, colour = alpha-weighted mean of straight colours × α.
    let mut s = [Vec4::ZERO; 6];
    s[0] = Vec4::new(1.0, 0.0, 0.0, 1.0); // straight red, α 1
    s[1] = Vec4::new(0.0, 0.5, 0.0, 0.5); // straight green, α 0.5
    let o = Preset::Opaque.combine(&s);
    assert!(
        (o - Vec4::new(2.0 / 3.0, 1.0 / 3.0, 0.0, 1.0))
            .abs()
            .max_element()
            < 1e-6,
        "{o}"
    );
    // max keeps rgb ≤ a.
    let m = Preset::Max.combine(&s);
    assert!(m.x <= m.w && m.y <= m.w);
}

#[test]
fn expressions_parse_evaluate_and_report_columns() {
    let e = Expr::parse("max(px, nx) * 0.5 + mean(py, ny, pz, nz) * 0.5").unwrap();
    let mut s = [Vec4::ZERO; 6];
    s[0] = Vec4::splat(0.8);
    s[2] = Vec4::splat(0.4);
    assert!(
        (e.combine(&s) - Vec4::splat(0.4 + 0.05))
            .abs()
            .max_element()
            < 1e-6
    );
    let e = Expr::parse("rgba(px.r, py.g, 0, max(px.a, py.a)) / 2 - -1e-1").unwrap();
    assert!(
        (e.combine(&s) - Vec4::new(0.5, 0.3, 0.1, 0.5))
            .abs()
            .max_element()
            < 1e-6
    );
    let col = |src: &str| Expr::parse(src).unwrap_err().column;
    assert_eq!(col("max(px, qx)"), 9);
    assert_eq!(col("px +"), 5);
    assert_eq!(col("px + * py"), 6);
    assert_eq!(col("px.q"), 4);
    assert_eq!(col("(px"), 4);
    assert_eq!(col("px $ 1"), 4);
    assert_eq!(col("clamp(px, 0)"), 1);
    assert_eq!(col(""), 1);
    assert!(Expr::parse("px py")
        .unwrap_err()
        .message
        .contains("unexpected"));
    // Through the CLI syntax the column counts the `expr:` prefix.
    match CombineFn::from_str("expr:px + * py") {
        Err(CombineParseError::Expr(e)) => assert_eq!(e.column, 11),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        CombineFn::from_str("median"),
        Err(CombineParseError::Unknown(_))
    ));
    assert!(matches!(
        CombineFn::from_str("opaque"),
        Ok(CombineFn::Preset(Preset::Opaque))
    ));
    // Clamping: NaN → 0, rgb ≤ a ≤ 1.
    let e = Expr::parse("px / 0 - 2").unwrap();
    let c = clamp_premultiplied(e.combine(&[Vec4::ZERO; 6]));
    assert_eq!(c, Vec4::ZERO);
    assert_eq!(
        clamp_premultiplied(Vec4::new(2.0, -1.0, f32::NAN, 3.0)),
        Vec4::new(1.0, 0.0, 0.0, 1.0)
    );
    assert_eq!(
        clamp_premultiplied(Vec4::new(0.9, 0.2, 0.1, 0.5)),
        Vec4::new(0.5, 0.2, 0.1, 0.5)
    );
}

#[test]
fn deep_expressions_are_refused_not_overflowing() {
    let src = "(".repeat(100_000) + "px" + &")".repeat(100_000);
    assert!(Expr::parse(&src).is_err());
}

#[test]
fn toksvig_average_and_quantization() {
    // Two opposite unit normals of equal weight: zero, no NaN.
    assert_eq!(
        average_normal(Vec3::Z * 0.5 - Vec3::Z * 0.5, 1.0),
        Vec3::ZERO
    );
    assert_eq!(average_normal(Vec3::ZERO, 0.0), Vec3::ZERO);
    let n = average_normal(Vec3::new(0.5, 0.0, 0.5), 1.0);
    assert!((n.length() - 0.5f32.sqrt()).abs() < 1e-6);
    assert_eq!(toksvig_factor(1.0, 32.0), 1.0);
    assert_eq!(toksvig_factor(0.0, 32.0), 0.0);
    assert_eq!(encode_normal(Vec3::new(1.0, -1.0, 0.0)), [127, 129, 0, 0]);
    assert_eq!(
        encode_rgba8(Vec4::new(0.0, 0.5, 1.0, 1.0)),
        [0, 188, 255, 255]
    );
    for b in 0..=255u8 {
        assert_eq!(
            (srgb_oetf(srgb_eotf(b as f32 / 255.0)) * 255.0).round() as u8,
            b
        );
        assert_eq!(encode_rgba8(decode_rgba8([b, b, b, b])), [b, b, b, b]);
    }
}

#[test]
fn box_prisms_tile_the_box() {
    let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 5.0, 4.0));
    let prisms = box_prisms(min, max);
    let mut area = 0.0;
    for p in &prisms {
        let v = p.pos.map(Vec3::from_array);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        assert!(
            n.y > 0.0 && n.x == 0.0 && n.z == 0.0,
            "bottom triangle faces up"
        );
        area += 0.5 * n.length();
        for k in 0..3 {
            assert_eq!(v[k].y, min.y);
            assert_eq!(
                v[k + 3],
                v[k] + Vec3::Y * (max.y - min.y),
                "vertex {} above {k}",
                k + 3
            );
        }
        for (pos, uvw) in p.pos.iter().zip(&p.uvw) {
            let want = (Vec3::from_array(*pos) - min) / (max - min);
            assert!((Vec3::from_array(*uvw) - want).abs().max_element() < 1e-6);
        }
    }
    assert!((area - 8.0).abs() < 1e-5);
}

fn premul() -> impl Strategy<Value = Vec4> {
    (0.0f32..=1.0, 0.0f32..=1.0, 0.0f32..=1.0, 0.0f32..=1.0)
        .prop_map(|(r, g, b, a)| Vec4::new(r * a, g * a, b * a, a))
}

fn over64(f: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [0, 1, 2, 3].map(|i| f[i] + (1.0 - f[3]) * b[i])
}

fn to64(v: Vec4) -> [f64; 4] {
    v.to_array().map(|x| x as f64)
}

proptest! {
    #[test]
    fn over_matches_f64_reference_and_is_associative(a in premul(), b in premul(), c in premul()) {
        let left = over(over(a, b), c);
        let right = over(a, over(b, c));
        let reference = over64(to64(a), over64(to64(b), to64(c)));
        for v in [left, right] {
            prop_assert!(v.is_finite());
            prop_assert!((0.0..=1.0 + 1e-6).contains(&v.w));
            for i in 0..4 {
                prop_assert!((v[i] as f64 - reference[i]).abs() < 1e-5);
            }
            for i in 0..3 {
                prop_assert!(v[i] <= v.w + 1e-6);
            }
        }
    }

    #[test]
    fn mip_step_of_random_grid_stays_valid(
        dims in (1usize..7, 1usize..7, 1usize..7),
        seed in any::<u64>(),
        d in 0usize..6,
    ) {
        let mut x = seed | 1;
        let mut rnd = move || { x ^= x << 13; x ^= x >> 7; x ^= x << 17; (x >> 40) as f32 / (1u64 << 24) as f32 };
        let g = grid([dims.0, dims.1, dims.2], |_| {
            let a = rnd();
            [rnd() * a, rnd() * a, rnd() * a, a]
        });
        let out = downsample(&g, Dir::ALL[d]);
        for v in &out.data {
            prop_assert!(v.iter().all(|c| c.is_finite() && *c >= 0.0));
            prop_assert!(v[3] <= 1.0 + 1e-6);
            prop_assert!(v[0] <= v[3] + 1e-5 && v[1] <= v[3] + 1e-5 && v[2] <= v[3] + 1e-5);
        }
    }
}
