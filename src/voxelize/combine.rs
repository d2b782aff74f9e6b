//! Combining the six direction volumes into one (VB paper §3.2, the user function `f` of
//! Figure 3), at every MIP level.
//!
//! Inputs are the six premultiplied linear RGBA values of a voxel in the order
//! `+X, −X, +Y, −Y, +Z, −Z` (`s[0] = px` is what the camera on the +X side saw).
//!
//! Presets (`c` = premultiplied rgb, `a` = alpha, `d` runs over the six directions):
//! - `mean`:  `(Σ_d s_d) / 6` on all four channels (the paper's neutral choice);
//! - `max`:   per-channel `max_d s_d` (keeps thin features; `rgb ≤ a` holds since every
//!   `c_d ≤ a_d ≤ max a`);
//! - `min`:   per-channel `min_d s_d` (only what every direction sees);
//! - `opaque`: `a = max_d a_d`, `c = a · (Σ_d c_d) / (Σ_d a_d)` — the opacity of the most
//!   opaque view with the alpha-weighted mean of the straight colours (for leaves and
//!   other thin elements that should not turn transparent); 0 when every `a_d` is 0.
//! - `expr:...` (see [`super::expr`]) and any [`Combine`] implementation.
//!
//! Every result is clamped to a valid premultiplied value by [`clamp_premultiplied`].
//!
//! Memory: the presets are **streamed** — one direction's pyramid at a time is folded into
//! an f32 accumulator per level above 0 (4 floats per voxel; 5 for `opaque` and `min`), in
//! the fixed order above, so results do not depend on scheduling; level 0 is combined at
//! the end from the six directions' sparse level 0, one z plane at a time
//! (`combine_level0`, same order, same arithmetic), so it never needs a full-size
//! accumulator; `voxelize --prune` folds level 0 too, direction by direction, into a
//! sparse accumulator over the voxels seen (`super::level0`), and frees each stack. Expressions and custom functions need all six values at once, so the six
//! pyramids are kept, brick-sparse in f16 (8 bytes per voxel per direction), and combined
//! brick by brick (`combine_level_bricks`).

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::brick_grid::{self, for_each_voxel, local, BrickAccum, Bricked, B3};
use super::coverage::{scale_opacity, Columns};
use super::expr::{Expr, ExprError};
use super::grid3::{Disjoint, Grid3, Texel};
use super::quantize::{clamp_premultiplied, encode_normal};
use super::slices::DirSlices;
use super::toksvig::average_normal;

/// A voxel combination function. `s` is premultiplied RGBA in the order
/// `+X, −X, +Y, −Y, +Z, −Z`. The result is clamped by [`clamp_premultiplied`].
pub trait Combine: Sync {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4;
}

/// The built-in functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    Mean,
    Max,
    Min,
    Opaque,
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Mean => "mean",
            Preset::Max => "max",
            Preset::Min => "min",
            Preset::Opaque => "opaque",
        }
    }
}

impl Combine for Preset {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4 {
        match self {
            Preset::Mean => s.iter().fold(Vec4::ZERO, |a, b| a + *b) / 6.0,
            Preset::Max => s.iter().fold(s[0], |a, b| a.max(*b)),
            Preset::Min => s.iter().fold(s[0], |a, b| a.min(*b)),
            Preset::Opaque => {
                let a = s.iter().fold(0.0f32, |a, b| a.max(b.w));
                let sum = s.iter().fold(Vec4::ZERO, |a, b| a + *b);
                opaque_colour(sum.truncate(), sum.w, a)
            }
        }
    }
}

/// The value of a preset's accumulated floats `a` (see [`Accum`]) before clamping; `None`
/// where nothing is written: no direction saw the voxel (or, for `min`, not all six did).
#[inline]
pub(crate) fn finished_value(preset: Preset, a: &[f32]) -> Option<Vec4> {
    if a[..4] == [0.0; 4] {
        return None;
    }
    Some(match preset {
        Preset::Mean => Vec4::from_slice(a) / 6.0,
        Preset::Max => Vec4::from_slice(a),
        Preset::Min if a[4] < 6.0 => return None,
        Preset::Min => Vec4::from_slice(a),
        Preset::Opaque => opaque_colour(Vec3::from_slice(a), a[3], a[4]),
    })
}

