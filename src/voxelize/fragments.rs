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
use super::Dir;
use crate::material::Shader;
use crate::scene::{AlphaMode, Material, Scene};

mod voxels;

/// Sub-sample precision: vertices snap to 1/(2·K·SUB) of a voxel.
pub(crate) const SUB: i64 = 16;

/// One non-empty level-0 voxel of a direction: pixel column `u` of its image row, slice `s`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vox {
    pub u: u16,
    pub s: u16,
    /// Premultiplied linear RGBA.
    pub rgba: [f32; 4],
}

/// Everything the row loop needs of one triangle seen from one direction (the scene's
/// triangle is not read again, except for normals).
#[derive(Clone, Copy)]
pub(crate) struct TriSetup {
    /// Fixed-point (u, v) of the vertices, counter-clockwise.
    pub p: [[i64; 2]; 3],
    /// Depth of each vertex in voxels.
    pub t: [f64; 3],
    pub area: i64,
    /// 1 or 0 subtracted from each edge function (tie rule).
    pub bias: [i64; 3],
    /// Texture coordinates and vertex colours of the slots.
    pub uv: [Vec2; 3],
    pub col: [Vec4; 3],
    pub tri: u32,
    pub material: u32,
    /// Original vertex index of each slot.
    pub perm: [u8; 3],
    /// Whether the + direction of the axis sees the triangle's back (the − direction then
    /// sees its front, and the other way round).
    pub back: bool,
    /// Which of the axis's two directions see it: bit 0 the + one, bit 1 the − one.
    pub vis: u8,
    pub rows: [u32; 2],
    pub cols: [u32; 2],
}

/// A row's non-empty voxels, their weighted normals (when asked for), its fragment count
/// and its projected coverage (see [`DirSlices::coverage`]).
pub(crate) type RowOut = (Vec<Vox>, Vec<[f32; 3]>, u64, f64);

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
    /// Whether `rgba` is already shaded (a textured `Mask` fragment, shaded with the mean
    /// of its samples' texels by [`fragment`]).
    shaded: bool,
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
///
/// The stages, in order: [`triangle_row`] (coverage, [`slice_groups`], [`alpha_test`],
/// [`fragment`]) per triangle, then [`Scratch::shade`], [`Scratch::sort_by_voxel`] and
/// [`Scratch::composite`].
#[inline(always)]
fn raster_row<const K: usize, const AVX: bool>(
    ctx: &RowCtx<'_>,
    j: usize,
    scratch: &mut Scratch,
) -> [RowOut; 2] {
    let depth_n = ctx.grid.dims[ctx.dir.axis()];
    let width = ctx.grid.dims[ctx.dir.image_axes()[0]] as usize;
    scratch.frags.clear();
    scratch.normals.clear();
    let mut smp = Samples {
        off: [[0i64; 64]; 3],
        tx: [0f64; 64],
        ty: [0f64; 64],
        ts: [0f64; 64],
        have_t: false,
    };
    // Kept apart from `smp`: its growth is a call that would otherwise see (and make the
    // compiler reload) the sample tables.
    let mut groups: Vec<(u32, u64)> = Vec::with_capacity(64);
    for &ti in &ctx.bins[j] {
        let s = &ctx.setups[ti as usize];
        triangle_row::<K, AVX>(ctx, j, depth_n, s, &mut smp, &mut groups, scratch);
    }
    let (count, seen) = scratch.shade(ctx.shader, depth_n);
    scratch.sort_by_voxel(count, depth_n, width);
    scratch.composite::<K>(ctx.sides, ctx.normals, seen, width)
}

/// The per-sample tables of the triangle being rasterized, kept from one triangle to the
/// next of a row (not zeroed again).
struct Samples {
    /// Per edge, the offsets `si·ex + sj·ey` of its function at the samples.
    off: [[i64; 64]; 3],
    /// Per sample, its depth offset along u and along v from sample (0, 0).
    tx: [f64; 64],
    ty: [f64; 64],
    /// Per sample, its depth in the current pixel.
    ts: [f64; 64],
    /// Whether `tx` and `ty` hold the current triangle's offsets yet (made when a pixel
    /// first needs them).
    have_t: bool,
}

