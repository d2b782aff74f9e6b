//! Peak-memory estimates of [`super::voxelize`] and `voxelize --prune`, checked against
//! [`super::VoxelizeOptions::memory_limit`] before anything is allocated (see the module
//! docs of [`super`] for what each path holds).

use rayon::prelude::*;

use super::combine::{CombineFn, Preset};
use super::grid::{self, GridSpec};
use super::{ao, brick_grid, Bake, VoxelizeOptions};
use crate::scene::Scene;

/// Estimated peak memory of [`super::voxelize`] for a grid (see the module docs of
/// [`super`]), in bytes, in the worst case where every level-0 voxel is non-empty from
/// every direction (the estimate `voxelize` checks bounds that by the scene's triangles,
/// see [`estimate_peak_bytes_sparse`]).
pub fn estimate_peak_bytes(
    dims: [u32; 3],
    mip_count: u32,
    combine: &CombineFn,
    normals: bool,
) -> u64 {
    let n: u64 = dims.iter().map(|&d| d as u64).product();
    estimate_peak_bytes_sparse(dims, mip_count, combine, normals, n)
}

/// The sizes both estimates start from (bytes unless said otherwise).
struct Sizes {
    /// Level-0 voxels, and at most that many non-empty ones.
    n: u64,
    sparse: u64,
    /// Voxels of all levels, and of the levels above 0.
    all: u64,
    coarse: u64,
    /// One direction's sparse level 0 (voxel + weighted normal).
    vox: u64,
    /// One direction's levels 1 and 2 while its pyramid is built.
    pyr: u64,
    /// The dense RGBA8 (+ snorm8) output of every level.
    output: u64,
}

fn sizes(dims: [u32; 3], mip_count: u32, normals: bool, sparse: u64) -> Sizes {
    let nrm = normals as u64;
    let level = |l: u32| level_voxels(dims, l);
    let n = level(0);
    let sparse = sparse.min(n);
    let all: u64 = (0..mip_count).map(level).sum();
    let level1 = n.div_ceil(8);
    Sizes {
        n,
        sparse,
        all,
        coarse: all - n,
        vox: sparse * (20 + 12 * nrm),
        pyr: (16 + 8 * nrm) * (level1 + level1.div_ceil(8)),
        output: 4 * all * (1 + nrm),
    }
}

fn level_voxels(dims: [u32; 3], l: u32) -> u64 {
    grid::level_dims(dims, l)
        .iter()
        .map(|&d| d as u64)
        .product()
}

/// A preset accumulator's colour bytes per voxel: 4 floats (5 for `opaque` and `min`).
fn colour_width(p: Preset) -> u64 {
    if matches!(p, Preset::Opaque | Preset::Min) {
        20
    } else {
        16
    }
}

/// A preset's accumulators of the levels above 0: [`colour_width`] per voxel, plus 8
/// bytes of normal sums.
fn accumulator_bytes(p: Preset, coarse: u64, normals: bool) -> u64 {
    colour_width(p) * coarse + 8 * coarse * normals as u64
}

/// [`estimate_peak_bytes`] when at most `sparse` level-0 voxels of each direction are
/// non-empty: the larger of the two phases — while the directions are processed (the
/// sparse level 0 of the directions done so far, one direction's level 1 and 2, the
/// accumulators of the coarser levels or the stored f16 pyramids) and while the levels are
/// finished (accumulators or pyramids turning into the RGBA8/snorm8 output).
pub fn estimate_peak_bytes_sparse(
    dims: [u32; 3],
    mip_count: u32,
    combine: &CombineFn,
    normals: bool,
    sparse: u64,
) -> u64 {
    let z = sizes(dims, mip_count, normals, sparse);
    let (building, finishing) = match combine {
        CombineFn::Preset(p) => {
            let acc = accumulator_bytes(*p, z.coarse, normals);
            // All six sparse stacks are kept for level 0, plus its per-plane tables.
            let kept = 6 * z.vox + 2 * 8 * z.sparse;
            (kept + acc + z.pyr, kept + acc + z.output)
        }
        // Six f16 pyramids (brick-sparse, counted dense) + the sparse level 0 of the two
        // directions of the axis being converted (a paired pass makes both at once).
        _ => {
            let nacc = 8 * z.all * normals as u64;
            (48 * z.all + 2 * z.vox + nacc, 48 * z.all + nacc + z.output)
        }
    };
    building.max(finishing) + (64 << 20)
}

