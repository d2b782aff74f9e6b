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

use super::brick_grid::{for_each_voxel, local, BrickAccum, Bricked, Layout, B3};
use super::grid3::{Disjoint, Texel};
use super::mip::downsample_bricks;
use super::slices::DirSlices;
use super::Dir;

/// One MIP step of a direction's weighted normals `nrm`, occluded by the colour volume `rgba`
/// of the same level (same footprints and compositing as the colour, see [`super::mip`]).
/// `colour_next` is the colour's next level: the normals get its bricks (a superset of
/// theirs, since a normal is non-zero only where the colour is).
pub(crate) fn downsample_normals<T: Texel>(
    nrm: &Bricked<[f16; 4]>,
    rgba: &Bricked<T>,
    view: Dir,
    colour_next: &Layout,
) -> Bricked<[f16; 4]> {
    downsample_bricks(nrm, Some(rgba), view, Some(colour_next))
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

/// How `--normals auto` decides, before the bake ([`judge_normals`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalsJudgement {
    /// Judged on the bake itself: bake with mean normals, then judge level
    /// [`AUTO_NORMALS_LEVEL`] (clamped). For volumes of one MIP level (no coarser level).
    OnTheBake,
    /// The coherence of a bake at the judged level's size ([`coarse_normal_coherence`];
    /// `None`: it saw nothing).
    Coarse(Option<f32>),
}

/// Whether a coherence keeps the normals (at least [`AUTO_NORMALS_MIN_COHERENCE`]; an
/// empty level does not).
pub fn keeps(coherence: Option<f32>) -> bool {
    coherence.is_some_and(|k| k >= AUTO_NORMALS_MIN_COHERENCE)
}

/// A finished bake's judgement: the coherence of its judged level ([`AUTO_NORMALS_LEVEL`]
/// clamped to its `mip_count` levels; `coherence_at` reads it), `None` where the bake has no
/// mean normals (none, or moments), and whether the volume is a surface, whose level 0
/// keeps its opacity ([`super::CoverageScales::settle_level0`]) and whose normals a judged
/// bake keeps: `surface` where it was judged before the bake
/// ([`super::VoxelizeOptions::surface`]), else whether that coherence passes.
pub(crate) fn judge_baked(
    mip_count: usize,
    mean_normals: bool,
    surface: Option<bool>,
    coherence_at: impl FnOnce(usize) -> Option<f32>,
) -> (Option<f32>, bool) {
    let l = AUTO_NORMALS_LEVEL.min(mip_count.saturating_sub(1));
    let k = if mean_normals { coherence_at(l) } else { None };
    (k, surface.unwrap_or_else(|| keeps(k)))
}

/// `--normals auto`'s judgement, before the bake: on a coarse bake
/// ([`coarse_normal_coherence`] at level [`AUTO_NORMALS_LEVEL`], clamped to the last
/// level), or on the bake itself for a volume of one MIP level.
pub fn judge_normals(
    scene: &crate::scene::Scene,
    opts: &super::VoxelizeOptions,
) -> Result<NormalsJudgement, super::VoxelizeError> {
    let grid = super::grid_for(scene, opts)?;
    let mips = opts.mip_levels.unwrap_or_else(|| grid.full_mip_count());
    let level = AUTO_NORMALS_LEVEL.min(mips.saturating_sub(1) as usize) as u32;
    if level == 0 {
        return Ok(NormalsJudgement::OnTheBake);
    }
    Ok(NormalsJudgement::Coarse(coarse_normal_coherence(
        scene, opts, level,
    )?))
}

