//! Where the slices go: the slice planning of Volumetric Billboards §3.3 shared by the
//! CPU slicer (`billow::eval::slicer`) and the viewer (`billow_view`'s volume plan), so
//! both draw the same slices with the same f32 operations.
//!
//! - `v₀` ([`voxel_size`]): the world size of a level-0 voxel, minimum over the cells.
//! - Adaptive spacing at depth `z` ([`Spacing::Adaptive`]): `d(z) = bias ·
//!   max(pixel_size(z), v₀)`, one pixel's footprint, never finer than the magnified
//!   voxel; [`Spacing::Uniform`]: constant `d`.
//! - Slices front to back from the nearest cell depth ([`slice_depths`]): `z₀ = z_min +
//!   d(z_min)/2`, `z_{i+1} = z_i + d(z_i)` while `z < z_max`; the renderers draw them in
//!   reverse.
//! - The MIP level a slice samples ([`slice_lod`]): `λ = clamp(log2(d/v₀), 0, L)`.
//! - Stored normals → view space per cell: [`normal_matrix`], [`shade_normal`].

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use billow_format::Prism;
use glam::{Mat3, Vec3};

/// Slice spacing mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spacing {
    /// The paper's adaptive spacing scaled by `bias` (1 = paper; > 1 fewer slices).
    Adaptive { bias: f32 },
    /// Constant world-space spacing.
    Uniform { spacing: f32 },
}

impl Spacing {
    /// The same mode with slices `f` times farther apart.
    pub fn scaled(self, f: f32) -> Spacing {
        match self {
            Spacing::Adaptive { bias } => Spacing::Adaptive { bias: bias * f },
            Spacing::Uniform { spacing } => Spacing::Uniform {
                spacing: spacing * f,
            },
        }
    }
}

/// [`slice_depths`] would need more slices than its limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManySlices {
    /// A bounded estimate of how many the depth range needs (always > `limit`).
    pub needed: usize,
    pub limit: usize,
}

/// World size of a level-0 voxel: per cell, the affine map uvw → world (from vertices
/// 0, 1, 2, 3) scaled by the level-0 dims, `cbrt(|det J| / (w·h·d))` (the geometric
/// mean of the three voxel edge lengths); the minimum over the cells (the finest).
/// `None` when no cell has a non-degenerate uvw mapping.
pub fn voxel_size(cells: &[Prism], dims: [u32; 3]) -> Option<f32> {
    let n = f64::from(dims[0]) * f64::from(dims[1]) * f64::from(dims[2]);
    let mut best: Option<f32> = None;
    for c in cells {
        let p = |i: usize| Vec3::from(c.pos[i]) - Vec3::from(c.pos[0]);
        let t = |i: usize| Vec3::from(c.uvw[i]) - Vec3::from(c.uvw[0]);
        let pm = Mat3::from_cols(p(1), p(2), p(3));
        let tm = Mat3::from_cols(t(1), t(2), t(3));
        let dt = f64::from(tm.determinant());
        if dt.abs() < 1e-12 {
            continue;
        }
        let v = (f64::from(pm.determinant()) / dt).abs() / n;
        let s = v.cbrt() as f32;
        if s > 0.0 && s.is_finite() {
            best = Some(best.map_or(s, |b| b.min(s)));
        }
    }
    best
}

/// World size of a texel of MIP level `level` of a texture of level-0 size `dims0` drawn
/// on `cells`: [`voxel_size`] at that level's size (`max(1, d >> level)` per axis, the GPU
/// rule). For sides that are multiples of `2^level` this is `2^level · v₀`; otherwise a
/// texel spans `d / max(1, d >> level)` level-0 voxels along each axis (more than
/// `2^level` where a side was rounded down), and this is their geometric mean.
pub fn level_texel_size(cells: &[Prism], dims0: [u32; 3], level: u32) -> Option<f32> {
    voxel_size(cells, billow_format::mip_dims(dims0, level))
}

/// The MIP level `λ` a slice of spacing `d` samples: `clamp(log2(d / v₀), 0, max_lod)`,
/// `v₀` the asset's level-0 voxel size ([`voxel_size`]; for LOD bands the finest over the
/// bands, SPEC §8.6) and `max_lod` its last level. One rule for the CPU slicer
/// (`billow::eval::slicer`) and the viewer's volume plan; `volume.wgsl` (its
/// `volume_math.wgsl`'s `slice_lod`) is tested against it
/// (`viewer/tests/volume_math_gpu.rs`). A banded asset draws each slice with the band
/// whose `[first_level, next band's first_level)` holds `λ`, sampling its texture at
/// `λ − first_level`.
#[inline]
pub fn slice_lod(d: f32, v0: f32, max_lod: f32) -> f32 {
    (d / v0).log2().clamp(0.0, max_lod)
}

