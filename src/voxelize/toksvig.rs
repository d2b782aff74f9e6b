//! Normal MIP filtering after Toksvig, *Mipmapping normal maps* (JGT 10(3), 2005).
//!
//! Toksvig's observation: averaging unit normals gives a vector whose length `|N̄| ≤ 1`
//! measures how much they disagree; keep the **shortened** average instead of
//! renormalising it, and derive the roughness from its length at shading time:
//! `ft = |N̄| / (|N̄| + s (1 − |N̄|))` scales a Blinn–Phong exponent `s`
//! ([`toksvig_factor`]), equivalently a variance `σ² = (1 − |N̄|) / |N̄|` ([`toksvig_variance`]).
//!
//! billow carries the **alpha-weighted normal sum** `Nw = Σ weight · n` next to the
//! premultiplied colour; the weight of a fragment is its visible opacity, so `Nw` filters
//! exactly like a premultiplied colour channel: composited along the view axis (what is
//! hidden does not count), averaged across it. At every level, for every direction,
//! `|Nw| ≤ α`. The six directions are combined as `N̄ = Σ_d Nw_d / Σ_d α_d` (the
//! alpha-weighted mean of everything the six cameras saw, independent of the colour
//! combine function), which is Toksvig's average of all the unit normals that fell in the
//! voxel. Opposite normals cancel to a zero vector, never NaN; an empty voxel has `N̄ = 0`.
//!
//! Storage: the per-direction `Nw` and the running sums `(Σ Nw, Σ α)` are f16 (the result
//! is quantized to snorm8, whose step 1/127 is far above f16's 2⁻¹¹ relative error), which
//! keeps `--normals` at 512³ within the memory budget.

use glam::Vec3;
use half::f16;
use rayon::prelude::*;

use super::mip::{downsample_with, Grid3, Texel};
use super::slices::DirSlices;
use super::Dir;

/// One MIP step of a direction's weighted normals `nrm`, occluded by the colour volume `rgba`
/// of the same level (same footprints and compositing as the colour, see [`super::mip`]).
pub(crate) fn downsample_normals<T: Texel>(
    nrm: &Grid3<[f16; 4]>,
    rgba: &Grid3<T>,
    view: Dir,
) -> Grid3<[f16; 4]> {
    downsample_with(nrm, rgba, view)
}

/// Toksvig's average normal `Σ Nw / Σ α` (length ≤ 1; zero when `Σ α` is 0).
pub fn average_normal(weighted_sum: Vec3, alpha_sum: f32) -> Vec3 {
    if alpha_sum.is_nan() || alpha_sum <= 1e-6 || !weighted_sum.is_finite() {
        return Vec3::ZERO;
    }
    let n = weighted_sum / alpha_sum;
    let len = n.length();
    if len > 1.0 {
        n / len
    } else {
        n
    }
}

/// Toksvig factor `ft = |N̄| / (|N̄| + s (1 − |N̄|))` for a Blinn–Phong exponent `s`;
/// the filtered exponent is `ft · s`. 0 for a zero-length normal.
pub fn toksvig_factor(len: f32, s: f32) -> f32 {
    let len = len.clamp(0.0, 1.0);
    let d = len + s * (1.0 - len);
    if d > 0.0 {
        len / d
    } else {
        0.0
    }
}

/// Variance of the normal distribution implied by a shortened normal: `(1 − |N̄|) / |N̄|`
/// (infinite for a zero-length normal).
pub fn toksvig_variance(len: f32) -> f32 {
    let len = len.clamp(0.0, 1.0);
    (1.0 - len) / len
}

/// Below this [`normal_coherence`] at MIP level [`AUTO_NORMALS_LEVEL`],
/// `voxelize --normals auto` drops the normals: the surface is thin or fuzzy at the scale
/// the MIP filter averages over (docs/voxelize.md, "Normals").
pub const AUTO_NORMALS_MIN_COHERENCE: f32 = 0.8;

/// The MIP level whose coherence `--normals auto` judges (clamped to the last level):
/// 4³ voxels per texel, where Toksvig's filter starts to average (the LOD at 4× the
/// distance where level 0 is magnified).
pub const AUTO_NORMALS_LEVEL: usize = 2;

