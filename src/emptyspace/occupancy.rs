//! Which blocks of a volume must stay drawn ([`needed_blocks`]): the support of every
//! non-empty texel of the MIP levels a tier covers, on a grid of `A × A × A` blocks; and
//! which blocks hold any data at all ([`DataGrid`]), what aprons must carry.
//!
//! A renderer that samples level `L` trilinearly at a point `X` (level-0 texel units,
//! `x_L = X · n_L / n_0 − 0.5`) reads texels `floor(x_L)` and `floor(x_L) + 1`, so texel
//! `i` of level `L` contributes to every point with `|x_L − i| < 1`, i.e. to
//! `X ∈ ((i − 0.5) · n_0 / n_L, (i + 1.5) · n_0 / n_L)`. A block is *needed* when that
//! open interval (per axis) meets it for some non-empty texel of some level `L < levels`.
//! Outside the needed blocks the source renders exactly transparent at those levels, so
//! dropping them changes nothing (formats/SPEC.md §8.6).
//!
//! A texel is **empty** when its alpha byte is `≤ threshold`; with `threshold = 0` it must
//! in addition have zero colour bytes (premultiplied colour with zero alpha is zero, but an
//! additive texel would not be), so the default loses nothing at all.

/// Needed blocks, x fastest.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockGrid {
    /// Blocks per axis: `ceil(dims / block)`.
    pub dims: [usize; 3],
    pub needed: Vec<bool>,
}

impl BlockGrid {
    pub fn index(&self, b: [usize; 3]) -> usize {
        b[0] + self.dims[0] * (b[1] + self.dims[1] * b[2])
    }

    pub fn is_needed(&self, b: [usize; 3]) -> bool {
        self.needed[self.index(b)]
    }

    pub fn count(&self) -> usize {
        self.needed.iter().filter(|&&n| n).count()
    }
}

/// Whether an RGBA8 texel counts as empty at `threshold` (see the module docs).
pub fn is_empty_texel(t: &[u8], threshold: u8) -> bool {
    if threshold == 0 {
        t[0] == 0 && t[1] == 0 && t[2] == 0 && t[3] == 0
    } else {
        t[3] <= threshold
    }
}

/// The needed blocks of a volume whose level `L` is `levels[L]` (RGBA8, `level_dims[L]`),
/// level-0 size `dims0`, considering levels `0..levels_used`.
pub fn needed_blocks(
    levels: &[&[u8]],
    level_dims: &[[u32; 3]],
    dims0: [u32; 3],
    block: usize,
    levels_used: usize,
    threshold: u8,
) -> BlockGrid {
    let n0 = dims0.map(|d| d as usize);
    let dims = n0.map(|d| d.div_ceil(block));
    let mut grid = BlockGrid {
        dims,
        needed: vec![false; dims[0] * dims[1] * dims[2]],
    };
    for (l, bytes) in levels.iter().enumerate().take(levels_used) {
        let nl = level_dims[l].map(|d| d as usize);
        // Per axis and texel index: the block range its support meets (inclusive).
        let ranges = support_ranges(n0, nl, block, dims);
        for z in 0..nl[2] {
            for y in 0..nl[1] {
                for x in 0..nl[0] {
                    let o = 4 * (x + nl[0] * (y + nl[1] * z));
                    if is_empty_texel(&bytes[o..o + 4], threshold) {
                        continue;
                    }
                    let (rx, ry, rz) = (ranges[0][x], ranges[1][y], ranges[2][z]);
                    for bz in rz.0..=rz.1 {
                        for by in ry.0..=ry.1 {
                            for bx in rx.0..=rx.1 {
                                let i = grid.index([bx, by, bz]);
                                grid.needed[i] = true;
                            }
                        }
                    }
                }
            }
        }
    }
    grid
}