fn opaque_colour(rgb_sum: Vec3, alpha_sum: f32, alpha_max: f32) -> Vec4 {
    if alpha_sum > 0.0 {
        (rgb_sum * (alpha_max / alpha_sum)).extend(alpha_max)
    } else {
        Vec4::ZERO
    }
}

/// What combines the six volumes.
#[derive(Clone)]
pub enum CombineFn {
    Preset(Preset),
    /// A parsed expression (`--combine 'expr:...'`).
    Expr(Expr),
    /// Any library-provided function.
    Custom(Arc<dyn Combine + Send + Sync>),
}

impl Default for CombineFn {
    fn default() -> Self {
        CombineFn::Preset(Preset::Mean)
    }
}

impl fmt::Debug for CombineFn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CombineFn::Preset(p) => write!(f, "{}", p.name()),
            CombineFn::Expr(e) => write!(f, "expr:{}", e.source()),
            CombineFn::Custom(_) => write!(f, "custom"),
        }
    }
}

impl fmt::Display for CombineFn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

impl Combine for CombineFn {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4 {
        match self {
            CombineFn::Preset(p) => p.combine(s),
            CombineFn::Expr(e) => e.combine(s),
            CombineFn::Custom(c) => c.combine(s),
        }
    }
}

/// Why a `--combine` argument was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CombineParseError {
    #[error(
        "unknown combine function '{0}': expected mean, max, min, opaque or expr:<expression>"
    )]
    Unknown(String),
    /// Columns are counted in the whole argument (including the `expr:` prefix), from 1.
    #[error("combine expression: {0}")]
    Expr(ExprError),
}

impl CombineParseError {
    /// Whether the argument parses but is over a size limit (see [`ExprError::too_large`]).
    pub fn too_large(&self) -> bool {
        match self {
            CombineParseError::Unknown(_) => false,
            CombineParseError::Expr(e) => e.too_large,
        }
    }
}

impl FromStr for CombineFn {
    type Err = CombineParseError;
    /// `mean | max | min | opaque | expr:<expression>`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        const PREFIX: &str = "expr:";
        match s.trim() {
            "mean" => Ok(CombineFn::Preset(Preset::Mean)),
            "max" => Ok(CombineFn::Preset(Preset::Max)),
            "min" => Ok(CombineFn::Preset(Preset::Min)),
            "opaque" => Ok(CombineFn::Preset(Preset::Opaque)),
            _ if s.starts_with(PREFIX) => Expr::parse(&s[PREFIX.len()..])
                .map(CombineFn::Expr)
                .map_err(|mut e| {
                    e.column += PREFIX.chars().count();
                    CombineParseError::Expr(e)
                }),
            other => Err(CombineParseError::Unknown(other.into())),
        }
    }
}

/// Voxels per chunk of parallel work in [`combine_level`].
const CH: usize = 4096;

/// Streaming accumulator of a preset: one brick-sparse f32 buffer per MIP level, folded one
/// direction at a time in direction order. Only the bricks some direction holds are
/// allocated, and only non-empty voxels are folded.
pub(crate) struct Accum {
    preset: Preset,
    /// Per level, `width` floats per voxel: 4 (`mean`, `max`: Σ or max rgba) or 5
    /// (`opaque`: Σ rgba, max a; `min`: min rgba, directions that saw the voxel).
    levels: Vec<BrickAccum<f32>>,
    width: usize,
}

impl Accum {
    /// Accumulators for levels of these sizes (nothing is allocated until folded).
    pub fn new(preset: Preset, level_dims: &[[usize; 3]]) -> Self {
        let width = if matches!(preset, Preset::Opaque | Preset::Min) {
            5
        } else {
            4
        };
        Accum {
            preset,
            levels: level_dims
                .iter()
                .map(|&d| BrickAccum::new(d, width))
                .collect(),
            width,
        }
    }

