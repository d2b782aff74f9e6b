//! Brick-sparse grids: the working set of the MIP and combine stages above level 0
//! (docs/voxelize.md, "Cost that follows the surface").
//!
//! A grid of `dims` voxels is cut into bricks of [`B`]³ voxels (the last brick of an axis
//! may stick out of the grid; its outside voxels stay zero and are never read as data).
//! Only *occupied* bricks are allocated: a brick table maps every brick to a slot or to
//! [`EMPTY`], and slot `s` holds its [`B3`] voxels at `data[s·B3 ..]`, x fastest inside the
//! brick. An absent brick reads as zeros everywhere, which is what the dense grid it
//! replaces held there, so every filter that gives zero for all-zero inputs computes the
//! same values on bricks as on the dense grid, in the same order, with the same bytes.

use rayon::prelude::*;

#[cfg(test)]
use super::grid3::Grid3;
use super::grid3::Texel;

/// Brick side in voxels.
pub const B: usize = 8;
/// Voxels per brick.
pub const B3: usize = B * B * B;
/// The brick table's mark for a brick that holds nothing.
pub const EMPTY: u32 = u32::MAX;

/// Which bricks of a grid are allocated, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub dims: [usize; 3],
    /// Bricks per axis.
    pub nb: [usize; 3],
    /// Per brick (x fastest), its slot or [`EMPTY`].
    pub slot: Vec<u32>,
    /// Per slot, its brick, in increasing brick order.
    pub bricks: Vec<u32>,
}

impl Layout {
    /// The layout with exactly the bricks marked in `occupied` (one flag per brick).
    pub fn from_flags(dims: [usize; 3], occupied: &[bool]) -> Self {
        let nb = dims.map(|d| d.div_ceil(B));
        debug_assert_eq!(occupied.len(), nb.iter().product::<usize>());
        let mut slot = vec![EMPTY; occupied.len()];
        let mut bricks = Vec::new();
        for (b, &o) in occupied.iter().enumerate() {
            if o {
                slot[b] = bricks.len() as u32;
                bricks.push(b as u32);
            }
        }
        Layout {
            dims,
            nb,
            slot,
            bricks,
        }
    }
    /// Brick coordinates of brick `b`.
    #[inline]
    pub fn coords(&self, b: usize) -> [usize; 3] {
        [
            b % self.nb[0],
            (b / self.nb[0]) % self.nb[1],
            b / (self.nb[0] * self.nb[1]),
        ]
    }
    #[inline]
    pub fn brick_of(&self, bc: [usize; 3]) -> usize {
        bc[0] + self.nb[0] * (bc[1] + self.nb[1] * bc[2])
    }
    /// Where voxel `p` lives in `data`, or `None` in an absent brick.
    #[inline]
    pub fn offset(&self, p: [usize; 3]) -> Option<usize> {
        let s = self.slot[self.brick_of(p.map(|v| v / B))];
        (s != EMPTY).then(|| s as usize * B3 + local(p))
    }
}

/// A voxel's index inside its brick.
#[inline]
pub fn local(p: [usize; 3]) -> usize {
    (p[0] % B) + B * ((p[1] % B) + B * (p[2] % B))
}

/// A brick-sparse grid (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Bricked<T> {
    pub layout: Layout,
    pub data: Vec<T>,
}

