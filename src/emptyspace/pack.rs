//! Packing brick slots into one 3D atlas (formats/SPEC.md §8.6), in whole blocks.
//!
//! Every slot is a box of whole blocks (`A³` voxels: the brick rounded up to blocks plus
//! its apron), so every slot origin is a multiple of `A` voxels and MIP level
//! `L ≤ log2 A` of the atlas holds each brick at an integer texel offset.
//!
//! The packer is a deterministic layered shelf packer: slots sorted by height (y), then
//! depth (z), then width (x), then index, all descending except the index; a *layer* is a
//! slab along y as high as its first slot; inside it, *rows* along x (at most `width`
//! blocks) are stacked along z (at most `depth` blocks); a row is as deep as its deepest
//! slot. Every `width` from the widest slot to the total width and every `depth` likewise
//! is tried, and the packing with the smallest atlas volume wins (ties: the smallest
//! largest side, then the smallest `width`, then `depth`).

/// Where each slot went, in blocks, and the atlas size in blocks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Packing {
    pub origins: Vec<[usize; 3]>,
    pub dims: [usize; 3],
}

fn shelf(sizes: &[[usize; 3]], order: &[usize], width: usize, depth: usize) -> Option<Packing> {
    let mut origins = vec![[0; 3]; sizes.len()];
    let (mut layer_y, mut layer_h) = (0usize, 0usize);
    let (mut row_z, mut row_d) = (0usize, 0usize);
    let mut x = 0usize;
    let mut dims = [0usize; 3];
    let mut first = true;
    for &i in order {
        let s = sizes[i];
        if s[0] > width || s[2] > depth {
            return None;
        }
        if first {
            layer_h = s[1];
            first = false;
        }
        if x + s[0] > width {
            // New row.
            x = 0;
            row_z += row_d;
            row_d = 0;
        }
        if row_z + s[2] > depth {
            // New layer.
            layer_y += layer_h;
            layer_h = s[1];
            row_z = 0;
            row_d = 0;
            x = 0;
        }
        origins[i] = [x, layer_y, row_z];
        x += s[0];
        row_d = row_d.max(s[2]);
        dims[0] = dims[0].max(x);
        dims[1] = dims[1].max(layer_y + s[1]);
        dims[2] = dims[2].max(row_z + s[2]);
    }
    Some(Packing { origins, dims })
}

/// Packs boxes of `sizes` blocks; no side of the atlas exceeds `max_side` blocks
/// (`None` when that is impossible with this packer).
pub fn pack(sizes: &[[usize; 3]], max_side: usize) -> Option<Packing> {
    if sizes.is_empty() {
        return Some(Packing {
            origins: Vec::new(),
            dims: [0; 3],
        });
    }
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by(|&a, &b| {
        let (sa, sb) = (sizes[a], sizes[b]);
        (sb[1], sb[2], sb[0], a).cmp(&(sa[1], sa[2], sa[0], b))
    });
    let max_w = sizes.iter().map(|s| s[0]).max().unwrap_or(1);
    let max_d = sizes.iter().map(|s| s[2]).max().unwrap_or(1);
    let sum_w: usize = sizes.iter().map(|s| s[0]).sum();
    let sum_d: usize = sizes.iter().map(|s| s[2]).sum();
    let mut best: Option<(usize, usize, usize, usize, Packing)> = None;
    for width in max_w..=sum_w.min(max_side) {
        for depth in max_d..=sum_d.min(max_side) {
            let Some(p) = shelf(sizes, &order, width, depth) else {
                continue;
            };
            if p.dims.iter().any(|&d| d > max_side) {
                continue;
            }
            let vol = p.dims.iter().product::<usize>();
            let side = p.dims.iter().copied().max().unwrap_or(0);
            let key = (vol, side, width, depth);
            if best.as_ref().is_none_or(|b| key < (b.0, b.1, b.2, b.3)) {
                best = Some((vol, side, width, depth, p));
            }
        }
    }
    best.map(|b| b.4)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn overlaps(a: ([usize; 3], [usize; 3]), b: ([usize; 3], [usize; 3])) -> bool {
        (0..3).all(|i| a.0[i] < b.0[i] + b.1[i] && b.0[i] < a.0[i] + a.1[i])
    }

    #[test]
    fn slots_never_overlap_and_stay_inside() {
        let sizes = vec![
            [3, 2, 1],
            [1, 1, 1],
            [2, 3, 2],
            [4, 1, 1],
            [1, 2, 3],
            [2, 2, 2],
        ];
        let p = pack(&sizes, 64).unwrap();
        for (i, size) in sizes.iter().enumerate() {
            for (k, dim) in p.dims.iter().enumerate() {
                assert!(p.origins[i][k] + size[k] <= *dim);
            }
            for (j, sj) in sizes.iter().enumerate().take(i) {
                assert!(
                    !overlaps((p.origins[i], *size), (p.origins[j], *sj)),
                    "{i} and {j} overlap: {p:?}"
                );
            }
        }
        let total: usize = sizes.iter().map(|s| s.iter().product::<usize>()).sum();
        assert!(p.dims.iter().product::<usize>() >= total);
    }

    #[test]
    fn equal_cubes_pack_densely_and_limits_are_respected() {
        let p = pack(&[[2, 2, 2]; 8], 64).unwrap();
        assert_eq!(p.dims.iter().product::<usize>(), 64);
        assert!(pack(&[[5, 1, 1]], 4).is_none());
        assert_eq!(pack(&[], 4).unwrap().dims, [0; 3]);
    }
}