/// One triangle's constants over a row of `K × K`-sample pixels.
struct TriRow<'a> {
    s: &'a TriSetup,
    m: &'a Material,
    /// The `Mask` alpha cutoff, if the material has one.
    cutoff: Option<f32>,
    /// Texture coordinates and vertex colours of the slots.
    uvs: [Vec2; 3],
    cols: [Vec4; 3],
    inv_area: f64,
    /// Edge i runs from vertex i+1 to vertex i+2; its step per sample along u and v.
    ex: [i64; 3],
    ey: [i64; 3],
    /// Depth differences of vertices 1 and 2 from vertex 0.
    dt1: f64,
    dt2: f64,
    /// Depth step per sample along u and v (exactly 0 for a constant-depth triangle).
    dtx: f64,
    dty: f64,
    /// The largest and the least sample offset of each edge function over a pixel: the
    /// whole pixel is outside an edge when even its best sample is, inside all three
    /// when even its worst sample is.
    hi: [i64; 3],
    lo: [i64; 3],
}

impl<'a> TriRow<'a> {
    #[inline(always)]
    fn new<const K: usize>(shader: &'a Shader<'_>, s: &'a TriSetup) -> Self {
        let km1 = K as i64 - 1;
        let m = shader.material(s.material);
        let cutoff = match m.alpha_mode {
            AlphaMode::Mask { cutoff } => Some(cutoff),
            _ => None,
        };
        let inv_area = 1.0 / s.area as f64;
        let ex: [i64; 3] =
            [0, 1, 2].map(|i| -(s.p[(i + 2) % 3][1] - s.p[(i + 1) % 3][1]) * 2 * SUB);
        let ey: [i64; 3] = [0, 1, 2].map(|i| (s.p[(i + 2) % 3][0] - s.p[(i + 1) % 3][0]) * 2 * SUB);
        let (dt1, dt2) = (s.t[1] - s.t[0], s.t[2] - s.t[0]);
        TriRow {
            s,
            m,
            cutoff,
            uvs: s.uv,
            cols: s.col,
            inv_area,
            ex,
            ey,
            dt1,
            dt2,
            dtx: (ex[1] as f64 * dt1 + ex[2] as f64 * dt2) * inv_area,
            dty: (ey[1] as f64 * dt1 + ey[2] as f64 * dt2) * inv_area,
            hi: [0, 1, 2].map(|q| km1 * (ex[q].max(0) + ey[q].max(0))),
            lo: [0, 1, 2].map(|q| km1 * (ex[q].min(0) + ey[q].min(0))),
        }
    }

    /// Barycentrics (b1, b2) of a point whose biased edge values are e1, e2.
    #[inline(always)]
    fn bary(&self, e1: i64, e2: i64) -> (f64, f64) {
        let b1 = (e1 + self.s.bias[1]) as f64 * self.inv_area;
        let b2 = (e2 + self.s.bias[2]) as f64 * self.inv_area;
        (b1, b2)
    }

    /// Depth at barycentrics (b1, b2); written so a constant-depth triangle gives exactly
    /// its depth.
    #[inline(always)]
    fn depth(&self, b1: f64, b2: f64) -> f64 {
        self.s.t[0] + b1 * self.dt1 + b2 * self.dt2
    }

    /// The f32 barycentric weights, texture coordinates and vertex colour at (b1, b2).
    #[inline(always)]
    fn attributes(&self, b1: f64, b2: f64) -> ([f32; 3], Vec2, Vec4) {
        let (uvs, cols_v) = (&self.uvs, &self.cols);
        let (b1, b2) = (b1 as f32, b2 as f32);
        let b0 = 1.0 - b1 - b2;
        (
            [b0, b1, b2],
            uvs[0] * b0 + uvs[1] * b1 + uvs[2] * b2,
            cols_v[0] * b0 + cols_v[1] * b1 + cols_v[2] * b2,
        )
    }

