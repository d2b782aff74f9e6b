//! Image error metrics on premultiplied linear RGBA.
//!
//! - RMSE per channel (r, g, b, a) and over all four channels; PSNR = `10·log10(1/MSE)`
//!   (peak 1; `+∞` for identical images).
//! - The same RMSE over the **covered pixels** only (`rmse_covered`): the union of the
//!   reference's and the asset's coverage, pixels where either alpha exceeds
//!   [`COVERED_ALPHA`] (half an 8-bit step). The whole-frame RMSE shrinks with the empty
//!   background (at 16× the framed distance the object is a few pixels wide); this one
//!   does not: `rmse² · pixels = rmse_covered² · covered pixels`.
//! - Alpha coverage: mean `|Δα|`, and the relative coverage difference
//!   `(Σα_test − Σα_ref) / Σα_ref` (signed: negative = the asset is too transparent).
//! - Mean covered luminance: `Σ Y(premultiplied rgb) / Σ α` over the image, the
//!   alpha-weighted mean linear luminance (Rec. 709) of what covers the pixels, which does
//!   not depend on how much is covered; and its relative difference (signed: positive =
//!   the asset is brighter than the mesh).
//! - SSIM ([`super::ssim`]) on sRGB-encoded luma of the premultiplied colour (i.e. over
//!   black) and on alpha.
//! - FLIP (LDR-ꟻLIP, Andersson et al. 2020, NVIDIA's implementation through the `nv-flip`
//!   crate): the mean of its per-pixel perceptual error map (0 = identical, 1 = maximal),
//!   on the premultiplied colour over black encoded as 8-bit sRGB — the image a display
//!   shows, which is what LDR-FLIP is defined on — at [`FLIP_PIXELS_PER_DEGREE`].
//!
//! Accumulation is in f64.

use serde::Serialize;

use super::image::linear_to_srgb;
use super::ssim::ssim;
use super::{EvalError, ImageF32};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImageError {
    pub rmse_rgba: [f64; 4],
    pub rmse: f64,
    /// RMSE over all four channels over the covered pixels only (see the module docs); 0
    /// when no pixel is covered.
    pub rmse_covered: f64,
    /// Fraction of the frame's pixels that are covered (the union of both coverages).
    pub covered_fraction: f64,
    pub psnr_rgba: [f64; 4],
    pub psnr: f64,
    pub mean_abs_alpha: f64,
    pub coverage_reference: f64,
    pub coverage_test: f64,
    /// `(coverage_test − coverage_reference) / coverage_reference`; 0 when both are 0.
    pub coverage_rel_diff: f64,
    pub ssim_luma: f64,
    pub ssim_alpha: f64,
    /// Mean LDR-FLIP error of the colour over black (0 = identical).
    pub flip: f64,
    /// Mean covered linear luminance of the reference and of the test (see the module
    /// docs; 0 for an empty image).
    pub luminance_reference: f64,
    pub luminance_test: f64,
    /// `(luminance_test − luminance_reference) / luminance_reference`; 0 when both are 0.
    pub luminance_rel_diff: f64,
}

/// A pixel is covered when the reference's or the test's alpha exceeds this: half an 8-bit
/// step, so that a pixel an 8-bit display shows as empty in both is not.
pub const COVERED_ALPHA: f32 = 0.5 / 255.0;

