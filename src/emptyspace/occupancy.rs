//! Which blocks of a volume must stay drawn: the support of every non-empty texel of every
//! exactly-kept MIP level, on a grid of `A × A × A` blocks (`A` = the brick alignment).
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
/// level-0 size `dims0`, considering levels `0..exact_levels`.
pub fn needed_blocks(
    levels: &[Vec<u8>],
    level_dims: &[[u32; 3]],
    dims0: [u32; 3],
    block: usize,
    exact_levels: usize,
    threshold: u8,
) -> BlockGrid {
    let n0 = dims0.map(|d| d as usize);
    let dims = n0.map(|d| d.div_ceil(block));
    let mut grid = BlockGrid {
        dims,
        needed: vec![false; dims[0] * dims[1] * dims[2]],
    };
    for (l, bytes) in levels.iter().enumerate().take(exact_levels) {
        let nl = level_dims[l].map(|d| d as usize);
        // Per axis and texel index: the block range its support meets (inclusive).
        let ranges: [Vec<(usize, usize)>; 3] = std::array::from_fn(|ax| {
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
        });
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_voxel_needs_the_blocks_its_filter_support_touches() {
        // 16 voxels along x, blocks of 4; one voxel at x = 7 (last of block 1):
        // support (6.5, 8.5) meets blocks 1 and 2.
        let mut l0 = vec![0u8; 16 * 4];
        l0[7 * 4 + 3] = 10;
        let g = needed_blocks(&[l0], &[[16, 1, 1]], [16, 1, 1], 4, 1, 0);
        assert_eq!(g.needed, vec![false, true, true, false]);
        // Voxel 5 (inside block 1): support (4.5, 6.5), block 1 only.
        let mut l0 = vec![0u8; 16 * 4];
        l0[5 * 4 + 3] = 10;
        let g = needed_blocks(&[l0], &[[16, 1, 1]], [16, 1, 1], 4, 1, 0);
        assert_eq!(g.needed, vec![false, true, false, false]);
    }

    #[test]
    fn the_threshold_drops_faint_texels_and_zero_keeps_colour_only_texels() {
        let l0 = vec![0, 0, 0, 3, 5, 0, 0, 0];
        let g = needed_blocks(std::slice::from_ref(&l0), &[[2, 1, 1]], [2, 1, 1], 1, 1, 3);
        assert_eq!(g.count(), 0);
        let g = needed_blocks(&[l0], &[[2, 1, 1]], [2, 1, 1], 1, 1, 0);
        assert_eq!(g.count(), 2);
    }
}