    /// Fills `off` with the sample offsets of the edge functions, `si·ex + sj·ey` (exact
    /// integers).
    #[inline(always)]
    fn edge_offsets<const K: usize>(&self, off: &mut [[i64; 64]; 3]) {
        for (o, (x, y)) in off.iter_mut().zip(self.ex.iter().zip(&self.ey)) {
            let along: [i64; 8] = std::array::from_fn(|c| c as i64 * x);
            for r in 0..K {
                let base = r as i64 * y;
                for (d, a) in o[r * K..r * K + K].iter_mut().zip(&along) {
                    *d = base + a;
                }
            }
        }
    }
}

/// The slice a depth `0 ≤ t ≤ depth_n` falls in (`depth_n` itself: the last one).
#[inline(always)]
fn slice_of(t: f64, depth_n: u32) -> u32 {
    (t as u32).min(depth_n - 1)
}

/// Coverage, slice groups (into `groups`, per pixel) and fragments of triangle `s` over
/// the pixels of row `j` it spans, appended to `scratch.frags` (and its shading normals,
/// when asked for).
#[inline(always)]
fn triangle_row<const K: usize, const AVX: bool>(
    ctx: &RowCtx<'_>,
    j: usize,
    depth_n: u32,
    s: &TriSetup,
    smp: &mut Samples,
    groups: &mut Vec<(u32, u64)>,
    scratch: &mut Scratch,
) {
    let t = TriRow::new::<K>(ctx.shader, s);
    t.edge_offsets::<K>(&mut smp.off);
    smp.have_t = false;
    let k = K as i64;
    let fk = 2 * k * SUB;
    let i0 = s.cols[0] as usize;
    let sp0 = [i0 as i64 * fk + SUB, j as i64 * fk + SUB];
    // Edge values at sample (0, 0) of the pixel, biased by the tie rule; a pixel step
    // is K sample steps.
    let mut e00 = [
        cross2(s.p[1], s.p[2], sp0) - s.bias[0],
        cross2(s.p[2], s.p[0], sp0) - s.bias[1],
        cross2(s.p[0], s.p[1], sp0) - s.bias[2],
    ];
    let step = t.ex.map(|x| x * k);
    let (hi, lo) = (t.hi, t.lo);
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
            full_mask::<K>()
        } else {
            coverage::<K, AVX>(e, &smp.off, lo)
        };
        if mask == 0 {
            continue;
        }
        slice_groups::<K, AVX>(&t, e, mask, depth_n, smp, groups);
        for &(slice, gmask) in groups.iter() {
            let Some((f, bw)) = fragment::<K>(ctx.shader, &t, e, &smp.off, slice, gmask, i) else {
                continue;
            };
            if ctx.normals.on() {
                scratch.normals.push(shading_normal(ctx.scene, s, bw));
            }
            scratch.frags.push(f);
        }
    }
}

/// Fills `groups` with the `(slice, samples)` groups of the covered samples `mask` of
/// the pixel whose edge values at sample (0, 0) are `e`.
#[inline(always)]
fn slice_groups<const K: usize, const AVX: bool>(
    t: &TriRow<'_>,
    e: [i64; 3],
    mask: u64,
    depth_n: u32,
    smp: &mut Samples,
    groups: &mut Vec<(u32, u64)>,
) {
    let km1 = K as i64 - 1;
    let depth_f = depth_n as f64;
    // Depth is linear over the pixel's samples: extremes at the corners.
    let t00 = {
        let (b1, b2) = t.bary(e[1], e[2]);
        t.depth(b1, b2)
    };
    let tmin = t00 + (km1 as f64) * (t.dtx.min(0.0) + t.dty.min(0.0));
    let tmax = t00 + (km1 as f64) * (t.dtx.max(0.0) + t.dty.max(0.0));
    groups.clear();
    if tmin >= 0.0 && tmax <= depth_f && slice_of(tmin, depth_n) == slice_of(tmax, depth_n) {
        groups.push((slice_of(tmin, depth_n), mask));
    } else if tmax >= 0.0 && tmin <= depth_f {
        if !smp.have_t {
            for b in 0..K * K {
                smp.tx[b] = (b % K) as i64 as f64 * t.dtx;
                smp.ty[b] = (b / K) as i64 as f64 * t.dty;
            }
            smp.have_t = true;
        }
        for b in 0..K * K {
            smp.ts[b] = t00 + smp.tx[b] + smp.ty[b];
        }
        // Every sample's depth lies within `delta` of the corners' range (their
        // rounding errors are below 1e-15 of these magnitudes), so only the
        // planes inside [lo, hi] need comparing.
        let delta = 1e-9 * (1.0 + t00.abs() + km1 as f64 * (t.dtx.abs() + t.dty.abs()));
        let (lo, hi) = (tmin - delta, tmax + delta);
        split_at_planes::<K, AVX>(&smp.ts, mask, lo, hi, depth_n, groups);
    }
}

