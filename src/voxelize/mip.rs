//! Per-direction MIP pyramids (VB paper §3.2, Figure 3; after Decaudin & Neyret 2004).
//!
//! Each of the six direction volumes is filtered on its own, *before* the six are combined:
//! along that direction's view axis the children are **composited** front-over-back as
//! seen from that direction (so an opaque front layer hides what lies behind it), across
//! the view axis they are **averaged**. Composite first (per child column), then average
//! the columns: a parent voxel holds the mean of what the rays through its footprint see.
//!
//! Colours are premultiplied: `over(F, B) = F + (1 − F.a) · B` on all four channels.
//!
//! # Odd and non-power-of-two sizes
//! Level `i + 1` has `max(1, d >> 1)` voxels per axis, like every GPU 3D texture, and the
//! renderer addresses every level with the same normalised uvw. So parent `j` covers the
//! same part of the box as children `[j·r, (j+1)·r)` with `r = d / max(1, d >> 1)`: exactly
//! 2 for even `d`, more than 2 for odd `d` (5 → 2: r = 2.5, children 0, 1 and half of 2).
//! The filter uses exactly those footprints (computed with integers, so exact):
//! - across the view axis, a child is weighted by the fraction of it inside the footprint
//!   and the sum is divided by `r` (a box filter; total coverage is preserved);
//! - along the view axis, a fraction `f` of a child of opacity `a` is treated as a slab of
//!   homogeneous material `f` times as thick: opacity `1 − (1 − a)^f`, colour scaled by the
//!   same factor over `a`. The parent composites its (partial) children, so the opacity of
//!   a whole column is preserved at every level whatever the size.
//!
//! An axis of size 1 stays 1 (`r = 1`: a copy along that axis).

use glam::Vec4;
use half::f16;
use rayon::prelude::*;

use super::Dir;

/// Premultiplied `front over back`.
#[inline]
pub fn over(front: Vec4, back: Vec4) -> Vec4 {
    front + (1.0 - front.w) * back
}

/// Storage of one RGBA (or normal) voxel; the arithmetic is always f32/f64.
pub trait Texel: Copy + Send + Sync + Default + 'static {
    fn load(self) -> [f32; 4];
    fn store(v: [f32; 4]) -> Self;
}

impl Texel for [f32; 4] {
    #[inline]
    fn load(self) -> [f32; 4] {
        self
    }
    #[inline]
    fn store(v: [f32; 4]) -> Self {
        v
    }
}

impl Texel for [f16; 4] {
    #[inline]
    fn load(self) -> [f32; 4] {
        self.map(f16::to_f32)
    }
    #[inline]
    fn store(v: [f32; 4]) -> Self {
        v.map(f16::from_f32)
    }
}

/// A dense 3D array, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid3<T> {
    pub dims: [usize; 3],
    pub data: Vec<T>,
}

impl<T: Texel> Grid3<T> {
    pub fn new(dims: [usize; 3]) -> Self {
        Grid3 {
            dims,
            data: vec![T::default(); dims[0] * dims[1] * dims[2]],
        }
    }
    #[inline]
    pub fn index(&self, p: [usize; 3]) -> usize {
        p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])
    }
    #[inline]
    pub fn get(&self, p: [usize; 3]) -> [f32; 4] {
        self.data[self.index(p)].load()
    }
}

/// The children a parent covers along one axis: `(child index, fraction of it inside)`.
pub type Taps = Vec<Vec<(usize, f32)>>;

/// Footprints of the `max(1, d >> 1)` parents over `d` children (see the module docs).
pub fn taps(d: usize) -> Taps {
    let p = (d >> 1).max(1);
    // In units of 1/p child: parent j covers [j·d, (j+1)·d), child c covers [c·p, (c+1)·p).
    (0..p)
        .map(|j| {
            let (lo, hi) = (j * d, (j + 1) * d);
            (lo / p..hi.div_ceil(p))
                .filter_map(|c| {
                    let overlap = hi.min((c + 1) * p).saturating_sub(lo.max(c * p));
                    (overlap > 0).then_some((c, overlap as f32 / p as f32))
                })
                .collect()
        })
        .collect()
}