/// How much one normal per texel says about a volume's surface at one MIP level: the
/// opacity-weighted mean length of the level's Toksvig normals, `Σ α·|n̄| / Σ α` (`rgba`:
/// RGBA8 texels, alpha last; `normals`: snorm8 texels, SPEC §8.4, same order). Near 1 for a
/// smooth closed surface (each texel sees one side of it, and its normals agree); small
/// for thin double-sided sheets, thin beams, fur and foliage, whose two faces (normals
/// flipped towards each camera) cancel in the six-direction average, or whose normals
/// point every way within one texel. `None` for an empty level.
pub fn normal_coherence(rgba: &[u8], normals: &[u8]) -> Option<f32> {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (c, n) in rgba.chunks_exact(4).zip(normals.chunks_exact(4)) {
        if c[3] == 0 {
            continue;
        }
        let a = f64::from(c[3]) / 255.0;
        let len = super::quantize::decode_normal([n[0], n[1], n[2], n[3]]).length();
        num += a * f64::from(len.min(1.0));
        den += a;
    }
    (den > 0.0).then(|| (num / den) as f32)
}

/// Running sums `(Σ Nw, Σ α)` of one MIP level over the six directions.
pub(crate) struct NormalAccum {
    pub levels: Vec<Vec<[f16; 4]>>,
    /// Level 0 already encoded elsewhere ([`super::combine::combine_level0`]).
    level0: Option<Vec<u8>>,
}

impl NormalAccum {
    pub fn new(level_sizes: &[usize]) -> Self {
        NormalAccum {
            levels: level_sizes
                .iter()
                .map(|&n| vec![[f16::ZERO; 4]; n])
                .collect(),
            level0: None,
        }
    }

    /// Hands over level 0's encoded normals (then [`NormalAccum::finish_level`]`(0)`
    /// returns them).
    pub fn set_level0(&mut self, encoded: Vec<u8>) {
        self.level0 = Some(encoded);
    }

    /// Adds one direction's level.
    pub fn fold<T: Texel>(&mut self, level: usize, nrm: &Grid3<[f16; 4]>, rgba: &Grid3<T>) {
        self.levels[level]
            .par_chunks_mut(4096)
            .zip(nrm.data.par_chunks(4096).zip(rgba.data.par_chunks(4096)))
            .for_each(|(acc, (n, c))| {
                for ((a, n), c) in acc.iter_mut().zip(n).zip(c) {
                    let (n, c) = (n.load(), c.load());
                    if c[3] == 0.0 && n == [0.0; 4] {
                        continue;
                    }
                    let s = a.load();
                    *a = <[f16; 4]>::store([s[0] + n[0], s[1] + n[1], s[2] + n[2], s[3] + c[3]]);
                }
            });
    }

    /// Adds one direction's sparse level 0 (its weighted normals and colour alpha).
    pub fn fold_sparse(&mut self, s: &DirSlices) {
        let Some(nrm) = s.nrm.as_ref() else {
            return;
        };
        let acc = &mut self.levels[0];
        for j in 0..s.row_count() {
            let (row, first) = s.row(j);
            for (k, v) in row.iter().enumerate() {
                let i = s.index(j, v);
                let n = nrm[first + k];
                let a = acc[i].load();
                acc[i] =
                    <[f16; 4]>::store([a[0] + n[0], a[1] + n[1], a[2] + n[2], a[3] + v.rgba[3]]);
            }
        }
    }

    /// Encoded snorm8 normals of one level (see [`super::quantize::encode_normal`]).
    pub fn finish_level(&mut self, level: usize) -> Vec<u8> {
        if level == 0 {
            if let Some(done) = self.level0.take() {
                return done;
            }
        }
        let acc = std::mem::take(&mut self.levels[level]);
        let mut out = vec![0u8; acc.len() * 4];
        out.par_chunks_mut(4 * 4096)
            .zip(acc.par_chunks(4096))
            .for_each(|(o, a)| {
                for (o, a) in o.chunks_exact_mut(4).zip(a) {
                    let s = a.load();
                    let n = average_normal(Vec3::new(s[0], s[1], s[2]), s[3]);
                    o.copy_from_slice(&super::quantize::encode_normal(n));
                }
            });
        out
    }
}

