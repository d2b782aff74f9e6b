//! Image error metrics on premultiplied linear RGBA.
//!
//! - RMSE per channel (r, g, b, a) and over all four channels; PSNR = `10·log10(1/MSE)`
//!   (peak 1; `+∞` for identical images).
//! - Alpha coverage: mean `|Δα|`, and the relative coverage difference
//!   `(Σα_test − Σα_ref) / Σα_ref` (signed: negative = the asset is too transparent).
//! - SSIM ([`super::ssim`]) on sRGB-encoded luma of the premultiplied colour (i.e. over
//!   black) and on alpha.
//!
//! Accumulation is in f64.

use serde::Serialize;

use super::ssim::ssim;
use super::{EvalError, ImageF32};

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImageError {
    pub rmse_rgba: [f64; 4],
    pub rmse: f64,
    pub psnr_rgba: [f64; 4],
    pub psnr: f64,
    pub mean_abs_alpha: f64,
    pub coverage_reference: f64,
    pub coverage_test: f64,
    /// `(coverage_test − coverage_reference) / coverage_reference`; 0 when both are 0.
    pub coverage_rel_diff: f64,
    pub ssim_luma: f64,
    pub ssim_alpha: f64,
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
    for (r, t) in reference.data.iter().zip(&test.data) {
        for c in 0..4 {
            let d = f64::from(t[c]) - f64::from(r[c]);
            se[c] += d * d;
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
            .map(|p| super::image::linear_to_srgb(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z))
            .collect()
    };
    let alpha = |img: &ImageF32| -> Vec<f32> { img.data.iter().map(|p| p.w).collect() };
    let (w, h) = (reference.width as usize, reference.height as usize);
    Ok(ImageError {
        rmse_rgba: mse.map(f64::sqrt),
        rmse: mse_all.sqrt(),
        psnr_rgba: mse.map(psnr),
        psnr: psnr(mse_all),
        mean_abs_alpha: abs_a / n,
        coverage_reference: cov_r / n,
        coverage_test: cov_t / n,
        coverage_rel_diff: rel,
        ssim_luma: ssim(&luma(reference), &luma(test), w, h),
        ssim_alpha: ssim(&alpha(reference), &alpha(test), w, h),
    })
}
