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
//! - **Supersampling** (MSAA-style): each pixel has `K × K` stratified coverage samples
//!   at `((i + (si + ½)/K), (j + (sj + ½)/K))`. Coverage is exact with integer edge
//!   functions on vertices snapped to `1/(32 K)` of a voxel and a consistent tie rule on
//!   shared edges (a sample on an edge shared by two triangles belongs to exactly one of
//!   them). A triangle's covered samples in one pixel are grouped by slice, and each group
//!   (a *fragment*) is **shaded once**, at the centroid of its samples; for `Mask`
//!   materials the alpha test is done per sample (alpha channel only), so cut-out edges
//!   keep their sub-voxel shape.
//! - **Slice binning**: a sample at depth `t` (in voxels from the grid's min face along
//!   the view axis) belongs to slice `k = floor(t)`, i.e. voxel k spans `[k, k + 1)` ×
//!   voxel size, whichever side the camera is on; `t = dims` (the far face of the grid)
//!   belongs to the last slice; samples outside `[0, dims]` are clipped.
//! - Within one voxel, fragments are composited front to back per sample, ordered by the
//!   depth of their shading point (ties: lower triangle index first); the voxel is the
//!   mean of its `K²` samples, so thin geometry gets fractional alpha.
//! - **Faces**: single-sided triangles are seen only from the directions their front
//!   (counter-clockwise) face faces; double-sided ones from both, their normal flipped
//!   towards the camera when seen from the back. Edge-on triangles are not seen.
//! - **Normals** (optional): per voxel, `Σ` over samples and fragments of
//!   `visible weight × unit shading normal` / `K²` — the alpha-weighted normal sum, which
//!   filters like a premultiplied colour (see [`super::toksvig`]); a fragment's normal is
//!   taken at its shading point.
//! - The result is sparse ([`DirSlices`]): the non-empty voxels of each image row.

use glam::{Vec2, Vec3, Vec4};
use half::f16;
use rayon::prelude::*;

use super::grid::GridSpec;
use super::mip::{Grid3, Texel};
use super::shade::Shader;
use super::Dir;
use crate::scene::{AlphaMode, Scene};

/// Sub-sample precision: vertices snap to 1/(2·K·SUB) of a voxel.
const SUB: i64 = 16;
/// Largest projected coordinate kept, in voxels (keeps edge functions in i64).
const MAX_COORD: f64 = (1u64 << 20) as f64;
/// Largest supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 8;

/// One non-empty level-0 voxel of a direction: pixel column `u` of its image row, slice `s`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vox {
    pub u: u16,
    pub s: u16,
    /// Premultiplied linear RGBA.
    pub rgba: [f32; 4],
}

/// One direction's slices at level 0, sparse: the non-empty voxels of every image row.
pub(crate) struct DirSlices {
    pub dir: Dir,
    /// The grid's level-0 dimensions.
    pub dims: [usize; 3],
    /// Row `j`'s voxels are `vox[rows[j]..rows[j + 1]]`, sorted by `(u, s)`.
    pub vox: Vec<Vox>,
    pub rows: Vec<usize>,
    /// Σ weight·normal per voxel (parallel to `vox`), when normals were asked for.
    pub nrm: Option<Vec<[f32; 3]>>,
    pub fragments: u64,
}

impl DirSlices {
    /// Number of image rows.
    pub fn row_count(&self) -> usize {
        self.rows.len() - 1
    }
    /// Row `j`'s voxels and the index of its first one in `vox`.
    #[inline]
    pub fn row(&self, j: usize) -> (&[Vox], usize) {
        (&self.vox[self.rows[j]..self.rows[j + 1]], self.rows[j])
    }
    /// The grid index (x fastest) of voxel `v` of row `j`.
    #[inline]
    pub fn index(&self, j: usize, v: &Vox) -> usize {
        let (a, [ua, va]) = (self.dir.axis(), self.dir.image_axes());
        let mut p = [0usize; 3];
        p[a] = v.s as usize;
        p[ua] = v.u as usize;
        p[va] = j;
        p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])
    }
    /// The grid indices of all voxels, in `vox` order.
    pub fn indices(&self) -> Vec<usize> {
        (0..self.row_count())
            .into_par_iter()
            .flat_map_iter(|j| {
                let (row, _) = self.row(j);
                row.iter().map(move |v| self.index(j, v))
            })
            .collect()
    }
    /// The colour as a dense grid.
    pub fn to_dense<T: Texel>(&self) -> Grid3<T> {
        let mut g = Grid3::<T>::new(self.dims);
        for (i, v) in self.indices().into_iter().zip(&self.vox) {
            g.data[i] = T::store(v.rgba);
        }
        g
    }
    /// The weighted normals as a dense grid `(Σ w·n, 0)`, when present.
    pub fn dense_normals(&self) -> Option<Grid3<[f16; 4]>> {
        let nrm = self.nrm.as_ref()?;
        let mut g = Grid3::<[f16; 4]>::new(self.dims);
        for (i, n) in self.indices().into_iter().zip(nrm) {
            g.data[i] = <[f16; 4]>::store([n[0], n[1], n[2], 0.0]);
        }
        Some(g)
    }
}

