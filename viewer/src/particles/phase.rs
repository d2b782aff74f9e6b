//! The phase function of dust and smoke, as printed in Umenhoffer et al. (§3.1):
//!
//! `P(μ, g) = 1/(4π) · 3(1 − g²)(1 + μ²) / (2(2 + g²)(1 + g² + 2gμ)^{3/2})`,
//!
//! the Cornette–Shanks form of Henyey–Greenstein. `μ = ω′·ω` with `ω′` the direction
//! from the particle **towards the light** and `ω` the direction towards the viewer, so
//! with the printed `+2gμ` a positive `g` scatters forward (light behind the particle,
//! `μ = −1`). It integrates to 1 over the sphere analytically; the LUT stores it over
//! `(μ, g)` and normalises each `g` row so that its linear interpolant — what the GPU's
//! filtering reads — integrates to exactly 1 (`2π ∫ P dμ`), which also keeps rows near
//! `g = ±1`, where the lobe is far narrower than a LUT texel, energy-conserving.

use std::f64::consts::PI;

/// The printed formula (f64).
pub fn phase(mu: f64, g: f64) -> f64 {
    let g2 = g * g;
    let denom = (1.0 + g2 + 2.0 * g * mu).max(0.0).powf(1.5);
    let num = 3.0 * (1.0 - g2) * (1.0 + mu * mu);
    if denom <= 0.0 {
        return 0.0; // only at |g| = 1, μ = ∓1 (the lobe's limit): excluded from the LUT
    }
    num / (2.0 * (2.0 + g2) * denom) / (4.0 * PI)
}

/// LUT sizes: `MU` samples of μ ∈ [−1, 1] (columns), `G` of g ∈ [−G_MAX, G_MAX] (rows).
pub const MU: usize = 128;
pub const G: usize = 64;
pub const G_MAX: f64 = 0.98;

/// Row-major `G × MU` table, each row normalised (module docs).
pub fn lut() -> Vec<f32> {
    let mut out = Vec::with_capacity(MU * G);
    for gi in 0..G {
        let g = -G_MAX + 2.0 * G_MAX * gi as f64 / (G - 1) as f64;
        let row: Vec<f64> = (0..MU)
            .map(|i| phase(-1.0 + 2.0 * i as f64 / (MU - 1) as f64, g))
            .collect();
        let h = 2.0 / (MU - 1) as f64;
        let trap = h * (row.iter().sum::<f64>() - 0.5 * (row[0] + row[MU - 1]));
        let k = 1.0 / (2.0 * PI * trap);
        out.extend(row.iter().map(|v| (v * k) as f32));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `2π ∫ P dμ` by the midpoint rule with `n` intervals, in `w = ln(1 + g² + 2gμ)`
    /// (uniform in μ for g = 0): near |g| = 1 the lobe is narrower than any uniform step.
    fn integral(g: f64, n: usize) -> f64 {
        if g.abs() < 1e-9 {
            let h = 2.0 / n as f64;
            let s: f64 = (0..n).map(|i| phase(-1.0 + (i as f64 + 0.5) * h, g)).sum();
            return s * h * 2.0 * PI;
        }
        let (v0, v1) = ((1.0 - g.abs()).powi(2), (1.0 + g.abs()).powi(2));
        let (w0, w1) = (v0.ln(), v1.ln());
        let h = (w1 - w0) / n as f64;
        let s: f64 = (0..n)
            .map(|i| {
                let v = (w0 + (i as f64 + 0.5) * h).exp();
                let mu = (v - 1.0 - g * g) / (2.0 * g);
                // dμ = dv / (2|g|) = v dw / (2|g|)
                phase(mu.clamp(-1.0, 1.0), g) * v / (2.0 * g.abs())
            })
            .sum();
        s * h * 2.0 * PI
    }

    #[test]
    fn integrates_to_one_for_every_g() {
        for &g in &[-0.999, -0.99, -0.9, -0.5, 0.0, 0.3, 0.8, 0.99, 0.999] {
            let i = integral(g, 200_000);
            assert!(i.is_finite() && (i - 1.0).abs() < 1e-6, "g = {g}: ∫ = {i}");
        }
        assert!((phase(0.3, 0.0) - 3.0 * (1.0 + 0.09) / (16.0 * PI)).abs() < 1e-12);
    }

    #[test]
    fn lut_rows_integrate_to_one_and_are_finite() {
        let t = lut();
        assert_eq!(t.len(), MU * G);
        assert!(t.iter().all(|v| v.is_finite() && *v >= 0.0));
        let h = 2.0 / (MU - 1) as f64;
        for gi in 0..G {
            let row = &t[gi * MU..(gi + 1) * MU];
            let trap = h
                * (row.iter().map(|&v| f64::from(v)).sum::<f64>()
                    - 0.5 * f64::from(row[0] + row[MU - 1]));
            assert!((2.0 * PI * trap - 1.0).abs() < 1e-5, "row {gi}");
        }
        // Positive g scatters forward: towards μ = −1 (light behind the particle).
        let last = &t[(G - 1) * MU..];
        assert!(last[0] > 10.0 * last[MU - 1]);
    }
}
