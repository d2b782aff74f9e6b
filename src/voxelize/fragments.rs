//! One image row of a direction's slice stack: coverage masks, slice groups, shading and
//! per-voxel compositing (the conventions are those of [`super::slices`]).
//!
//! The row loop is generic over the supersampling factor `K` so that every per-sample
//! loop has a constant trip count and no data-dependent branch: coverage is the sign of
//! three integer edge functions at the `K²` samples, evaluated from per-(row, triangle)
//! tables of sample offsets; slice groups are formed by comparing the samples' slice
//! indices all at once; the centroid sums come from per-row bit tables. Every value is
//! computed with exactly the arithmetic of the straightforward per-sample loop (the
//! same integer edge values, the same f64 expressions in the same order), so the
//! result is the same bit for bit.

use glam::{Vec2, Vec3, Vec4};

use super::grid::GridSpec;
use super::lanes::{at_least, negative};
use super::slices::{RowOut, TriSetup, Vox, SUB};
use super::Dir;
use crate::scene::{AlphaMode, Scene};
use crate::shade::Shader;

/// A fragment: one triangle in one voxel, covering the samples of `mask`.
struct Frag {
    /// `slice << 32 | depth` (ascending: the − direction's front first); with `tri`, the
    /// sort key.
    key: u64,
    /// Bit `sj·K + si`: the samples it covers (0 once shading discarded it).
    mask: u64,
    tri: u32,
    material: u32,
    /// The interpolated vertex colour until shaded, then premultiplied linear RGBA.
    rgba: Vec4,
    /// Texture coordinates of the shading point.
    uv: Vec2,
    /// Pixel column.
    u: u32,
    /// Which directions see it (bit 0: +, bit 1: −), as [`TriSetup::vis`].
    vis: u8,
}

