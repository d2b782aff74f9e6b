//! Extinction space: how volume texels are filtered so that thin opaque layers stay
//! opaque (docs/eval.md, "Thin layers").
//!
//! A premultiplied texel `(rgb, α)` becomes `(σ·c, σ)` with `σ = −ln(1 − α)` its optical
//! depth over one voxel (capped at [`MAX_OPTICAL_DEPTH`]) and `c = rgb/α` its straight
//! colour ([`to_extinction`]); these are filtered linearly (trilinear within a MIP level,
//! linear between levels) and turned back into premultiplied RGBA ([`from_extinction`]).
//! The CPU sampler (`billow::eval::volume_sampler`) filters the converted texels in f32;
//! the viewer uploads them converted ([`extinction_texel`], an `Rgba16Float` 3D texture)
//! and lets the texture unit filter them — one hardware trilinear sample per level
//! instead of eight loads and conversions.

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec4;

/// The largest optical depth a texel holds: `ln 510`, the optical depth of
/// `α = 1 − 1/510` (half an 8-bit step below 1). An opaque texel (α = 1, infinite
/// optical depth) is given this one, so that filtering stays finite.
pub const MAX_OPTICAL_DEPTH: f32 = 6.234_411;

/// A premultiplied texel in extinction space: `(σ·c, σ)` with `σ = −ln(1 − α)` the
/// texel's optical depth over one voxel (capped at [`MAX_OPTICAL_DEPTH`]) and `c = rgb/α`
/// its straight colour. Filtering these linearly interpolates the *optical depth* (what
/// the opacity correction `α' = 1 − (1 − α)^(d/d₀)` assumes α encodes), so a ray through
/// a one-voxel opaque layer stays opaque between texel centres; filtering α linearly
/// would give that layer an optical depth of only 2 (86 % opacity head-on) — the
/// see-through stripes of thin layers (docs/eval.md, "Thin layers").
#[inline]
pub fn to_extinction(c: Vec4) -> Vec4 {
    to_extinction_capped(c, MAX_OPTICAL_DEPTH)
}

/// [`to_extinction`] with the optical depth of an opaque texel (one whose own is at least
/// [`MAX_OPTICAL_DEPTH`], within half an 8-bit step of opaque) set to `cap`: a texel of a
/// coarser level, [`crate::slicing::opaque_optical_depth`], whose opaque texels are as
/// dense as level 0's.
#[inline]
pub fn to_extinction_capped(c: Vec4, cap: f32) -> Vec4 {
    let a = c.w.min(1.0);
    if !(a > 0.0) {
        return Vec4::ZERO;
    }
    let s = -(-a).ln_1p();
    let s = if s >= MAX_OPTICAL_DEPTH { cap } else { s };
    (c.truncate() * (s / a)).extend(s)
}

/// Back from [`to_extinction`] space to premultiplied RGBA: `α = 1 − e^(−σ)`, colour
/// `(σ·c)/σ · α`. `σ` within 1e-4 of [`MAX_OPTICAL_DEPTH`] (every texel under the
/// filter opaque) gives α = 1 exactly. [`slab_sample`] over one texel.
#[inline]
pub fn from_extinction(e: Vec4) -> Vec4 {
    slab_sample(e, 1.0, MAX_OPTICAL_DEPTH - 1e-4)
}

/// The optical depth at or above which the viewer's filtered sample of textures stored
/// as f16 is opaque: the CPU's `MAX_OPTICAL_DEPTH − 1e-4` lowered by one f16 step
/// (2⁻⁸ at 6.2), so that a footprint of opaque texels stored as f16 (6.234375) and
/// filtered with the hardware's weights still gives α = 1 (`volume_math.wgsl`'s
/// `OPAQUE_OPTICAL_DEPTH`, tested equal by `viewer/tests/volume_math_gpu.rs`).
pub const OPAQUE_F16_OPTICAL_DEPTH: f32 = 6.2304;