    /// Folds one non-empty voxel value `v` into `a`.
    #[inline]
    pub(crate) fn fold_one(preset: Preset, a: &mut [f32], v: [f32; 4]) {
        match preset {
            Preset::Mean => (0..4).for_each(|c| a[c] += v[c]),
            // Every value is ≥ 0, so a maximum starting from 0 is the maximum.
            Preset::Max => (0..4).for_each(|c| a[c] = a[c].max(v[c])),
            Preset::Min => {
                if a[4] == 0.0 {
                    a[..4].copy_from_slice(&v);
                } else {
                    (0..4).for_each(|c| a[c] = a[c].min(v[c]));
                }
                a[4] += 1.0;
            }
            Preset::Opaque => {
                (0..4).for_each(|c| a[c] += v[c]);
                a[4] = a[4].max(v[3]);
            }
        }
    }

    /// Folds one direction's volume of MIP level `level`.
    pub fn fold<T: Texel>(&mut self, level: usize, grid: &Bricked<T>) {
        let (w, preset) = (self.width, self.preset);
        let acc = &mut self.levels[level];
        acc.reserve(&grid.layout);
        acc.for_each_brick(&grid.layout, |acc, i| {
            for (a, v) in acc
                .chunks_exact_mut(w)
                .zip(&grid.data[i * B3..(i + 1) * B3])
            {
                let v = v.load();
                // Empty voxels change nothing (for `min`, they are counted as missing).
                if v == [0.0; 4] {
                    continue;
                }
                Self::fold_one(preset, a, v);
            }
        });
    }

    /// The column optical depths of level `level` as it is finished
    /// ([`super::coverage::Columns`]).
    pub fn columns(&self, level: usize) -> Columns {
        let (w, preset) = (self.width, self.preset);
        let acc = &self.levels[level];
        Columns::build(acc.dims, |bc, out| {
            let slot = acc.slot[bc[0] + acc.nb[0] * (bc[1] + acc.nb[1] * bc[2])];
            if slot == brick_grid::EMPTY {
                return false;
            }
            let brick = &acc.data[slot as usize * B3 * w..(slot as usize + 1) * B3 * w];
            for (o, a) in out.iter_mut().zip(brick.chunks_exact(w)) {
                *o = finished_value(preset, a).map_or(0.0, |v| clamp_premultiplied(v).w);
            }
            true
        })
    }

    /// The combined, clamped level with its optical depth scaled by `k`
    /// ([`Accum::coverage_scale`]), encoded RGBA8 (see [`super::quantize`]), dense; frees
    /// the level's buffer.
    pub fn finish_level(&mut self, level: usize, k: f32) -> Vec<u8> {
        let (w, preset) = (self.width, self.preset);
        let acc = std::mem::replace(&mut self.levels[level], BrickAccum::new([0; 3], w));
        let dims = acc.dims;
        let mut out = vec![0u8; dims.iter().product::<usize>() * 4];
        let enc = super::quantize::Encoder::get();
        let dst = Disjoint::new(&mut out);
        acc.data
            .par_chunks(B3 * w)
            .zip(&acc.bricks)
            .for_each(|(brick, &b)| {
                for_each_voxel(acc.coords(b as usize), dims, |p| {
                    let a = &brick[local(p) * w..local(p) * w + w];
                    let Some(v) = finished_value(preset, a) else {
                        return;
                    };
                    let i = p[0] + dims[0] * (p[1] + dims[1] * p[2]);
                    let v = scale_opacity(clamp_premultiplied(v), k);
                    // SAFETY: every voxel lies in one brick, and each brick is one task.
                    unsafe { dst.slice_mut(4 * i, 4) }
                        .copy_from_slice(&enc.rgba8(clamp_premultiplied(v)));
                });
            });
        out
    }
}

