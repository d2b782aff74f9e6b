//! The volume pass's WGSL copies of billow-core functions (`shaders/volume_math.wgsl`,
//! and `shaders/volume_loads.wgsl`'s `to_extinction`), run in a compute pass on the
//! headless device and read back, against the Rust they copy (shaders cannot call it):
//!
//! - `slice_lod` ↔ [`billow_core::slicing::slice_lod`], the per-slice MIP level the CPU
//!   slicer and the viewer's plan use: within 4 ulp-ish (`2e-6 · (1 + |λ|)`) — the GPU's
//!   `log2` is not correctly rounded — and exactly 0 and `max_lod` where clamped;
//! - `band_holds` ↔ [`billow_core::slicing::band_holds`] over the ranges
//!   [`billow_core::slicing::band_lod_range`] gives banded assets, at and around each
//!   band's first level: exactly (that the ranges hold the band
//!   [`billow_core::slicing::slice_band`] picks is the core's own test);
//! - `depth_fade` ↔ [`billow_core::slicing::slab_fade`] (no surface: the shader's 3e38,
//!   the core's infinity): within 1e-6;
//! - `slab_sample` ↔ [`billow_core::extinction::slab_sample`] with
//!   [`billow_core::extinction::OPAQUE_F16_OPTICAL_DEPTH`]: α within 2e-6, colour within
//!   `2e-6 · (1 + |c|)`, opaque exactly where the core says so;
//! - `to_extinction` ↔ [`billow_core::extinction::to_density`]: within `2e-6 · (1 + |x|)`;
//! - the shader's constants equal the core's `MAX_OPTICAL_DEPTH` and
//!   `OPAQUE_F16_OPTICAL_DEPTH` exactly.

mod common;

use billow_core::extinction::{
    slab_sample, to_density, MAX_OPTICAL_DEPTH, OPAQUE_F16_OPTICAL_DEPTH,
};
use billow_core::slicing::{band_holds, band_lod_range, slab_fade, slice_lod};
use billow_view::volume_math_gpu::{volume_math_on_gpu, MathCase};
use glam::Vec4;

/// The shader's "no surface" distance (`volume.wgsl`, `scene_distance`).
const NO_SURFACE: f32 = 3.0e38;

/// The first levels of the textures of banded assets (the base's 0, then each band's).
const BAND_LEVELS: [&[u32]; 4] = [&[0], &[0, 2], &[0, 1, 3], &[0, 3, 4, 7]];

fn cases() -> Vec<MathCase> {
    let mut lods = Vec::new();
    for v0 in [1e-3f32, 0.01, 0.37, 1.0, 5.0] {
        for max in [0.0f32, 3.0, 6.5, 7.0, 12.0] {
            for k in -4..=14 {
                lods.push([v0 * (k as f32).exp2(), v0, max]);
                lods.push([v0 * (k as f32 * 0.73 + 0.1).exp2(), v0, max]);
            }
        }
    }
    let mut fades = Vec::new();
    for thickness in [0.0f32, 1e-4, 0.25, 1.0, 37.0] {
        for slab0 in [0.5f32, 3.0, 120.0] {
            for z in [
                NO_SURFACE, 0.0, 0.4, 3.0, 3.1, 3.25, 4.0, 120.01, 157.0, 1e6,
            ] {
                fades.push([z, slab0, thickness]);
            }
        }
    }
    let mut slabs = Vec::new();
    for s in [
        0.0f32,
        1e-7,
        1e-3,
        0.05,
        0.5,
        3.0,
        6.2,
        6.229,
        OPAQUE_F16_OPTICAL_DEPTH,
        6.234_375,
        MAX_OPTICAL_DEPTH,
        9.0,
    ] {
        for ratio in [0.0f32, 0.125, 0.6, 1.0, 2.7, 40.0] {
            let c = [0.9f32, 0.35, 0.02];
            slabs.push(([c[0] * s, c[1] * s, c[2] * s, s], ratio));
        }
    }
    let mut texels = Vec::new();
    for a in (0..=255u32).step_by(3).chain([1, 254, 255]) {
        for ratio in [1.0f32, 1.587_401, 2.0, 4.0, 0.5] {
            let a = a as f32 / 255.0;
            texels.push(([0.8 * a, 0.3 * a, 0.05 * a, a], ratio));
        }
    }
    let mut bands = Vec::new();
    for levels in BAND_LEVELS {
        for b in 0..levels.len() {
            let [lo, hi] = band_lod_range(levels, b);
            for f in levels.iter().chain(&[9]) {
                let f = *f as f32;
                for lambda in [f, f - 1e-6, f + 1e-6, f - 0.5, f + 0.25, 0.0] {
                    bands.push([lo, hi, lambda, 0.0]);
                }
            }
        }
    }
    let n = lods
        .len()
        .max(fades.len())
        .max(slabs.len())
        .max(texels.len())
        .max(bands.len());
    (0..n)
        .map(|i| {
            let l = lods[i % lods.len()];
            let (e, ratio) = slabs[i % slabs.len()];
            let (c, tratio) = texels[i % texels.len()];
            // One ratio per case: the slab's, or the texel's on the cases past the slabs.
            let ratio = if i < slabs.len() { ratio } else { tratio };
            let c = if i < slabs.len() {
                [0.4, 0.2, 0.1, 0.5]
            } else {
                c
            };
            MathCase {
                lod: [l[0], l[1], l[2], ratio],
                fade: {
                    let f = fades[i % fades.len()];
                    [f[0], f[1], f[2], 0.0]
                },
                e,
                c,
                band: bands[i % bands.len()],
            }
        })
        .collect()
}

