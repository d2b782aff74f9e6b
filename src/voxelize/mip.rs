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

use half::f16;
use rayon::prelude::*;

use super::brick_grid::{local, Bricked, Layout, B, B3, EMPTY};
use super::grid3::{Disjoint, Grid3, Texel};
use super::slices::DirSlices;
use super::Dir;

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
pub(crate) fn downsample_sparse<T: Texel>(
    s: &DirSlices,
) -> (Bricked<T>, Option<Bricked<[f16; 4]>>) {
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
    // The parent bricks some non-empty child reaches (colour and normals alike: a child
    // with a normal has a non-zero colour); only they are allocated.
    // Per child coordinate, the bricks of its parents.
    let bricks_of = |inv: &[Vec<(usize, f32)>]| -> Vec<Vec<usize>> {
        inv.iter()
            .map(|l| {
                let mut b: Vec<usize> = l.iter().map(|&(p, _)| p / B).collect();
                b.dedup();
                b
            })
            .collect()
    };
    let (bj, bu, bs) = (
        bricks_of(&inverse_taps(&tj, dims[va])),
        bricks_of(&inv_u),
        bricks_of(&inv_s),
    );
    let nb = nd.map(|d| d.div_ceil(B));
    let nbricks: usize = nb.iter().product();
    let occupied = (0..dims[va])
        .into_par_iter()
        .fold(
            || vec![false; nbricks],
            |mut f, cj| {
                let (row, _) = s.row(cj);
                // Parents of one child are consecutive, so a child's parent bricks are a run
                // (first, last); neighbours in a column with the same run mark the same bricks.
                let run = |l: &[usize]| (l[0], l[l.len() - 1]);
                let mut last = (usize::MAX, (0, 0));
                for v in row {
                    let key = (v.u as usize, run(&bs[v.s as usize]));
                    if key == last {
                        continue;
                    }
                    last = key;
                    for &jb in &bj[cj] {
                        for &ub in &bu[v.u as usize] {
                            for &sb in &bs[v.s as usize] {
                                let mut bc = [0usize; 3];
                                bc[a] = sb;
                                bc[ua] = ub;
                                bc[va] = jb;
                                f[bc[0] + nb[0] * (bc[1] + nb[1] * bc[2])] = true;
                            }
                        }
                    }
                }
                f
            },
        )
        .reduce(
            || vec![false; nbricks],
            |mut x, y| {
                x.iter_mut().zip(y).for_each(|(x, y)| *x |= y);
                x
            },
        );
    let layout = Layout::from_flags(nd, &occupied);
    let mut out = Bricked::<T>::zeroed(layout.clone());
    let mut out_n = normals.map(|_| Bricked::<[f16; 4]>::zeroed(layout.clone()));
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
                let i = layout
                    .offset(p)
                    .expect("a reached parent's brick is allocated");
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

/// One MIP step of a brick-sparse direction volume (occluded by `alpha_src`'s alpha, or by
/// its own with `None`): the same filter, in the same order, as [`downsample_with`] on the
/// dense grid (so the same values), computed only for the
/// parent bricks whose footprint meets an allocated child brick of `src`; or, when given,
/// exactly the bricks of `layout` (the colour's layout for the normals, a superset of
/// theirs: a normal is non-zero only where the colour is).
pub(crate) fn downsample_bricks<T: Texel, A: Texel>(
    src: &Bricked<T>,
    alpha_src: Option<&Bricked<A>>,
    view: Dir,
    layout: Option<&Layout>,
) -> Bricked<T> {
    let dims = src.dims();
    let nd = dims.map(|d| (d >> 1).max(1));
    let a = view.axis();
    let axis_taps: [Taps; 3] = std::array::from_fn(|ax| {
        let mut t = taps(dims[ax]);
        if ax == a && view.positive() {
            // Front to back: the camera on the + side sees high indices first.
            t.iter_mut().for_each(|l| l.reverse());
        }
        t
    });
    let ratio = |ax: usize| dims[ax] as f64 / nd[ax] as f64;
    let across: Vec<usize> = (0..3).filter(|&x| x != a).collect();
    let norm = 1.0 / (ratio(across[0]) * ratio(across[1]));
    // The children of parent brick `bo` along `ax`: [lo, hi).
    let span = |ax: usize, bo: usize| -> (usize, usize) {
        let (p0, p1) = (bo * B, ((bo + 1) * B).min(nd[ax]) - 1);
        let c = |p: usize| {
            let l = &axis_taps[ax][p];
            let (x, y) = (l[0].0, l[l.len() - 1].0);
            (x.min(y), x.max(y))
        };
        (c(p0).0, c(p1).1 + 1)
    };
    let sl = &src.layout;
    let made;
    let layout = match layout {
        Some(l) => l,
        None => {
            let nb = nd.map(|d| d.div_ceil(B));
            let flags: Vec<bool> = (0..nb.iter().product::<usize>())
                .into_par_iter()
                .map(|b| {
                    let bc = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])];
                    let r = [0, 1, 2].map(|ax| span(ax, bc[ax]));
                    (r[2].0 / B..=(r[2].1 - 1) / B).any(|z| {
                        (r[1].0 / B..=(r[1].1 - 1) / B).any(|y| {
                            (r[0].0 / B..=(r[0].1 - 1) / B)
                                .any(|x| sl.slot[sl.brick_of([x, y, z])] != EMPTY)
                        })
                    })
                })
                .collect();
            made = Layout::from_flags(nd, &flags);
            &made
        }
    };
    // One parent: the children composited along the view axis front to back, averaged
    // across (the arithmetic and order of `downsample_with`). `sv`/`sa`: the gathered
    // footprint from `lo`, with strides `st`; `sa` empty: the alpha is the value's own.
    let parent = |p: [usize; 3], sv: &[T], sa: &[A], lo: [usize; 3], st: [usize; 3]| -> T {
        let mut acc = [0.0f64; 4];
        let tu = &axis_taps[across[0]][p[across[0]]];
        let tv = &axis_taps[across[1]][p[across[1]]];
        let tw = &axis_taps[a][p[a]];
        for &(cu, wu) in tu {
            let ou = (cu - lo[across[0]]) * st[across[0]];
            for &(cv, wv) in tv {
                let ov = (cv - lo[across[1]]) * st[across[1]];
                // Composite the column of children along the view axis, front first.
                let mut col = [0.0f64; 4];
                let mut transmit = 1.0f64;
                for &(cw, f) in tw {
                    let i = ou + ov + (cw - lo[a]) * st[a];
                    let v = sv[i].load();
                    let alpha = if sa.is_empty() { v[3] } else { sa[i].load()[3] } as f64;
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
        T::store(acc.map(|v| (v * norm) as f32))
    };
    let mut out = Bricked::<T>::zeroed(layout.clone());
    out.data
        .par_chunks_mut(B3)
        .zip(&layout.bricks)
        .for_each_init(
            || (Vec::<T>::new(), Vec::<A>::new(), Vec::<bool>::new()),
            |(sv, sa, rows), (brick, &b)| {
                let bc = layout.coords(b as usize);
                let r = [0, 1, 2].map(|ax| span(ax, bc[ax]));
                let lo = r.map(|r| r.0);
                let ext = r.map(|r| r.1 - r.0);
                gather(src, lo, ext, sv);
                match alpha_src {
                    Some(g) => gather(g, lo, ext, sa),
                    None => sa.clear(),
                }
                let st = [1, ext[0], ext[0] * ext[1]];
                // Rows along x of the footprint that hold anything: as in the dense step,
                // parents whose child rows are all empty stay zero.
                rows.clear();
                rows.extend(
                    sv.chunks_exact(ext[0])
                        .map(|row| row.iter().any(|v| v.load() != [0.0; 4])),
                );
                let hi = [0, 1, 2].map(|ax| ((bc[ax] + 1) * B).min(nd[ax]));
                for z in bc[2] * B..hi[2] {
                    for y in bc[1] * B..hi[1] {
                        let (ty, tz) = (&axis_taps[1][y], &axis_taps[2][z]);
                        let any = ty.iter().any(|&(cy, _)| {
                            tz.iter()
                                .any(|&(cz, _)| rows[(cy - lo[1]) + ext[1] * (cz - lo[2])])
                        });
                        if !any {
                            continue;
                        }
                        for x in bc[0] * B..hi[0] {
                            let p = [x, y, z];
                            brick[local(p)] = parent(p, sv, sa, lo, st);
                        }
                    }
                }
            },
        );
    out
}

/// The voxels `[lo, lo + ext)` of `g` into `out` (x fastest; zeros where no brick is).
fn gather<T: Texel>(g: &Bricked<T>, lo: [usize; 3], ext: [usize; 3], out: &mut Vec<T>) {
    out.clear();
    out.resize(ext.iter().product(), T::default());
    let l = &g.layout;
    let hi = [0, 1, 2].map(|ax| lo[ax] + ext[ax]);
    for bz in lo[2] / B..=(hi[2] - 1) / B {
        for by in lo[1] / B..=(hi[1] - 1) / B {
            for bx in lo[0] / B..=(hi[0] - 1) / B {
                let s = l.slot[l.brick_of([bx, by, bz])];
                if s == EMPTY {
                    continue;
                }
                let brick = &g.data[s as usize * B3..(s as usize + 1) * B3];
                let z0 = lo[2].max(bz * B);
                let z1 = hi[2].min(bz * B + B);
                let y0 = lo[1].max(by * B);
                let y1 = hi[1].min(by * B + B);
                let x0 = lo[0].max(bx * B);
                let x1 = hi[0].min(bx * B + B);
                for z in z0..z1 {
                    for y in y0..y1 {
                        let from = local([x0, y, z]);
                        let to = (x0 - lo[0]) + ext[0] * ((y - lo[1]) + ext[1] * (z - lo[2]));
                        out[to..to + (x1 - x0)].copy_from_slice(&brick[from..from + (x1 - x0)]);
                    }
                }
            }
        }
    }
}
