//! kd-tree subdivision of a volume into axis-aligned non-empty boxes (VB paper §4,
//! Figure 14; Vidal, Mei & Decaudin 2008), on the grid of needed blocks
//! ([`super::occupancy`]).
//!
//! **Cost.** A box `B` of `s_x × s_y × s_z` blocks of `A³` voxels costs
//!
//! ```text
//! C(B) = A·(s_x + h_x⁻ + h_x⁺) · A·(s_y + h_y⁻ + h_y⁺) · A·(s_z + h_z⁻ + h_z⁺) + W
//! ```
//!
//! voxels: the atlas texels it occupies — its rasterized volume, empty voxels included,
//! plus its apron, one block per side (SPEC §8.6), counted only on the faces where the
//! apron holds data (`h = 1`: a cut through content, or content at the volume's border);
//! an all-zero apron is shared with the neighbouring bricks in the atlas
//! ([`super::pack`]), so it costs nothing — plus `W`, the cost of one more cell (two
//! prisms clipped against every slice, a draw's worth of set-up), expressed in voxels
//! ([`KdParams::cell_cost`]). A tree costs the sum over its leaves. For a block-compressed
//! output ([`KdParams::pair_align`]) the x and y spans are grown to whole pairs of blocks
//! (4 texels, one BC block) on the source's grid, as the slots will be.
//!
//! **Splitting.** A node is first shrunk to the tight bounds of its needed blocks (free:
//! it removes only empty space). Every plane between blocks along x, y and z is tried; the
//! children are shrunk to their tight bounds and the plane with the least
//! `C(left) + C(right)` wins (ties: the lowest axis, then the lowest plane — deterministic).
//!
//! **Growing, then pruning.** A greedy kd-tree that stops at the first split without gain
//! cannot hollow out a shell (the first cut through a hollow object gains nothing; the
//! second does), so the tree is grown first and pruned bottom-up. A node is split at its
//! best plane unless
//! 1. it contains no needed block (then it is dropped, not a leaf);
//! 2. its depth is `max_depth` (the root has depth 0);
//! 3. every block in it is needed (splitting can only add aprons);
//! 4. no plane leaves at least `min_box` blocks on both sides (before shrinking).
//!
//! Then, from the leaves up, a split is kept only if its subtree costs less than the node
//! as one leaf by at least `min_gain` of that: `C(subtree) < (1 − min_gain) · C(node)`;
//! otherwise the node becomes a leaf.
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
    /// Whether boxes carry aprons (`h` above can be 1).
    pub apron: bool,
    /// Per-box cost `W`, in voxels.
    pub cell_cost: f64,
    /// Smallest box edge a split may leave, in blocks (≥ 1).
    pub min_box: usize,
    pub max_depth: u32,
    /// Smallest relative cost reduction worth a split, in `[0, 1)`.
    pub min_gain: f64,
    /// Slots whose x and y extents are whole pairs of blocks on the source's even block
    /// grid ([`aligned_span`]): what keeps a block-compressed atlas's 4×4 blocks one to one
    /// with the source's (`billow emptyspace --compress bc`).
    pub pair_align: bool,
}

/// The span of blocks `[lo − h⁻, hi + h⁺)` along one axis, grown outward to even block
/// coordinates when `pair` is set (the x and y axes of a [`KdParams::pair_align`] tier):
/// `(start, len)`.
pub fn aligned_span(lo: i64, hi: i64, pair: bool) -> (i64, i64) {
    if pair {
        let (a, b) = (lo.div_euclid(2) * 2, (hi + 1).div_euclid(2) * 2);
        (a, b - a)
    } else {
        (lo, hi - lo)
    }
}

/// Needed-block oracle (a [`super::occupancy::BlockGrid`] in practice).
pub trait Needed {
    fn dims(&self) -> [usize; 3];
    fn needed(&self, b: [usize; 3]) -> bool;
    /// Whether the apron of `b` on face `axis`, `upper` side — the one-block layer just
    /// outside that face, over the face grown by one block on the other axes — holds data.
    fn apron_has_data(&self, _b: &BlockBox, _axis: usize, _upper: bool) -> bool {
        true
    }
}