impl<T: Texel> Bricked<T> {
    /// All bricks of `layout` allocated, zero.
    pub fn zeroed(layout: Layout) -> Self {
        let n = layout.bricks.len() * B3;
        Bricked {
            layout,
            data: vec![T::default(); n],
        }
    }
    pub fn dims(&self) -> [usize; 3] {
        self.layout.dims
    }
    /// Voxel `p` (zero in an absent brick).
    #[cfg(test)]
    pub fn get(&self, p: [usize; 3]) -> [f32; 4] {
        self.layout
            .offset(p)
            .map_or([0.0; 4], |i| self.data[i].load())
    }
    /// The bricks of `g` that hold a non-zero voxel.
    #[cfg(test)]
    pub fn from_dense(g: &Grid3<T>) -> Self {
        let nb = g.dims.map(|d| d.div_ceil(B));
        let n: usize = nb.iter().product();
        let occupied: Vec<bool> = (0..n)
            .into_par_iter()
            .map(|b| {
                let bc = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])];
                voxels_of(bc, g.dims).any(|p| g.get(p) != [0.0; 4])
            })
            .collect();
        let mut out = Self::zeroed(Layout::from_flags(g.dims, &occupied));
        let layout = &out.layout;
        out.data
            .par_chunks_mut(B3)
            .zip(&layout.bricks)
            .for_each(|(brick, &b)| {
                for p in voxels_of(layout.coords(b as usize), g.dims) {
                    brick[local(p)] = g.data[g.index(p)];
                }
            });
        out
    }
    /// The bricks of a direction's sparse level 0 that hold one of its voxels, with the
    /// values [`super::slices::DirSlices::to_dense`] stores (zeros elsewhere).
    pub fn from_slices(s: &super::slices::DirSlices) -> Self {
        let dims = s.dims;
        let nb = dims.map(|d| d.div_ceil(B));
        let at = |i: usize| {
            [
                i % dims[0],
                (i / dims[0]) % dims[1],
                i / (dims[0] * dims[1]),
            ]
        };
        let brick = |p: [usize; 3]| p[0] / B + nb[0] * (p[1] / B + nb[1] * (p[2] / B));
        let indices = s.indices();
        let mut occupied = vec![false; nb.iter().product()];
        for &i in &indices {
            occupied[brick(at(i))] = true;
        }
        let mut out = Self::zeroed(Layout::from_flags(dims, &occupied));
        for (&i, v) in indices.iter().zip(&s.vox) {
            let o = out
                .layout
                .offset(at(i))
                .expect("the voxel's brick is occupied");
            out.data[o] = T::store(v.rgba);
        }
        out
    }
    /// The dense grid (zeros where no brick is).
    #[cfg(test)]
    pub fn to_dense(&self) -> Grid3<T> {
        let mut g = Grid3::<T>::new(self.layout.dims);
        let dims = g.dims;
        for (brick, &b) in self.data.chunks_exact(B3).zip(&self.layout.bricks) {
            for p in voxels_of(self.layout.coords(b as usize), dims) {
                let i = g.index(p);
                g.data[i] = brick[local(p)];
            }
        }
        g
    }
}

/// Calls `f` with every voxel of brick `bc` inside a grid of `dims`, x fastest.
#[inline]
pub fn for_each_voxel(bc: [usize; 3], dims: [usize; 3], mut f: impl FnMut([usize; 3])) {
    let hi = [0, 1, 2].map(|a| ((bc[a] + 1) * B).min(dims[a]));
    for z in bc[2] * B..hi[2] {
        for y in bc[1] * B..hi[1] {
            for x in bc[0] * B..hi[0] {
                f([x, y, z]);
            }
        }
    }
}

/// The voxels of brick `bc` inside a grid of `dims`, x fastest.
pub fn voxels_of(bc: [usize; 3], dims: [usize; 3]) -> impl Iterator<Item = [usize; 3]> {
    let lo = bc.map(|c| c * B);
    let hi = [0, 1, 2].map(|a| (lo[a] + B).min(dims[a]));
    (lo[2]..hi[2])
        .flat_map(move |z| (lo[1]..hi[1]).flat_map(move |y| (lo[0]..hi[0]).map(move |x| [x, y, z])))
}

/// A brick-sparse accumulator: `width` floats per voxel, bricks added as values are folded
/// into them (one direction at a time, in direction order).
pub(crate) struct BrickAccum<T> {
    pub dims: [usize; 3],
    pub nb: [usize; 3],
    /// Per brick, its slot or [`EMPTY`].
    pub slot: Vec<u32>,
    /// Per slot, its brick.
    pub bricks: Vec<u32>,
    pub width: usize,
    pub data: Vec<T>,
}

