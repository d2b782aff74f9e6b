//! Six-direction slice stacks (VB paper §3.2): what an orthographic camera looking along
//! one axis sees between the near and far planes of each slice.
//!
//! Instead of rendering every slice with its own clip planes, each triangle is rasterized
//! once per direction and its fragments are binned into slices by depth, which gives the
//! same images in one pass.
//!
//! # Conventions
//! - [`Dir::PosX`] is the camera on the **+X side looking towards −X** (it sees faces whose
//!   normal has `n.x > 0`), and so on; its front-to-back order is decreasing x.
//! - The image of direction `d` uses the two other axes in increasing order (x,y,z) as
//!   (u, v); pixel `(i, j)` is voxel column `(i, j)` of the grid.
//! - **Supersampling**: each pixel gets `K × K` stratified samples at
//!   `((i + (si + ½)/K), (j + (sj + ½)/K))`. Coverage is exact with integer edge functions
//!   on vertices snapped to `1/(32 K)` of a voxel and a consistent tie rule on shared
//!   edges (a sample on an edge shared by two triangles belongs to exactly one of them).
//! - **Slice binning**: a fragment at depth `t` (in voxels from the grid's min face along
//!   the view axis) belongs to slice `k = floor(t)`, i.e. voxel k spans `[k, k + 1)` ×
//!   voxel size, whichever side the camera is on; `t = dims` (the far face of the grid)
//!   belongs to the last slice; fragments outside `[0, dims]` are clipped.
//! - Within one voxel and sample, fragments are composited front to back as seen from
//!   the direction (ties in depth: lower triangle index first); the voxel is the mean of
//!   its `K²` samples, so thin geometry gets fractional alpha.
//! - **Faces**: single-sided triangles are seen only from the directions their front
//!   (counter-clockwise) face faces; double-sided ones from both, their normal flipped
//!   towards the camera when seen from the back. Edge-on triangles are not seen.
//! - **Normals** (optional): per voxel, `Σ` over samples and fragments of
//!   `visible weight × unit shading normal` / `K²` — the alpha-weighted normal sum, which
//!   filters like a premultiplied colour (see [`super::toksvig`]).

use glam::{Vec2, Vec3, Vec4};
use half::f16;
use rayon::prelude::*;

use super::grid::GridSpec;
use super::mip::{Grid3, Texel};
use super::shade::Shader;
use super::Dir;
use crate::scene::Scene;

/// Sub-sample precision: vertices snap to 1/(2·K·SUB) of a voxel.
const SUB: i64 = 16;
/// Largest projected coordinate kept, in voxels (keeps edge functions in i64).
const MAX_COORD: f64 = (1u64 << 20) as f64;
/// Largest supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 8;

/// One direction's slices at level 0.
pub(crate) struct DirSlices<T> {
    pub rgba: Grid3<T>,
    /// (Σ weight·normal, 0) per voxel.
    pub nrm: Option<Grid3<[f16; 4]>>,
    pub fragments: u64,
}

struct TriSetup {
    tri: u32,
    /// Fixed-point (u, v) of the vertices, counter-clockwise.
    p: [[i64; 2]; 3],
    /// Depth of each vertex in voxels.
    t: [f64; 3],
    /// Original vertex index of each slot.
    perm: [usize; 3],
    area: i64,
    /// 1 or 0 subtracted from each edge function (tie rule).
    bias: [i64; 3],
    back: bool,
    rows: [usize; 2],
    cols: [usize; 2],
}

/// A row's non-empty voxels `(u, slice, premultiplied rgba, weighted normal)` and its fragment count.
type RowOut = (Vec<(u32, u32, Vec4, Vec3)>, u64);

pub(crate) struct Frag {
    /// `slice << 96 | sample << 88 | depth (front first) << 32 | triangle`: the sort key.
    key: u128,
    rgba: Vec4,
    n: Vec3,
}

/// A u32 whose order is `f32::total_cmp`'s (ascending), or the reverse when `descending`.
#[inline]
fn depth_key(d: f32, descending: bool) -> u32 {
    let b = d.to_bits() as i32;
    let ordered = (b ^ (((b >> 31) as u32) >> 1) as i32) as u32 ^ 0x8000_0000;
    if descending {
        !ordered
    } else {
        ordered
    }
}