/// The samples of `mask` (depths `ts`, all within `[lo, hi]`) grouped by slice into
/// `groups`. A sample at depth t (0 ≤ t ≤ depth_n) lies in slice s when it is
/// at least s and less than s + 1, except that depth_n itself is in the last slice:
/// comparisons with whole numbers, so exactly `slice_of(t)`.
#[inline(always)]
fn split_at_planes<const K: usize, const AVX: bool>(
    ts: &[f64; 64],
    mask: u64,
    lo: f64,
    hi: f64,
    depth_n: u32,
    groups: &mut Vec<(u32, u64)>,
) {
    let kk = K * K;
    let depth_f = depth_n as f64;
    let ge = |p: u32| {
        let pf = p as f64;
        if p == 0 || pf <= lo {
            u64::MAX
        } else if p >= depth_n || pf > hi {
            0
        } else {
            at_least::<AVX, false>(kk, ts, pf)
        }
    };
    let mut want = mask;
    if lo < 0.0 {
        want &= at_least::<AVX, false>(kk, ts, 0.0);
    }
    if hi > depth_f {
        want &= !at_least::<AVX, true>(kk, ts, depth_f);
    }
    let (s_lo, s_hi) = (
        slice_of(lo.max(0.0), depth_n),
        slice_of(hi.min(depth_f), depth_n),
    );
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
            let first = slice_of(ts[b], depth_n);
            let mut g = 0u64;
            let mut bits = rest;
            while bits != 0 {
                let c = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if slice_of(ts[c], depth_n) == first {
                    g |= 1 << c;
                }
            }
            groups.push((first, g));
            rest &= !g;
        }
    }
}

/// The samples of `gmask` that pass the `Mask` alpha test at `cutoff` (alpha channel
/// only, per sample), and the sum of their [`Shader::texel`]s (zero without a texture);
/// `e` and `off` as in [`fragment`].
///
/// The texels are summed so that the fragment is shaded with their mean: a cut-out
/// texture's colour is correlated with where it passes (a leaf's rim, filtered against
/// the cut-away background, is lighter than its middle), and one shading point at the
/// samples' centroid lies in the middle. Shaded there, the oak's leaves came out 10 %
/// darker than the ray-traced mesh, which shades every sample.
#[inline(always)]
fn alpha_test(
    shader: &Shader<'_>,
    t: &TriRow<'_>,
    cutoff: f32,
    e: [i64; 3],
    off: &[[i64; 64]; 3],
    gmask: u64,
) -> (u64, Vec4) {
    let (uvs, cols_v) = (&t.uvs, &t.cols);
    let mut gmask = gmask;
    let mut texels = Vec4::ZERO;
    let mut bits = gmask;
    while bits != 0 {
        let b = bits.trailing_zeros();
        bits &= bits - 1;
        let (b1, b2) = t.bary(e[1] + off[1][b as usize], e[2] + off[2][b as usize]);
        let (b1, b2) = (b1 as f32, b2 as f32);
        let b0 = 1.0 - b1 - b2;
        let uv = uvs[0] * b0 + uvs[1] * b1 + uvs[2] * b2;
        let va = cols_v[0].w * b0 + cols_v[1].w * b1 + cols_v[2].w * b2;
        if !shader.mask_pass(t.m, cutoff, uv, va) {
            gmask &= !(1 << b);
        } else if let Some(c) = shader.texel(t.m, uv) {
            texels += c;
        }
    }
    (gmask, texels)
}