/// The slice-LOD range `[lo, hi)` over which `band` of an asset draws its slices (SPEC
/// §8.6), `first_levels` the first level of each of its textures in order (the base
/// texture's 0, then each LOD band's, strictly increasing): `[f_b, f_{b+1})`, the base's
/// open below (`lo = −1`: every [`slice_lod`] is at least 0) and the last's above
/// (`hi = 1e30`). The viewer's plan puts it in each band's uniform; [`slice_band`] and the
/// viewer's `volume.wgsl` (its `volume_math.wgsl`'s `band_holds`, tested against
/// [`band_holds`] in `viewer/tests/volume_math_gpu.rs`) pick bands by it.
pub fn band_lod_range(first_levels: &[u32], band: usize) -> [f32; 2] {
    let lo = if band == 0 {
        -1.0
    } else {
        first_levels[band] as f32
    };
    let hi = first_levels.get(band + 1).map_or(1e30, |&f| f as f32);
    [lo, hi]
}

/// Whether a slice of LOD `lod` ([`slice_lod`]) draws the band whose slice-LOD range is
/// `range` ([`band_lod_range`]): `lo ≤ lod < hi`.
#[inline]
pub fn band_holds(range: [f32; 2], lod: f32) -> bool {
    lod >= range[0] && lod < range[1]
}

/// The band a slice of LOD `lod` draws (SPEC §8.6), `first_levels` as for
/// [`band_lod_range`]: the one whose range holds `lod` — the last starting at or below
/// it — and the base texture (0) where none does (a NaN `lod`). The CPU slicer's choice;
/// the viewer's plan and shader draw each band over exactly the slices whose LOD its
/// range holds.
pub fn slice_band(first_levels: &[u32], lod: f32) -> usize {
    (0..first_levels.len())
        .rposition(|b| band_holds(band_lod_range(first_levels, b), lod))
        .unwrap_or(0)
}

/// The opacity correction of one slice, agreeing with the bake's coverage-keeping levels
/// (`billow::voxelize::coverage`): a texel of level `l` holds the optical depth `σ` of
/// its own thickness `s_l` ([`level_texel_size`]), so a slice standing for a slab of
/// thickness `d` takes `σ · d / s_l` from it. At the fractional level `lod` (clamped to
/// `sizes`, one per level) the two nearest levels are blended by their densities:
/// `[(l₀, (1 − t) · d / s_l₀), (l₀ + 1, t · d / s_l₀₊₁)]` with `l₀ = floor(lod)`,
/// `t = lod − l₀` (`nearest`: the one level `round(lod)`, weight `d / s`). The sample is
/// `α = 1 − e^(−Σ wᵢ σᵢ)`. For power-of-two sides and a whole `lod` this is the paper's
/// `α' = 1 − (1 − α)^(d/d₀)`, `d₀ = v₀ · 2^lod`; blending optical depths of levels of
/// different thickness as if they had the same one (the correction before) made a
/// slice between two levels up to 6 % denser.
pub fn level_weights(lod: f32, d: f32, sizes: &[f32], nearest: bool) -> [(usize, f32); 2] {
    let max = sizes.len().saturating_sub(1);
    let lod = if lod.is_finite() {
        lod.clamp(0.0, max as f32)
    } else {
        0.0
    };
    let w = |l: usize| d / sizes[l];
    if nearest {
        let l = (lod.round() as usize).min(max);
        return [(l, w(l)), (l, 0.0)];
    }
    let l0 = (lod.floor() as usize).min(max);
    let t = lod - l0 as f32;
    if t <= 0.0 || l0 == max {
        return [(l0, w(l0)), (l0, 0.0)];
    }
    [(l0, (1.0 - t) * w(l0)), (l0 + 1, t * w(l0 + 1))]
}

pub use crate::extinction::MAX_OPTICAL_DEPTH;

