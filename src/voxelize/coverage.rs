//! Coverage that holds at every distance: the MIP levels of a volume are scaled in optical
//! depth so that, drawn by the slicer, each covers as much of the screen along each axis
//! as the mesh does.
//!
//! # Why volumes grew denser with distance
//! Measured on the bundled oak (128³, `opaque`, docs/voxelize.md "Coverage at a
//! distance"), three causes add up:
//! - **The MIP build assumes uncorrelated coverage.** Across the view axis a MIP step
//!   averages the composited child columns, and the renderer then composites the coarse
//!   texels along the ray as if what each holds were spread evenly over its footprint.
//!   Real coverage is correlated along the ray (a trunk, a clump of leaves, a solid's
//!   silhouette cover the same part of the footprint at every depth), and then
//!   `Π(1 − mean α) < mean Π(1 − α)`: the column of averages is more opaque than the
//!   average of the columns. One direction's own pyramid, composited along its own axis,
//!   was +1 %, +2.5 %, +5 %, +9 % and +16 % above its level 0 at levels 1–5.
//! - **The combine.** `opaque` (and `max`) give each voxel its most opaque direction's
//!   alpha: a leaf seen face-on from ±Y is opaque in its voxel, which the ±X views see
//!   edge-on. Level 0 of the oak's `opaque` volume drawn along an axis covered 8 % more
//!   than one direction's own stack (at 32³ the flowers: 29 %).
//! - **The slicer's filter**: extinction-space filtering (`1 − e^(−σ)` of an interpolated
//!   `σ`, concave) covers more than the texels' own columns where neighbours differ
//!   (+3.5 % at level 0, more on the large texels of coarse levels).
//!
//! # What is done
//! Like the billboard clouds' alpha MIPs ([`crate::bbcloud::atlas::coverage_chain`]), each
//! level gets **one scale of its optical depth**: `α' = 1 − (1 − α)^k`, colour scaled by
//! `α'/α` (premultiplied, straight colour kept). `k` is found by bisection so that the
//! level's **rendered projected coverage**, summed over the three axes, equals a target
//! ([`Model`]): for each axis, the level's texel columns are composited (`τ = Σ σ`,
//! `σ = −ln(1 − α)`, an opaque texel counted as the slicer caps it,
//! [`billow_core::slicing::MAX_OPTICAL_DEPTH`]; each texel's `σ` taken over its extent along the axis divided
//! by its size, as the slicer's opacity correction does,
//! [`billow_core::slicing::level_weights`]), the column optical depths are interpolated
//! bilinearly across with clamp-to-edge (what the slicer's trilinear extinction filter
//! does to them) at 4 × 4 points per texel, and `1 − e^(−τ)` is summed.
//! - **Level 0** is matched to the mesh's projected coverage along each axis, the mean of
//!   its two directions' level-0 stacks (`Σ_columns 1 − Π(1 − α)`, `stack_coverage`:
//!   what the 4×4-supersampled rasterizer saw, within 1 % of the ray-traced mesh on the
//!   oak), but only ever **thinned** (`k ≤ 1`): a combine that made it denser than any
//!   view of the mesh (`opaque`, `max` on foliage) is brought back, and one that made it
//!   thinner (`mean` on a closed one-sided surface, `min`) is kept as combined. Expressions
//!   and custom functions keep their level 0. Where the volume was judged foliage before
//!   the bake (`VoxelizeOptions::surface` = `Some(false)`: every `--normals` mode but
//!   `on`), level 0's opaque texels are thinned with the rest, as the optical depth the
//!   slicer gives them (`ln 510`): the same `k` everywhere in optical depth. Kept opaque, they took none of the thinning and the
//!   partly covered texels took all of it: the generated tree's level 0 was thinned by
//!   `k` = 0.087, its twigs (partly covered, dark bark) to a twelfth while its leaf clumps
//!   (opaque through the combine) stayed, and it read +7.2 % in luminance under the
//!   standard lights at 1×; with its opaque texels thinned too, `k` = 0.30, +4.9 %, RMSE
//!   0.0377 → 0.0360 (docs/accuracy.md, "Thinning opaque texels too"). A closed surface
//!   (`Volume::normal_coherence`) is not thinned at all, and a volume not judged before
//!   the bake keeps its opaque texels (a small excess of coverage over a solid's
//!   silhouette would otherwise make the whole solid translucent).
//! - **Levels 1 and up** are matched to level 0 as rendered (after its scale), `k` in
//!   `[1/16, 16]`: a distant volume covers what the near one does.
//!
//! Above level 0, fully opaque texels are unchanged by any `k`. The level-0
//! scale is applied to its RGBA8 bytes (a non-empty texel stays non-empty, so what
//! `emptyspace` prunes does not change); the coarse levels of a preset are scaled before
//! quantization. Every sum runs in a fixed order (each column front to back in increasing
//! coordinate), so `k` and the bytes do not depend on the number of threads, and the
//! dense and the brick-sparse (`--prune`) bakes compute the same `k`.