#[cfg(test)]
mod tests {
    //! Toksvig filtering through the real MIP path ([`downsample_normals`], the
    //! level-by-level step of every direction's pyramid, then [`NormalAccum`]).

    use super::*;

    /// A 2×2×2 direction volume, opaque, whose weighted normals are `left` in the x = 0
    /// voxels and `right` in the x = 1 voxels (siblings of one parent).
    fn siblings(left: Vec3, right: Vec3) -> (Grid3<[f16; 4]>, Grid3<[f32; 4]>) {
        let mut nrm = Grid3::<[f16; 4]>::new([2, 2, 2]);
        let mut rgba = Grid3::<[f32; 4]>::new([2, 2, 2]);
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..2 {
                    let i = nrm.index([x, y, z]);
                    let n = if x == 0 { left } else { right };
                    nrm.data[i] = <[f16; 4]>::store([n.x, n.y, n.z, 0.0]);
                    rgba.data[i] = [0.5, 0.5, 0.5, 1.0];
                }
            }
        }
        (nrm, rgba)
    }

    fn parent_normal(left: Vec3, right: Vec3, view: Dir) -> (Vec3, f32) {
        let (nrm, rgba) = siblings(left, right);
        let n1 = downsample_normals(&nrm, &rgba, view);
        let c1 = super::super::mip::downsample(&rgba, view);
        assert_eq!(n1.dims, [1, 1, 1]);
        let n = n1.get([0, 0, 0]);
        let a = c1.get([0, 0, 0])[3];
        (average_normal(Vec3::new(n[0], n[1], n[2]), a), a)
    }

    #[test]
    fn opposite_normals_in_sibling_voxels_cancel() {
        // Seen along z, the x siblings are averaged across the view axis: +X and −X cancel.
        for view in [Dir::PosZ, Dir::NegZ, Dir::PosY] {
            let (n, a) = parent_normal(Vec3::X, -Vec3::X, view);
            assert!(n.is_finite(), "{view:?}: NaN normal");
            assert_eq!(a, 1.0);
            assert!(
                n.length() < 1e-3,
                "{view:?}: shortened length {}",
                n.length()
            );
            // Roughness maximal: the Toksvig factor drives any exponent to 0, the variance
            // of the implied distribution is infinite (or huge).
            assert!(toksvig_factor(n.length(), 64.0) < 1e-3);
            assert!(toksvig_variance(n.length()) > 1e3);
            assert_eq!(crate::voxelize::quantize::encode_normal(n), [0, 0, 0, 0]);
        }
        // Along x the siblings are composited front to back: the opaque front one hides the
        // other, so its normal survives at full length.
        let (n, _) = parent_normal(Vec3::X, -Vec3::X, Dir::NegX);
        assert!((n.length() - 1.0).abs() < 1e-3, "{n}");
        // Perpendicular siblings: length 1/√2, no cancellation (Toksvig's shortening).
        let (n, _) = parent_normal(Vec3::X, Vec3::Y, Dir::PosZ);
        assert!(
            (n.length() - std::f32::consts::FRAC_1_SQRT_2).abs() < 2e-3,
            "{n}"
        );
        // Identical siblings: unit length, smooth.
        let (n, _) = parent_normal(Vec3::Z, Vec3::Z, Dir::PosZ);
        assert!((n - Vec3::Z).length() < 1e-3 && toksvig_factor(n.length(), 64.0) > 0.99);
    }

    #[test]
    fn cancelled_normals_stay_zero_through_the_accumulator() {
        // Two directions whose parent normals are +X and −X (e.g. the two sides of a
        // double-sided leaf): the combined level is a zero normal, encoded as zeros.
        let (pos, rgba) = siblings(Vec3::X, Vec3::X);
        let (neg, _) = siblings(-Vec3::X, -Vec3::X);
        let c1 = super::super::mip::downsample(&rgba, Dir::PosZ);
        let mut acc = NormalAccum::new(&[8, 1]);
        acc.fold(1, &downsample_normals(&pos, &rgba, Dir::PosZ), &c1);
        acc.fold(1, &downsample_normals(&neg, &rgba, Dir::NegZ), &c1);
        assert_eq!(acc.finish_level(1), vec![0, 0, 0, 0]);
    }
}