/// Fraction `f` of a premultiplied voxel `v` along the view axis (Beer–Lambert thickness).
/// `channels` are scaled like the colour (used for the alpha-weighted normals).
#[inline]
pub(crate) fn partial_scale(alpha: f64, f: f64) -> f64 {
    if f >= 1.0 {
        1.0
    } else if alpha <= 1e-9 {
        f
    } else if alpha >= 1.0 {
        1.0 / alpha.max(1.0)
    } else {
        (1.0 - (1.0 - alpha).powf(f)) / alpha
    }
}

/// One MIP step of a direction volume seen from `view`: composite along the view axis,
/// average across it. `alpha_of` reads the opacity that occludes (channel 3 for colour;
/// for normals the colour volume's alpha, see [`super::toksvig`]).
pub(crate) fn downsample_with<T: Texel, A: Texel>(
    src: &Grid3<T>,
    alpha_src: &Grid3<A>,
    view: Dir,
) -> Grid3<T> {
    let dims = src.dims;
    let nd = dims.map(|d| (d >> 1).max(1));
    let mut axis_taps = [taps(dims[0]), taps(dims[1]), taps(dims[2])];
    let a = view.axis();
    // Front-to-back order along the view axis: the camera on the + side sees high indices first.
    if view.positive() {
        axis_taps[a].iter_mut().for_each(|t| t.reverse());
    }
    let ratio = |ax: usize| dims[ax] as f64 / nd[ax] as f64;
    let across: Vec<usize> = (0..3).filter(|&x| x != a).collect();
    let norm = 1.0 / (ratio(across[0]) * ratio(across[1]));
    // Rows along x (index y + dims[1]·z) that hold anything: empty space is skipped.
    let occupied: Vec<bool> = src
        .data
        .par_chunks(dims[0])
        .map(|row| row.iter().any(|v| v.load() != [0.0; 4]))
        .collect();
    let (ty, tz) = (taps(dims[1]), taps(dims[2]));
    let mut out = Grid3::<T>::new(nd);
    let slice_len = nd[0] * nd[1];
    out.data
        .par_chunks_mut(slice_len)
        .enumerate()
        .for_each(|(z, slice)| {
            for y in 0..nd[1] {
                let any = ty[y]
                    .iter()
                    .any(|&(cy, _)| tz[z].iter().any(|&(cz, _)| occupied[cy + dims[1] * cz]));
                if !any {
                    continue;
                }
                for x in 0..nd[0] {
                    let p = [x, y, z];
                    let mut acc = [0.0f64; 4];
                    let tu = &axis_taps[across[0]][p[across[0]]];
                    let tv = &axis_taps[across[1]][p[across[1]]];
                    let tw = &axis_taps[a][p[a]];
                    for &(cu, wu) in tu {
                        for &(cv, wv) in tv {
                            // Composite the column of children along the view axis, front first.
                            let mut col = [0.0f64; 4];
                            let mut transmit = 1.0f64;
                            for &(cw, f) in tw {
                                let mut c = [0usize; 3];
                                c[across[0]] = cu;
                                c[across[1]] = cv;
                                c[a] = cw;
                                let v = src.get(c);
                                let alpha = alpha_src.get(c)[3] as f64;
                                let s = partial_scale(alpha, f as f64);
                                for k in 0..4 {
                                    col[k] += transmit * s * v[k] as f64;
                                }
                                transmit *= 1.0 - s * alpha;
                            }
                            let w = wu as f64 * wv as f64;
                            for k in 0..4 {
                                acc[k] += w * col[k];
                            }
                        }
                    }
                    slice[x + nd[0] * y] = T::store(acc.map(|v| (v * norm) as f32));
                }
            }
        });
    out
}

/// One MIP step of a premultiplied RGBA direction volume (see the module docs).
pub fn downsample<T: Texel>(src: &Grid3<T>, view: Dir) -> Grid3<T> {
    downsample_with(src, src, view)
}