/// Everything the row loop needs of one triangle seen from one direction (the scene's
/// triangle is not read again, except for normals).
struct TriSetup {
    /// Fixed-point (u, v) of the vertices, counter-clockwise.
    p: [[i64; 2]; 3],
    /// Depth of each vertex in voxels.
    t: [f64; 3],
    area: i64,
    /// 1 or 0 subtracted from each edge function (tie rule).
    bias: [i64; 3],
    /// Texture coordinates and vertex colours of the slots.
    uv: [Vec2; 3],
    col: [Vec4; 3],
    tri: u32,
    material: u32,
    /// Original vertex index of each slot.
    perm: [u8; 3],
    back: bool,
    rows: [u32; 2],
    cols: [u32; 2],
}

/// A row's non-empty voxels, their weighted normals (when asked for) and its fragment count.
type RowOut = (Vec<Vox>, Vec<[f32; 3]>, u64);

/// A shaded fragment: one triangle in one voxel, covering the samples of `mask`.
pub(crate) struct Frag {
    /// `slice << 32 | depth (front first)`: with `tri`, the sort key.
    key: u64,
    tri: u32,
    /// Bit `sj·K + si`: the samples it covers (0 once shading discarded it).
    mask: u64,
    /// The interpolated vertex colour until shaded, then premultiplied linear RGBA.
    rgba: Vec4,
    /// Texture coordinates of the shading point.
    uv: Vec2,
    n: Vec3,
    material: u32,
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
    let vx = |slot: usize| &tri.v[perm[slot]];
    Some(TriSetup {
        p,
        t,
        area,
        bias,
        uv: [vx(0).uv, vx(1).uv, vx(2).uv],
        col: [vx(0).color, vx(1).color, vx(2).color],
        tri: tri_index as u32,
        material: tri.material,
        perm: perm.map(|x| x as u8),
        back: facing < 0.0,
        rows: rows.map(|x| x as u32),
        cols: cols.map(|x| x as u32),
    })
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = const { std::cell::RefCell::new(Scratch { cols: Vec::new(), order: Vec::new() }) };
}

/// Per-thread buffers of [`raster_row`]: the fragments of each pixel column of the row.
pub(crate) struct Scratch {
    cols: Vec<Vec<Frag>>,
    /// A column's `(key, triangle, index)`, sorted.
    order: Vec<(u64, u32, u32)>,
}

impl Scratch {
    fn new(width: usize) -> Self {
        Scratch {
            cols: (0..width).map(|_| Vec::new()).collect(),
            order: Vec::new(),
        }
    }
}

