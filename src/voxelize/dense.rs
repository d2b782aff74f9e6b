//! The volume generation's MIP + combine stages (VB §3.2) for a level 0 that is already
//! a dense volume — procedural volumes (`noise_volume`, a test generator) rather than rendered
//! slice stacks. Level 0 is the same from all six directions; each direction's pyramid
//! composites along its view axis and averages across ([`super::mip::downsample`]), and
//! the six are combined per level with the user's function, exactly as `voxelize` does.

use rayon::prelude::*;

use super::combine::{combine_level, Combine};
use super::grid3::Grid3;
use super::mip::downsample;
use super::Dir;

/// Every MIP level of `level0` (premultiplied linear RGBA), RGBA8 `SrgbPremultiplied`,
/// down to 1×1×1.
pub fn pyramid_from_dense(level0: &Grid3<[f32; 4]>, f: &(dyn Combine + Sync)) -> Vec<Vec<u8>> {
    let mut levels = vec![combine_level(f, [level0; 6])];
    let mut cur: Vec<Grid3<[f32; 4]>> = vec![level0.clone(); 6];
    while cur[0].dims.iter().any(|&d| d > 1) {
        cur = Dir::ALL
            .par_iter()
            .zip(cur.par_iter())
            .map(|(&d, g)| downsample(g, d))
            .collect();
        let refs: [&Grid3<[f32; 4]>; 6] = std::array::from_fn(|i| &cur[i]);
        levels.push(combine_level(f, refs));
    }
    levels
}