/// Per-thread buffers of [`raster_row`] (kept between rows).
#[derive(Default)]
pub(crate) struct Scratch {
    frags: Vec<Frag>,
    /// Shading normals, parallel to `frags`, when asked for.
    normals: Vec<Vec3>,
    /// Per slice, then per pixel column: the first entry of its fragments.
    start: Vec<u32>,
    /// Surviving fragments (indices in `frags`) grouped by slice.
    by_slice: Vec<u32>,
    /// Surviving fragments grouped by column: `(key, triangle, index in frags)`.
    order: Vec<(u64, u32, u32)>,
    /// One voxel's fragments seen from one direction, in that direction's sort key.
    voxel: Vec<(u64, u32, u32)>,
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
pub(crate) fn cross2(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Per `K`-bit row of a sample mask: the number of set bits and the sum of their
/// positions (`si`), for every value of the row (`K ≤ 8`).
const ROW_BITS: ([u8; 256], [u8; 256]) = {
    let (mut n, mut s) = ([0u8; 256], [0u8; 256]);
    let mut v = 0;
    while v < 256 {
        let mut b = 0;
        while b < 8 {
            if v >> b & 1 == 1 {
                n[v] += 1;
                s[v] += b as u8;
            }
            b += 1;
        }
        v += 1;
    }
    (n, s)
};

/// `(n, Σ si, Σ sj)` over the samples of `mask`.
#[inline(always)]
fn mask_sums<const K: usize>(mask: u64) -> (i64, i64, i64) {
    let (mut n, mut ssi, mut ssj) = (0i64, 0i64, 0i64);
    let row = (1u64 << K) - 1;
    for sj in 0..K {
        let v = ((mask >> (sj * K)) & row) as usize;
        let c = ROW_BITS.0[v] as i64;
        n += c;
        ssi += ROW_BITS.1[v] as i64;
        ssj += sj as i64 * c;
    }
    (n, ssi, ssj)
}

/// The samples (bits `< K²`) where all three edge values `e + off` are ≥ 0; `lo[q]` is
/// the least of `off[q]` (an edge with `e + lo ≥ 0` covers every sample).
#[inline(always)]
fn coverage<const K: usize, const AVX: bool>(
    e: [i64; 3],
    off: &[[i64; 64]; 3],
    lo: [i64; 3],
) -> u64 {
    let mut neg = 0u64;
    for q in 0..3 {
        if e[q] + lo[q] < 0 {
            neg |= negative::<AVX>(K * K, e[q], &off[q]);
        }
    }
    !neg & full_mask::<K>()
}

#[inline(always)]
const fn full_mask<const K: usize>() -> u64 {
    if K * K == 64 {
        u64::MAX
    } else {
        (1u64 << (K * K)) - 1
    }
}

/// Rasterizes one pixel row `j` of both directions of the axis of `dir` (the + one) with
/// `K × K` samples per pixel; returns, for the + and the − direction, the non-empty voxels
/// of the row sorted by `(u, slice)`, their weighted normals (when asked for) and the
/// fragment count (see [`super::slices`] for the conventions).
///
/// Per (triangle, pixel) the coverage of the samples is one bit mask (exact integer edge
/// functions); covered samples are grouped by the slice their depth falls in (one group
/// unless the triangle crosses a slice plane inside the pixel), `Mask` materials drop the
/// samples that fail the alpha test (alpha channel only, per sample), and each group is
/// shaded **once**, at the centroid of its samples (MSAA-style). Shading is batched per
/// row (the texture fetches of different fragments are independent, so their cache
/// misses overlap); then the fragments are grouped by column and, within a voxel,
/// composited front to back per sample (a per-sample transmittance), so the voxel is the
/// mean of its `K²` samples' composites.
///
/// Coverage, slice groups and shading do not depend on which side the camera is on, so
/// they are done once for the two directions; each fragment remembers which of them see
/// it (single-sided triangles: one; double-sided: both, the normal flipped for one), and
/// only the per-voxel compositing runs once per direction, in its own depth order.
#[inline(always)]
fn raster_row<const K: usize, const AVX: bool>(
    ctx: &RowCtx<'_>,
    j: usize,
    scratch: &mut Scratch,
) -> [RowOut; 2] {
    let RowCtx {
        scene,
        shader,
        grid,
        dir,
        normals,
        sides,
        setups,
        bins,
    } = *ctx;
    let tris = &bins[j];
    let k = K as i64;
    let fk = 2 * k * SUB;
    let kk = K * K;
    let full = full_mask::<K>();
    let depth_n = grid.dims[dir.axis()];
    let depth_f = depth_n as f64;
    let width = grid.dims[dir.image_axes()[0]] as usize;
    let Scratch {
        frags,
        normals: frag_n,
        start,
        by_slice,
        order,
        voxel,
    } = scratch;
    frags.clear();
    frag_n.clear();
    let km1 = k - 1;
    let mut groups: Vec<(u32, u64)> = Vec::with_capacity(64);
    // Sample (si, sj) of bit b.
    let si = |b: usize| (b % K) as i64;
    let sj = |b: usize| (b / K) as i64;
    let mut off = [[0i64; 64]; 3];
    let (mut tx, mut ty) = ([0f64; 64], [0f64; 64]);
    let mut ts = [0f64; 64];
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
        // Sample offsets of the edge functions, `si·ex + sj·ey` (exact integers).
        for (o, (x, y)) in off.iter_mut().zip(ex.iter().zip(&ey)) {
            let along: [i64; 8] = std::array::from_fn(|c| c as i64 * x);
            for r in 0..K {
                let base = r as i64 * y;
                for (d, a) in o[r * K..r * K + K].iter_mut().zip(&along) {
                    *d = base + a;
                }
            }
        }
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
        // Per-sample depth offsets, computed when a pixel first needs them.
        let mut have_t = false;
        // The whole pixel is outside an edge when even its best sample is; inside all
        // three when even its worst sample is.
        let hi: [i64; 3] = [0, 1, 2].map(|q| km1 * (ex[q].max(0) + ey[q].max(0)));
        let lo: [i64; 3] = [0, 1, 2].map(|q| km1 * (ex[q].min(0) + ey[q].min(0)));
        let sy = j as i64 * fk + SUB;
        let i0 = s.cols[0] as usize;
        let sp0 = [i0 as i64 * fk + SUB, sy];
        // Edge values at sample (0, 0) of the pixel, biased by the tie rule; a pixel step
        // is K sample steps.
        let mut e00 = [
            cross2(s.p[1], s.p[2], sp0) - s.bias[0],
            cross2(s.p[2], s.p[0], sp0) - s.bias[1],
            cross2(s.p[0], s.p[1], sp0) - s.bias[2],
        ];
        let step = ex.map(|x| x * k);
        for i in i0..=s.cols[1] as usize {
            let e = e00;
            for q in 0..3 {
                e00[q] += step[q];
            }
            if e[0] + hi[0] < 0 || e[1] + hi[1] < 0 || e[2] + hi[2] < 0 {
                continue;
            }
            let all_in = e[0] + lo[0] >= 0 && e[1] + lo[1] >= 0 && e[2] + lo[2] >= 0;
            let mask = if all_in {
                full
            } else {
                coverage::<K, AVX>(e, &off, lo)
            };
            if mask == 0 {
                continue;
            }
            // Depth is linear over the pixel's samples: extremes at the corners.
            let t00 = {
                let (b1, b2) = bary(e[1], e[2]);
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
                if !have_t {
                    for b in 0..kk {
                        tx[b] = si(b) as f64 * dtx;
                        ty[b] = sj(b) as f64 * dty;
                    }
                    have_t = true;
                }
                // A sample at depth t (0 ≤ t ≤ depth_n) lies in slice s when it is at least
                // s and less than s + 1, except that depth_n itself is in the last slice:
                // comparisons with whole numbers, so exactly `slice_of(t)`.
                for b in 0..K * K {
                    ts[b] = t00 + tx[b] + ty[b];
                }
                // Every sample's depth lies within `delta` of the corners' range (their
                // rounding errors are below 1e-15 of these magnitudes), so only the
                // planes inside [lo, hi] need comparing.
                let delta = 1e-9 * (1.0 + t00.abs() + km1 as f64 * (dtx.abs() + dty.abs()));
                let (lo, hi) = (tmin - delta, tmax + delta);
                let ge = |p: u32| {
                    let pf = p as f64;
                    if p == 0 || pf <= lo {
                        u64::MAX
                    } else if p >= depth_n || pf > hi {
                        0
                    } else {
                        at_least::<AVX, false>(kk, &ts, pf)
                    }
                };
                let mut want = mask;
                if lo < 0.0 {
                    want &= at_least::<AVX, false>(kk, &ts, 0.0);
                }
                if hi > depth_f {
                    want &= !at_least::<AVX, true>(kk, &ts, depth_f);
                }
                let (s_lo, s_hi) = (slice_of(lo.max(0.0)), slice_of(hi.min(depth_f)));
                let mut below = ge(s_lo);
                let mut got = 0u64;
                for sl in s_lo..=s_hi {
                    let next = ge(sl + 1);
                    let g = want & below & !next;
                    if g != 0 {
                        groups.push((sl, g));
                        got |= g;
                    }
                    below = next;
                }
                if got != want {
                    // A sample rounded past a corner's slice: group them one by one.
                    groups.clear();
                    let mut rest = want;
                    while rest != 0 {
                        let b = rest.trailing_zeros() as usize;
                        let first = slice_of(ts[b]);
                        let mut g = 0u64;
                        let mut bits = rest;
                        while bits != 0 {
                            let c = bits.trailing_zeros() as usize;
                            bits &= bits - 1;
                            if slice_of(ts[c]) == first {
                                g |= 1 << c;
                            }
                        }
                        groups.push((first, g));
                        rest &= !g;
                    }
                }
            }
            for &(slice, gmask) in &groups {
                let mut gmask = gmask;
                // Edge values of sample `b` (bit index).
                let e_at = |b: u32, q: usize| e[q] + off[q][b as usize];
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
                let (n, ssi, ssj) = mask_sums::<K>(gmask);
                let sum = |q: usize| n * (e[q] + s.bias[q]) + ssi * ex[q] + ssj * ey[q];
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
                if normals {
                    frag_n.push(shading_normal(scene, s, bw));
                }
                let dk = depth_key(t as f32, false) as u64;
                frags.push(Frag {
                    key: (slice as u64) << 32 | dk,
                    mask: gmask,
                    tri: s.tri,
                    material: s.material,
                    rgba: col,
                    uv,
                    u: i as u32,
                    vis: s.vis,
                });
            }
        }
    }
    // Shading, batched per row; the survivors are counted per slice and per direction.
    let mut count = 0u64;
    let mut seen = [0u64; 2];
    start.clear();
    start.resize(depth_n as usize + 1, 0);
    for f in frags.iter_mut() {
        match shader.shade_tested(shader.material(f.material), f.uv, f.rgba) {
            Some(c) => {
                f.rgba = c;
                start[(f.key >> 32) as usize + 1] += 1;
                count += 1;
                seen[0] += (f.vis & 1) as u64;
                seen[1] += (f.vis >> 1) as u64;
            }
            None => f.mask = 0,
        }
    }
    // Grouped by (column, slice) with two stable counting sorts (by slice, then by
    // column), in generation order within a voxel.
    for z in 0..depth_n as usize {
        start[z + 1] += start[z];
    }
    by_slice.clear();
    by_slice.resize(count as usize, 0);
    for (i, f) in frags.iter().enumerate() {
        if f.mask != 0 {
            let p = &mut start[(f.key >> 32) as usize];
            by_slice[*p as usize] = i as u32;
            *p += 1;
        }
    }
    start.clear();
    start.resize(width + 1, 0);
    for &i in by_slice.iter() {
        start[frags[i as usize].u as usize + 1] += 1;
    }
    for u in 0..width {
        start[u + 1] += start[u];
    }
    order.clear();
    order.resize(count as usize, (0, 0, 0));
    {
        let mut fill = start[..width].to_vec();
        for &i in by_slice.iter() {
            let f = &frags[i as usize];
            let p = &mut fill[f.u as usize];
            order[*p as usize] = (f.key, f.tri, i);
            *p += 1;
        }
    }
    let inv_samples = 1.0 / kk as f32;
    // A direction has at most as many voxels as fragments: sized once, no regrowing.
    let mut out: [RowOut; 2] = [0, 1].map(|side| {
        let n = seen[side];
        let n_nrm = if normals { n as usize } else { 0 };
        (Vec::with_capacity(n as usize), Vec::with_capacity(n_nrm), n)
    });
    let mut transmit = [1.0f32; 64];
    let nrm_of = |i: u32, side: usize| {
        if !normals {
            Vec3::ZERO
        } else if side == 0 {
            frag_n[i as usize]
        } else {
            // The − direction sees the other face: the shading normal flipped (exactly).
            -frag_n[i as usize]
        }
    };
    for u in 0..width {
        let col = &order[start[u] as usize..start[u + 1] as usize];
        let mut g = 0;
        while g < col.len() {
            let slice = (col[g].0 >> 32) as u32;
            let mut end = g + 1;
            while end < col.len() && (col[end].0 >> 32) as u32 == slice {
                end += 1;
            }
            for (side, (vox, vox_n, _)) in out.iter_mut().enumerate() {
                let bit = 1u8 << side;
                if sides & bit == 0 {
                    continue;
                }
                // A fragment alone in its voxel (the common case): no compositing.
                let single = |i: u32| {
                    let f = &frags[i as usize];
                    let w = f.mask.count_ones() as f32;
                    (f.rgba * w, nrm_of(i, side) * (f.rgba.w * w))
                };
                let (c, nsum) = if end == g + 1 {
                    if frags[col[g].2 as usize].vis & bit == 0 {
                        continue;
                    }
                    single(col[g].2)
                } else {
                    // The voxel's fragments seen from this side, by (depth front to back,
                    // triangle): the + camera sees high depths first.
                    voxel.clear();
                    voxel.extend(
                        col[g..end]
                            .iter()
                            .filter(|e| frags[e.2 as usize].vis & bit != 0)
                            .map(|&(key, tri, i)| {
                                let key = if side == 0 { key ^ 0xffff_ffff } else { key };
                                (key, tri, i)
                            }),
                    );
                    match voxel.len() {
                        0 => continue,
                        1 => single(voxel[0].2),
                        _ => {
                            sort_small(voxel);
                            // Per-sample front-to-back compositing (ties in depth: lower
                            // triangle first).
                            let (mut c, mut nsum) = (Vec4::ZERO, Vec3::ZERO);
                            transmit[..kk].fill(1.0);
                            for &(_, _, i) in voxel.iter() {
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
                                nsum += nrm_of(i, side) * (f.rgba.w * w);
                            }
                            (c, nsum)
                        }
                    }
                };
                if c.w > 0.0 {
                    vox.push(Vox {
                        u: u as u16,
                        s: slice as u16,
                        rgba: (c * inv_samples).to_array(),
                    });
                    if normals {
                        vox_n.push((nsum * inv_samples).to_array());
                    }
                }
            }
            g = end;
        }
    }
    out
}

/// What every row of one axis's two slice stacks reads.
#[derive(Clone, Copy)]
pub(crate) struct RowCtx<'a> {
    pub scene: &'a Scene,
    pub shader: &'a Shader<'a>,
    pub grid: &'a GridSpec,
    /// The + direction of the axis.
    pub dir: Dir,
    /// Whether weighted normals are wanted.
    pub normals: bool,
    /// Which directions this pass rasterizes (bit 0: +, bit 1: −).
    pub sides: u8,
    /// The axis's triangle set-ups, sorted by first row.
    pub setups: &'a [TriSetup],
    /// Per image row, the indices in `setups` of the triangles that touch it.
    pub bins: &'a [Vec<u32>],
}