impl Needed for super::occupancy::BlockGrid {
    fn dims(&self) -> [usize; 3] {
        self.dims
    }
    fn needed(&self, b: [usize; 3]) -> bool {
        self.is_needed(b)
    }
}

/// The needed blocks of one tier with its data blocks, which decide the aprons' cost.
pub struct TierGrid<'a> {
    pub needed: &'a super::occupancy::BlockGrid,
    pub data: &'a super::occupancy::DataGrid,
}

impl Needed for TierGrid<'_> {
    fn dims(&self) -> [usize; 3] {
        self.needed.dims
    }
    fn needed(&self, b: [usize; 3]) -> bool {
        self.needed.is_needed(b)
    }
    fn apron_has_data(&self, b: &BlockBox, axis: usize, upper: bool) -> bool {
        let (lo, hi) = apron_slab(b, axis, upper);
        self.data.count(lo, hi) > 0
    }
}

/// The apron layer of `b` on one face: `[lo, hi)` in block coordinates (may reach −1 and
/// `dims`).
pub fn apron_slab(b: &BlockBox, axis: usize, upper: bool) -> ([i64; 3], [i64; 3]) {
    let mut lo = b.lo.map(|v| v as i64 - 1);
    let mut hi = b.hi.map(|v| v as i64 + 1);
    if upper {
        lo[axis] = b.hi[axis] as i64;
        hi[axis] = lo[axis] + 1;
    } else {
        hi[axis] = b.lo[axis] as i64;
        lo[axis] = hi[axis] - 1;
    }
    (lo, hi)
}