/// Rasterizes one pixel row `j` of direction `dir`; returns the non-empty voxels of the row
/// sorted by `(u, slice)`, their weighted normals (when asked for) and the fragment count.
///
/// Per (triangle, pixel) the coverage of the `K × K` samples is one bit mask (exact
/// integer edge functions, stepped incrementally from sample to sample); covered samples
/// are grouped by the slice their depth falls in (one group unless the triangle crosses a
/// slice plane inside the pixel), `Mask` materials drop the samples that fail the alpha
/// test (alpha channel only, per sample), and each group is shaded **once**, at the
/// centroid of its samples (MSAA-style). Fragments are binned per pixel column; within a
/// voxel they are composited front to back per sample (a per-sample transmittance), so
/// the voxel is the mean of its `K²` samples' composites.
#[allow(clippy::too_many_arguments)]
fn raster_row(
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    dir: Dir,
    k: i64,
    normals: bool,
    setups: &[TriSetup],
    tris: &[u32],
    j: usize,
    scratch: &mut Scratch,
) -> RowOut {
    let fk = 2 * k * SUB;
    let kk = (k * k) as usize;
    let full: u64 = if kk == 64 { u64::MAX } else { (1u64 << kk) - 1 };
    let depth_n = grid.dims[dir.axis()];
    let depth_f = depth_n as f64;
    let Scratch { cols, order } = scratch;
    let mut count = 0u64;
    let front_high = dir.positive();
    let km1 = k - 1;
    let mut groups: Vec<(u32, u64)> = Vec::with_capacity(64);
    // Sample (si, sj) of bit b.
    let (bit_si, bit_sj): ([i64; 64], [i64; 64]) = (
        std::array::from_fn(|b| b as i64 % k),
        std::array::from_fn(|b| b as i64 / k),
    );
    for &ti in tris {
        let s = &setups[ti as usize];
        let m = shader.material(s.material);
        let cutoff = match m.alpha_mode {
            AlphaMode::Mask { cutoff } => Some(cutoff),
            _ => None,
        };
        let inv_area = 1.0 / s.area as f64;
        let (uvs, cols_v) = (s.uv, s.col);
        // Edge i runs from vertex i+1 to vertex i+2; its step per sample along u and v.
        let ex: [i64; 3] =
            [0, 1, 2].map(|i| -(s.p[(i + 2) % 3][1] - s.p[(i + 1) % 3][1]) * 2 * SUB);
        let ey: [i64; 3] = [0, 1, 2].map(|i| (s.p[(i + 2) % 3][0] - s.p[(i + 1) % 3][0]) * 2 * SUB);
        let (dt1, dt2) = (s.t[1] - s.t[0], s.t[2] - s.t[0]);
        // Barycentrics (b1, b2) and depth of a point whose biased edge values are e1, e2.
        let bary = |e1: i64, e2: i64| {
            let b1 = (e1 + s.bias[1]) as f64 * inv_area;
            let b2 = (e2 + s.bias[2]) as f64 * inv_area;
            (b1, b2)
        };
        // Written so a constant-depth triangle gives exactly its depth.
        let depth = |b1: f64, b2: f64| s.t[0] + b1 * dt1 + b2 * dt2;
        // Depth step per sample along u and v (exactly 0 for a constant-depth triangle).
        let dtx = (ex[1] as f64 * dt1 + ex[2] as f64 * dt2) * inv_area;
        let dty = (ey[1] as f64 * dt1 + ey[2] as f64 * dt2) * inv_area;
        let sy = j as i64 * fk + SUB;
        for i in s.cols[0] as usize..=s.cols[1] as usize {
            let sp = [i as i64 * fk + SUB, sy];
            let e00 = [
                cross2(s.p[1], s.p[2], sp) - s.bias[0],
                cross2(s.p[2], s.p[0], sp) - s.bias[1],
                cross2(s.p[0], s.p[1], sp) - s.bias[2],
            ];
            // Whole pixel outside one edge, or inside all three?
            let mut all_in = true;
            let mut out = false;
            for q in 0..3 {
                let (lx, hx) = (km1 * ex[q].min(0), km1 * ex[q].max(0));
                let (ly, hy) = (km1 * ey[q].min(0), km1 * ey[q].max(0));
                if e00[q] + hx + hy < 0 {
                    out = true;
                    break;
                }
                all_in &= e00[q] + lx + ly >= 0;
            }
            if out {
                continue;
            }
            let mask = if all_in {
                full
            } else {
                let mut mask = 0u64;
                let mut bit = 0;
                for sj in 0..k {
                    let mut e = [0, 1, 2].map(|q| e00[q] + sj * ey[q]);
                    for _ in 0..k {
                        if (e[0] | e[1] | e[2]) >= 0 {
                            mask |= 1 << bit;
                        }
                        bit += 1;
                        for q in 0..3 {
                            e[q] += ex[q];
                        }
                    }
                }
                mask
            };
            if mask == 0 {
                continue;
            }
            // Edge values of sample `b` (bit index).
            let e_at =
                |b: u32, q: usize| e00[q] + bit_si[b as usize] * ex[q] + bit_sj[b as usize] * ey[q];
            // Depth is linear over the pixel's samples: extremes at the corners.
            let t00 = {
                let (b1, b2) = bary(e00[1], e00[2]);
                depth(b1, b2)
            };
            let tmin = t00 + (km1 as f64) * (dtx.min(0.0) + dty.min(0.0));
            let tmax = t00 + (km1 as f64) * (dtx.max(0.0) + dty.max(0.0));
            let slice_of = |t: f64| (t as u32).min(depth_n - 1);
            // (slice, samples) groups.
            groups.clear();
            if tmin >= 0.0 && tmax <= depth_f && slice_of(tmin) == slice_of(tmax) {
                groups.push((slice_of(tmin), mask));
            } else if tmax >= 0.0 && tmin <= depth_f {
                let mut bits = mask;
                while bits != 0 {
                    let b = bits.trailing_zeros();
                    bits &= bits - 1;
                    let t = t00 + bit_si[b as usize] as f64 * dtx + bit_sj[b as usize] as f64 * dty;
                    if !(0.0..=depth_f).contains(&t) {
                        continue;
                    }
                    // t ≥ 0 here, so truncation is floor.
                    let sl = slice_of(t);
                    match groups.iter_mut().find(|g| g.0 == sl) {
                        Some(g) => g.1 |= 1 << b,
                        None => groups.push((sl, 1 << b)),
                    }
                }
            }
            for &(slice, gmask) in &groups {
                let mut gmask = gmask;
                if let Some(cutoff) = cutoff {
                    let mut bits = gmask;
                    while bits != 0 {
                        let b = bits.trailing_zeros();
                        bits &= bits - 1;
                        let (b1, b2) = bary(e_at(b, 1), e_at(b, 2));
                        let (b1, b2) = (b1 as f32, b2 as f32);
                        let b0 = 1.0 - b1 - b2;
                        let uv = uvs[0] * b0 + uvs[1] * b1 + uvs[2] * b2;
                        let va = cols_v[0].w * b0 + cols_v[1].w * b1 + cols_v[2].w * b2;
                        if !shader.mask_pass(m, cutoff, uv, va) {
                            gmask &= !(1 << b);
                        }
                    }
                    if gmask == 0 {
                        continue;
                    }
                }
                // Shading point: the centroid of the group's samples (inside the triangle).
                let n = gmask.count_ones() as i64;
                let (mut ssi, mut ssj) = (0i64, 0i64);
                if gmask == full {
                    ssi = k * (k * (k - 1) / 2);
                    ssj = ssi;
                } else {
                    let mut bits = gmask;
                    while bits != 0 {
                        let b = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        ssi += bit_si[b];
                        ssj += bit_sj[b];
                    }
                }
                let sum = |q: usize| n * (e00[q] + s.bias[q]) + ssi * ex[q] + ssj * ey[q];
                let inv = inv_area / n as f64;
                let (mut b1, mut b2) = (sum(1) as f64 * inv, sum(2) as f64 * inv);
                let mut t = depth(b1, b2);
                let at = |b1: f64, b2: f64| {
                    let (b1, b2) = (b1 as f32, b2 as f32);
                    let b0 = 1.0 - b1 - b2;
                    (
                        [b0, b1, b2],
                        uvs[0] * b0 + uvs[1] * b1 + uvs[2] * b2,
                        cols_v[0] * b0 + cols_v[1] * b1 + cols_v[2] * b2,
                    )
                };
                let (mut bw, mut uv, mut col) = at(b1, b2);
                if let Some(cutoff) = cutoff {
                    // A cut-out between the samples: shade at the first sample that passed.
                    if !shader.mask_pass(m, cutoff, uv, col.w) {
                        let b = gmask.trailing_zeros();
                        (b1, b2) = bary(e_at(b, 1), e_at(b, 2));
                        t = depth(b1, b2);
                        (bw, uv, col) = at(b1, b2);
                    }
                }
                let nrm = if normals {
                    let tri = &scene.triangles[s.tri as usize];
                    let vx = |slot: usize| &tri.v[s.perm[slot] as usize];
                    let geo_n = tri.cross().normalize_or_zero() * if s.back { -1.0 } else { 1.0 };
                    let mut nv = Vec3::ZERO;
                    for (slot, w) in bw.iter().enumerate() {
                        nv += vx(slot).normal * *w;
                    }
                    let nv = nv.normalize_or_zero();
                    let nv = if nv == Vec3::ZERO {
                        geo_n
                    } else if s.back {
                        -nv
                    } else {
                        nv
                    };
                    if nv.is_finite() {
                        nv
                    } else {
                        Vec3::ZERO
                    }
                } else {
                    Vec3::ZERO
                };
                count += 1;
                let dk = depth_key(t as f32, front_high) as u64;
                cols[i].push(Frag {
                    key: (slice as u64) << 32 | dk,
                    tri: s.tri,
                    mask: gmask,
                    rgba: col,
                    uv,
                    n: nrm,
                    material: s.material,
                });
            }
        }
    }
    // Shading, batched per row: the texture fetches of different fragments are
    // independent, so their cache misses overlap.
    for f in cols.iter_mut().flatten() {
        match shader.shade_tested(shader.material(f.material), f.uv, f.rgba) {
            Some(c) => f.rgba = c,
            None => {
                f.mask = 0;
                count -= 1;
            }
        }
    }
    let inv_samples = 1.0 / kk as f32;
    let mut out = Vec::new();
    let mut out_n = Vec::new();
    let mut transmit = [1.0f32; 64];
    for (u, frags) in cols.iter_mut().enumerate() {
        if frags.is_empty() {
            continue;
        }
        // Sorted by (slice, depth front to back, triangle): small keys, not the fragments.
        order.clear();
        order.extend(
            frags
                .iter()
                .enumerate()
                .filter(|(_, f)| f.mask != 0)
                .map(|(i, f)| (f.key, f.tri, i as u32)),
        );
        if order.len() > 1 {
            order.sort_unstable();
        }
        let mut g = 0;
        while g < order.len() {
            let slice = (order[g].0 >> 32) as u32;
            let mut end = g + 1;
            while end < order.len() && (order[end].0 >> 32) as u32 == slice {
                end += 1;
            }
            let (mut c, mut nsum) = (Vec4::ZERO, Vec3::ZERO);
            if end == g + 1 {
                let f = &frags[order[g].2 as usize];
                let w = f.mask.count_ones() as f32;
                c = f.rgba * w;
                nsum = f.n * (f.rgba.w * w);
            } else {
                // Per-sample front-to-back compositing (ties in depth: lower triangle first).
                transmit[..kk].fill(1.0);
                for &(_, _, i) in &order[g..end] {
                    let f = &frags[i as usize];
                    let mut w = 0.0f32;
                    let keep = 1.0 - f.rgba.w;
                    let mut bits = f.mask;
                    while bits != 0 {
                        let b = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        w += transmit[b];
                        transmit[b] *= keep;
                    }
                    c += f.rgba * w;
                    nsum += f.n * (f.rgba.w * w);
                }
            }
            if c.w > 0.0 {
                out.push(Vox {
                    u: u as u16,
                    s: slice as u16,
                    rgba: (c * inv_samples).to_array(),
                });
                if normals {
                    out_n.push((nsum * inv_samples).to_array());
                }
            }
            g = end;
        }
        frags.clear();
    }
    (out, out_n, count)
}

