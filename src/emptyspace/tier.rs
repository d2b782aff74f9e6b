//! One *tier* of a pruned volume (formats/SPEC.md §8.6): two consecutive MIP levels
//! `k, k + 1` of the source, cut into kd-tree boxes of 2×2×2-texel blocks, packed with
//! their aprons into a two-level atlas, each box becoming two prism cells.
//!
//! A renderer draws tier `k` on the slices whose LOD `λ` lies in `[k, k + 1)`, sampling
//! its atlas at `λ − k`: levels `0` and `1` of the atlas are exact copies of the source's
//! levels `k` and `k + 1`, so every trilinear (and level-linear) sample inside a box reads
//! exactly the texels the source reads — one texel beyond the box at either level, which is
//! the one-block apron.

use billow_format::Prism;
use glam::Vec3;

use super::brick_copy::{fill_level_with, Brick};
use super::kdtree::{aligned_span, subdivide, BlockBox, KdParams, TierGrid};
use super::occupancy::{tier_needed_blocks, DataGrid, TierTexels};
use super::pack::{pack, Slot};
use billow_core::cells::box_prisms;

/// Parameters of one tier (the kd-tree's, in this tier's texels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TierParams {
    pub kd: KdParams,
    /// Largest atlas side, in blocks.
    pub max_side: usize,
}

/// A built tier.
#[derive(Clone, Debug, PartialEq)]
pub struct Tier {
    /// Atlas level-0 size, texels (level 1 is half of it).
    pub dims: [u32; 3],
    pub colour: Vec<Vec<u8>>,
    pub normals: Option<Vec<Vec<u8>>>,
    /// The kd-tree's boxes, in blocks of this tier.
    pub boxes: Vec<BlockBox>,
    /// Blocks in this tier's level (`n / 2` per axis).
    pub blocks: u64,
    pub cells: Vec<Prism>,
}

impl Tier {
    pub fn bytes(&self) -> u64 {
        let n = |l: &[Vec<u8>]| l.iter().map(|v| v.len() as u64).sum::<u64>();
        n(&self.colour) + self.normals.as_deref().map_or(0, n)
    }
}

/// Consecutive all-zero layers of the slot `[lo, hi)` (blocks) seen from each face.
fn soft_depths(data: &DataGrid, lo: [i64; 3], hi: [i64; 3]) -> [usize; 6] {
    let mut out = [0; 6];
    for a in 0..3 {
        let n = (hi[a] - lo[a]) as usize;
        for (side, o) in out[2 * a..2 * a + 2].iter_mut().enumerate() {
            while *o < n {
                let (mut l, mut h) = (lo, hi);
                if side == 0 {
                    l[a] = lo[a] + *o as i64;
                    h[a] = l[a] + 1;
                } else {
                    h[a] = hi[a] - *o as i64;
                    l[a] = h[a] - 1;
                }
                if data.count(l, h) > 0 {
                    break;
                }
                *o += 1;
            }
        }
    }
    out
}

/// Two prisms of the world box `[pmin, pmax]` with the voxelizer's topology
/// ([`box_prisms`]), corner positions taken exactly from `pmin`/`pmax` (so neighbouring
/// boxes share faces bit for bit) and `uvw(t)` at corner `t ∈ {0, 1}³`.
pub fn box_cells(pmin: Vec3, pmax: Vec3, uvw: impl Fn([f32; 3]) -> [f32; 3]) -> [Prism; 2] {
    box_prisms(Vec3::ZERO, Vec3::ONE).map(|p| {
        let t = p.uvw;
        Prism {
            pos: t.map(|t| [0, 1, 2].map(|a| if t[a] > 0.5 { pmax[a] } else { pmin[a] })),
            uvw: t.map(&uvw),
        }
    })
}

/// A tier laid out but not yet filled: its boxes and where each goes in the atlas.
pub struct TierPlan {
    boxes: Vec<BlockBox>,
    /// Each box's slot (box plus apron, blocks of the tier's level 0) and its placement.
    bricks: Vec<Brick>,
    /// Atlas size in blocks: level 1's texels (level 0 has twice as many per axis).
    blocks: [usize; 3],
    /// The source level's size (texels).
    n: [usize; 3],
    normals: bool,
}

impl TierPlan {
    /// The atlas's bytes once filled (both levels, colour and normals).
    pub fn bytes(&self) -> u64 {
        // Level 0 holds 8 texels per block, level 1 one.
        let blocks = self.blocks.iter().map(|&v| v as u64).product::<u64>();
        4 * 9 * blocks * (1 + self.normals as u64)
    }
}