/// What [`normal_coherence`] at MIP level `level` of a bake with normals would say,
/// without baking them at full size: the coherence of level 0 of a bake over the same box
/// at that level's size, with the same combine, one MIP level, no baked lighting (which
/// changes colour, not alpha or normals), and as many samples per texel area as the level
/// averages (K·2^level per axis, at most [`super::MAX_SUPERSAMPLE`]). At 512³ and level 2
/// that bake is 128³, 1/64 of the voxels.
///
/// It is not the same number: level 2 of the full bake composites 4 level-0 slices per
/// texel through two MIP steps; the coarse voxel composites its fragments per sample
/// instead. On the meshes of docs/voxelize.md, "Normals", the two are within 0.05 and make
/// the same decisions.
pub fn coarse_normal_coherence(
    scene: &crate::scene::Scene,
    opts: &super::VoxelizeOptions,
    level: u32,
) -> Result<Option<f32>, super::VoxelizeError> {
    let grid = super::grid_for(scene, opts)?;
    let o = super::VoxelizeOptions {
        resolution: super::Resolution::Exact(grid.level_dims(level)),
        // The samples per texel area of the level judged (capped): one sample per coarse
        // voxel would see one normal where level 2 averages 16 of the bake's samples.
        supersample: (opts.supersample << level.min(3)).min(super::MAX_SUPERSAMPLE),
        bounds: Some(grid.bounds()),
        align: 1,
        mip_levels: Some(1),
        normals: true,
        moments: false,
        surface: None,
        bake: super::Bake::None,
        ..opts.clone()
    };
    let quiet = |_: super::Stage, _: f32| {};
    // One level: the bake records its level 0's coherence ([`judge_baked`]).
    Ok(if matches!(o.combine, super::CombineFn::Preset(_)) {
        super::voxelize_sparse(scene, &o, &quiet)?.normal_coherence
    } else {
        super::voxelize(scene, &o, &quiet)?.normal_coherence
    })
}

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

/// Running sums `(Σ Nw, Σ α)` of one MIP level over the six directions: brick-sparse
/// above level 0; level 0 is dense only when folded from the sparse stacks
/// ([`NormalAccum::fold_sparse`], expressions and custom functions).
pub(crate) struct NormalAccum {
    dense0: Vec<[f16; 4]>,
    dims0: [usize; 3],
    levels: Vec<BrickAccum<[f16; 4]>>,
    /// Level 0 already encoded elsewhere ([`super::combine::combine_level0`]).
    level0: Option<Vec<u8>>,
}

impl NormalAccum {
    /// Accumulators for levels of these sizes; `dense0`: level 0 is folded with
    /// [`NormalAccum::fold_sparse`] (else it comes encoded, [`NormalAccum::set_level0`]).
    pub fn new(level_dims: &[[usize; 3]], dense0: bool) -> Self {
        let n0 = if dense0 {
            level_dims[0].iter().product()
        } else {
            0
        };
        NormalAccum {
            dense0: vec![[f16::ZERO; 4]; n0],
            dims0: level_dims[0],
            levels: level_dims.iter().map(|&d| BrickAccum::new(d, 1)).collect(),
            level0: None,
        }
    }

    /// Level 0, already encoded (from the level-0 combine).
    pub fn set_level0(&mut self, encoded: Vec<u8>) {
        self.level0 = Some(encoded);
    }

    /// Folds one direction's weighted normals of `level` (occluding colour `rgba`, whose
    /// bricks the normals share).
    pub fn fold<T: Texel>(&mut self, level: usize, nrm: &Bricked<[f16; 4]>, rgba: &Bricked<T>) {
        debug_assert_eq!(nrm.layout.bricks, rgba.layout.bricks);
        let acc = &mut self.levels[level];
        acc.reserve(&rgba.layout);
        acc.for_each_brick(&rgba.layout, |acc, i| {
            let r = i * B3..(i + 1) * B3;
            for ((a, n), c) in acc.iter_mut().zip(&nrm.data[r.clone()]).zip(&rgba.data[r]) {
                let (n, c) = (n.load(), c.load());
                if c[3] == 0.0 && n == [0.0; 4] {
                    continue;
                }
                let s = a.load();
                *a = <[f16; 4]>::store([s[0] + n[0], s[1] + n[1], s[2] + n[2], s[3] + c[3]]);
            }
        });
    }