// `!(a > b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use rayon::prelude::*;

use super::brick_grid::{B, B3};
use super::quantize::{srgb_eotf, Encoder};
use super::slices::DirSlices;
use crate::sparse_level::SparseLevel;
use crate::texture::clamp_edge_taps;

/// The largest optical depth a level-0 texel holds when the slicer filters it
/// ([`billow_core::slicing::MAX_OPTICAL_DEPTH`], `ln 510`).
const MAX_OPTICAL_DEPTH: f64 = billow_core::slicing::MAX_OPTICAL_DEPTH as f64;

/// Smallest and largest optical-depth scale of a level above 0.
pub const K_RANGE: (f64, f64) = (1.0 / 16.0, 16.0);

/// Projected coverage of one direction's level-0 stack along its own axis, exactly as the
/// rasterizer's samples saw it ([`DirSlices::coverage`]), in level-0 texel faces.
pub(crate) fn stack_coverage(s: &DirSlices) -> f64 {
    s.coverage
}

/// The mesh's projected coverage per axis (x, y, z): the mean of its two directions'
/// `stack_coverage` (`per_dir` indexed like [`super::Dir::ALL`]).
pub fn mesh_coverage(per_dir: &[f64; 6]) -> [f64; 3] {
    std::array::from_fn(|a| 0.5 * (per_dir[2 * a] + per_dir[2 * a + 1]))
}