/// The cost `C(B)` of the module docs (with [`KdParams::pair_align`], the x and y spans
/// grown to whole pairs of blocks).
pub fn box_cost(grid: &impl Needed, b: &BlockBox, p: &KdParams) -> f64 {
    (0..3)
        .map(|a| {
            let h = |upper| i64::from(p.apron && grid.apron_has_data(b, a, upper));
            let (lo, hi) = (b.lo[a] as i64 - h(false), b.hi[a] as i64 + h(true));
            let (_, len) = aligned_span(lo, hi, p.pair_align && a < 2);
            (p.block as i64 * len) as f64
        })
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

/// Per slab along `axis`: the tight bounds of the needed blocks in that slab of `b`
/// (block by block; [`Bits::slab_bounds`] computes the same from the bits).
#[cfg(test)]
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

/// The needed blocks as bits: row `(y, z)` is `words` words, bit `x % 64` of word `x / 64`
/// for block `x`. A node's slab bounds then cost a word per 64 blocks of each row.
struct Bits {
    dims: [usize; 3],
    words: usize,
    bits: Vec<u64>,
}

/// The bits of `[x0, x1)` in word `k`.
#[inline]
fn range_mask(k: usize, x0: usize, x1: usize) -> u64 {
    let (lo, hi) = (64 * k, 64 * k + 64);
    let a = x0.max(lo) - lo;
    let b = x1.min(hi) - lo;
    let upto = |n: usize| if n >= 64 { u64::MAX } else { (1u64 << n) - 1 };
    upto(b) & !upto(a)
}

/// Grows the range `r` (inclusive) to hold `v`.
#[inline]
fn grow(r: &mut Option<(usize, usize)>, v: usize) {
    *r = Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
}

impl Bits {
    fn new(grid: &impl Needed) -> Self {
        let dims = grid.dims();
        let words = dims[0].div_ceil(64);
        let mut bits = vec![0u64; words * dims[1] * dims[2]];
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                let row = &mut bits[words * (y + dims[1] * z)..][..words];
                for x in 0..dims[0] {
                    if grid.needed([x, y, z]) {
                        row[x / 64] |= 1 << (x % 64);
                    }
                }
            }
        }
        Bits { dims, words, bits }
    }

    #[inline]
    fn row(&self, y: usize, z: usize) -> &[u64] {
        &self.bits[self.words * (y + self.dims[1] * z)..][..self.words]
    }

    /// Every block of `b` is needed.
    fn full(&self, b: &BlockBox) -> bool {
        let (k0, k1) = (b.lo[0] / 64, (b.hi[0] - 1) / 64 + 1);
        (b.lo[2]..b.hi[2]).all(|z| {
            (b.lo[1]..b.hi[1]).all(|y| {
                let row = self.row(y, z);
                (k0..k1).all(|k| {
                    let m = range_mask(k, b.lo[0], b.hi[0]);
                    row[k] & m == m
                })
            })
        })
    }

    /// Per axis, per slab of `b` along it: the tight bounds of the needed blocks in that
    /// slab (what [`slab_bounds`] finds block by block), from one pass over the rows.
    fn slab_bounds(&self, b: &BlockBox) -> [Vec<Option<BlockBox>>; 3] {
        let n = b.size();
        let (k0, k1) = (b.lo[0] / 64, (b.hi[0] - 1) / 64 + 1);
        let nw = k1 - k0;
        // Per y (per z) of the node: the OR of its rows over z (over y), and the range of
        // z (of y) whose row holds a needed block.
        let mut col_y = vec![0u64; n[1] * nw];
        let mut col_z = vec![0u64; n[2] * nw];
        let mut z_of_y = vec![None; n[1]];
        let mut y_of_z = vec![None; n[2]];
        for z in b.lo[2]..b.hi[2] {
            let zz = z - b.lo[2];
            for y in b.lo[1]..b.hi[1] {
                let yy = y - b.lo[1];
                let row = self.row(y, z);
                let mut any = false;
                for k in k0..k1 {
                    let w = row[k] & range_mask(k, b.lo[0], b.hi[0]);
                    if w != 0 {
                        any = true;
                        col_y[yy * nw + k - k0] |= w;
                        col_z[zz * nw + k - k0] |= w;
                    }
                }
                if any {
                    grow(&mut z_of_y[yy], z);
                    grow(&mut y_of_z[zz], y);
                }
            }
        }
        // The x range of the bits of `cols`.
        let x_range = |cols: &[u64]| -> Option<(usize, usize)> {
            let first = cols.iter().position(|&w| w != 0)?;
            let last = cols.iter().rposition(|&w| w != 0)?;
            Some((
                64 * (k0 + first) + cols[first].trailing_zeros() as usize,
                64 * (k0 + last) + 63 - cols[last].leading_zeros() as usize,
            ))
        };
        // Per x of the node: the range of the rows (of `cols`, `count` of them, from
        // `base`) that hold it.
        let per_x = |cols: &[u64], count: usize, base: usize| -> Vec<Option<(usize, usize)>> {
            let mut r = vec![None; n[0]];
            for i in 0..count {
                for (k, &w) in cols[i * nw..(i + 1) * nw].iter().enumerate() {
                    let mut bits = w;
                    while bits != 0 {
                        let x = 64 * (k0 + k) + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        grow(&mut r[x - b.lo[0]], base + i);
                    }
                }
            }
            r
        };
        let ys = per_x(&col_y, n[1], b.lo[1]);
        let zs = per_x(&col_z, n[2], b.lo[2]);
        let sx = (0..n[0])
            .map(|i| {
                let x = b.lo[0] + i;
                let ((y0, y1), (z0, z1)) = (ys[i]?, zs[i]?);
                Some(BlockBox {
                    lo: [x, y0, z0],
                    hi: [x + 1, y1 + 1, z1 + 1],
                })
            })
            .collect();
        let sy = (0..n[1])
            .map(|i| {
                let y = b.lo[1] + i;
                let (x0, x1) = x_range(&col_y[i * nw..(i + 1) * nw])?;
                let (z0, z1) = z_of_y[i]?;
                Some(BlockBox {
                    lo: [x0, y, z0],
                    hi: [x1 + 1, y + 1, z1 + 1],
                })
            })
            .collect();
        let sz = (0..n[2])
            .map(|i| {
                let z = b.lo[2] + i;
                let (x0, x1) = x_range(&col_z[i * nw..(i + 1) * nw])?;
                let (y0, y1) = y_of_z[i]?;
                Some(BlockBox {
                    lo: [x0, y0, z],
                    hi: [x1 + 1, y1 + 1, z + 1],
                })
            })
            .collect();
        [sx, sy, sz]
    }
}

