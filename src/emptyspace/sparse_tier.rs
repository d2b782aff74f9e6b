//! A tier of the empty-space removal read from two consecutive brick-sparse levels
//! ([`SparseLevel`], what `voxelize --prune` hands over): the same texels, byte for byte,
//! as from the dense levels.

use super::occupancy::TierTexels;
use crate::sparse_level::SparseLevel;

/// Two consecutive sparse levels `k`, `k + 1`: the input of one tier.
#[derive(Clone, Copy, Debug)]
pub struct SparseTier<'a> {
    pub levels: [&'a SparseLevel; 2],
}

impl TierTexels for SparseTier<'_> {
    fn n(&self) -> [usize; 3] {
        self.levels[0].dims
    }
    fn has_normals(&self) -> bool {
        self.levels[0].has_normals()
    }
    fn get(&self, l: usize, normals: bool, p: [usize; 3]) -> [u8; 4] {
        self.levels[l].get(normals, p)
    }
    fn for_each_texel(&self, l: usize, f: &mut dyn FnMut([usize; 3], [u8; 4])) {
        self.levels[l].for_each_texel(f)
    }
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::volume_from_fn;
    use super::super::{prune, prune_sparse, EmptySpaceOptions, Pruned};
    use crate::sparse_level::*;
    use billow_format::{mip_dims, VolumeAsset};

    fn sparse_of(a: &VolumeAsset) -> Vec<SparseLevel> {
        let v = a.header.volume.unwrap();
        let dims: Vec<[usize; 3]> = (0..v.mip_count)
            .map(|l| mip_dims(v.dims, l).map(|d| d as usize))
            .collect();
        from_dense(&dims, &a.levels, a.normals.as_deref())
    }

    fn shell(a: &VolumeAsset) -> VolumeAsset {
        VolumeAsset {
            levels: Vec::new(),
            normals: a.normals.as_ref().map(|_| Vec::new()),
            ..a.clone()
        }
    }

    fn same(mut a: Pruned, mut b: Pruned) {
        a.stats.seconds = 0.0;
        b.stats.seconds = 0.0;
        assert_eq!(a.stats, b.stats);
        assert_eq!(a.asset.to_bytes().unwrap(), b.asset.to_bytes().unwrap());
    }

    /// Blobs in a volume of `dims` (some texels faint), with or without normals.
    fn blobs(dims: [u32; 3], normals: bool) -> VolumeAsset {
        volume_from_fn(dims, normals, |x, y, z| {
            let on = (x.abs_diff(9) <= 3 && y.abs_diff(6) <= 2 && z.abs_diff(9) <= 4)
                || (x.abs_diff(dims[0] - 6) <= 3 && y.abs_diff(dims[1] - 5) <= 2 && z < 5)
                || ((20..30).contains(&x) && y == 16 && z == 20);
            if on {
                let a = if (x + y + z) % 5 == 0 { 6 } else { 200 };
                [
                    (x * 5 % 200) as u8 % a,
                    (y * 7) as u8 % a,
                    (z * 3) as u8 % a,
                    a,
                ]
            } else {
                [0; 4]
            }
        })
    }

    #[test]
    fn a_sparse_source_prunes_to_the_same_bytes_as_the_dense_one() {
        let cases = [
            (blobs([48, 32, 40], true), EmptySpaceOptions::default()),
            (blobs([64, 40, 48], false), EmptySpaceOptions::default()),
            (
                blobs([48, 32, 40], true),
                EmptySpaceOptions {
                    threshold: 10,
                    ..Default::default()
                },
            ),
            // Odd sides: kept whole (densified from the bricks).
            (blobs([47, 32, 40], true), EmptySpaceOptions::default()),
            // Nothing at all: the empty asset.
            (
                volume_from_fn([32, 16, 16], false, |_, _, _| [0; 4]),
                EmptySpaceOptions::default(),
            ),
            // Full: no layout is smaller, kept whole.
            (
                volume_from_fn([32, 16, 16], true, |_, _, _| [9, 9, 9, 90]),
                EmptySpaceOptions::default(),
            ),
        ];
        for (a, o) in cases {
            let dense = prune(&a, &o).unwrap();
            let sparse = prune_sparse(&shell(&a), sparse_of(&a), &o).unwrap();
            same(dense, sparse);
        }
    }

    #[test]
    fn bricks_read_back_as_the_dense_level() {
        let a = blobs([40, 24, 17], true);
        for (l, s) in sparse_of(&a).iter().enumerate() {
            let (c, n) = s.to_dense();
            assert_eq!(c, a.levels[l]);
            assert_eq!(n.as_ref(), a.normals.as_ref().map(|n| &n[l]));
            if l == 0 {
                let all: usize = s.dims.iter().map(|d| d.div_ceil(BRICK)).product();
                assert!(s.brick_count() < all, "{} of {all} bricks", s.brick_count());
            }
        }
    }

    #[test]
    fn a_sparse_prune_refuses_levels_that_do_not_match_the_header() {
        let a = blobs([48, 32, 40], false);
        let mut levels = sparse_of(&a);
        levels.pop();
        let e = prune_sparse(&shell(&a), levels, &EmptySpaceOptions::default()).unwrap_err();
        assert!(
            matches!(e, super::super::EmptySpaceError::InvalidAsset(_)),
            "{e}"
        );
    }
}