/// The two axes across `axis`, in increasing order.
#[inline]
fn across(axis: usize) -> [usize; 2] {
    match axis {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// A level's column optical depths along each axis.
pub struct Columns {
    dims: [usize; 3],
    /// Per axis, per column (the two other axes in increasing order, the first fastest):
    /// `Σ σ` over its texels that are not opaque.
    tau: [Vec<f64>; 3],
    /// Per axis, per column: how many of its texels are opaque (`σ ≥` [`MAX_OPTICAL_DEPTH`]).
    opaque: [Vec<u32>; 3],
}

impl Columns {
    /// The columns of a level of `dims` whose alphas `fill(brick, out)` writes brick by
    /// brick (8³ bricks, x fastest inside; `false`: the brick is empty). Each column is
    /// summed in increasing coordinate, so two sources of the same alphas give the same
    /// sums.
    pub fn build(
        dims: [usize; 3],
        fill: impl Fn([usize; 3], &mut [f32; B3]) -> bool + Sync,
    ) -> Self {
        let nb = dims.map(|d| d.div_ceil(B));
        let make = |axis: usize| -> (Vec<f64>, Vec<u32>) {
            let [u, v] = across(axis);
            let (nu, nv) = (dims[u], dims[v]);
            // One task per column of bricks along the axis: it owns the B×B columns it holds.
            let tasks: Vec<(usize, usize)> = (0..nb[v])
                .flat_map(|bv| (0..nb[u]).map(move |bu| (bu, bv)))
                .collect();
            let parts: Vec<(Vec<f64>, Vec<u32>)> = tasks
                .par_iter()
                .map(|&(bu, bv)| {
                    let mut tau = vec![0.0f64; B * B];
                    let mut op = vec![0u32; B * B];
                    let mut alpha = [0.0f32; B3];
                    for bw in 0..nb[axis] {
                        let mut bc = [0usize; 3];
                        bc[axis] = bw;
                        bc[u] = bu;
                        bc[v] = bv;
                        if !fill(bc, &mut alpha) {
                            continue;
                        }
                        for lw in 0..B.min(dims[axis] - bw * B) {
                            for lv in 0..B.min(nv - bv * B) {
                                for lu in 0..B.min(nu - bu * B) {
                                    let mut l = [0usize; 3];
                                    l[axis] = lw;
                                    l[u] = lu;
                                    l[v] = lv;
                                    let a = alpha[l[0] + B * (l[1] + B * l[2])];
                                    if !(a > 0.0) {
                                        continue;
                                    }
                                    let s = -(-f64::from(a.min(1.0))).ln_1p();
                                    if s < MAX_OPTICAL_DEPTH {
                                        tau[lu + B * lv] += s;
                                    } else {
                                        op[lu + B * lv] += 1;
                                    }
                                }
                            }
                        }
                    }
                    (tau, op)
                })
                .collect();
            let mut tau = vec![0.0f64; nu * nv];
            let mut op = vec![0u32; nu * nv];
            for (&(bu, bv), (t, o)) in tasks.iter().zip(parts) {
                for lv in 0..B.min(nv - bv * B) {
                    for lu in 0..B.min(nu - bu * B) {
                        let i = bu * B + lu + nu * (bv * B + lv);
                        tau[i] = t[lu + B * lv];
                        op[i] = o[lu + B * lv];
                    }
                }
            }
            (tau, op)
        };
        let [x, y, z] = [0, 1, 2].map(make);
        Columns {
            dims,
            tau: [x.0, y.0, z.0],
            opaque: [x.1, y.1, z.1],
        }
    }

    /// The columns of a dense RGBA8 level (x fastest).
    pub fn from_rgba8(dims: [usize; 3], bytes: &[u8]) -> Self {
        Self::build(dims, |bc, out| {
            let mut any = false;
            for lz in 0..B {
                for ly in 0..B {
                    for lx in 0..B {
                        let p = [bc[0] * B + lx, bc[1] * B + ly, bc[2] * B + lz];
                        let a = if p[0] < dims[0] && p[1] < dims[1] && p[2] < dims[2] {
                            bytes[4 * (p[0] + dims[0] * (p[1] + dims[1] * p[2])) + 3]
                        } else {
                            0
                        };
                        any |= a != 0;
                        out[lx + B * (ly + B * lz)] = f32::from(a) / 255.0;
                    }
                }
            }
            any
        })
    }

    /// The columns of a brick-sparse RGBA8 level.
    pub fn from_sparse(level: &SparseLevel) -> Self {
        Self::build(level.dims, |bc, out| level.brick_alpha(bc, out))
    }
}

/// The optical depth the slicer takes per unit of a texel's `σ` along `axis`, for a level
/// of size `dims` (`dims0`, `voxel`: level 0's size and voxel size): the texel's extent
/// along the axis over its size, the geometric mean of its extents
/// ([`billow_core::slicing::level_texel_size`]), which the slicer's opacity correction
/// divides by. 1 for cubic texels.
fn along(dims: [usize; 3], dims0: [usize; 3], voxel: [f64; 3], axis: usize) -> f64 {
    let e: [f64; 3] = std::array::from_fn(|a| voxel[a] * dims0[a] as f64 / dims[a] as f64);
    e[axis] / (e[0] * e[1] * e[2]).cbrt()
}

/// How many level-0 texels thick (in optical depth) an opaque texel of a level of size
/// `dims` is: its size over level 0's ([`billow_core::slicing::opaque_optical_depth`]).
fn opaque_scale(dims: [usize; 3], dims0: [usize; 3], voxel: [f64; 3]) -> f64 {
    let e: f64 = (0..3)
        .map(|a| voxel[a] * dims0[a] as f64 / dims[a] as f64)
        .product();
    (e / (voxel[0] * voxel[1] * voxel[2])).cbrt()
}

/// The area of one texel face across `axis` in level-0 texel faces.
fn face(dims: [usize; 3], dims0: [usize; 3], axis: usize) -> f64 {
    let [u, v] = across(axis);
    (dims0[u] as f64 / dims[u] as f64) * (dims0[v] as f64 / dims[v] as f64)
}

/// Points per texel per axis across at which the rendered coverage is summed.
const S: usize = 4;

/// A level's rendered projected coverage as a function of its optical-depth scale `k`
/// (module docs): per axis, the interpolated column optical depths at `S × S` points of
/// every texel face, split into the part that scales with `k` and the opaque part.
pub struct Model {
    axes: Vec<(Vec<f64>, Vec<f64>, f64)>,
    /// Whether the opaque texels' optical depth scales with `k` too (level 0's thinning).
    opaque_scales: bool,
}

impl Model {
    pub fn new(c: &Columns, dims0: [usize; 3], voxel: [f64; 3]) -> Self {
        let axes = (0..3)
            .map(|axis| {
                let [u, v] = across(axis);
                let (nu, nv) = (c.dims[u], c.dims[v]);
                let m = along(c.dims, dims0, voxel, axis);
                let cap = MAX_OPTICAL_DEPTH * opaque_scale(c.dims, dims0, voxel);
                // Per point along one axis of n texels: (i0, i1, t), clamp-to-edge.
                let (tu, tv) = (clamp_edge_taps(nu, S), clamp_edge_taps(nv, S));
                let (tau, op) = (&c.tau[axis], &c.opaque[axis]);
                let lerp2 = |g: &dyn Fn(usize) -> f64, qu: usize, qv: usize| {
                    let (a0, a1, ta) = tu[qu];
                    let (b0, b1, tb) = tv[qv];
                    let row = |b: usize| g(a0 + nu * b) * (1.0 - ta) + g(a1 + nu * b) * ta;
                    row(b0) * (1.0 - tb) + row(b1) * tb
                };
                let w = tu.len();
                let mut scaled = vec![0.0f64; w * tv.len()];
                let mut fixed = vec![0.0f64; w * tv.len()];
                scaled
                    .par_chunks_mut(w)
                    .zip(fixed.par_chunks_mut(w))
                    .enumerate()
                    .for_each(|(qv, (s, f))| {
                        for qu in 0..w {
                            s[qu] = m * lerp2(&|i| tau[i], qu, qv);
                            f[qu] = m * lerp2(&|i| f64::from(op[i]) * cap, qu, qv);
                        }
                    });
                (scaled, fixed, face(c.dims, dims0, axis) / (S * S) as f64)
            })
            .collect();
        Model {
            axes,
            opaque_scales: false,
        }
    }

    /// The rendered projected coverage along each axis with the optical depth scaled by
    /// `k`, in level-0 texel faces.
    pub fn coverage(&self, k: f64) -> [f64; 3] {
        std::array::from_fn(|a| {
            let (s, f, w) = &self.axes[a];
            let rows: Vec<f64> = s
                .par_chunks(4096)
                .zip(f.par_chunks(4096))
                .map(|(s, f)| {
                    s.iter()
                        .zip(f)
                        .map(|(&s, &f)| {
                            let t = if self.opaque_scales {
                                k * (s + f)
                            } else {
                                k * s + f
                            };
                            if t > 0.0 {
                                -(-t).exp_m1()
                            } else {
                                0.0
                            }
                        })
                        .sum::<f64>()
                })
                .collect();
            rows.iter().sum::<f64>() * w
        })
    }

    /// The scale `k` in `[lo, hi]` whose [`Model::coverage`] is on average, over the three
    /// axes, relatively as far above `want` as below it: `Σ_a coverage_a(k) / want_a = 3`
    /// (an axis the mesh does not cover is left out), the nearer end when it cannot be;
    /// 1 when nothing is to be matched, or already within 10⁻⁴.
    pub fn solve(&self, want: &[f64; 3], (lo, hi): (f64, f64)) -> f64 {
        let axes: Vec<usize> = (0..3).filter(|&a| want[a] > 0.0).collect();
        let n = axes.len() as f64;
        let have = |k: f64| {
            let c = self.coverage(k);
            axes.iter().map(|&a| c[a] / want[a]).sum::<f64>()
        };
        let h1 = have(1.0);
        if axes.is_empty() || !(h1 > 0.0) || ((h1 - n) / n).abs() < 1e-4 {
            return 1.0f64.clamp(lo, hi);
        }
        // Bisection on ln k: the coverage grows with k.
        let (mut a, mut b) = if h1 > n {
            if lo >= 1.0 || have(lo) >= n {
                return lo.min(1.0);
            }
            (lo.ln(), 0.0)
        } else {
            if hi <= 1.0 || have(hi) <= n {
                return hi.max(1.0);
            }
            (0.0, hi.ln())
        };
        for _ in 0..40 {
            let m = 0.5 * (a + b);
            let h = have(m.exp());
            if ((h - n) / n).abs() < 1e-5 {
                return m.exp();
            }
            if h > n {
                b = m;
            } else {
                a = m;
            }
        }
        (0.5 * (a + b)).exp()
    }
}

/// A premultiplied value with its optical depth scaled by `k`: `α' = 1 − (1 − α)^k`,
/// colour scaled by `α'/α`.
#[inline]
pub fn scale_opacity(v: glam::Vec4, k: f32) -> glam::Vec4 {
    billow_core::compositing::correct_premultiplied(v, k)
}

/// An RGBA8 `SrgbPremultiplied` texel with its optical depth scaled by `k`
/// ([`scale_opacity`] on the decoded value, encoded again). A texel with alpha 0 is kept
/// as it is, and a non-zero alpha byte stays at least 1, so a non-empty texel stays
/// non-empty. An opaque texel (alpha 255) stays opaque, or with `opaque_too` is scaled
/// as the optical depth the slicer gives it ([`billow_core::slicing::MAX_OPTICAL_DEPTH`], `ln 510`).
pub fn scale_rgba8(px: [u8; 4], k: f32, opaque_too: bool, enc: &Encoder) -> [u8; 4] {
    if px[3] == 0 || k == 1.0 || (px[3] == 255 && !opaque_too) {
        return px;
    }
    let a = if px[3] == 255 {
        -(-MAX_OPTICAL_DEPTH as f32).exp_m1()
    } else {
        f32::from(px[3]) / 255.0
    };
    let c = glam::Vec4::new(
        srgb_eotf(f32::from(px[0]) / 255.0),
        srgb_eotf(f32::from(px[1]) / 255.0),
        srgb_eotf(f32::from(px[2]) / 255.0),
        a,
    );
    let mut out = enc.rgba8(super::quantize::clamp_premultiplied(scale_opacity(c, k)));
    out[3] = out[3].max(1);
    out
}

/// What a bake's levels are scaled by, and how the three targets came out (in level-0
/// texel faces): the mesh's projected coverage per axis, and level 0's rendered one
/// before and after its scale.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverageScales {
    /// Per level, the optical-depth scale `k` its alpha got (1: unchanged).
    pub scales: Vec<f32>,
    pub mesh: [f64; 3],
    pub level0_before: [f64; 3],
    pub level0_after: [f64; 3],
    /// Whether level 0's opaque texels are thinned with the rest (a volume judged foliage
    /// before the bake, `VoxelizeOptions::surface` = `Some(false)`).
    pub level0_opaque_thinned: bool,
}

impl CoverageScales {
    /// Level 0's thinning, whose scale the bake found (`scales[0]`), applied by `apply` —
    /// or, for a `surface` (normals coherent enough to keep, `Volume::normal_coherence`),
    /// given up: its partly covered voxels are a closed surface's, and thinning them all
    /// by one scale opens it (spot: k = 0.14, eval RMSE at 1× 0.0841 thinned against
    /// 0.0718 kept). Coarser levels keep the mesh's coverage either way.
    pub(crate) fn settle_level0(&mut self, surface: bool, apply: impl FnOnce(f32)) {
        let Some(k) = self.scales.first_mut() else {
            return;
        };
        if surface {
            *k = 1.0;
            self.level0_after = self.level0_before;
        } else {
            apply(*k);
        }
    }
}

/// Level 0's scale (matched to `mesh`, never above 1; `thin`: whether it may be scaled at
/// all; `opaque_too`: whether its opaque texels are scaled too) and its rendered coverage
/// per axis after it, from its columns.
pub(crate) fn level0_scale(
    cols: &Columns,
    voxel: [f64; 3],
    mesh: &[f64; 3],
    thin: bool,
    opaque_too: bool,
) -> (f32, [f64; 3], [f64; 3]) {
    let mut model = Model::new(cols, cols.dims, voxel);
    model.opaque_scales = opaque_too;
    let before = model.coverage(1.0);
    if !thin {
        return (1.0, before, before);
    }
    let k = model.solve(mesh, (K_RANGE.0, 1.0));
    (k as f32, before, model.coverage(k))
}

/// A coarse level's scale: its rendered coverage summed over the axes equals `target`'s.
pub(crate) fn level_scale(
    cols: &Columns,
    dims0: [usize; 3],
    voxel: [f64; 3],
    target: &[f64; 3],
) -> f32 {
    Model::new(cols, dims0, voxel).solve(target, K_RANGE) as f32
}

/// [`scale_rgba8`] over a dense RGBA8 level.
pub(crate) fn scale_level_rgba8(bytes: &mut [u8], k: f32, opaque_too: bool) {
    if k == 1.0 {
        return;
    }
    let enc = Encoder::get();
    bytes.par_chunks_mut(4 * 4096).for_each(|c| {
        for px in c.chunks_exact_mut(4) {
            let v = scale_rgba8([px[0], px[1], px[2], px[3]], k, opaque_too, enc);
            px.copy_from_slice(&v);
        }
    });
}

/// [`scale_rgba8`] over a brick-sparse level's stored texels.
pub(crate) fn scale_sparse_level(level: &mut SparseLevel, k: f32, opaque_too: bool) {
    if k == 1.0 {
        return;
    }
    let enc = Encoder::get();
    level.map_colour(|c| scale_rgba8(c, k, opaque_too, enc));
}