/// Rasterizes the slice stack of direction `dir` into its sparse level 0.
/// `progress` gets the fraction of rows done.
pub(crate) fn rasterize(
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    dir: Dir,
    k: u32,
    normals: bool,
    progress: &mut dyn FnMut(f32),
) -> DirSlices {
    let k = k.clamp(1, MAX_SUPERSAMPLE) as i64;
    let [ua, va] = dir.image_axes();
    let dims = grid.dims.map(|d| d as usize);
    let setups: Vec<TriSetup> = (0..scene.triangles.len())
        .into_par_iter()
        .filter_map(|i| setup(scene, grid, dir, k, i))
        .collect();
    // Sorted by first row (then triangle), so that a row's triangles lie close together in
    // memory; the order of triangles within a row does not change the result (fragments
    // are sorted by a key that includes the triangle).
    let mut setups = setups;
    setups.par_sort_by_key(|s| (s.rows[0], s.tri));
    let nrows = dims[va];
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nrows];
    for (i, s) in setups.iter().enumerate() {
        for bin in &mut bins[s.rows[0] as usize..=s.rows[1] as usize] {
            bin.push(i as u32);
        }
    }
    let mut vox = Vec::new();
    let mut nrm = normals.then(Vec::new);
    let mut rows = Vec::with_capacity(nrows + 1);
    rows.push(0);
    let mut fragments = 0u64;
    let chunk = nrows.div_ceil(8).max(8);
    for chunk_start in (0..nrows).step_by(chunk) {
        let outs: Vec<RowOut> = (chunk_start..(chunk_start + chunk).min(nrows))
            .into_par_iter()
            .map(|j| {
                SCRATCH.with_borrow_mut(|scratch| {
                    if scratch.cols.len() < dims[ua] {
                        *scratch = Scratch::new(dims[ua]);
                    }
                    raster_row(
                        scene, shader, grid, dir, k, normals, &setups, &bins[j], j, scratch,
                    )
                })
            })
            .collect();
        for (v, n, count) in outs {
            fragments += count;
            vox.extend_from_slice(&v);
            if let Some(nrm) = nrm.as_mut() {
                nrm.extend_from_slice(&n);
            }
            rows.push(vox.len());
        }
        progress(((chunk_start + chunk).min(nrows)) as f32 / nrows.max(1) as f32);
    }
    DirSlices {
        dir,
        dims,
        vox,
        rows,
        nrm,
        fragments,
    }
}