/// Estimated peak memory of [`super::voxelize_sparse`] followed by
/// [`crate::emptyspace::prune_sparse`] (`voxelize --prune`) when at most `sparse` level-0
/// voxels are non-empty (from any direction: the bound is on the voxels the triangles
/// meet), in bytes: the largest of three phases.
/// - While the directions are processed: the level-0 accumulator (per voxel seen: 4 bytes
///   of index, 16 or 20 of colour, 12 or 16 more with normals), the two stacks of one
///   rasterization pass, one direction's levels 1 and 2 and the coarse accumulators.
/// - While the levels are finished: the accumulators beside the packed output (per level
///   at most `min(level voxels, sparse)` texels stored, 4 bytes each, 8 with normals,
///   plus the brick tables), counted twice for level 0's parts before they are joined,
///   and one coarse level's whole bricks before they are packed.
/// - While it is pruned: the packed output, tier 0's occupancy grids and the atlases.
///   The atlases cannot be known before the kd-tree has run, so they are counted as the
///   dense output's size; a prune whose atlases pay off is smaller. The prune itself
///   refuses an atlas that would pass the limit before allocating it
///   ([`crate::emptyspace::EmptySpaceOptions::memory_limit`]).
///
/// At 1024³ on the bench tree this is well under the dense [`estimate_peak_bytes_sparse`]
/// (docs/benchmarks.md lists both beside the measured peaks).
pub fn estimate_peak_bytes_pruned(
    dims: [u32; 3],
    mip_count: u32,
    preset: Preset,
    normals: bool,
    sparse: u64,
) -> u64 {
    let z = sizes(dims, mip_count, normals, sparse);
    let nrm = normals as u64;
    let w = colour_width(preset);
    let w_nrm = if matches!(preset, Preset::Max | Preset::Min) {
        16
    } else {
        12
    };
    let acc0 = z.sparse * (4 + w + w_nrm * nrm);
    // Two stacks: their voxels and per image row an 8-byte start.
    let rows = z.n / dims.iter().copied().min().unwrap_or(1).max(1) as u64;
    let stacks = 2 * (z.vox + 8 * rows);
    let acc = accumulator_bytes(preset, z.coarse, normals);
    let texel = 4 * (1 + nrm);
    let b3 = brick_grid::B3 as u64;
    let level = |l: u32| level_voxels(dims, l);
    // Per level: stored bricks, and the packed bytes (texels, brick tables, slot grid).
    let stored = |l: u32| level(l).div_ceil(b3).min(z.sparse);
    let packed: u64 = (0..mip_count)
        .map(|l| {
            let texels = level(l).min(z.sparse);
            texel * texels + (4 + 64 + 8) * stored(l) + 4 * level(l).div_ceil(b3)
        })
        .sum();
    // A coarse level's whole bricks before they are packed.
    let whole = (1..mip_count)
        .map(|l| texel * b3 * stored(l))
        .max()
        .unwrap_or(0);
    let building = acc0 + stacks + z.pyr + acc;
    // Level 0's packed parts (per brick layer) are held twice while they are joined.
    let finishing = acc0 + acc + 2 * packed + whole;
    let occupancy = 5 * z.n.div_ceil(8);
    let pruning = packed + occupancy + z.output;
    building.max(finishing).max(pruning) + (64 << 20)
}

/// An upper bound on the non-empty level-0 voxels of one direction: a fragment lies in a
/// voxel its triangle intersects, and a triangle intersects at most
/// `(A + 2 (w_u + w_v) + 4) (⌈L⌉ + 1)` voxels. In voxel units, seen along its dominant
/// normal axis it touches at most `A + 2 (w_u + w_v) + 4` voxel columns (its projection,
/// of area `A` and extents `w`, grown by a voxel on every side), and in each its depth
/// changes by at most `L = (|n_u| + |n_v|) / |n_a| ≤ 2`, so it spans at most `⌈L⌉ + 1`
/// voxels there (1 for a triangle facing the axis, 3 at the steepest).
pub(super) fn sparse_bound(scene: &Scene, grid: &GridSpec) -> u64 {
    let n = grid.voxel_count();
    let sum: f64 = scene
        .triangles
        .par_iter()
        .map(|t| {
            let p =
                t.v.map(|v| ((v.position - grid.min) / grid.voxel).as_dvec3());
            if !p.iter().all(|q| q.is_finite()) {
                return 0.0;
            }
            let nrm = (p[1] - p[0]).cross(p[2] - p[0]).abs();
            let a = nrm.max_position();
            let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            let w = hi - lo;
            let across = w[0] + w[1] + w[2] - w[a];
            let area = 0.5 * nrm[a];
            // Degenerate (zero-area) triangles: the steepest case.
            let slope = if nrm[a] > 0.0 {
                ((nrm[0] + nrm[1] + nrm[2] - nrm[a]) / nrm[a]).min(2.0)
            } else {
                2.0
            };
            (area + 2.0 * across + 4.0) * (slope.ceil() + 1.0)
        })
        .sum();
    if sum.is_finite() {
        (sum.ceil() as u64).min(n)
    } else {
        n
    }
}