/// The optical depth an opaque texel of size `size` holds (`v0`: the size of a texel of
/// level 0 of the same texture, [`voxel_size`]; each LOD band of a pruned asset is its own
/// texture): [`MAX_OPTICAL_DEPTH`] per level-0 texel of thickness, so that opaque texels
/// of every level have the same density and a slice between two levels
/// ([`level_weights`]) blends their colours linearly, as it does for a homogeneous medium.
pub fn opaque_optical_depth(size: f32, v0: f32) -> f32 {
    let r = size / v0;
    if r.is_finite() && r > 0.0 {
        MAX_OPTICAL_DEPTH * r
    } else {
        MAX_OPTICAL_DEPTH
    }
}

/// A texel of a level of size `dims` of a texture whose level 0 is `dims0`, drawn on the
/// same cells: its size over a level-0 texel's, `cbrt(Π dims0 / dims)` ([`voxel_size`]
/// scales as the cube root of the texel count). A renderer that filters between levels in
/// hardware stores each level's optical depth divided by this (a density per level-0
/// texel) so that the blend of two levels is what [`level_weights`] gives; opaque texels
/// then hold [`MAX_OPTICAL_DEPTH`] at every level ([`opaque_optical_depth`]).
pub fn level_size_ratio(dims0: [u32; 3], dims: [u32; 3]) -> f32 {
    let r: f64 = (0..3)
        .map(|a| f64::from(dims0[a].max(1)) / f64::from(dims[a].max(1)))
        .product();
    r.cbrt() as f32
}

/// The slab the farthest slice stands for: from `z − d/2` (its own spacing `d` at depth
/// `z`) to the far end `z_max` of the sliced depth range, so that the slabs of a
/// [`slice_depths`] list cover the whole range (its last slice's centre lies before
/// `z_max`, so this is more than `d/2`; at most `3d/2`). Every other slice stands for
/// `d`. Without it, a range only one or two slices deep (a distant object) lost up to
/// half a slice of its optical depth.
pub fn far_slab(z: f32, d: f32, z_max: f32) -> f32 {
    let t = z_max - (z - 0.5 * d);
    if t > 0.5 * d {
        t
    } else {
        0.5 * d
    }
}

/// Slice depths and spacings `(depth, d)`, **front to back**, over `[z_min, z_max]`.
/// `pixel_size_at(z)`: the world size of one pixel at view depth `z` (the camera's,
/// e.g. [`crate::camera::Camera::pixel_size_at`]); `v0`: [`voxel_size`]; at most
/// `limit` slices.
pub fn slice_depths(
    pixel_size_at: impl Fn(f32) -> f32,
    spacing: Spacing,
    v0: f32,
    z_min: f32,
    z_max: f32,
    limit: usize,
) -> Result<Vec<(f32, f32)>, TooManySlices> {
    let d_at = |z: f32| match spacing {
        Spacing::Adaptive { bias } => bias * pixel_size_at(z).max(v0),
        Spacing::Uniform { spacing } => spacing,
    };
    let mut out = Vec::new();
    let mut z = z_min + 0.5 * d_at(z_min);
    while z < z_max {
        if out.len() >= limit {
            // Count how many would be needed (bounded estimate) for the message.
            let needed = ((z_max - z_min) / d_at(z_min).max(f32::MIN_POSITIVE)) as usize;
            return Err(TooManySlices {
                needed: needed.max(limit + 1),
                limit,
            });
        }
        let d = d_at(z);
        out.push((z, d));
        let next = z + d;
        if !(next > z) {
            break; // spacing below f32 resolution at this depth
        }
        z = next;
    }
    Ok(out)
}

