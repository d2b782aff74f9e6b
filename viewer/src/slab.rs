//! Slab partitioning (VB paper §3.3, "Slab partitioning"): the slices are grouped into
//! slabs — regions between planes orthogonal to the view axis — and every cell is
//! assigned to the slabs its depth range meets. Slabs are drawn one after the other from
//! the farthest; a slab no cell meets is not drawn at all, and within a slab only its
//! cells are intersected with its slices.
//!
//! Thickness rule (the paper's): a slab holds at least `min_slices` slices and is not
//! thinner than the mean depth extent of the cells.
//!
//! Equivalence: a slice at depth `s` can only cut a cell whose depth range `[z0, z1]`
//! contains `s`, and every slice belongs to exactly one slab, so the pairs (slice, cell)
//! that can give a polygon are all drawn exactly once, in the same order within a slice
//! (cells by ascending ID). The image is the same as without partitioning — a test
//! checks it bit for bit.

/// One slab: a run of back-to-front slice indices and the IDs of its cells (ascending).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Slab {
    /// First slice (index into the back-to-front slice list) and one past the last.
    pub slices: (u32, u32),
    pub cells: Vec<u32>,
}

/// Partitions back-to-front `slices` (`depth` decreasing) into slabs and assigns the
/// cells (`depth ranges`, view distances `[near, far]`; `near > far` = never cut).
/// `partition = false` gives one slab with every slice and every cell (the paper's plain
/// slicing). Slabs without cells are dropped; their count is returned with the slabs.
pub fn partition(
    slice_depths: &[f32],
    cell_ranges: &[(f32, f32)],
    partition: bool,
    min_slices: u32,
) -> (Vec<Slab>, usize) {
    let n = slice_depths.len();
    if n == 0 || cell_ranges.is_empty() {
        return (Vec::new(), 0);
    }
    if !partition {
        let slab = Slab {
            slices: (0, n as u32),
            cells: (0..cell_ranges.len() as u32).collect(),
        };
        return (vec![slab], 0);
    }
    let mean_extent = cell_ranges
        .iter()
        .map(|(a, b)| f64::from(b - a))
        .sum::<f64>()
        / cell_ranges.len() as f64;
    let min_slices = min_slices.max(1) as usize;
    // Slab boundaries over the slice list: [start, end) runs.
    let mut bounds: Vec<(usize, usize)> = Vec::new();
    let mut start = 0;
    while start < n {
        let mut end = (start + min_slices).min(n);
        while end < n && f64::from(slice_depths[start] - slice_depths[end - 1]) < mean_extent {
            end += 1;
        }
        bounds.push((start, end));
        start = end;
    }
    // Each slab's depth interval [lo, hi] (its slices' depths; decreasing order).
    let hi: Vec<f32> = bounds.iter().map(|b| slice_depths[b.0]).collect();
    let lo: Vec<f32> = bounds.iter().map(|b| slice_depths[b.1 - 1]).collect();
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); bounds.len()];
    for (id, &(z0, z1)) in cell_ranges.iter().enumerate() {
        if z0 > z1 {
            continue; // an empty range: a cell no slice may cut (another band's)
        }
        // Slabs are ordered by decreasing depth: first slab with lo <= z1 .. last with hi >= z0.
        let first = lo.partition_point(|&l| l > z1);
        let last = hi.partition_point(|&h| h >= z0);
        for c in cells.iter_mut().take(last).skip(first) {
            c.push(id as u32);
        }
    }
    let mut out = Vec::new();
    let mut empty = 0;
    for (b, c) in bounds.into_iter().zip(cells) {
        if c.is_empty() {
            empty += 1;
            continue;
        }
        out.push(Slab {
            slices: (b.0 as u32, b.1 as u32),
            cells: c,
        });
    }
    (out, empty)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every (slice, cell) pair with the slice inside the cell's range is in exactly one
    /// slab; a slab lists only cells whose range meets its depth interval.
    fn check(depths: &[f32], cells: &[(f32, f32)], min_slices: u32) -> usize {
        let (slabs, empty) = partition(depths, cells, true, min_slices);
        let mut seen = vec![0u32; depths.len() * cells.len()];
        for s in &slabs {
            assert!(s.cells.windows(2).all(|w| w[0] < w[1]), "ascending IDs");
            for &c in &s.cells {
                let (z0, z1) = cells[c as usize];
                let (hi, lo) = (depths[s.slices.0 as usize], depths[s.slices.1 as usize - 1]);
                assert!(lo <= z1 && z0 <= hi, "slab {s:?} lists cell {c} outside it");
                for i in s.slices.0..s.slices.1 {
                    seen[i as usize * cells.len() + c as usize] += 1;
                }
            }
        }
        for (i, &d) in depths.iter().enumerate() {
            for (c, &(z0, z1)) in cells.iter().enumerate() {
                let n = seen[i * cells.len() + c];
                if z0 <= d && d <= z1 {
                    assert_eq!(n, 1, "slice {i} (depth {d}) × cell {c} drawn {n} times");
                } else {
                    assert!(n <= 1);
                }
            }
        }
        empty
    }

    #[test]
    fn two_far_groups_leave_empty_slabs_out() {
        let depths: Vec<f32> = (0..200).rev().map(|i| 1.0 + i as f32 * 0.5).collect();
        let mut cells = Vec::new();
        for k in 0..10 {
            cells.push((2.0 + k as f32 * 0.3, 5.0 + k as f32 * 0.3));
            cells.push((80.0 + k as f32 * 0.2, 84.0 + k as f32 * 0.2));
        }
        let empty = check(&depths, &cells, 8);
        assert!(
            empty >= 5,
            "the gap between the groups is {empty} empty slabs"
        );
    }

    #[test]
    fn edge_cases() {
        assert_eq!(partition(&[], &[(0.0, 1.0)], true, 4).0.len(), 0);
        assert_eq!(partition(&[1.0], &[], true, 4).0.len(), 0);
        // One slice exactly on a cell's face.
        check(&[3.0, 2.0, 1.0], &[(1.0, 2.0), (3.0, 3.0)], 1);
        // Unpartitioned: one slab with everything.
        let (s, _) = partition(&[3.0, 2.0], &[(0.0, 1.0), (5.0, 6.0)], false, 4);
        assert_eq!(
            s,
            vec![Slab {
                slices: (0, 2),
                cells: vec![0, 1]
            }]
        );
        // Pseudo-random ranges.
        let mut x = 12345u32;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x % 1000) as f32 / 10.0
        };
        let depths: Vec<f32> = (0..300).rev().map(|i| i as f32 / 3.0).collect();
        let cells: Vec<(f32, f32)> = (0..100)
            .map(|_| {
                let (a, b) = (r(), r());
                (a.min(b), a.max(b))
            })
            .collect();
        for m in [1, 3, 16, 1000] {
            check(&depths, &cells, m);
        }
    }
}