#[inline]
fn cross2(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

fn setup(scene: &Scene, grid: &GridSpec, dir: Dir, k: i64, tri_index: usize) -> Option<TriSetup> {
    let tri = &scene.triangles[tri_index];
    let (a, [ua, va]) = (dir.axis(), dir.image_axes());
    let facing = tri.cross()[a] * if dir.positive() { 1.0 } else { -1.0 };
    let double_sided = scene.materials[tri.material as usize].double_sided;
    if !(facing > 0.0 || (double_sided && facing < 0.0)) {
        return None;
    }
    let f = (2 * k * SUB) as f64;
    let mut p = [[0i64; 2]; 3];
    let mut t = [0f64; 3];
    if !tri.v.iter().all(|v| v.position.is_finite()) {
        return None;
    }
    for (i, v) in tri.v.iter().enumerate() {
        let q = v.position;
        let rel = |ax: usize| (q[ax] as f64 - grid.min[ax] as f64) / grid.voxel[ax] as f64;
        let snap = |x: f64| (x.clamp(-MAX_COORD, MAX_COORD) * f).round() as i64;
        p[i] = [snap(rel(ua)), snap(rel(va))];
        t[i] = rel(a);
    }
    if !t.iter().all(|x| x.is_finite()) {
        return None;
    }
    let mut perm = [0, 1, 2];
    let mut area = cross2(p[0], p[1], p[2]);
    if area == 0 {
        return None;
    }
    if area < 0 {
        p.swap(1, 2);
        t.swap(1, 2);
        perm.swap(1, 2);
        area = -area;
    }
    // Edge i is opposite vertex i: from vertex i+1 to vertex i+2.
    let bias = [0, 1, 2].map(|i| {
        let (s, e) = (p[(i + 1) % 3], p[(i + 2) % 3]);
        let (dx, dy) = (e[0] - s[0], e[1] - s[1]);
        i64::from(!(dy > 0 || (dy == 0 && dx < 0)))
    });
    let fk = 2 * k * SUB;
    let range = |ax: usize, n: u32| {
        let lo = p.iter().map(|q| q[ax]).min().unwrap().div_euclid(fk).max(0);
        let hi = p
            .iter()
            .map(|q| q[ax])
            .max()
            .unwrap()
            .div_euclid(fk)
            .min(n as i64 - 1);
        (lo <= hi).then_some([lo as usize, hi as usize])
    };
    let cols = range(0, grid.dims[ua])?;
    let rows = range(1, grid.dims[va])?;
    if t.iter().all(|&x| x < 0.0) || t.iter().all(|&x| x > grid.dims[a] as f64) {
        return None;
    }
    Some(TriSetup {
        tri: tri_index as u32,
        p,
        t,
        perm,
        area,
        bias,
        back: facing < 0.0,
        rows,
        cols,
    })
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = const { std::cell::RefCell::new(Scratch { cols: Vec::new() }) };
}

/// Per-thread buffers of [`raster_row`]: the fragments of each pixel column of the row.
pub(crate) struct Scratch {
    cols: Vec<Vec<Frag>>,
}

impl Scratch {
    fn new(width: usize) -> Self {
        Scratch {
            cols: (0..width).map(|_| Vec::new()).collect(),
        }
    }
}

/// Rasterizes one pixel row `j` of direction `dir`; returns the non-empty voxels of the row
/// as `(u, slice, premultiplied rgba, weighted normal)` and the fragment count.
///
/// Fragments are binned per pixel column as they are generated and each column is sorted
/// on its own (small, cache-resident sorts); the order within a column is the total order
/// (slice, sample, depth front to back, triangle), so the result is the same as one sort
/// of the whole row.
#[allow(clippy::too_many_arguments)]
fn raster_row(
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    dir: Dir,
    k: i64,
    normals: bool,
    tris: &[&TriSetup],
    j: usize,
    scratch: &mut Scratch,
) -> RowOut {
    let fk = 2 * k * SUB;
    let depth_n = grid.dims[dir.axis()];
    let cols = &mut scratch.cols;
    let mut count = 0u64;
    let front_high = dir.positive();
    for s in tris {
        let tri = &scene.triangles[s.tri as usize];
        let m = shader.material(tri.material);
        let geo_n = tri.cross().normalize_or_zero() * if s.back { -1.0 } else { 1.0 };
        let inv_area = 1.0 / s.area as f64;
        for sj in 0..k {
            let sy = j as i64 * fk + (2 * sj + 1) * SUB;
            for i in s.cols[0]..=s.cols[1] {
                for si in 0..k {
                    let sp = [i as i64 * fk + (2 * si + 1) * SUB, sy];
                    let e0 = cross2(s.p[1], s.p[2], sp) - s.bias[0];
                    let e1 = cross2(s.p[2], s.p[0], sp) - s.bias[1];
                    let e2 = cross2(s.p[0], s.p[1], sp) - s.bias[2];
                    if e0 < 0 || e1 < 0 || e2 < 0 {
                        continue;
                    }
                    // Exact barycentrics (undo the bias).
                    let b1 = (e1 + s.bias[1]) as f64 * inv_area;
                    let b2 = (e2 + s.bias[2]) as f64 * inv_area;
                    let b0 = 1.0 - b1 - b2;
                    // Written so a constant-depth triangle gives exactly its depth.
                    let t = s.t[0] + b1 * (s.t[1] - s.t[0]) + b2 * (s.t[2] - s.t[0]);
                    if !(0.0..=depth_n as f64).contains(&t) {
                        continue;
                    }
                    // t ≥ 0 here, so truncation is floor.
                    let slice = (t as u32).min(depth_n - 1);
                    let bw = [b0 as f32, b1 as f32, b2 as f32];
                    let vx = |slot: usize| &tri.v[s.perm[slot]];
                    let mut uv = Vec2::ZERO;
                    let mut col = Vec4::ZERO;
                    for (slot, w) in bw.iter().enumerate() {
                        uv += vx(slot).uv * *w;
                        col += vx(slot).color * *w;
                    }
                    let Some(rgba) = shader.shade(m, uv, col) else {
                        continue;
                    };
                    let n = if normals {
                        let mut n = Vec3::ZERO;
                        for (slot, w) in bw.iter().enumerate() {
                            n += vx(slot).normal * *w;
                        }
                        let n = n.normalize_or_zero();
                        let n = if n == Vec3::ZERO {
                            geo_n
                        } else if s.back {
                            -n
                        } else {
                            n
                        };
                        if n.is_finite() {
                            n
                        } else {
                            Vec3::ZERO
                        }
                    } else {
                        Vec3::ZERO
                    };
                    count += 1;
                    let sub = (sj * k + si) as u128;
                    let depth = depth_key(t as f32, front_high) as u128;
                    cols[i].push(Frag {
                        key: (slice as u128) << 96 | sub << 88 | depth << 32 | s.tri as u128,
                        rgba,
                        n,
                    });
                }
            }
        }
    }
    let inv_samples = 1.0 / (k * k) as f64;
    let mut out = Vec::new();
    for (u, frags) in cols.iter_mut().enumerate() {
        if frags.is_empty() {
            continue;
        }
        let u = u as u32;
        frags.sort_unstable_by_key(|f| f.key);
        let mut g = 0;
        while g < frags.len() {
            let slice = (frags[g].key >> 96) as u32;
            let mut voxel = [0.0f64; 7];
            while g < frags.len() && (frags[g].key >> 96) as u32 == slice {
                let sub = frags[g].key >> 88;
                let mut acc = [0.0f64; 7];
                while g < frags.len() && frags[g].key >> 88 == sub {
                    let f = &frags[g];
                    let transmit = 1.0 - acc[3];
                    if transmit > 0.0 {
                        let w = transmit * f.rgba.w as f64;
                        let src = f.rgba.to_array().map(|c| transmit * c as f64);
                        let nrm = f.n.to_array().map(|c| w * c as f64);
                        for (a, s) in acc.iter_mut().zip(src.iter().chain(&nrm)) {
                            *a += s;
                        }
                    }
                    g += 1;
                }
                for c in 0..7 {
                    voxel[c] += acc[c];
                }
            }
            let v = voxel.map(|x| (x * inv_samples) as f32);
            out.push((
                u,
                slice,
                Vec4::new(v[0], v[1], v[2], v[3]),
                Vec3::new(v[4], v[5], v[6]),
            ));
        }
        frags.clear();
    }
    (out, count)
}

/// Rasterizes the slice stack of direction `dir` into a level-0 volume.
/// `progress` gets the fraction of rows done.
pub(crate) fn rasterize<T: Texel>(
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    dir: Dir,
    k: u32,
    normals: bool,
    progress: &mut dyn FnMut(f32),
) -> DirSlices<T> {
    let k = k.clamp(1, MAX_SUPERSAMPLE) as i64;
    let (a, [ua, va]) = (dir.axis(), dir.image_axes());
    let dims = grid.dims.map(|d| d as usize);
    let setups: Vec<TriSetup> = (0..scene.triangles.len())
        .into_par_iter()
        .filter_map(|i| setup(scene, grid, dir, k, i))
        .collect();
    // Bin triangles into pixel rows, in triangle order.
    let nrows = dims[va];
    let mut bins: Vec<Vec<&TriSetup>> = vec![Vec::new(); nrows];
    for s in &setups {
        for bin in &mut bins[s.rows[0]..=s.rows[1]] {
            bin.push(s);
        }
    }
    let mut rgba = Grid3::<T>::new(dims);
    let mut nrm = normals.then(|| Grid3::<[f16; 4]>::new(dims));
    let mut fragments = 0u64;
    const CHUNK: usize = 16;
    for chunk_start in (0..nrows).step_by(CHUNK) {
        let rows: Vec<RowOut> = (chunk_start..(chunk_start + CHUNK).min(nrows))
            .into_par_iter()
            .map(|j| {
                SCRATCH.with_borrow_mut(|scratch| {
                    if scratch.cols.len() < dims[ua] {
                        *scratch = Scratch::new(dims[ua]);
                    }
                    raster_row(scene, shader, grid, dir, k, normals, &bins[j], j, scratch)
                })
            })
            .collect();
        for (r, (voxels, count)) in rows.into_iter().enumerate() {
            let j = chunk_start + r;
            fragments += count;
            for (u, slice, c, n) in voxels {
                let mut p = [0usize; 3];
                p[a] = slice as usize;
                p[ua] = u as usize;
                p[va] = j;
                let idx = rgba.index(p);
                rgba.data[idx] = T::store(c.to_array());
                if let Some(g) = nrm.as_mut() {
                    g.data[idx] = <[f16; 4]>::store([n.x, n.y, n.z, 0.0]);
                }
            }
        }
        progress(((chunk_start + CHUNK).min(nrows)) as f32 / nrows.max(1) as f32);
    }
    DirSlices {
        rgba,
        nrm,
        fragments,
    }
}