/// The matrix taking a volume's stored normals to view space, for one cell (`view_cell`:
/// its vertices in view space, `uvw` its texture coordinates), used by the CPU slicer and
/// the viewer's volume plan alike (the viewer's `object_to_view` is the linear part of
/// camera view × instance):
///
/// - a box asset's normals are in its object space, which the cells' positions are given
///   in: the normal matrix of `object_to_view` (the inverse transpose of its linear part;
///   a rotation for the CPU slicer's camera, where objects are not transformed);
/// - a shell's (`shell`: repeat addressing) are in the tile's space, which uvw addresses
///   (a tile baked on the unit box, as `billow shell` expects): the inverse transpose of
///   the cell's uvw → view Jacobian (from vertices 0, 1, 2, 3), so the fur of a torus
///   turns with its surface.
///
/// Only the direction of the result matters ([`shade_normal`] keeps the Toksvig length).
/// A degenerate map gives the zero matrix (unlit: the ambient term).
pub fn normal_matrix(
    object_to_view: Mat3,
    shell: bool,
    view_cell: &[[f32; 3]; 6],
    uvw: &[[f32; 3]; 6],
) -> Mat3 {
    let m = if shell {
        let p = |i: usize| Vec3::from(view_cell[i]) - Vec3::from(view_cell[0]);
        let t = |i: usize| Vec3::from(uvw[i]) - Vec3::from(uvw[0]);
        let pm = Mat3::from_cols(p(1), p(2), p(3));
        let tm = Mat3::from_cols(t(1), t(2), t(3));
        if tm.determinant().abs() < 1e-20 {
            return Mat3::ZERO;
        }
        pm * tm.inverse()
    } else {
        object_to_view
    };
    let det = m.determinant();
    if !(det.abs() > 1e-30 && det.is_finite()) {
        return Mat3::ZERO;
    }
    m.inverse().transpose()
}

/// A stored-frame Toksvig normal `n` (`|n| ≤ 1`) in view space: the direction of
/// `nmat · n` with the length of `n` (the roughness stays the stored one).
#[inline]
pub fn shade_normal(nmat: Mat3, n: Vec3) -> Vec3 {
    let v = nmat * n;
    let l = v.length();
    if l > 0.0 && l.is_finite() {
        v * (n.length() / l)
    } else {
        Vec3::ZERO
    }
}