/// The best split of a (tight) node: `(cost, left, right)`.
fn best_split(
    grid: &impl Needed,
    bits: &Bits,
    b: &BlockBox,
    p: &KdParams,
) -> Option<(f64, Option<BlockBox>, Option<BlockBox>)> {
    let cost = |x: &Option<BlockBox>| x.as_ref().map_or(0.0, |x| box_cost(grid, x, p));
    let mut best: Option<(f64, Option<BlockBox>, Option<BlockBox>)> = None;
    if (0..3).all(|axis| b.hi[axis] - b.lo[axis] < 2 * p.min_box) {
        return None;
    }
    let all = bits.slab_bounds(b);
    for (axis, slabs) in all.iter().enumerate() {
        let n = b.hi[axis] - b.lo[axis];
        if n < 2 * p.min_box {
            continue;
        }
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

/// Grows the subtree of the (tight) node `b`, prunes it, and returns its cost and leaves.
fn recurse(
    grid: &impl Needed,
    bits: &Bits,
    b: BlockBox,
    depth: u32,
    p: &KdParams,
) -> (f64, Vec<BlockBox>) {
    let leaf = box_cost(grid, &b, p);
    if depth >= p.max_depth || bits.full(&b) {
        return (leaf, vec![b]);
    }
    let Some((_, l, r)) = best_split(grid, bits, &b, p) else {
        return (leaf, vec![b]);
    };
    let (mut cost, mut leaves) = (0.0, Vec::new());
    for child in [l, r].into_iter().flatten() {
        let (c, mut v) = recurse(grid, bits, child, depth + 1, p);
        cost += c;
        leaves.append(&mut v);
    }
    if cost < (1.0 - p.min_gain) * leaf {
        (cost, leaves)
    } else {
        (leaf, vec![b])
    }
}

/// The leaves of the kd-tree over the whole grid (empty when nothing is needed).
pub fn subdivide(grid: &impl Needed, p: &KdParams) -> Vec<BlockBox> {
    let d = grid.dims();
    let root = BlockBox { lo: [0; 3], hi: d };
    let mut out = Vec::new();
    if let Some(t) = tight(grid, &root) {
        let bits = Bits::new(grid);
        out = recurse(grid, &bits, t, 0, p).1;
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
            apron: true,
            cell_cost: 0.0,
            min_box: 1,
            max_depth: 16,
            min_gain: 0.0,
            pair_align: false,
        }
    }

    #[test]
    fn slab_bounds_from_bits_equal_the_block_by_block_ones() {
        let mut r = crate::rng::Pcg32::seeded(5, 11);
        for dims in [[70, 9, 7], [130, 5, 6], [64, 3, 4], [3, 8, 5], [200, 2, 3]] {
            for density in [0.02f32, 0.3, 0.97] {
                let n: usize = dims.iter().product();
                let on: Vec<[usize; 3]> = (0..n)
                    .filter(|_| r.next_f32() < density)
                    .map(|i| {
                        [
                            i % dims[0],
                            (i / dims[0]) % dims[1],
                            i / (dims[0] * dims[1]),
                        ]
                    })
                    .collect();
                let g = grid(dims, &on);
                let bits = Bits::new(&g);
                for _ in 0..40 {
                    let mut c = |a: usize| {
                        let (u, v) = (
                            r.below(dims[a] as u32) as usize,
                            r.below(dims[a] as u32) as usize,
                        );
                        (u.min(v), u.max(v) + 1)
                    };
                    let (x, y, z) = (c(0), c(1), c(2));
                    let b = BlockBox {
                        lo: [x.0, y.0, z.0],
                        hi: [x.1, y.1, z.1],
                    };
                    let fast = bits.slab_bounds(&b);
                    for (axis, slabs) in fast.iter().enumerate() {
                        assert_eq!(slabs, &slab_bounds(&g, &b, axis), "{dims:?} {b:?} {axis}");
                    }
                    let full = (b.lo[2]..b.hi[2]).all(|z| {
                        (b.lo[1]..b.hi[1]).all(|y| (b.lo[0]..b.hi[0]).all(|x| g.needed([x, y, z])))
                    });
                    assert_eq!(bits.full(&b), full, "{dims:?} {b:?}");
                }
            }
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
