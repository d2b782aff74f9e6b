//! Premultiplied-alpha compositing and opacity correction for the slice spacing.
//!
//! Opacity correction (volume rendering with a sample distance `d` different from the
//! distance `d₀` an opacity was defined for): `α' = 1 − (1 − α)^(d/d₀)`. Written as
//! `α' = −expm1(r · ln_1p(−α))`, `r = d/d₀`, it keeps full relative precision for tiny
//! α (where `1 − (1 − α)^r` cancels catastrophically in f32: α = 1e-7 would give 0 or
//! 1.19e-7) and is exact at α = 0 (→ 0) and α = 1 (→ 1). Premultiplied colour is scaled
//! by `α'/α`, whose limit for α → 0 is `r`; α ≤ 0 uses that limit.

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec4;

/// Opacity corrected for the spacing ratio `ratio = d / d₀`. `alpha` is clamped to
/// `[0,1]`; `ratio ≤ 0` (or NaN) gives 0.
#[inline]
pub fn corrected_alpha(alpha: f32, ratio: f32) -> f32 {
    if !(ratio > 0.0) {
        return 0.0;
    }
    let a = alpha.clamp(0.0, 1.0);
    if a >= 1.0 {
        return 1.0;
    }
    (-(ratio * (-a).ln_1p()).exp_m1()).clamp(0.0, 1.0)
}

/// A premultiplied sample with its opacity corrected for `ratio` (colour scaled by α'/α).
#[inline]
pub fn correct_premultiplied(c: Vec4, ratio: f32) -> Vec4 {
    if ratio == 1.0 {
        return c;
    }
    let a = c.w.clamp(0.0, 1.0);
    let a2 = corrected_alpha(a, ratio);
    let scale = if a > 0.0 { a2 / a } else { ratio.max(0.0) };
    (c.truncate() * scale).extend(a2)
}

/// Back-to-front "over": `src` is in front of `dst` (both premultiplied).
#[inline]
pub fn over(src: Vec4, dst: Vec4) -> Vec4 {
    src + dst * (1.0 - src.w)
}

/// Front-to-back accumulation: `acc` is in front of `src`.
#[inline]
pub fn under(acc: Vec4, src: Vec4) -> Vec4 {
    acc + src * (1.0 - acc.w)
}