impl Accum {
    /// [`Accum::finish_level`] kept brick-sparse: the accumulator's bricks (in its slot
    /// order) and their RGBA8 bytes (`4 · B3` per brick, x fastest inside it; zero
    /// outside the level); frees the level's buffer.
    pub fn finish_level_bricks(&mut self, level: usize, k: f32) -> (Vec<u32>, Vec<u8>) {
        let (w, preset) = (self.width, self.preset);
        let acc = std::mem::replace(&mut self.levels[level], BrickAccum::new([0; 3], w));
        let dims = acc.dims;
        let mut out = vec![0u8; acc.bricks.len() * 4 * B3];
        let enc = super::quantize::Encoder::get();
        out.par_chunks_mut(4 * B3)
            .zip(acc.data.par_chunks(B3 * w))
            .zip(&acc.bricks)
            .for_each(|((o, brick), &b)| {
                for_each_voxel(acc.coords(b as usize), dims, |p| {
                    let a = &brick[local(p) * w..local(p) * w + w];
                    let Some(v) = finished_value(preset, a) else {
                        return;
                    };
                    let v = scale_opacity(clamp_premultiplied(v), k);
                    o[4 * local(p)..4 * local(p) + 4]
                        .copy_from_slice(&enc.rgba8(clamp_premultiplied(v)));
                });
            });
        (acc.bricks, out)
    }
}

/// Combines six stored pyramids' level voxel by voxel with any [`Combine`], encoded RGBA8.
pub(crate) fn combine_level<T: Texel>(f: &(dyn Combine + Sync), dirs: [&Grid3<T>; 6]) -> Vec<u8> {
    let n = dirs[0].data.len();
    let mut out = vec![0u8; n * 4];
    let enc = super::quantize::Encoder::get();
    out.par_chunks_mut(4 * CH).enumerate().for_each(|(ci, o)| {
        for (j, o) in o.chunks_exact_mut(4).enumerate() {
            let i = ci * CH + j;
            let s = dirs.map(|g| Vec4::from_array(g.data[i].load()));
            o.copy_from_slice(&enc.rgba8(clamp_premultiplied(f.combine(&s))));
        }
    });
    out
}

/// [`combine_level`] of six brick-sparse grids (one layout each): the same bytes, with
/// `f` evaluated only in the bricks some direction holds. Everywhere else all six values
/// are zero, so the voxel gets `f` of six zeros, computed once.
pub(crate) fn combine_level_bricks<T: Texel>(
    f: &(dyn Combine + Sync),
    dirs: [&Bricked<T>; 6],
) -> Vec<u8> {
    let dims = dirs[0].dims();
    let enc = super::quantize::Encoder::get();
    let voxel = |s: [Vec4; 6]| enc.rgba8(clamp_premultiplied(f.combine(&s)));
    let outside = voxel([Vec4::ZERO; 6]);
    let n = dims.iter().product::<usize>();
    let mut out = outside.repeat(n);
    let l = &dirs[0].layout;
    // Bricks held by any direction, by brick layer (z): each layer writes its own planes.
    let held: Vec<bool> = (0..l.slot.len())
        .map(|b| dirs.iter().any(|d| d.layout.slot[b] != brick_grid::EMPTY))
        .collect();
    let layer = l.nb[0] * l.nb[1];
    let plane = 4 * dims[0] * dims[1];
    out.par_chunks_mut(plane * brick_grid::B)
        .enumerate()
        .for_each(|(bz, o)| {
            for b in (bz * layer..(bz + 1) * layer).filter(|&b| held[b]) {
                let slots = dirs.map(|d| d.layout.slot[b]);
                for p in brick_grid::voxels_of(l.coords(b), dims) {
                    let s = std::array::from_fn(|d| match slots[d] {
                        brick_grid::EMPTY => Vec4::ZERO,
                        slot => {
                            Vec4::from_array(dirs[d].data[slot as usize * B3 + local(p)].load())
                        }
                    });
                    let i = 4 * (p[0] + dims[0] * (p[1] + dims[1] * (p[2] - bz * brick_grid::B)));
                    o[i..i + 4].copy_from_slice(&voxel(s));
                }
            }
        });
    out
}

