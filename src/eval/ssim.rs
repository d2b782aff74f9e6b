//! SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) on one channel of values in `[0,1]`.
//!
//! Implemented here rather than taken from a crate, after looking: `image-compare` 0.5
//! works on 8-bit images and its SSIM uses non-overlapping 8×8 windows whose "variances"
//! are unnormalised sums (not Wang et al.'s statistic); `dssim-core` is a different,
//! multi-scale metric in Lab and AGPL-3.0, which this MIT/Apache project cannot link.
//! The perceptual metric billow takes from a crate is FLIP (`nv-flip`, see
//! [`super::metrics`]); this SSIM is checked by the unit tests below (identity, the closed
//! form for constant images, symmetry, bounds) and in `super::metrics` (it falls with noise
//! and blur). Standard parameters: Gaussian window σ = 1.5 truncated to 11×11 (separable,
//! normalised; clamp-to-edge at the borders, so every pixel gets a value),
//! `C1 = (0.01)²`, `C2 = (0.03)²`, dynamic range 1. Returns the mean SSIM map; 1 for
//! identical inputs. Accumulation in f64.

/// Mean SSIM of `a` and `b`, both `w × h`, row-major.
pub fn ssim(a: &[f32], b: &[f32], w: usize, h: usize) -> f64 {
    if w == 0 || h == 0 || a.len() != w * h || b.len() != w * h {
        return f64::NAN;
    }
    const R: i64 = 5;
    let sigma = 1.5f64;
    let mut k = [0.0f64; (2 * R + 1) as usize];
    for (i, v) in k.iter_mut().enumerate() {
        let x = i as f64 - R as f64;
        *v = (-x * x / (2.0 * sigma * sigma)).exp();
    }
    let s: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= s);
    let blur = |src: &[f64]| -> Vec<f64> {
        let mut tmp = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for (i, kv) in k.iter().enumerate() {
                    let xx = (x as i64 + i as i64 - R).clamp(0, w as i64 - 1) as usize;
                    acc += kv * src[y * w + xx];
                }
                tmp[y * w + x] = acc;
            }
        }
        let mut out = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for (i, kv) in k.iter().enumerate() {
                    let yy = (y as i64 + i as i64 - R).clamp(0, h as i64 - 1) as usize;
                    acc += kv * tmp[yy * w + x];
                }
                out[y * w + x] = acc;
            }
        }
        out
    };
    let fa: Vec<f64> = a.iter().map(|&v| f64::from(v)).collect();
    let fb: Vec<f64> = b.iter().map(|&v| f64::from(v)).collect();
    let prod = |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(x, y)| x * y).collect() };
    let (ma, mb) = (blur(&fa), blur(&fb));
    let (saa, sbb, sab) = (
        blur(&prod(&fa, &fa)),
        blur(&prod(&fb, &fb)),
        blur(&prod(&fa, &fb)),
    );
    let (c1, c2) = (0.01f64 * 0.01, 0.03f64 * 0.03);
    let mut total = 0.0;
    for i in 0..w * h {
        let (mx, my) = (ma[i], mb[i]);
        let vx = (saa[i] - mx * mx).max(0.0);
        let vy = (sbb[i] - my * my).max(0.0);
        let cxy = sab[i] - mx * my;
        total +=
            ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
    total / (w * h) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_and_bounds() {
        let (w, h) = (13, 9);
        // Constant images a and b: both variances and the covariance are 0, so
        // SSIM = (2ab + C1)/(a² + b² + C1) exactly, at every pixel.
        for (a, b) in [(0.5f32, 0.5f32), (0.2, 0.6), (0.0, 1.0), (0.9, 0.1)] {
            let (x, y) = (vec![a; w * h], vec![b; w * h]);
            let (a, b) = (f64::from(a), f64::from(b));
            let c1 = 1e-4;
            let want = (2.0 * a * b + c1) / (a * a + b * b + c1);
            assert!((ssim(&x, &y, w, h) - want).abs() < 1e-9, "{a} {b}");
        }
        // A pattern against itself: exactly 1; against its negative: far below 0;
        // symmetric; invalid sizes give NaN.
        let x: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 17) as f32 / 16.0).collect();
        let neg: Vec<f32> = x.iter().map(|v| 1.0 - v).collect();
        assert_eq!(ssim(&x, &x, w, h), 1.0);
        let s = ssim(&x, &neg, w, h);
        assert!((-1.0..0.0).contains(&s), "{s}");
        assert_eq!(s, ssim(&neg, &x, w, h));
        assert!(ssim(&x, &x, w + 1, h).is_nan());
        assert!(ssim(&[], &[], 0, 0).is_nan());
    }
}