/// Two consecutive MIP levels `k` and `k + 1` of a volume, the input of one tier: level
/// `k` is `n` texels (every side even), level `k + 1` exactly `n / 2`.
#[derive(Clone, Copy, Debug)]
pub struct TierSource<'a> {
    pub n: [usize; 3],
    pub colour: [&'a [u8]; 2],
    pub normals: Option<[&'a [u8]; 2]>,
}

impl TierSource<'_> {
    /// Texel bytes of level `l ∈ {0, 1}` at `p`, clamped to the level (clamp-to-edge).
    pub fn texel(&self, l: usize, p: [i64; 3]) -> (&[u8], Option<&[u8]>) {
        let n = self.n.map(|d| d >> l);
        let c = [0, 1, 2].map(|a| p[a].clamp(0, n[a] as i64 - 1) as usize);
        let o = 4 * (c[0] + n[0] * (c[1] + n[1] * c[2]));
        (
            &self.colour[l][o..o + 4],
            self.normals.map(|nr| &nr[l][o..o + 4]),
        )
    }

    /// Whether block `b` (2×2×2 level-`k` texels, one level-`k+1` texel; outside the grid:
    /// what clamp-to-edge reads there) has any non-zero colour or normal byte.
    pub fn block_has_data(&self, b: [i64; 3]) -> bool {
        let nz = |(c, n): (&[u8], Option<&[u8]>)| {
            c.iter().any(|&v| v != 0) || n.is_some_and(|n| n.iter().any(|&v| v != 0))
        };
        if nz(self.texel(1, b)) {
            return true;
        }
        (0..8).any(|i| {
            let p = [0, 1, 2].map(|a| 2 * b[a] + ((i >> a) & 1) as i64);
            nz(self.texel(0, p))
        })
    }
}

/// What a tier reads of its two levels: [`TierSource`] (dense bytes) or a brick-sparse
/// source ([`crate::sparse_level`]). Every method must give the same answers as the dense
/// levels would, so that a tier comes out byte for byte the same from either.
pub trait TierTexels: Sync {
    /// Level-`k` size in texels (every side even; level `k + 1` is `n / 2`).
    fn n(&self) -> [usize; 3];
    fn has_normals(&self) -> bool;
    /// Colour (`normals = false`) or normal bytes of level `l ∈ {0, 1}` at `p` (inside
    /// the level); zero normals when there are none.
    fn get(&self, l: usize, normals: bool, p: [usize; 3]) -> [u8; 4];
    /// Calls `f(p, colour)` for every texel of level `l` that is not empty at threshold 0
    /// ([`is_empty_texel`]), in any order (it may also be called for empty ones).
    fn for_each_texel(&self, l: usize, f: &mut dyn FnMut([usize; 3], [u8; 4]));

    /// [`TierSource::block_has_data`].
    fn block_has_data(&self, b: [i64; 3]) -> bool {
        let n = self.n();
        let nz = |l: usize, p: [i64; 3]| {
            let c = [0, 1, 2].map(|a| p[a].clamp(0, (n[a] >> l) as i64 - 1) as usize);
            self.get(l, false, c) != [0; 4]
                || (self.has_normals() && self.get(l, true, c) != [0; 4])
        };
        if nz(1, b) {
            return true;
        }
        (0..8).any(|i| {
            let p = [0, 1, 2].map(|a| 2 * b[a] + ((i >> a) & 1) as i64);
            nz(0, p)
        })
    }
}

impl TierTexels for TierSource<'_> {
    fn n(&self) -> [usize; 3] {
        self.n
    }
    fn has_normals(&self) -> bool {
        self.normals.is_some()
    }
    fn get(&self, l: usize, normals: bool, p: [usize; 3]) -> [u8; 4] {
        let n = self.n.map(|d| d >> l);
        let o = 4 * (p[0] + n[0] * (p[1] + n[1] * p[2]));
        let bytes = if normals {
            match self.normals {
                Some(nr) => nr[l],
                None => return [0; 4],
            }
        } else {
            self.colour[l]
        };
        [bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]
    }
    fn for_each_texel(&self, l: usize, f: &mut dyn FnMut([usize; 3], [u8; 4])) {
        let n = self.n.map(|d| d >> l);
        let bytes = self.colour[l];
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    let o = 4 * (x + n[0] * (y + n[1] * z));
                    let t = [bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]];
                    if t != [0; 4] {
                        f([x, y, z], t);
                    }
                }
            }
        }
    }
    fn block_has_data(&self, b: [i64; 3]) -> bool {
        TierSource::block_has_data(self, b)
    }
}

