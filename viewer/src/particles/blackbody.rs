//! Black-body colour of fire (Umenhoffer et al. §3.2): Planck's spectral radiance
//! `L(λ, T) = 2C₁ / (λ⁵ (e^{C₂/(λT)} − 1))` (the paper's constants) integrated against the
//! CIE 1931 colour-matching functions ([`super::cie1931`], 5 nm) to XYZ, converted to
//! linear sRGB (IEC 61966-2-1 matrix, D65 white), tabulated over temperature.
//!
//! Scale: the table is divided by the luminance `Y` at [`NORM_K`], so a flame at that
//! temperature has luminance 1 and hotter ones are brighter (the frame is floating point;
//! the final resolve clamps). Colours outside the sRGB gamut (the deep red of cool
//! flames) are clipped to non-negative components.

use super::cie1931::{CMF, START_NM, STEP_NM};

pub const C1: f64 = 3.7418e-16;
pub const C2: f64 = 1.4388e-2;
/// Temperature (K) whose colour has luminance 1 in the table.
pub const NORM_K: f64 = 2000.0;
/// Table range and size: `N` entries from 0 K to `T_MAX` K.
pub const T_MAX: f64 = 10_000.0;
pub const N: usize = 256;

/// Planck's radiance at wavelength `lambda` metres (0 at 0 K).
pub fn planck(lambda: f64, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let x = C2 / (lambda * t);
    if x > 700.0 {
        return 0.0; // e^x overflows; the radiance is 0 to f64 precision
    }
    2.0 * C1 / (lambda.powi(5) * x.exp_m1())
}

/// CIE XYZ of a black body at `t` K (5 nm rectangle rule, unnormalised).
pub fn xyz(t: f64) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (i, c) in CMF.iter().enumerate() {
        let l = planck((START_NM + STEP_NM * i as f64) * 1e-9, t);
        for k in 0..3 {
            s[k] += l * c[k] * STEP_NM;
        }
    }
    s
}

/// Chromaticity `(x, y)` at `t` K.
pub fn chromaticity(t: f64) -> (f64, f64) {
    let [x, y, z] = xyz(t);
    let s = x + y + z;
    (x / s, y / s)
}

pub fn xyz_to_linear_srgb(c: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = c;
    [
        3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z,
        -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z,
        0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z,
    ]
}

/// `N` linear-sRGB colours from 0 to `T_MAX` K, luminance 1 at [`NORM_K`].
pub fn lut() -> Vec<[f32; 3]> {
    let norm = xyz(NORM_K)[1];
    (0..N)
        .map(|i| {
            let t = T_MAX * i as f64 / (N - 1) as f64;
            let c = xyz(t).map(|v| v / norm);
            xyz_to_linear_srgb(c).map(|v| v.max(0.0) as f32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chromaticities_match_illuminant_a_and_d65() {
        let (x, y) = chromaticity(2856.0);
        assert!(
            (x - 0.4476).abs() < 0.005 && (y - 0.4074).abs() < 0.005,
            "2856 K: {x} {y}"
        );
        // The Planckian locus passes 0.005 below D65 (0.3127, 0.3290) in y.
        let (x, y) = chromaticity(6504.0);
        assert!(
            (x - 0.3127).abs() < 0.01 && (y - 0.3290).abs() < 0.01,
            "6504 K: {x} {y}"
        );
    }

    #[test]
    fn table_is_finite_and_luminance_monotone_from_zero() {
        let t = lut();
        assert_eq!(t.len(), N);
        assert_eq!(t[0], [0.0; 3], "0 K is black");
        let lum = |c: &[f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        for w in t.windows(2) {
            assert!(w[1].iter().all(|v| v.is_finite() && *v >= 0.0));
            assert!(
                lum(&w[1]) >= lum(&w[0]),
                "luminance must not decrease with T"
            );
        }
        // Luminance 1 at NORM_K (the gamut clip can only lower it a little).
        let i = (NORM_K / T_MAX * (N - 1) as f64).round() as usize;
        let k = (N - 1) as f64 / T_MAX * NORM_K - i as f64;
        assert!(k.abs() < 0.5);
        assert!((lum(&t[i]) - 1.0).abs() < 0.1, "{}", lum(&t[i]));
        // Fire colours: red > green > blue at 1500 K, nearly white at 6500 K.
        let c = t[(1500.0 / T_MAX * (N - 1) as f64) as usize];
        assert!(c[0] > c[1] && c[1] > c[2], "{c:?}");
        let w = t[(6500.0 / T_MAX * (N - 1) as f64) as usize];
        assert!(w[2] / w[0] > 0.8 && w[2] / w[0] < 1.25, "{w:?}");
    }
}