impl<T: Copy + Default + Send + Sync> BrickAccum<T> {
    pub fn new(dims: [usize; 3], width: usize) -> Self {
        let nb = dims.map(|d| d.div_ceil(B));
        BrickAccum {
            dims,
            nb,
            slot: vec![EMPTY; nb.iter().product()],
            bricks: Vec::new(),
            width,
            data: Vec::new(),
        }
    }
    /// Brick coordinates of brick `b`.
    #[inline]
    pub fn coords(&self, b: usize) -> [usize; 3] {
        [
            b % self.nb[0],
            (b / self.nb[0]) % self.nb[1],
            b / (self.nb[0] * self.nb[1]),
        ]
    }
    /// Allocates (zeroed) every brick of `layout` not allocated yet.
    pub fn reserve(&mut self, layout: &Layout) {
        debug_assert_eq!(layout.dims, self.dims);
        for &b in &layout.bricks {
            let s = &mut self.slot[b as usize];
            if *s == EMPTY {
                *s = self.bricks.len() as u32;
                self.bricks.push(b);
            }
        }
        self.data
            .resize(self.bricks.len() * B3 * self.width, T::default());
    }
    /// Runs `f(accumulator brick, input brick index)` for every brick of `layout` in
    /// parallel (each accumulator brick is given to one task only); the bricks must have
    /// been [`reserve`](Self::reserve)d.
    pub fn for_each_brick(&mut self, layout: &Layout, f: impl Fn(&mut [T], usize) + Sync) {
        let per = B3 * self.width;
        let slot = &self.slot;
        let base = super::grid3::Disjoint::new(&mut self.data);
        layout.bricks.par_iter().enumerate().for_each(|(i, &b)| {
            let s = slot[b as usize] as usize;
            // SAFETY: the bricks of a layout are distinct, so their accumulator slots are.
            let acc = unsafe { base.slice_mut(s * per, per) };
            f(acc, i);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::super::mip::{downsample, downsample_bricks, downsample_with};
    use super::super::Dir;
    use super::*;
    use crate::rng::Pcg32;
    use half::f16;

    /// A sparse random volume: a few blobs of premultiplied colour (some faint, some
    /// opaque), weighted normals `|n| ≤ α` where the colour is.
    fn volume(dims: [usize; 3], seed: u64) -> (Grid3<[f32; 4]>, Grid3<[f16; 4]>) {
        let mut r = Pcg32::seeded(seed, 7);
        let mut c = Grid3::<[f32; 4]>::new(dims);
        let mut n = Grid3::<[f16; 4]>::new(dims);
        for _ in 0..6 {
            let centre = dims.map(|d| r.below(d as u32) as usize);
            let rad = 1 + r.below(4) as usize;
            for z in centre[2].saturating_sub(rad)..(centre[2] + rad).min(dims[2]) {
                for y in centre[1].saturating_sub(rad)..(centre[1] + rad).min(dims[1]) {
                    for x in centre[0].saturating_sub(rad)..(centre[0] + rad).min(dims[0]) {
                        if r.below(3) == 0 {
                            continue;
                        }
                        let a = if r.below(4) == 0 { 1.0 } else { r.next_f32() };
                        let i = c.index([x, y, z]);
                        c.data[i] = [a * r.next_f32(), a * r.next_f32(), a * r.next_f32(), a];
                        let m = a * r.range_f32(-0.57, 0.57);
                        n.data[i] = [m, -m, 0.5 * m, 0.0].map(f16::from_f32);
                    }
                }
            }
        }
        (c, n)
    }

    #[test]
    fn bricked_mip_steps_equal_the_dense_ones_bit_for_bit() {
        for (k, dims) in [
            [16, 16, 16],
            [13, 8, 21],
            [5, 1, 9],
            [33, 17, 40],
            [24, 7, 2],
        ]
        .into_iter()
        .enumerate()
        {
            let (c, n) = volume(dims, k as u64);
            let (cb, nb) = (Bricked::from_dense(&c), Bricked::from_dense(&n));
            assert_eq!(cb.to_dense(), c);
            for dir in Dir::ALL {
                let dense = downsample(&c, dir);
                let sparse = downsample_bricks::<_, [f32; 4]>(&cb, None, dir, None);
                assert_eq!(sparse.to_dense(), dense, "{dims:?} {dir:?}");
                let dense_n = downsample_with(&n, &c, dir);
                let sparse_n = downsample_bricks(&nb, Some(&cb), dir, Some(&sparse.layout));
                assert_eq!(sparse_n.to_dense(), dense_n, "normals {dims:?} {dir:?}");
            }
        }
    }

    #[test]
    fn an_empty_volume_allocates_nothing() {
        let g = Grid3::<[f32; 4]>::new([40, 24, 16]);
        let b = Bricked::from_dense(&g);
        assert!(b.data.is_empty());
        let d = downsample_bricks::<_, [f32; 4]>(&b, None, Dir::PosX, None);
        assert!(d.data.is_empty() && d.layout.bricks.is_empty());
        assert_eq!(d.to_dense(), downsample(&g, Dir::PosX));
    }

    #[test]
    fn only_bricks_near_data_are_allocated() {
        // One voxel in a 128³ volume: level 1 (64³, 512 bricks) needs one brick, its
        // parent's, in every direction.
        let mut g = Grid3::<[f32; 4]>::new([128; 3]);
        let i = g.index([70, 9, 100]);
        g.data[i] = [0.25, 0.25, 0.25, 0.5];
        let b = Bricked::from_dense(&g);
        assert_eq!(b.layout.bricks.len(), 1);
        for dir in Dir::ALL {
            let d = downsample_bricks::<_, [f32; 4]>(&b, None, dir, None);
            assert_eq!(d.layout.bricks.len(), 1, "{dir:?}");
            assert_eq!(d.to_dense(), downsample(&g, dir));
        }
    }

    #[test]
    fn the_bricked_combine_equals_the_dense_one_byte_for_byte() {
        use super::super::combine::{combine_level, combine_level_bricks, CombineFn};
        // Some give zero for six zeros (only the held bricks differ from zero), some
        // colour the empty space too (every voxel outside the bricks gets f(0)).
        let fns = [
            "expr:max(px, nx, py, ny, pz, nz)",
            "expr:px + rgba(0.1, 0.05, 0.02, 0.1)",
            "expr:mean(px, nx, py, ny, pz, nz) * 2 - 0.01",
            "mean",
        ];
        for (k, dims) in [[16, 16, 16], [13, 8, 21], [5, 1, 9], [33, 17, 40]]
            .into_iter()
            .enumerate()
        {
            // Six directions with different holes: a seventh of the blobs each misses.
            let dense: Vec<Grid3<[f16; 4]>> = (0..6)
                .map(|d| {
                    let (c, _) = volume(dims, 10 * k as u64 + d);
                    let mut g = Grid3::<[f16; 4]>::new(dims);
                    for (o, v) in g.data.iter_mut().zip(&c.data) {
                        *o = <[f16; 4]>::store(*v);
                    }
                    g
                })
                .collect();
            let bricked: Vec<Bricked<[f16; 4]>> = dense.iter().map(Bricked::from_dense).collect();
            let dr: [&Grid3<[f16; 4]>; 6] = std::array::from_fn(|d| &dense[d]);
            let br: [&Bricked<[f16; 4]>; 6] = std::array::from_fn(|d| &bricked[d]);
            for f in fns {
                let f: CombineFn = f.parse().unwrap();
                assert!(
                    combine_level_bricks(&f, br) == combine_level(&f, dr),
                    "{f} at {dims:?}"
                );
            }
        }
    }
}