/// A filtered extinction-space sample `e = (σ·c, σ)` over a slab `ratio` texels thick,
/// back to premultiplied RGBA: `α = 1 − e^(−σ·ratio)`, colour `(σ·c)/σ · α`; `α = 1`
/// exactly where `σ ≥ opaque` (every texel under the filter opaque). The CPU sampler
/// passes its level-weighted sum (`ratio` 1, `opaque` the weighted caps); the viewer's
/// `slab_sample` (`volume_math.wgsl`) is this with [`OPAQUE_F16_OPTICAL_DEPTH`], tested
/// against it by `viewer/tests/volume_math_gpu.rs`. Zero for an empty sample or a slab
/// of no thickness.
#[inline]
pub fn slab_sample(e: Vec4, ratio: f32, opaque: f32) -> Vec4 {
    let s = e.w;
    if !(s > 0.0) || !(ratio > 0.0) {
        return Vec4::ZERO;
    }
    let a = if s >= opaque {
        1.0
    } else {
        -(-s * ratio).exp_m1()
    };
    (e.truncate() * (a / s)).extend(a)
}

/// [`to_extinction`] of a texel of a MIP level whose texels are `ratio` level-0 texels in
/// size ([`crate::slicing::level_size_ratio`]), its optical depth per level-0 texel (a
/// density: `σ / ratio`), opaque texels at [`MAX_OPTICAL_DEPTH`] whatever the level
/// ([`crate::slicing::opaque_optical_depth`]). What the viewer's volume textures hold
/// (`billow_view::volume_pass::extinction_levels`) and its filter by loads computes
/// (`volume_loads.wgsl`'s `to_extinction`, tested against this by
/// `viewer/tests/volume_math_gpu.rs`); `ratio` 1 is [`to_extinction`].
#[inline]
pub fn to_density(c: Vec4, ratio: f32) -> Vec4 {
    let e = to_extinction_capped(c, MAX_OPTICAL_DEPTH * ratio);
    if ratio != 1.0 {
        e / ratio
    } else {
        e
    }
}

/// The sRGB EOTF of an 8-bit value (IEC 61966-2-1), computed in f64 and rounded to f32:
/// what `*_SRGB` texture formats and the library's decode table give.
#[inline]
pub fn srgb8_to_linear(v: u8) -> f32 {
    let c = f64::from(v) / 255.0;
    (if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }) as f32
}

/// A stored RGBA8 texel (`srgb`: sRGB-encoded premultiplied colour, else linear) decoded
/// to linear premultiplied RGBA and taken to extinction space ([`to_extinction`]): what
/// the CPU sampler filters and what the viewer's volume texture holds.
#[inline]
pub fn extinction_texel(t: [u8; 4], srgb: bool) -> Vec4 {
    let c = |v: u8| {
        if srgb {
            srgb8_to_linear(v)
        } else {
            f32::from(v) / 255.0
        }
    };
    to_extinction(Vec4::new(
        c(t[0]),
        c(t[1]),
        c(t[2]),
        f32::from(t[3]) / 255.0,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_limits() {
        for a in 0..=255u8 {
            let c = Vec4::new(0.2, 0.1, 0.05, 1.0) * (f32::from(a) / 255.0);
            let back = from_extinction(to_extinction(c));
            assert!((back - c).abs().max_element() < 1e-5, "{a}: {c} -> {back}");
        }
        assert_eq!(to_extinction(Vec4::ZERO), Vec4::ZERO);
        assert_eq!(
            to_extinction(Vec4::new(1.0, 1.0, 1.0, 1.0)).w,
            MAX_OPTICAL_DEPTH
        );
        assert_eq!(from_extinction(Vec4::splat(MAX_OPTICAL_DEPTH)).w, 1.0);
        assert_eq!(from_extinction(Vec4::splat(f32::NAN)), Vec4::ZERO);
    }

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb8_to_linear(0), 0.0);
        assert_eq!(srgb8_to_linear(255), 1.0);
        assert!((srgb8_to_linear(188) - 0.502_886).abs() < 1e-6);
    }
}