/// [`estimate_peak_bytes_sparse`] (or, for the brick-sparse path, `sparse`,
/// [`estimate_peak_bytes_pruned`]) for this scene, plus what the bake needs (AO: its
/// cache and the BVH).
pub(super) fn estimate_bytes(
    scene: &Scene,
    opts: &VoxelizeOptions,
    grid: &GridSpec,
    mips: u32,
    sparse: bool,
) -> u64 {
    let bake = match opts.bake {
        Bake::None => 0,
        Bake::Ao { .. } => ao::AoBaker::estimate_bytes(grid.dims, scene.triangles.len()),
    };
    let s = sparse_bound(scene, grid);
    let peak = match opts.combine {
        CombineFn::Preset(p) if sparse => {
            estimate_peak_bytes_pruned(grid.dims, mips, p, opts.normals, s)
        }
        _ => estimate_peak_bytes_sparse(grid.dims, mips, &opts.combine, opts.normals, s),
    };
    peak + bake
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, SceneBuilder, Vertex};
    use crate::voxelize::{grid_for, slice_stack, Dir, Resolution};
    use billow_core::Aabb;
    use glam::Vec2;
    use glam::{Vec3, Vec4};
    use proptest::prelude::*;

    fn vertex(p: [f32; 3]) -> Vertex {
        Vertex {
            position: Vec3::from_array(p),
            normal: Vec3::Z,
            uv: Vec2::ZERO,
            color: Vec4::ONE,
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// The memory estimates rest on [`sparse_bound`]: no direction's slice stack has
        /// more non-empty voxels, whatever the triangles' slopes (axis-facing, steep,
        /// degenerate) and the supersampling. Seen failing with the depth span taken as
        /// `⌈L⌉` voxels instead of `⌈L⌉ + 1`.
        #[test]
        fn the_sparse_bound_bounds_every_direction(
            at in prop::collection::vec(prop::array::uniform3(4.0f32..28.0), 1..12),
            offsets in prop::collection::vec(prop::array::uniform3(prop::array::uniform3(-4.0f32..4.0)), 12),
            flat in prop::collection::vec(0usize..4, 12),
            k in 1u32..5,
        ) {
            let mut sb = SceneBuilder::new();
            let m = sb.material(Material {
                double_sided: true,
                ..Material::default()
            });
            let mesh = sb.mesh("t");
            for (i, c) in at.iter().enumerate() {
                let mut t = offsets[i].map(|o| [0, 1, 2].map(|a| c[a] + o[a]));
                // Some triangles face an axis exactly (flat[i] < 3: that axis).
                if flat[i] < 3 {
                    let (a, d) = (flat[i], t[0][flat[i]]);
                    t[1][a] = d;
                    t[2][a] = d;
                }
                sb.triangle(t.map(vertex), m, mesh);
            }
            let scene = sb.finish();
            let opts = VoxelizeOptions {
                resolution: Resolution::Exact([32; 3]),
                bounds: Some(Aabb {
                    min: Vec3::ZERO,
                    max: Vec3::splat(32.0),
                }),
                supersample: k,
                ..VoxelizeOptions::default()
            };
            let grid = grid_for(&scene, &opts).unwrap();
            let bound = sparse_bound(&scene, &grid);
            // Small triangles in a large grid: the bound is not just the grid.
            prop_assert!(bound < grid.voxel_count());
            for dir in Dir::ALL {
                let s = slice_stack(&scene, &opts, dir).unwrap();
                let n = s.rgba.iter().filter(|c| c.w > 0.0).count() as u64;
                prop_assert!(n <= bound, "{dir:?}: {n} non-empty voxels, bound {bound}");
            }
        }
    }
}
