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

use super::slices::DirSlices;
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
    let a = view.axis();
    // Per axis, the children of every parent as offsets into `src.data`; front to back
    // along the view axis: the camera on the + side sees high indices first.
    let strides = [1, dims[0], dims[0] * dims[1]];
    let axis_taps: [FlatTaps; 3] = std::array::from_fn(|ax| {
        FlatTaps::new(&taps(dims[ax]), strides[ax], ax == a && view.positive())
    });
    let ratio = |ax: usize| dims[ax] as f64 / nd[ax] as f64;
    let across: Vec<usize> = (0..3).filter(|&x| x != a).collect();
    let norm = 1.0 / (ratio(across[0]) * ratio(across[1]));
    // Rows along x (index y + dims[1]·z) that hold anything: empty space is skipped.
    let occupied: Vec<bool> = src
        .data
        .par_chunks(dims[0])
        .map(|row| row.iter().any(|v| v.load() != [0.0; 4]))
        .collect();
    let mut out = Grid3::<T>::new(nd);
    let slice_len = nd[0] * nd[1];
    let (data, alphas) = (&src.data, &alpha_src.data);
    out.data
        .par_chunks_mut(slice_len)
        .enumerate()
        .for_each(|(z, slice)| {
            for y in 0..nd[1] {
                // A child row's y and z offsets add up to its first voxel's offset.
                let (ty, tz) = (axis_taps[1].of(y), axis_taps[2].of(z));
                let any = ty
                    .iter()
                    .any(|&(oy, _)| tz.iter().any(|&(oz, _)| occupied[(oy + oz) / dims[0]]));
                if !any {
                    continue;
                }
                for x in 0..nd[0] {
                    let p = [x, y, z];
                    let mut acc = [0.0f64; 4];
                    let tu = axis_taps[across[0]].of(p[across[0]]);
                    let tv = axis_taps[across[1]].of(p[across[1]]);
                    let tw = axis_taps[a].of(p[a]);
                    for &(ou, wu) in tu {
                        for &(ov, wv) in tv {
                            // Composite the column of children along the view axis, front first.
                            let mut col = [0.0f64; 4];
                            let mut transmit = 1.0f64;
                            for &(ow, f) in tw {
                                let i = ou + ov + ow;
                                let v = data[i].load();
                                let alpha = alphas[i].load()[3] as f64;
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

/// [`Taps`] of one axis flattened for the filter loop: per parent, its children as offsets
/// into the source grid's data (child index × the axis's stride) with their fractions.
struct FlatTaps {
    start: Vec<usize>,
    taps: Vec<(usize, f32)>,
}

impl FlatTaps {
    fn new(t: &Taps, stride: usize, reverse: bool) -> Self {
        let mut start = Vec::with_capacity(t.len() + 1);
        let mut taps = Vec::new();
        start.push(0);
        for list in t {
            let from = taps.len();
            taps.extend(list.iter().map(|&(c, f)| (c * stride, f)));
            if reverse {
                taps[from..].reverse();
            }
            start.push(taps.len());
        }
        FlatTaps { start, taps }
    }
    #[inline]
    fn of(&self, parent: usize) -> &[(usize, f32)] {
        &self.taps[self.start[parent]..self.start[parent + 1]]
    }
}

/// One MIP step of a premultiplied RGBA direction volume (see the module docs).
pub fn downsample<T: Texel>(src: &Grid3<T>, view: Dir) -> Grid3<T> {
    downsample_with(src, src, view)
}

/// For each of `d` children, the parents that cover it and the fraction inside each
/// (the inverse of [`taps`]).
fn inverse_taps(t: &Taps, d: usize) -> Vec<Vec<(usize, f32)>> {
    let mut inv = vec![Vec::new(); d];
    for (p, list) in t.iter().enumerate() {
        for &(c, f) in list {
            inv[c].push((p, f));
        }
    }
    inv
}

/// Level 1 of a direction straight from its sparse level 0 (the same filter as
/// [`downsample_with`]: composite the children along the view axis front to back, average
/// across), colour and — when present — weighted normals (occluded by the colour's
/// alpha). Only the non-empty level-0 voxels are read; the level-0 grid is never dense.
pub(crate) fn downsample_sparse<T: Texel>(s: &DirSlices) -> (Grid3<T>, Option<Grid3<[f16; 4]>>) {
    let dims = s.dims;
    let view = s.dir;
    let (a, [ua, va]) = (view.axis(), view.image_axes());
    let nd = dims.map(|d| (d >> 1).max(1));
    let inv_u = inverse_taps(&taps(dims[ua]), dims[ua]);
    let tj = taps(dims[va]);
    let inv_s = inverse_taps(&taps(dims[a]), dims[a]);
    let ratio = |ax: usize| dims[ax] as f64 / nd[ax] as f64;
    let norm = (1.0 / (ratio(ua) * ratio(va))) as f32;
    let (wu, ws) = (nd[ua], nd[a]);
    let normals = s.nrm.as_ref();
    let mut out = Grid3::<T>::new(nd);
    let mut out_n = normals.map(|_| Grid3::<[f16; 4]>::new(nd));
    let (out_w, out_nw) = (
        Disjoint::new(&mut out.data),
        out_n.as_mut().map(|g| Disjoint::new(&mut g.data)),
    );
    // Per thread: one parent row's plane `[u' · ws + s']` (colour, normals) and one child
    // column composited per parent slice; every buffer is left zeroed after use.
    struct Bufs {
        plane: Vec<[f32; 4]>,
        plane_n: Vec<[f32; 4]>,
        col: Vec<[f32; 4]>,
        col_n: Vec<[f32; 3]>,
        transmit: Vec<f32>,
        touched: Vec<usize>,
    }
    let init = || Bufs {
        plane: vec![[0.0; 4]; wu * ws],
        plane_n: vec![[0.0; 4]; if normals.is_some() { wu * ws } else { 0 }],
        col: vec![[0.0; 4]; ws],
        col_n: vec![[0.0; 3]; ws],
        transmit: vec![1.0; ws],
        touched: Vec::new(),
    };
    (0..nd[va]).into_par_iter().for_each_init(init, |b, jp| {
        let Bufs {
            plane,
            plane_n,
            col,
            col_n,
            transmit,
            touched,
        } = b;
        let mut any = false;
        for &(cj, wj) in &tj[jp] {
            let (row, first) = s.row(cj);
            let mut g = 0;
            while g < row.len() {
                any = true;
                let u = row[g].u;
                let mut end = g + 1;
                while end < row.len() && row[end].u == u {
                    end += 1;
                }
                // Front to back: the camera on the + side sees high slices first.
                let mut visit = |i: usize| {
                    let v = &row[i];
                    let alpha = v.rgba[3];
                    for &(sp, f) in &inv_s[v.s as usize] {
                        if transmit[sp] == 1.0 && !touched.contains(&sp) {
                            touched.push(sp);
                        }
                        let sc = partial_scale(alpha as f64, f as f64) as f32;
                        let w = transmit[sp] * sc;
                        for (o, x) in col[sp].iter_mut().zip(v.rgba) {
                            *o += w * x;
                        }
                        if let Some(n) = normals {
                            for (o, x) in col_n[sp].iter_mut().zip(n[first + i]) {
                                *o += w * x;
                            }
                        }
                        transmit[sp] *= 1.0 - sc * alpha;
                    }
                };
                if view.positive() {
                    (g..end).rev().for_each(&mut visit);
                } else {
                    (g..end).for_each(&mut visit);
                }
                for &sp in touched.iter() {
                    for &(up, fu) in &inv_u[u as usize] {
                        let w = wj * fu;
                        for (o, x) in plane[up * ws + sp].iter_mut().zip(col[sp]) {
                            *o += w * x;
                        }
                        if normals.is_some() {
                            for (o, x) in plane_n[up * ws + sp].iter_mut().zip(col_n[sp]) {
                                *o += w * x;
                            }
                        }
                    }
                    col[sp] = [0.0; 4];
                    col_n[sp] = [0.0; 3];
                    transmit[sp] = 1.0;
                }
                touched.clear();
                g = end;
            }
        }
        if !any {
            return;
        }
        for up in 0..wu {
            for sp in 0..ws {
                let v = std::mem::take(&mut plane[up * ws + sp]);
                let n = plane_n.get_mut(up * ws + sp).map(std::mem::take);
                if v == [0.0; 4] && n.is_none_or(|n| n == [0.0; 4]) {
                    continue;
                }
                let mut p = [0usize; 3];
                p[a] = sp;
                p[ua] = up;
                p[va] = jp;
                let i = p[0] + nd[0] * (p[1] + nd[1] * p[2]);
                // SAFETY: parent row `jp` writes only the voxels with `p[va] == jp`.
                unsafe { out_w.write(i, T::store(v.map(|x| x * norm))) };
                if let (Some(g), Some(n)) = (&out_nw, n) {
                    unsafe { g.write(i, <[f16; 4]>::store(n.map(|x| x * norm))) };
                }
            }
        }
    });
    (out, out_n)
}

/// A slice that parallel tasks write at indices no two tasks share.
pub(crate) struct Disjoint<T> {
    ptr: *mut T,
    len: usize,
}

// SAFETY: writers promise disjoint indices (see `write`).
unsafe impl<T: Send> Sync for Disjoint<T> {}
unsafe impl<T: Send> Send for Disjoint<T> {}

impl<T> Disjoint<T> {
    pub(crate) fn new(data: &mut [T]) -> Self {
        Disjoint {
            ptr: data.as_mut_ptr(),
            len: data.len(),
        }
    }
    /// # Safety
    /// No other task may write or read index `i` at the same time, and the slice given
    /// to [`Disjoint::new`] must outlive every write.
    #[inline]
    pub(crate) unsafe fn write(&self, i: usize, v: T) {
        assert!(i < self.len);
        unsafe { self.ptr.add(i).write(v) };
    }
}
