//! kd-tree subdivision of a volume into axis-aligned non-empty boxes (VB paper §4,
//! Figure 14; Vidal, Mei & Decaudin 2008), on the grid of needed blocks
//! ([`super::occupancy`]).
//!
//! **Cost.** A box `B` of `s_x × s_y × s_z` blocks of `A³` voxels costs
//!
//! ```text
//! C(B) = (A·s_x + 2p)(A·s_y + 2p)(A·s_z + 2p) + W
//! ```
//!
//! voxels: the atlas texels it occupies — its rasterized volume, empty voxels included,
//! plus its apron of `p` voxels per side (`p = A`, SPEC §8.6) — plus `W`, the cost of one
//! more cell (two prisms clipped against every slice, a draw's worth of set-up), expressed
//! in voxels ([`KdParams::cell_cost`]). A tree costs the sum over its leaves.
//!
//! **Splitting.** A node is first shrunk to the tight bounds of its needed blocks (free:
//! it removes only empty space). Every plane between blocks along x, y and z is tried; the
//! children are shrunk to their tight bounds and the plane with the least
//! `C(left) + C(right)` wins (ties: the lowest axis, then the lowest plane — deterministic).
//!
//! **Stopping rules**, checked in this order — a node becomes a leaf when
//! 1. it contains no needed block (then it is dropped, not a leaf);
//! 2. its depth is `max_depth` (the root has depth 0);
//! 3. no plane leaves at least `min_box` blocks on both sides (before shrinking);
//! 4. the best split does not gain at least `min_gain` of the node's cost:
//!    `C(left) + C(right) ≥ (1 − min_gain) · C(node)`.
//!
//! Leaves are returned depth first, left child before right.

/// A box of blocks, `lo` inclusive, `hi` exclusive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockBox {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
}