/// How many voxels ahead [`combine_level0`] asks for the scattered reads of a plane.
const PREFETCH: usize = 16;

/// A hint that `x` will be read soon (no effect on the result).
#[inline(always)]
fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults and does not change memory; SSE is baseline on
    // x86_64.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// Level 0 of a preset combination, straight from the six directions' sparse level 0
/// (in [`super::Dir::ALL`] order), one z plane at a time: each plane's voxels of the six
/// directions are folded into a small plane-sized accumulator (in direction order, as
/// [`Accum`] does) and encoded RGBA8 at once, so level 0 never has a full-size
/// accumulator. With `normals`, also the plane's Toksvig normals (`Σ Nw / Σ α`, snorm8).
/// Also returns the number of voxels whose alpha byte is not 0.
pub(crate) fn combine_level0(
    preset: Preset,
    dirs: &[DirSlices],
    normals: bool,
) -> (Vec<u8>, Option<Vec<u8>>, u64) {
    let dims = dirs[0].dims;
    let plane = dims[0] * dims[1];
    let ((out, out_n), count) = level0_planes(preset, dirs, normals, |init, work| {
        let mut out = vec![0u8; plane * dims[2] * 4];
        let mut out_n = normals.then(|| vec![0u8; plane * dims[2] * 4]);
        match out_n.as_mut() {
            Some(on) => out
                .par_chunks_mut(plane * 4)
                .zip(on.par_chunks_mut(plane * 4))
                .enumerate()
                .for_each_init(init, |b, (z, (o, on))| work(b, z, o, Some(on))),
            None => out
                .par_chunks_mut(plane * 4)
                .enumerate()
                .for_each_init(init, |b, (z, o)| work(b, z, o, None)),
        }
        (out, out_n)
    });
    (out, out_n, count)
}

/// Per thread, the plane accumulators of [`level0_planes`] (left zeroed after each plane)
/// and the plane indices folded into (a voxel is listed when it is first folded into,
/// possibly more than once if a fold leaves it zero, which is harmless).
type Level0Bufs = (Vec<f32>, Vec<[f32; 4]>, Vec<u32>);