/// The viewing condition of the FLIP metric: `nv_flip::DEFAULT_PIXELS_PER_DEGREE`, 67 pixels
/// per degree (a 0.7 m wide 3840-pixel monitor seen from 0.7 m).
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// 8-bit sRGB RGB of the premultiplied colour over black (what a display shows).
fn srgb8_over_black(img: &ImageF32) -> Vec<u8> {
    img.data
        .iter()
        .flat_map(|p| {
            [p.x, p.y, p.z].map(|c| {
                let c = if c.is_finite() {
                    c.clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (linear_to_srgb(c) * 255.0).round() as u8
            })
        })
        .collect()
}

/// Mean LDR-FLIP error of `test` against `reference` (same size, at least 1×1), both shown
/// over black; see the module docs.
pub fn flip(reference: &ImageF32, test: &ImageF32) -> f64 {
    let (w, h) = (reference.width, reference.height);
    if w == 0 || h == 0 || test.width != w || test.height != h {
        return f64::NAN;
    }
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8_over_black(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8_over_black(test));
    let map = nv_flip::flip(r, t, FLIP_PIXELS_PER_DEGREE);
    let v = map.to_vec();
    v.iter().map(|&e| f64::from(e)).sum::<f64>() / v.len().max(1) as f64
}

fn psnr(mse: f64) -> f64 {
    if mse <= 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

/// Compares `test` against `reference` (same size).
pub fn compare(reference: &ImageF32, test: &ImageF32) -> Result<ImageError, EvalError> {
    if reference.width != test.width || reference.height != test.height {
        return Err(EvalError::SizeMismatch {
            a_w: reference.width,
            a_h: reference.height,
            b_w: test.width,
            b_h: test.height,
        });
    }
    let n = reference.data.len().max(1) as f64;
    let mut se = [0.0f64; 4];
    let mut abs_a = 0.0;
    let (mut cov_r, mut cov_t) = (0.0, 0.0);
    let (mut se_covered, mut covered) = (0.0f64, 0u64);
    let (mut lum_r, mut lum_t) = (0.0f64, 0.0f64);
    let y709 = |p: &glam::Vec4| {
        0.2126 * f64::from(p.x) + 0.7152 * f64::from(p.y) + 0.0722 * f64::from(p.z)
    };
    for (r, t) in reference.data.iter().zip(&test.data) {
        lum_r += y709(r);
        lum_t += y709(t);
        let mut se_px = 0.0;
        for c in 0..4 {
            let d = f64::from(t[c]) - f64::from(r[c]);
            se[c] += d * d;
            se_px += d * d;
        }
        if r.w > COVERED_ALPHA || t.w > COVERED_ALPHA {
            covered += 1;
            se_covered += se_px;
        }
        abs_a += (f64::from(t.w) - f64::from(r.w)).abs();
        cov_r += f64::from(r.w);
        cov_t += f64::from(t.w);
    }
    let mse = se.map(|s| s / n);
    let mse_all = mse.iter().sum::<f64>() / 4.0;
    let rel = if cov_r > 0.0 {
        (cov_t - cov_r) / cov_r
    } else if cov_t > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    let luma = |img: &ImageF32| -> Vec<f32> {
        img.data
            .iter()
            .map(|p| linear_to_srgb(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z))
            .collect()
    };
    let alpha = |img: &ImageF32| -> Vec<f32> { img.data.iter().map(|p| p.w).collect() };
    let (w, h) = (reference.width as usize, reference.height as usize);
    let mean_lum = |lum: f64, cov: f64| if cov > 0.0 { lum / cov } else { 0.0 };
    let (luminance_reference, luminance_test) = (mean_lum(lum_r, cov_r), mean_lum(lum_t, cov_t));
    let luminance_rel_diff = if luminance_reference > 0.0 {
        (luminance_test - luminance_reference) / luminance_reference
    } else if luminance_test > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    Ok(ImageError {
        rmse_rgba: mse.map(f64::sqrt),
        rmse: mse_all.sqrt(),
        rmse_covered: if covered > 0 {
            (se_covered / (4.0 * covered as f64)).sqrt()
        } else {
            0.0
        },
        covered_fraction: covered as f64 / n,
        psnr_rgba: mse.map(psnr),
        psnr: psnr(mse_all),
        mean_abs_alpha: abs_a / n,
        coverage_reference: cov_r / n,
        coverage_test: cov_t / n,
        coverage_rel_diff: rel,
        ssim_luma: ssim(&luma(reference), &luma(test), w, h),
        ssim_alpha: ssim(&alpha(reference), &alpha(test), w, h),
        flip: flip(reference, test),
        luminance_reference,
        luminance_test,
        luminance_rel_diff,
    })
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;

    fn image(w: u32, h: u32, mut f: impl FnMut(u32, u32) -> Vec4) -> ImageF32 {
        let mut img = ImageF32::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.data[(y * w + x) as usize] = f(x, y);
            }
        }
        img
    }

    /// A deterministic pattern with structure at several scales.
    fn pattern(x: u32, y: u32) -> Vec4 {
        let (fx, fy) = (x as f32, y as f32);
        let v =
            0.5 + 0.25 * (fx * 0.4).sin() * (fy * 0.3).cos() + 0.2 * ((x / 8 + y / 8) % 2) as f32;
        let a = if (x + 2 * y).is_multiple_of(11) {
            0.5
        } else {
            1.0
        };
        Vec4::new(v * 0.9, v * 0.6, v * 0.3, 1.0) * a
    }

    #[test]
    fn covered_luminance_does_not_depend_on_coverage() {
        // Reference: half the pixels covered by grey 0.5 (premultiplied, α 1). Test: every
        // pixel covered by the same grey at α 0.5 (premultiplied 0.25): as bright.
        let r = image(4, 4, |x, _| {
            if x < 2 {
                Vec4::new(0.5, 0.5, 0.5, 1.0)
            } else {
                Vec4::ZERO
            }
        });
        let t = image(4, 4, |_, _| Vec4::new(0.25, 0.25, 0.25, 0.5));
        let e = compare(&r, &t).unwrap();
        assert!((e.luminance_reference - 0.5).abs() < 1e-9, "{e:?}");
        assert!(e.luminance_rel_diff.abs() < 1e-9, "{e:?}");
        let brighter = image(4, 4, |_, _| Vec4::new(0.3, 0.3, 0.3, 0.5));
        let e = compare(&r, &brighter).unwrap();
        assert!((e.luminance_rel_diff - 0.2).abs() < 1e-6, "{e:?}");
    }

    #[test]
    fn covered_rmse_is_over_the_union_of_both_coverages() {
        // 8×8, empty but for one pixel covered only in the reference (α 1 → 0) and one
        // only in the test (α 0 → 0.5): 2 of 64 pixels covered. Squared errors: 4·1 and
        // 4·0.25, so over the covered pixels MSE = 5 / 8, over the frame 5 / 256.
        let r = image(8, 8, |x, y| {
            Vec4::splat(if (x, y) == (1, 1) { 1.0 } else { 0.0 })
        });
        let t = image(8, 8, |x, y| {
            Vec4::splat(if (x, y) == (6, 2) { 0.5 } else { 0.0 })
        });
        let e = compare(&r, &t).unwrap();
        assert_eq!(e.covered_fraction, 2.0 / 64.0);
        assert!(
            (e.rmse_covered - (5.0f64 / 8.0).sqrt()).abs() < 1e-9,
            "{e:?}"
        );
        assert!((e.rmse - (5.0f64 / 256.0).sqrt()).abs() < 1e-9, "{e:?}");
        // Below half an 8-bit step is not covered; nothing covered is 0, not NaN.
        let faint = image(8, 8, |_, _| Vec4::splat(0.25 / 255.0));
        let e = compare(&faint, &image(8, 8, |_, _| Vec4::ZERO)).unwrap();
        assert_eq!((e.covered_fraction, e.rmse_covered), (0.0, 0.0));
    }

    #[test]
    fn known_rmse_and_psnr() {
        // Every channel off by 0.1 on half the pixels: MSE = 0.005, RMSE = √0.005, PSNR
        // = 10·log10(1/0.005) = 23.0103 dB; coverage: α +0.1 on half → +0.05 mean.
        let r = image(8, 4, |_, _| Vec4::splat(0.5));
        let t = image(8, 4, |x, _| Vec4::splat(if x < 4 { 0.6 } else { 0.5 }));
        let e = compare(&r, &t).unwrap();
        assert!((e.rmse - 0.005f64.sqrt()).abs() < 1e-6, "{}", e.rmse);
        assert!((e.psnr - 23.010_299_956).abs() < 1e-4, "{}", e.psnr);
        for c in 0..4 {
            assert!((e.rmse_rgba[c] - 0.005f64.sqrt()).abs() < 1e-6);
        }
        assert!((e.mean_abs_alpha - 0.05).abs() < 1e-6);
        assert!(
            (e.coverage_rel_diff - 0.1).abs() < 1e-6,
            "{}",
            e.coverage_rel_diff
        );
        // Identical: zero error, infinite PSNR, SSIM exactly 1, FLIP 0.
        let same = compare(&r, &r).unwrap();
        assert_eq!((same.rmse, same.psnr), (0.0, f64::INFINITY));
        assert_eq!((same.coverage_rel_diff, same.flip), (0.0, 0.0));
        assert!(compare(&r, &ImageF32::new(4, 8)).is_err());
    }

    #[test]
    fn ssim_and_flip_grow_with_noise_and_blur() {
        let (w, h) = (48, 40);
        let r = image(w, h, pattern);
        let e0 = compare(&r, &r).unwrap();
        assert_eq!((e0.ssim_luma, e0.ssim_alpha), (1.0, 1.0));
        let noisy = |amp: f32| {
            let mut rng = crate::rng::Pcg32::seeded(7, 0);
            image(w, h, |x, y| {
                let p = pattern(x, y);
                let n = amp * rng.range_f32(-1.0, 1.0);
                (p.truncate() + glam::Vec3::splat(n))
                    .clamp(glam::Vec3::ZERO, glam::Vec3::splat(p.w))
                    .extend(p.w)
            })
        };
        let blurred = |radius: i64| {
            image(w, h, |x, y| {
                let mut acc = Vec4::ZERO;
                let mut n = 0.0;
                for dy in -radius..=radius {
                    for dx in -radius..=radius {
                        let xx = (x as i64 + dx).clamp(0, w as i64 - 1) as u32;
                        let yy = (y as i64 + dy).clamp(0, h as i64 - 1) as u32;
                        acc += pattern(xx, yy);
                        n += 1.0;
                    }
                }
                acc / n
            })
        };
        let mut last = e0;
        for amp in [0.02, 0.08, 0.2] {
            let e = compare(&r, &noisy(amp)).unwrap();
            assert!(
                e.ssim_luma < last.ssim_luma - 0.005,
                "noise {amp}: SSIM {} after {}",
                e.ssim_luma,
                last.ssim_luma
            );
            assert!(
                e.flip > last.flip,
                "noise {amp}: FLIP {} after {}",
                e.flip,
                last.flip
            );
            last = e;
        }
        let mut last = e0;
        for radius in [1, 2, 4] {
            let e = compare(&r, &blurred(radius)).unwrap();
            assert!(
                e.ssim_luma < last.ssim_luma,
                "blur {radius}: SSIM {} after {}",
                e.ssim_luma,
                last.ssim_luma
            );
            assert!(
                e.ssim_alpha < 0.9,
                "blur {radius}: alpha SSIM {}",
                e.ssim_alpha
            );
            assert!(
                e.flip > last.flip,
                "blur {radius}: FLIP {} after {}",
                e.flip,
                last.flip
            );
            last = e;
        }
        // FLIP's extremes: black against white is close to its maximum of 1.
        let black = image(16, 16, |_, _| Vec4::new(0.0, 0.0, 0.0, 1.0));
        let white = image(16, 16, |_, _| Vec4::ONE);
        let f = flip(&black, &white);
        assert!(f > 0.9 && f <= 1.0, "black vs white FLIP {f}");
    }
}