impl BlockBox {
    pub fn size(&self) -> [usize; 3] {
        [0, 1, 2].map(|a| self.hi[a] - self.lo[a])
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdParams {
    /// Voxels per block edge, `A`.
    pub block: usize,
    /// Apron voxels per side, `p`.
    pub apron: usize,
    /// Per-box cost `W`, in voxels.
    pub cell_cost: f64,
    /// Smallest box edge a split may leave, in blocks (≥ 1).
    pub min_box: usize,
    pub max_depth: u32,
    /// Smallest relative cost reduction worth a split, in `[0, 1)`.
    pub min_gain: f64,
}

/// Needed-block oracle (a [`super::occupancy::BlockGrid`] in practice).
pub trait Needed {
    fn dims(&self) -> [usize; 3];
    fn needed(&self, b: [usize; 3]) -> bool;
}

impl Needed for super::occupancy::BlockGrid {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }
    fn needed(&self, b: [usize; 3]) -> bool {
        self.is_needed(b)
    }
}

/// The cost `C(B)` of the module docs.
pub fn box_cost(b: &BlockBox, p: &KdParams) -> f64 {
    let s = b.size();
    (0..3)
        .map(|a| (p.block * s[a] + 2 * p.apron) as f64)
        .product::<f64>()
        + p.cell_cost
}

fn union(a: Option<BlockBox>, b: Option<BlockBox>) -> Option<BlockBox> {
    match (a, b) {
        (Some(a), Some(b)) => Some(BlockBox {
            lo: [0, 1, 2].map(|i| a.lo[i].min(b.lo[i])),
            hi: [0, 1, 2].map(|i| a.hi[i].max(b.hi[i])),
        }),
        (a, None) => a,
        (None, b) => b,
    }
}

/// Tight bounds of the needed blocks inside `b`, if any.
pub fn tight(grid: &impl Needed, b: &BlockBox) -> Option<BlockBox> {
    let mut out: Option<BlockBox> = None;
    for z in b.lo[2]..b.hi[2] {
        for y in b.lo[1]..b.hi[1] {
            for x in b.lo[0]..b.hi[0] {
                if grid.needed([x, y, z]) {
                    let c = BlockBox {
                        lo: [x, y, z],
                        hi: [x + 1, y + 1, z + 1],
                    };
                    out = union(out, Some(c));
                }
            }
        }
    }
    out
}

/// Per slab along `axis`: the tight bounds of the needed blocks in that slab of `b`.
fn slab_bounds(grid: &impl Needed, b: &BlockBox, axis: usize) -> Vec<Option<BlockBox>> {
    let mut slabs = vec![None; b.hi[axis] - b.lo[axis]];
    for z in b.lo[2]..b.hi[2] {
        for y in b.lo[1]..b.hi[1] {
            for x in b.lo[0]..b.hi[0] {
                let p = [x, y, z];
                if grid.needed(p) {
                    let k = p[axis] - b.lo[axis];
                    slabs[k] = union(
                        slabs[k],
                        Some(BlockBox {
                            lo: p,
                            hi: [x + 1, y + 1, z + 1],
                        }),
                    );
                }
            }
        }
    }
    slabs
}

/// The best split of a (tight) node: `(cost, left, right)`.
fn best_split(
    grid: &impl Needed,
    b: &BlockBox,
    p: &KdParams,
) -> Option<(f64, Option<BlockBox>, Option<BlockBox>)> {
    let cost = |x: &Option<BlockBox>| x.as_ref().map_or(0.0, |x| box_cost(x, p));
    let mut best: Option<(f64, Option<BlockBox>, Option<BlockBox>)> = None;
    for axis in 0..3 {
        let n = b.hi[axis] - b.lo[axis];
        if n < 2 * p.min_box {
            continue;
        }
        let slabs = slab_bounds(grid, b, axis);
        let mut prefix = vec![None; n + 1];
        for k in 0..n {
            prefix[k + 1] = union(prefix[k], slabs[k]);
        }
        let mut suffix = vec![None; n + 1];
        for k in (0..n).rev() {
            suffix[k] = union(suffix[k + 1], slabs[k]);
        }
        for k in p.min_box..=n - p.min_box {
            let c = cost(&prefix[k]) + cost(&suffix[k]);
            if best.as_ref().is_none_or(|(bc, _, _)| c < *bc) {
                best = Some((c, prefix[k], suffix[k]));
            }
        }
    }
    best
}

fn recurse(grid: &impl Needed, b: BlockBox, depth: u32, p: &KdParams, out: &mut Vec<BlockBox>) {
    if depth >= p.max_depth {
        out.push(b);
        return;
    }
    match best_split(grid, &b, p) {
        Some((c, l, r)) if c < (1.0 - p.min_gain) * box_cost(&b, p) => {
            for child in [l, r].into_iter().flatten() {
                recurse(grid, child, depth + 1, p, out);
            }
        }
        _ => out.push(b),
    }
}

/// The leaves of the kd-tree over the whole grid (empty when nothing is needed).
pub fn subdivide(grid: &impl Needed, p: &KdParams) -> Vec<BlockBox> {
    let d = grid.dims();
    let root = BlockBox { lo: [0; 3], hi: d };
    let mut out = Vec::new();
    if let Some(t) = tight(grid, &root) {
        recurse(grid, t, 0, p, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emptyspace::occupancy::BlockGrid;

    fn grid(dims: [usize; 3], on: &[[usize; 3]]) -> BlockGrid {
        let mut g = BlockGrid {
            dims,
            needed: vec![false; dims.iter().product()],
        };
        for &b in on {
            let i = g.index(b);
            g.needed[i] = true;
        }
        g
    }

    fn params() -> KdParams {
        KdParams {
            block: 4,
            apron: 4,
            cell_cost: 0.0,
            min_box: 1,
            max_depth: 16,
            min_gain: 0.0,
        }
    }

    #[test]
    fn two_far_clusters_become_two_tight_boxes() {
        let g = grid([16, 4, 4], &[[0, 0, 0], [1, 1, 0], [14, 2, 3], [15, 3, 3]]);
        let boxes = subdivide(&g, &params());
        assert_eq!(
            boxes,
            vec![
                BlockBox {
                    lo: [0, 0, 0],
                    hi: [2, 2, 1]
                },
                BlockBox {
                    lo: [14, 2, 3],
                    hi: [16, 4, 4]
                }
            ]
        );
    }

    #[test]
    fn a_full_grid_is_one_box_and_stopping_rules_hold() {
        let all: Vec<[usize; 3]> = (0..27).map(|i| [i % 3, (i / 3) % 3, i / 9]).collect();
        let g = grid([3, 3, 3], &all);
        assert_eq!(subdivide(&g, &params()).len(), 1);
        // max_depth 0: the tight root, whatever the gain.
        let g = grid([16, 4, 4], &[[0, 0, 0], [15, 3, 3]]);
        let p = KdParams {
            max_depth: 0,
            ..params()
        };
        assert_eq!(subdivide(&g, &p).len(), 1);
        // A huge per-cell cost forbids splitting.
        let p = KdParams {
            cell_cost: 1e12,
            ..params()
        };
        assert_eq!(subdivide(&g, &p).len(), 1);
        // min_box 9 on a 16-block axis: no plane leaves 9 on both sides.
        let p = KdParams {
            min_box: 9,
            ..params()
        };
        assert_eq!(subdivide(&g, &p).len(), 1);
        assert!(subdivide(&grid([4, 4, 4], &[]), &params()).is_empty());
    }
}