/// The plane work of [`combine_level0`]: `drive(init, work)` calls `work(bufs, z, o, on)`
/// for every z plane (`o`, `on`: the plane's zeroed RGBA8 and snorm8 bytes, written there)
/// with `bufs` from `init`, in any order and on any thread; returns what `drive` returns
/// and the number of voxels whose alpha byte is not 0.
#[allow(clippy::type_complexity)]
fn level0_planes<R>(
    preset: Preset,
    dirs: &[DirSlices],
    normals: bool,
    drive: impl FnOnce(
        &(dyn Fn() -> Level0Bufs + Sync),
        &(dyn Fn(&mut Level0Bufs, usize, &mut [u8], Option<&mut [u8]>) + Sync),
    ) -> R,
) -> (R, u64) {
    let dims = dirs[0].dims;
    let plane = dims[0] * dims[1];
    let w = if matches!(preset, Preset::Opaque | Preset::Min) {
        5
    } else {
        4
    };
    // Per direction, per z plane: (index in the plane, index in `vox`) of its voxels.
    // Directions whose image rows are z planes need no table (their row z is the plane).
    // (start of each plane's run, (index in the plane, index in `vox`)).
    let by_plane: Vec<Option<Table>> = dirs
        .par_iter()
        .map(|s| (s.dir.image_axes()[1] != 2).then(|| plane_table(s, dims)))
        .collect();
    let enc = super::quantize::Encoder::get();
    let init = || -> Level0Bufs {
        (
            vec![0.0f32; plane * w],
            vec![[0.0f32; 4]; plane * normals as usize],
            Vec::new(),
        )
    };
    let non_empty = std::sync::atomic::AtomicU64::new(0);
    let work =
        |(acc, nacc, list): &mut Level0Bufs, z: usize, o: &mut [u8], mut on: Option<&mut [u8]>| {
            list.clear();
            let mut count = 0u64;
            for (s, table) in dirs.iter().zip(&by_plane) {
                let nrm = s.nrm.as_deref();
                let mut fold = |i: usize, k: usize| {
                    let v = &s.vox[k];
                    let a = &mut acc[i * w..i * w + w];
                    if a[..4] == [0.0; 4] {
                        list.push(i as u32);
                    }
                    Accum::fold_one(preset, a, v.rgba);
                    if let Some(n) = nrm {
                        let (n, a) = (n[k], &mut nacc[i]);
                        *a = [a[0] + n[0], a[1] + n[1], a[2] + n[2], a[3] + v.rgba[3]];
                    }
                };
                match table {
                    None => {
                        let (row, first) = s.row(z);
                        for (k, v) in row.iter().enumerate() {
                            fold(s.index(z, v) - z * plane, first + k);
                        }
                    }
                    Some((start, list)) => {
                        // The plane's voxels lie scattered over the whole stack (one per
                        // column at most): their reads are issued ahead of their use.
                        let run = &list[start[z]..start[z + 1]];
                        for (at, &(i, k)) in run.iter().enumerate() {
                            if let Some(&(_, ahead)) = run.get(at + PREFETCH) {
                                prefetch(&s.vox[ahead as usize]);
                                if let Some(n) = nrm {
                                    prefetch(&n[ahead as usize]);
                                }
                            }
                            fold(i as usize, k as usize);
                        }
                    }
                }
            }
            // Only the voxels folded into are finished (and left zeroed); the others stay 0.
            for &i in list.iter() {
                let i = i as usize;
                let a = &mut acc[i * w..i * w + w];
                if a[..4] != [0.0; 4] {
                    let v = match preset {
                        Preset::Mean => Vec4::from_slice(a) / 6.0,
                        Preset::Max => Vec4::from_slice(a),
                        Preset::Min if a[4] < 6.0 => Vec4::ZERO,
                        Preset::Min => Vec4::from_slice(a),
                        Preset::Opaque => opaque_colour(Vec3::from_slice(a), a[3], a[4]),
                    };
                    let px = enc.rgba8(clamp_premultiplied(v));
                    count += u64::from(px[3] != 0);
                    o[4 * i..4 * i + 4].copy_from_slice(&px);
                }
                a.fill(0.0);
                if let Some(on) = on.as_deref_mut() {
                    let a = &mut nacc[i];
                    if *a == [0.0; 4] {
                        continue;
                    }
                    let n = average_normal(Vec3::new(a[0], a[1], a[2]), a[3]);
                    *a = [0.0; 4];
                    on[4 * i..4 * i + 4].copy_from_slice(&encode_normal(n));
                }
            }
            non_empty.fetch_add(count, std::sync::atomic::Ordering::Relaxed);
        };
    let r = drive(&init, &work);
    (r, non_empty.into_inner())
}

/// A direction's voxels bucketed by z plane (a counting sort), in row order, so each
/// plane's keys increase: (start of each plane's run, (index in the plane, index in
/// `vox`)). For directions whose image rows are not z planes (view axis z).
pub(super) type Table = (Vec<usize>, Vec<(u32, u32)>);

pub(super) fn plane_table(s: &DirSlices, dims: [usize; 3]) -> Table {
    let plane = dims[0] * dims[1];
    let mut start = vec![0usize; dims[2] + 1];
    for v in &s.vox {
        start[v.s as usize + 1] += 1;
    }
    for z in 0..dims[2] {
        start[z + 1] += start[z];
    }
    let mut fill = start.clone();
    let mut list = vec![(0u32, 0u32); s.vox.len()];
    for j in 0..s.row_count() {
        let (row, first) = s.row(j);
        for (k, v) in row.iter().enumerate() {
            let z = v.s as usize;
            list[fill[z]] = ((s.index(j, v) - z * plane) as u32, (first + k) as u32);
            fill[z] += 1;
        }
    }
    (start, list)
}

impl Combine for Expr {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4 {
        self.eval(s)
    }
}