fn close(a: Vec4, b: Vec4, tol: f32) -> bool {
    (a - b)
        .abs()
        .cmple(Vec4::splat(tol) * (Vec4::ONE + b.abs()))
        .all()
}

#[test]
fn wgsl_volume_math_matches_billow_core() {
    let Some((cases, out)) = common::check_on_gpu(
        "wgsl_volume_math_matches_billow_core",
        cases(),
        volume_math_on_gpu,
    ) else {
        return;
    };
    let mut bad = Vec::new();
    let (mut worst_lod, mut worst_slab, mut worst_ext) = (0f32, 0f32, 0f32);
    for (k, o) in cases.iter().zip(&out) {
        let [max_depth, opaque] = [o.scalars[2], o.scalars[3]];
        if max_depth != MAX_OPTICAL_DEPTH || opaque != OPAQUE_F16_OPTICAL_DEPTH {
            bad.push(format!("constants: {max_depth} {opaque}"));
        }
        let lod = slice_lod(k.lod[0], k.lod[1], k.lod[2]);
        let got = o.scalars[0];
        worst_lod = worst_lod.max((got - lod).abs());
        let clamped = lod == 0.0 || lod == k.lod[2];
        if (clamped && got != lod) || (got - lod).abs() > 2e-6 * (1.0 + lod.abs()) {
            bad.push(format!("slice_lod{:?}: gpu {got}, core {lod}", &k.lod[..3]));
        }
        let [lo, hi, lambda, _] = k.band;
        let holds = band_holds([lo, hi], lambda);
        if (o.band[0] == 1.0) != holds {
            bad.push(format!(
                "band_holds([{lo}, {hi}], {lambda}): gpu {}, core {holds}",
                o.band[0]
            ));
        }
        let z = if k.fade[0] >= NO_SURFACE {
            f32::INFINITY
        } else {
            k.fade[0]
        };
        let fade = slab_fade(z, k.fade[1], k.fade[2]);
        if (o.scalars[1] - fade).abs() > 1e-6 {
            bad.push(format!(
                "depth_fade{:?}: gpu {}, core {fade}",
                &k.fade[..3],
                o.scalars[1]
            ));
        }
        let ratio = k.lod[3];
        let want = slab_sample(Vec4::from(k.e), ratio, OPAQUE_F16_OPTICAL_DEPTH);
        let got = Vec4::from(o.slab);
        worst_slab = worst_slab.max((got - want).abs().max_element());
        if !close(got, want, 2e-6) || ((want.w == 1.0) != (got.w == 1.0)) {
            bad.push(format!(
                "slab_sample({:?}, {ratio}): gpu {got}, core {want}",
                k.e
            ));
        }
        if ratio <= 0.0 {
            continue; // a texel has a size (the slab cases' zero ratio)
        }
        let want = to_density(Vec4::from(k.c), ratio);
        let got = Vec4::from(o.extinction);
        worst_ext = worst_ext.max(
            ((got - want) / (Vec4::ONE + want.abs()))
                .abs()
                .max_element(),
        );
        if !close(got, want, 2e-6) {
            bad.push(format!(
                "to_extinction({:?}, {ratio}): gpu {got}, core {want}",
                k.c
            ));
        }
    }
    eprintln!(
        "{} cases; worst |Δ| slice_lod {worst_lod:e}, slab_sample {worst_slab:e}, \
         to_extinction (relative) {worst_ext:e}",
        cases.len()
    );
    let count = |f: &str| bad.iter().filter(|b| b.starts_with(f)).count();
    let counts: Vec<String> = [
        "constants",
        "slice_lod",
        "band_holds",
        "depth_fade",
        "slab_sample",
        "to_extinction",
    ]
    .iter()
    .map(|f| format!("{f} {}", count(f)))
    .collect();
    assert!(
        bad.is_empty(),
        "{} mismatches ({}), the first:\n{}",
        bad.len(),
        counts.join(", "),
        bad[..bad.len().min(20)].join("\n")
    );
}