/// [`needed_blocks`] of a tier's two levels (blocks of 2, threshold 0) from any
/// [`TierTexels`]: the same grid, since marking is an OR over the non-empty texels.
pub fn tier_needed_blocks(src: &dyn TierTexels) -> BlockGrid {
    let n0 = src.n();
    let block = 2;
    let dims = n0.map(|d| d.div_ceil(block));
    let mut grid = BlockGrid {
        dims,
        needed: vec![false; dims[0] * dims[1] * dims[2]],
    };
    for l in 0..2 {
        let nl = n0.map(|d| d >> l);
        let ranges = support_ranges(n0, nl, block, dims);
        src.for_each_texel(l, &mut |p, t| {
            if is_empty_texel(&t, 0) {
                return;
            }
            let (rx, ry, rz) = (ranges[0][p[0]], ranges[1][p[1]], ranges[2][p[2]]);
            for bz in rz.0..=rz.1 {
                for by in ry.0..=ry.1 {
                    for bx in rx.0..=rx.1 {
                        let i = bx + dims[0] * (by + dims[1] * bz);
                        grid.needed[i] = true;
                    }
                }
            }
        });
    }
    grid
}

/// Blocks with data on the block grid (`n / 2` blocks) padded by two blocks on every side
/// (a slot's apron, grown to a pair of blocks for block compression, reaches that far),
/// as a summed-volume table so that any box can be queried in O(1).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DataGrid {
    /// Unpadded grid size in blocks.
    pub dims: [usize; 3],
    /// `(d + 5)` entries per axis (padded size + 1), x fastest.
    sums: Vec<u32>,
}

/// Blocks of padding of [`DataGrid`] on each side.
const PAD: i64 = 2;

impl DataGrid {
    pub fn new<S: TierTexels + ?Sized>(src: &S) -> DataGrid {
        let dims = src.n().map(|d| d / 2);
        let s = dims.map(|d| d + 2 * PAD as usize + 1);
        let mut sums = vec![0u32; s[0] * s[1] * s[2]];
        let at = |x: usize, y: usize, z: usize| x + s[0] * (y + s[1] * z);
        for z in 1..s[2] {
            for y in 1..s[1] {
                for x in 1..s[0] {
                    let b = [x, y, z].map(|v| v as i64 - 1 - PAD);
                    let v = u32::from(src.block_has_data(b));
                    sums[at(x, y, z)] =
                        v + sums[at(x - 1, y, z)] + sums[at(x, y - 1, z)] + sums[at(x, y, z - 1)]
                            - sums[at(x - 1, y - 1, z)]
                            - sums[at(x - 1, y, z - 1)]
                            - sums[at(x, y - 1, z - 1)]
                            + sums[at(x - 1, y - 1, z - 1)];
                }
            }
        }
        DataGrid { dims, sums }
    }

    /// Data blocks in `[lo, hi)` (block coordinates, clipped to `-2 ..= dims + 1`).
    pub fn count(&self, lo: [i64; 3], hi: [i64; 3]) -> u32 {
        let s = self.dims.map(|d| d + 2 * PAD as usize + 1);
        let c = |v: i64, a: usize| (v + PAD).clamp(0, s[a] as i64 - 1) as usize;
        let (l, h) = (
            [0, 1, 2].map(|a| c(lo[a], a)),
            [0, 1, 2].map(|a| c(hi[a], a)),
        );
        if (0..3).any(|a| h[a] <= l[a]) {
            return 0;
        }
        let at = |x: usize, y: usize, z: usize| i64::from(self.sums[x + s[0] * (y + s[1] * z)]);
        (at(h[0], h[1], h[2]) - at(l[0], h[1], h[2]) - at(h[0], l[1], h[2]) - at(h[0], h[1], l[2])
            + at(l[0], l[1], h[2])
            + at(l[0], h[1], l[2])
            + at(h[0], l[1], l[2])
            - at(l[0], l[1], l[2])) as u32
    }
}