/// The fragment of the samples `gmask` in `slice` of pixel column `i` (edge values `e` at
/// its sample (0, 0), sample offsets `off`), with the barycentric weights of its shading
/// point, or `None` when the alpha test leaves no sample.
#[inline(always)]
fn fragment<const K: usize>(
    shader: &Shader<'_>,
    t: &TriRow<'_>,
    e: [i64; 3],
    off: &[[i64; 64]; 3],
    slice: u32,
    gmask: u64,
    i: usize,
) -> Option<(Frag, [f32; 3])> {
    let s = t.s;
    let mut gmask = gmask;
    let mut texels = Vec4::ZERO;
    if let Some(cutoff) = t.cutoff {
        (gmask, texels) = alpha_test(shader, t, cutoff, e, off, gmask);
        if gmask == 0 {
            return None;
        }
    }
    // Shading point: the centroid of the group's samples (inside the triangle).
    let (n, ssi, ssj) = mask_sums::<K>(gmask);
    let sum = |q: usize| n * (e[q] + s.bias[q]) + ssi * t.ex[q] + ssj * t.ey[q];
    let inv = t.inv_area / n as f64;
    let (mut b1, mut b2) = (sum(1) as f64 * inv, sum(2) as f64 * inv);
    let mut depth = t.depth(b1, b2);
    let (mut bw, mut uv, mut col) = t.attributes(b1, b2);
    if let Some(cutoff) = t.cutoff {
        // A cut-out between the samples: shade at the first sample that passed.
        if !shader.mask_pass(t.m, cutoff, uv, col.w) {
            let b = gmask.trailing_zeros() as usize;
            (b1, b2) = t.bary(e[1] + off[1][b], e[2] + off[2][b]);
            depth = t.depth(b1, b2);
            (bw, uv, col) = t.attributes(b1, b2);
        }
    }
    let dk = depth_key(depth as f32, false) as u64;
    // A textured cut-out: shaded here, with its passed samples' mean texel.
    let shaded = t.cutoff.is_some() && t.m.base_color_texture.is_some();
    let rgba = if shaded {
        let mean = texels / gmask.count_ones() as f32;
        shader.shade_texel(t.m, mean, col)?
    } else {
        col
    };
    let f = Frag {
        key: (slice as u64) << 32 | dk,
        mask: gmask,
        tri: s.tri,
        material: s.material,
        rgba,
        uv,
        u: i as u32,
        vis: s.vis,
        shaded,
    };
    Some((f, bw))
}

/// What a bake sums per voxel besides the colour: nothing, the alpha-weighted unit normals
/// (Toksvig's mean, [`super::toksvig`]) or the alpha-weighted squares of their components
/// (the diagonal of the normals' second moment, [`super::toksvig`] "Moments").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalSums {
    #[default]
    Off,
    Mean,
    Moments,
}

impl NormalSums {
    /// Whether any normal sum is wanted.
    pub fn on(self) -> bool {
        self != NormalSums::Off
    }
    /// The sums a bake with these options wants.
    pub fn of(normals: bool, moments: bool) -> Self {
        match (normals, moments) {
            (false, _) => NormalSums::Off,
            (true, false) => NormalSums::Mean,
            (true, true) => NormalSums::Moments,
        }
    }
}

/// What every row of one axis's two slice stacks reads.
#[derive(Clone, Copy)]
pub(crate) struct RowCtx<'a> {
    pub scene: &'a Scene,
    pub shader: &'a Shader<'a>,
    pub grid: &'a GridSpec,
    /// The + direction of the axis.
    pub dir: Dir,
    /// Which weighted normal sums are wanted.
    pub normals: NormalSums,
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