/// A row rasterizer ([`raster_row`] for one `K`): row `j` of the context's direction.
pub(crate) type RowFn = fn(&RowCtx<'_>, usize, &mut Scratch) -> [RowOut; 2];

/// [`raster_row`] for `K`, compiled for the baseline instruction set.
fn row_base<const K: usize>(ctx: &RowCtx<'_>, j: usize, scratch: &mut Scratch) -> [RowOut; 2] {
    raster_row::<K, false>(ctx, j, scratch)
}

/// [`raster_row`] for `K`, compiled with AVX2 (wider integer and float vectors, BMI,
/// POPCNT). No fused multiply-add is enabled and Rust never contracts `a * b + c`, so
/// every operation rounds exactly as in [`row_base`]: the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
unsafe fn row_avx2_inner<const K: usize>(
    ctx: &RowCtx<'_>,
    j: usize,
    scratch: &mut Scratch,
) -> [RowOut; 2] {
    raster_row::<K, true>(ctx, j, scratch)
}

#[cfg(target_arch = "x86_64")]
fn row_avx2<const K: usize>(ctx: &RowCtx<'_>, j: usize, scratch: &mut Scratch) -> [RowOut; 2] {
    // SAFETY: only handed out by `row_fn` after the features were detected.
    unsafe { row_avx2_inner::<K>(ctx, j, scratch) }
}

/// Whether this CPU runs the AVX2 build of the row rasterizer.
pub(crate) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The row rasterizer for `k` samples per axis (1..=8): the AVX2 build when `simd` (the
/// caller has checked [`simd_available`]), else the baseline one.
pub(crate) fn row_fn(k: usize, simd: bool) -> RowFn {
    macro_rules! pick {
        ($f:ident) => {
            match k {
                1 => $f::<1>,
                2 => $f::<2>,
                3 => $f::<3>,
                4 => $f::<4>,
                5 => $f::<5>,
                6 => $f::<6>,
                7 => $f::<7>,
                _ => $f::<8>,
            }
        };
    }
    #[cfg(target_arch = "x86_64")]
    if simd && simd_available() {
        return pick!(row_avx2);
    }
    let _ = simd;
    pick!(row_base)
}

/// Sorts a voxel's `(key, triangle, index)` entries (few, usually): insertion sort for
/// short runs, the standard sort otherwise. Keys and triangles are never both equal.
#[inline]
fn sort_small(v: &mut [(u64, u32, u32)]) {
    if v.len() > 24 {
        v.sort_unstable();
        return;
    }
    for i in 1..v.len() {
        let x = v[i];
        let key = (x.0, x.1);
        let mut p = i;
        while p > 0 && (v[p - 1].0, v[p - 1].1) > key {
            v[p] = v[p - 1];
            p -= 1;
        }
        v[p] = x;
    }
}

/// The unit shading normal at barycentrics `bw` (interpolated vertex normals, the face
/// normal when they cancel), flipped towards the camera for a back face.
fn shading_normal(scene: &Scene, s: &TriSetup, bw: [f32; 3]) -> Vec3 {
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
}