    /// Folds one direction's sparse level 0 into the dense level 0.
    pub fn fold_sparse(&mut self, s: &DirSlices) {
        let Some(nrm) = s.nrm.as_ref() else {
            return;
        };
        let acc = &mut self.dense0;
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

    /// Encoded snorm8 normals of one level (see [`super::quantize::encode_normal`]), dense.
    pub fn finish_level(&mut self, level: usize) -> Vec<u8> {
        let encode = |a: &[f16; 4]| {
            let s = a.load();
            super::quantize::encode_normal(average_normal(Vec3::new(s[0], s[1], s[2]), s[3]))
        };
        if level == 0 {
            if let Some(done) = self.level0.take() {
                return done;
            }
            let acc = std::mem::take(&mut self.dense0);
            let mut out = vec![0u8; self.dims0.iter().product::<usize>() * 4];
            out.par_chunks_mut(4 * 4096)
                .zip(acc.par_chunks(4096))
                .for_each(|(o, a)| {
                    for (o, a) in o.chunks_exact_mut(4).zip(a) {
                        o.copy_from_slice(&encode(a));
                    }
                });
            return out;
        }
        let acc = std::mem::replace(&mut self.levels[level], BrickAccum::new([0; 3], 1));
        let dims = acc.dims;
        // Voxels nothing was folded into encode as 0 (a zero normal).
        let mut out = vec![0u8; dims.iter().product::<usize>() * 4];
        let dst = Disjoint::new(&mut out);
        acc.data
            .par_chunks(B3)
            .zip(&acc.bricks)
            .for_each(|(brick, &b)| {
                for_each_voxel(acc.coords(b as usize), dims, |p| {
                    let i = p[0] + dims[0] * (p[1] + dims[1] * p[2]);
                    // SAFETY: every voxel lies in one brick, and each brick is one task.
                    unsafe { dst.slice_mut(4 * i, 4) }.copy_from_slice(&encode(&brick[local(p)]));
                });
            });
        out
    }
}

impl NormalAccum {
    /// [`NormalAccum::finish_level`] of a level above 0 kept brick-sparse: the
    /// accumulator's bricks (in its slot order) and their snorm8 bytes (`4 · B3` per
    /// brick; zero outside the level).
    pub fn finish_level_bricks(&mut self, level: usize) -> (Vec<u32>, Vec<u8>) {
        debug_assert!(level > 0);
        let acc = std::mem::replace(&mut self.levels[level], BrickAccum::new([0; 3], 1));
        let dims = acc.dims;
        let mut out = vec![0u8; acc.bricks.len() * 4 * B3];
        out.par_chunks_mut(4 * B3)
            .zip(acc.data.par_chunks(B3))
            .zip(&acc.bricks)
            .for_each(|((o, brick), &b)| {
                for_each_voxel(acc.coords(b as usize), dims, |p| {
                    let s = brick[local(p)].load();
                    let n = average_normal(Vec3::new(s[0], s[1], s[2]), s[3]);
                    o[4 * local(p)..4 * local(p) + 4]
                        .copy_from_slice(&super::quantize::encode_normal(n));
                });
            });
        (acc.bricks, out)
    }
}

#[cfg(test)]
mod tests {
    //! Toksvig filtering through the real MIP path ([`downsample_normals`], the
    //! level-by-level step of every direction's pyramid, then [`NormalAccum`]).

    use super::super::grid3::Grid3;
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
        let (nrm, rgba) = (Bricked::from_dense(&nrm), Bricked::from_dense(&rgba));
        let c1 = downsample_bricks::<_, [f32; 4]>(&rgba, None, view, None);
        let n1 = downsample_normals(&nrm, &rgba, view, &c1.layout);
        assert_eq!(n1.dims(), [1, 1, 1]);
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
        let (pos, neg, rgba) = (
            Bricked::from_dense(&pos),
            Bricked::from_dense(&neg),
            Bricked::from_dense(&rgba),
        );
        let c1 = downsample_bricks::<_, [f32; 4]>(&rgba, None, Dir::PosZ, None);
        let mut acc = NormalAccum::new(&[[2, 2, 2], [1, 1, 1]], false);
        acc.fold(
            1,
            &downsample_normals(&pos, &rgba, Dir::PosZ, &c1.layout),
            &c1,
        );
        acc.fold(
            1,
            &downsample_normals(&neg, &rgba, Dir::NegZ, &c1.layout),
            &c1,
        );
        assert_eq!(acc.finish_level(1), vec![0, 0, 0, 0]);
    }
}