/// The kd-tree boxes of `src` and their atlas layout (`None` when the atlas would not fit
/// `max_side`), before any texel of the atlas is allocated.
pub fn plan_tier<S: TierTexels>(src: &S, p: &TierParams) -> Option<TierPlan> {
    let n = src.n();
    let needed = tier_needed_blocks(src);
    let data = DataGrid::new(src);
    let boxes = subdivide(
        &TierGrid {
            needed: &needed,
            data: &data,
        },
        &p.kd,
    );
    let ring = i64::from(p.kd.apron);
    let slots: Vec<([i64; 3], Slot)> = boxes
        .iter()
        .map(|b| {
            let span = [0, 1, 2].map(|a| {
                let (lo, hi) = (b.lo[a] as i64 - ring, b.hi[a] as i64 + ring);
                aligned_span(lo, hi, p.kd.pair_align && a < 2)
            });
            let lo = span.map(|s| s.0);
            let hi = span.map(|s| s.0 + s.1);
            let size = span.map(|s| s.1 as usize);
            let soft = if p.kd.apron {
                soft_depths(&data, lo, hi)
            } else {
                [0; 6]
            };
            (lo, Slot { size, soft })
        })
        .collect();
    // The occupancy grids are not read again: freed before the atlas is filled.
    drop((needed, data));
    let plain: Vec<Slot> = slots.iter().map(|s| s.1).collect();
    let packing = pack(&plain, p.max_side, p.kd.pair_align)?;
    // An empty tier still needs a valid two-level texture.
    let blocks = packing.dims.map(|d| d.max(1));
    let bricks: Vec<Brick> = slots
        .iter()
        .zip(&packing.placed)
        .map(|((lo, s), pl)| Brick {
            src: *lo,
            size: s.size,
            dst: pl.origin,
            perm: pl.perm,
        })
        .collect();
    Some(TierPlan {
        boxes,
        bricks,
        blocks,
        n,
        normals: src.has_normals(),
    })
}

/// Fills the atlas of `plan` from `src` and makes its cells.
pub fn fill_tier<S: TierTexels>(src: &S, world: (Vec3, Vec3), plan: TierPlan) -> Tier {
    let TierPlan {
        boxes,
        bricks,
        blocks,
        n,
        ..
    } = plan;
    let dims = blocks.map(|d| 2 * d);
    let n1 = n.map(|d| d / 2);
    let fill = |normals: bool| -> Vec<Vec<u8>> {
        [(dims, n, 2), (blocks, n1, 1)]
            .iter()
            .enumerate()
            .map(|(l, &(nd, ns, t))| {
                let mut out = vec![0u8; 4 * nd.iter().product::<usize>()];
                fill_level_with(|q| src.get(l, normals, q), ns, &mut out, nd, t, &bricks);
                out
            })
            .collect()
    };
    let colour = fill(false);
    let normals = src.has_normals().then(|| fill(true));
    // Cells: the box in the world (from the source's box cell), uvw into the atlas.
    let (wlo, whi) = world;
    let ext = whi - wlo;
    let mut cells = Vec::with_capacity(2 * boxes.len());
    for (b, br) in boxes.iter().zip(&bricks) {
        let w = |a: usize, v: usize| wlo[a] + ext[a] * (2.0 * v as f64 / n[a] as f64) as f32;
        let pmin = Vec3::from_array([0, 1, 2].map(|a| w(a, b.lo[a])));
        let pmax = Vec3::from_array([0, 1, 2].map(|a| w(a, b.hi[a])));
        let s = b.size();
        let uvw = |t: [f32; 3]| {
            [0, 1, 2].map(|a| {
                let src_axis = br.perm[a];
                let inset = (b.lo[src_axis] as i64 - br.src[src_axis]) as usize;
                let start = 2 * (br.dst[a] + inset);
                let v = start
                    + if t[src_axis] > 0.5 {
                        2 * s[src_axis]
                    } else {
                        0
                    };
                (v as f64 / dims[a] as f64) as f32
            })
        };
        cells.extend(box_cells(pmin, pmax, uvw));
    }
    Tier {
        dims: dims.map(|d| d as u32),
        colour,
        normals,
        boxes,
        blocks: n1.iter().map(|&v| v as u64).product(),
        cells,
    }
}