/// Sets every texel whose alpha byte is `≤ threshold` to zero (colour and normal), at every
/// level: what `--threshold` drops. `threshold = 0` changes nothing that is not all zero
/// already, except colour-only texels with zero alpha, which it keeps.
pub fn apply_threshold(colour: &mut [u8], normals: Option<&mut [u8]>, threshold: u8) {
    if threshold == 0 {
        return;
    }
    let mut dropped = Vec::new();
    for (i, t) in colour.chunks_exact_mut(4).enumerate() {
        if t[3] <= threshold {
            t.fill(0);
            dropped.push(i);
        }
    }
    if let Some(n) = normals {
        for i in dropped {
            n[4 * i..4 * i + 4].fill(0);
        }
    }
}

/// Per axis and texel index of a level of `nl` texels over a level 0 of `n0`: the range of
/// `block`-wide blocks (of `dims` per axis) that the texel's trilinear support meets,
/// inclusive.
fn support_ranges(
    n0: [usize; 3],
    nl: [usize; 3],
    block: usize,
    dims: [usize; 3],
) -> [Vec<(usize, usize)>; 3] {
    std::array::from_fn(|ax| {
        let scale = n0[ax] as f64 / nl[ax] as f64;
        (0..nl[ax])
            .map(|i| {
                let lo = (i as f64 - 0.5) * scale / block as f64;
                let hi = (i as f64 + 1.5) * scale / block as f64;
                let b0 = lo.floor().max(0.0) as usize;
                let b1 = (hi.ceil() as usize).saturating_sub(1).min(dims[ax] - 1);
                (b0.min(dims[ax] - 1), b1)
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_blocks_and_box_counts_include_clamped_border_reads() {
        // 4×2×2 texels level 0 (2×1×1 blocks), level 1 2×1×1; one texel at x = 3 (block 1).
        let mut c0 = vec![0u8; 4 * 4 * 2 * 2];
        c0[4 * 3 + 3] = 9;
        let c1 = vec![0u8; 2 * 4];
        let src = TierSource {
            n: [4, 2, 2],
            colour: [&c0, &c1],
            normals: None,
        };
        assert!(!src.block_has_data([0, 0, 0]));
        assert!(src.block_has_data([1, 0, 0]));
        // Beyond the +x border, clamp-to-edge reads texel 3 again; so do the blocks below
        // y = 0 and z = 0, not those above (they read the zero texels at y = 1, z = 1).
        assert!(src.block_has_data([2, 0, 0]));
        assert!(src.block_has_data([1, -1, -1]));
        assert!(!src.block_has_data([1, 1, 0]));
        assert!(!src.block_has_data([-1, 0, 0]));
        let g = DataGrid::new(&src);
        assert_eq!(g.count([-1, -1, -1], [3, 2, 2]), 2 * 2 * 2);
        assert_eq!(g.count([0, 0, 0], [1, 1, 1]), 0);
        assert_eq!(g.count([1, 0, 0], [2, 1, 1]), 1);
        assert_eq!(g.count([5, 0, 0], [9, 1, 1]), 0);
    }

    #[test]
    fn a_voxel_needs_the_blocks_its_filter_support_touches() {
        // 16 voxels along x, blocks of 4; one voxel at x = 7 (last of block 1):
        // support (6.5, 8.5) meets blocks 1 and 2.
        let mut l0 = vec![0u8; 16 * 4];
        l0[7 * 4 + 3] = 10;
        let g = needed_blocks(&[&l0], &[[16, 1, 1]], [16, 1, 1], 4, 1, 0);
        assert_eq!(g.needed, vec![false, true, true, false]);
        // Voxel 5 (inside block 1): support (4.5, 6.5), block 1 only.
        let mut l0 = vec![0u8; 16 * 4];
        l0[5 * 4 + 3] = 10;
        let g = needed_blocks(&[&l0], &[[16, 1, 1]], [16, 1, 1], 4, 1, 0);
        assert_eq!(g.needed, vec![false, true, false, false]);
    }

    #[test]
    fn the_threshold_drops_faint_texels_and_zero_keeps_colour_only_texels() {
        let l0 = vec![0, 0, 0, 3, 5, 0, 0, 0];
        let g = needed_blocks(&[&l0], &[[2, 1, 1]], [2, 1, 1], 1, 1, 3);
        assert_eq!(g.count(), 0);
        let g = needed_blocks(&[&l0], &[[2, 1, 1]], [2, 1, 1], 1, 1, 0);
        assert_eq!(g.count(), 2);
    }
}
