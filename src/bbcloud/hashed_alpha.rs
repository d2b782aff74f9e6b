//! Hashed alpha testing (Wyman & McGuire, "Hashed Alpha Testing", I3D 2017) of billboard
//! atlases: the alpha test's threshold is not a constant 0.5 but a hash, uniform in
//! (0, 1], of the texel cell the sample falls in, so a texel of alpha α passes with
//! probability α. A constant cut-off keeps a billboard's *own* coverage only if its MIPs
//! are rescaled, and even then the union of overlapping billboards thins out with distance
//! (the surviving texels of every layer crowd onto the dense clusters); with a hashed
//! threshold the expected coverage of every layer is its mean alpha and layers are
//! independent, so a distant canopy keeps the mesh's coverage while staying opaque,
//! depth-writing and order-independent (Lacewell §6 alpha-tests its billboards).
//!
//! - The cell is the texel grid of MIP level ⌊lod⌋ (texel coordinates of level 0 divided by
//!   2^⌊lod⌋, floored), keyed by the atlas, so the pattern is fixed to the billboard
//!   (stable under camera motion) and about one cell per pixel at any distance.
//! - Across MIP levels the hashes of levels ⌊lod⌋ and ⌊lod⌋ + 1 are blended by the fraction
//!   of lod and mapped back to a uniform value (the paper's CDF correction), so the pattern
//!   changes continuously with distance instead of re-rolling at each level.
//! - The hash is integer-only ([`hash3`]): the viewer's shader (`cloud.wgsl`) computes the
//!   same bits.

use glam::Vec2;

/// A 32-bit integer hash of three coordinates, as a float in [0, 1) (24 bits).
pub fn hash3(x: u32, y: u32, z: u32) -> f32 {
    let mut h =
        x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ z.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    (h >> 8) as f32 / 16_777_216.0
}

/// The alpha-test threshold of a sample at level-0 texel coordinates `texel` of atlas
/// `atlas`, seen at MIP level `lod` (module docs); in `[1e-6, 1]`.
pub fn hashed_threshold(texel: Vec2, lod: f32, atlas: u32) -> f32 {
    let lod = if lod.is_finite() {
        lod.clamp(0.0, 24.0)
    } else {
        24.0
    };
    let l0 = lod.floor();
    let f = lod - l0;
    let at = |l: f32| {
        let s = texel / 2f32.powi(l as i32);
        let (x, y) = (s.x.floor() as i64 as u32, s.y.floor() as i64 as u32);
        hash3(x, y, atlas ^ ((l as u32) << 24))
    };
    let x = (1.0 - f) * at(l0) + f * at(l0 + 1.0);
    let a = f.min(1.0 - f);
    let t = if a <= 1e-6 {
        x
    } else if x < a {
        x * x / (2.0 * a * (1.0 - a))
    } else if x < 1.0 - a {
        (x - 0.5 * a) / (1.0 - a)
    } else {
        1.0 - (1.0 - x) * (1.0 - x) / (2.0 * a * (1.0 - a))
    };
    t.clamp(1e-6, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The threshold is uniform at any lod (so a texel of alpha α passes with probability α),
    /// and fixed to the texel cell.
    #[test]
    fn thresholds_are_uniform_and_stable() {
        for lod in [0.0f32, 0.3, 0.5, 1.75, 3.0] {
            let n = 200u32;
            let mut below = [0u32; 4];
            for y in 0..n {
                for x in 0..n {
                    let t = hashed_threshold(Vec2::new(x as f32 * 7.3, y as f32 * 5.1), lod, 3);
                    for (k, b) in below.iter_mut().enumerate() {
                        if t <= 0.2 * (k + 1) as f32 {
                            *b += 1;
                        }
                    }
                }
            }
            for (k, b) in below.iter().enumerate() {
                let share = f64::from(*b) / f64::from(n * n);
                let want = 0.2 * (k + 1) as f64;
                assert!(
                    (share - want).abs() < 0.02,
                    "lod {lod}: P(t ≤ {want}) = {share}"
                );
            }
        }
        let a = hashed_threshold(Vec2::new(10.2, 4.9), 1.0, 0);
        assert_eq!(
            a,
            hashed_threshold(Vec2::new(11.9, 5.7), 1.0, 0),
            "same level-1 cell"
        );
    }
}