/// The part of a slab from `slab0`, `thickness` deep, in front of an opaque surface at
/// view distance `z`: `clamp((z − slab0)/thickness, 0, 1)` (1 without a surface). A slice
/// stands for its slab, so it fades as the slab meets the surface (the CPU slicer's, and
/// the viewer's `depth_fade` in `volume_math.wgsl`, tested against this by
/// `viewer/tests/volume_math_gpu.rs`).
#[inline]
pub fn slab_fade(z: f32, slab0: f32, thickness: f32) -> f32 {
    if !(z < f32::INFINITY) {
        return 1.0;
    }
    if !(thickness > 0.0) {
        return if slab0 < z { 1.0 } else { 0.0 };
    }
    ((z - slab0) / thickness).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No surface keeps the whole slab, a slab behind the surface none of it, one that
    /// straddles it the part in front; a flat slab is in front or not.
    #[test]
    fn a_slab_fades_by_the_part_in_front_of_the_surface() {
        assert_eq!(slab_fade(f32::INFINITY, 3.0, 1.0), 1.0);
        assert_eq!(slab_fade(2.0, 3.0, 1.0), 0.0);
        assert_eq!(slab_fade(3.25, 3.0, 1.0), 0.25);
        assert_eq!(slab_fade(9.0, 3.0, 1.0), 1.0);
        assert_eq!(
            (slab_fade(3.5, 3.0, 0.0), slab_fade(2.5, 3.0, 0.0)),
            (1.0, 0.0)
        );
    }

    /// `λ = log2(d/v₀)` between 0 and the last level.
    #[test]
    fn slice_lod_is_the_clamped_log_of_spacing_over_voxel() {
        assert_eq!(slice_lod(4.0, 1.0, 6.0), 2.0);
        assert_eq!(slice_lod(0.5, 1.0, 6.0), 0.0);
        assert_eq!(slice_lod(1e9, 1.0, 6.0), 6.0);
        assert_eq!(slice_lod(0.75, 0.25, 0.0), 0.0);
        assert!((slice_lod(3.0, 1.0, 6.0) - 3f32.log2()).abs() < 1e-7);
    }

    /// Uniform spacing: `z₀ = z_min + d/2`, then steps of `d`, front to back, below
    /// `z_max`; the limit is an error naming more than it.
    #[test]
    fn each_slice_draws_the_last_band_starting_at_or_below_its_lod() {
        for levels in [&[0u32][..], &[0, 2], &[0, 1, 3], &[0, 3, 4, 7]] {
            for k in 0..=40 {
                let lod = k as f32 * 0.25;
                let want = levels.iter().rposition(|&f| f as f32 <= lod).unwrap_or(0);
                assert_eq!(slice_band(levels, lod), want, "{levels:?} at {lod}");
                // Exactly one band's range holds each LOD: the one slice_band picks.
                for b in 0..levels.len() {
                    let holds = band_holds(band_lod_range(levels, b), lod);
                    assert_eq!(holds, b == want, "{levels:?} band {b} at {lod}");
                }
            }
            assert_eq!(slice_band(levels, f32::NAN), 0);
        }
        assert_eq!(band_lod_range(&[0, 2, 5], 0), [-1.0, 2.0]);
        assert_eq!(band_lod_range(&[0, 2, 5], 2), [5.0, 1e30]);
    }

    #[test]
    fn uniform_slices_start_half_a_step_in_and_stop_at_the_limit() {
        let s = Spacing::Uniform { spacing: 0.5 };
        let d = slice_depths(|_| 1.0, s, 0.1, 1.0, 3.0, 100).unwrap();
        assert_eq!(d, vec![(1.25, 0.5), (1.75, 0.5), (2.25, 0.5), (2.75, 0.5)]);
        let e = slice_depths(|_| 1.0, s, 0.1, 1.0, 3.0, 3).unwrap_err();
        assert_eq!(e.limit, 3);
        assert!(e.needed > 3);
    }

    /// A whole lod of a power-of-two texture is the paper's correction; between levels the
    /// two densities are blended; odd sides give thicker texels.
    #[test]
    fn level_weights_blend_densities() {
        let sizes = [1.0, 2.0, 4.0];
        assert_eq!(level_weights(1.0, 2.0, &sizes, false), [(1, 1.0), (1, 0.0)]);
        let [(a, wa), (b, wb)] = level_weights(1.5, 2f32.powf(1.5), &sizes, false);
        assert_eq!((a, b), (1, 2));
        // A homogeneous medium of density 1 per voxel: σ_l = s_l, and the slab gets d.
        assert!((wa * 2.0 + wb * 4.0 - 2f32.powf(1.5)).abs() < 1e-5);
        assert_eq!(level_weights(9.0, 4.0, &sizes, false), [(2, 1.0), (2, 0.0)]);
        assert_eq!(level_weights(1.6, 4.0, &sizes, true), [(2, 1.0), (2, 0.0)]);
        let cube = |n: f32| Prism {
            pos: [
                [0.0, 0.0, 0.0],
                [n, 0.0, 0.0],
                [n, 0.0, n],
                [0.0, n, 0.0],
                [n, n, 0.0],
                [n, n, n],
            ],
            uvw: [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 0.0, 1.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 1.0, 1.0],
            ],
        };
        let c = [cube(12.0)];
        assert!((level_texel_size(&c, [12, 12, 12], 2).unwrap() - 4.0).abs() < 1e-5);
        // 12 >> 3 = 1: the one texel spans all 12 voxels.
        assert!((level_texel_size(&c, [12, 12, 12], 3).unwrap() - 12.0).abs() < 1e-4);
    }

    /// The farthest slab reaches the end of the range: one slice of spacing 105 in a
    /// range 112 deep stands for all 112.
    #[test]
    fn the_far_slab_covers_the_range() {
        let d = slice_depths(
            |_| 105.0,
            Spacing::Adaptive { bias: 1.0 },
            1.0,
            0.0,
            112.0,
            10,
        )
        .unwrap();
        assert_eq!(d, vec![(52.5, 105.0)]);
        assert_eq!(far_slab(52.5, 105.0, 112.0), 112.0);
        let d = slice_depths(
            |_| 1.0,
            Spacing::Uniform { spacing: 4.0 },
            1.0,
            0.0,
            9.0,
            10,
        )
        .unwrap();
        let (z, s) = *d.last().unwrap();
        let total: f32 = d[..d.len() - 1].iter().map(|x| x.1).sum::<f32>() + far_slab(z, s, 9.0);
        assert!((total - 9.0).abs() < 1e-6, "{d:?}");
    }

    /// Adaptive spacing follows the pixel footprint, never finer than `v₀`, times `bias`.
    #[test]
    fn adaptive_spacing_is_bias_times_max_of_pixel_and_voxel() {
        let s = Spacing::Adaptive { bias: 2.0 };
        let d = slice_depths(|z| 0.01 * z, s, 0.05, 1.0, 20.0, 10_000).unwrap();
        for &(z, dz) in &d {
            assert_eq!(dz, 2.0 * (0.01 * z).max(0.05), "{z}");
        }
        assert!(d.windows(2).all(|w| w[1].0 == w[0].0 + w[0].1));
        assert_eq!(s.scaled(0.5), Spacing::Adaptive { bias: 1.0 });
    }
}
