//! The light a volume lets through to itself, for `billow eval --shadows`: per texel of
//! one coarse MIP level, the transmittance towards the light, `T = Π (1 − αₖ)` over the
//! level's opacity sampled one texel apart along the light (each level's alpha is the
//! opacity of one of its texels' thickness, VB paper §3.2), from [`BIAS`] level-0 texels
//! away (a surface one texel thick must not shadow itself: trilinear taps one texel away
//! still read it) to where the ray leaves the volume. The CPU slicer scales the
//! direct light of every shaded sample by `T` at its texture coordinate (trilinear).
//!
//! This is the volume's own occlusion under an ideal renderer, not the viewer's shadow
//! map (slices from the light, each occluding where its opacity reaches a cut-off, 3×3
//! PCF; docs/viewer.md, "Shadows"): eval measures what the asset can show, the viewer's
//! shadow slices are calibrated against the mesh separately. Only a plain volume is
//! shadowed: one box of cells mapping world space affinely onto `[0, 1]³`, no LOD bands
//! (pruned assets), no repeat (shells); [`ShadowGrid::for_volume`] says `None` otherwise.

use billow_format::Prism;
use glam::Vec3;
use rayon::prelude::*;

use super::volume_sampler::DecodedVolume;

/// The finest level whose largest side is at most this many texels is marched.
pub const MAX_SIDE: u32 = 64;

/// Level-0 texels between a point and the first sample towards the light (the shadow's
/// bias; in the marched level's texels, `BIAS / 2^level`).
pub const BIAS: f32 = 1.5;

/// Transmittance towards the light at the texel centres of one MIP level.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowGrid {
    dims: [usize; 3],
    t: Vec<f32>,
}

/// The box the cells cover, when they map world space affinely onto `[0, 1]³` (each
/// vertex's `uvw` is `(p − min) / (max − min)`): `(min, max)`.
fn cell_box(cells: &[Prism]) -> Option<(Vec3, Vec3)> {
    let pts = || {
        cells
            .iter()
            .flat_map(|c| c.pos.iter().map(|&p| Vec3::from(p)))
    };
    let lo = pts().fold(Vec3::INFINITY, Vec3::min);
    let hi = pts().fold(Vec3::NEG_INFINITY, Vec3::max);
    let size = hi - lo;
    if cells.is_empty() || size.min_element() <= 0.0 || !size.is_finite() {
        return None;
    }
    let affine = cells.iter().all(|c| {
        c.pos.iter().zip(&c.uvw).all(|(&p, &uvw)| {
            let want = (Vec3::from(p) - lo) / size;
            (want - Vec3::from(uvw)).abs().max_element() < 1e-4
        })
    });
    affine.then_some((lo, hi))
}

/// Whether [`ShadowGrid::for_volume`] can shadow `vol` drawn by `cells` (a plain volume).
pub fn shadowable(vol: &DecodedVolume, cells: &[Prism]) -> bool {
    vol.bands.is_empty()
        && !vol.repeat.iter().any(|&r| r)
        && !vol.levels.is_empty()
        && cell_box(cells).is_some()
}

impl ShadowGrid {
    /// The grid of `vol` (drawn by `cells`) lit from the world direction `light` (towards
    /// the light); `None` for anything but a plain volume (module docs) or a zero light.
    pub fn for_volume(vol: &DecodedVolume, cells: &[Prism], light: Vec3) -> Option<ShadowGrid> {
        if !shadowable(vol, cells) {
            return None;
        }
        let (lo, hi) = cell_box(cells)?;
        let level = vol
            .levels
            .iter()
            .position(|l| l.dims.iter().all(|&d| d <= MAX_SIDE))
            .unwrap_or(vol.levels.len() - 1);
        let dims = vol.levels[level].dims.map(|d| d as usize);
        // The light in the level's texel units: world → uvw divides by the box, uvw →
        // texels multiplies by the level's size.
        let texels_per_unit = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / (hi - lo);
        let step = (light * texels_per_unit).normalize_or_zero();
        if step == Vec3::ZERO || !step.is_finite() {
            return None;
        }
        let n = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
        let bias = BIAS / (level as f32).exp2();
        let plane = dims[0] * dims[1];
        let mut t = vec![1.0f32; plane * dims[2]];
        t.par_chunks_mut(plane).enumerate().for_each(|(z, out)| {
            for (i, cell) in out.iter_mut().enumerate() {
                let (x, y) = (i % dims[0], i / dims[0]);
                let mut p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 + bias * step;
                let mut trans = 1.0f32;
                while p.cmpge(Vec3::ZERO).all() && p.cmplt(n).all() && trans > 1e-4 {
                    let a = vol.sample_level(level, p / n).w.clamp(0.0, 1.0);
                    trans *= 1.0 - a;
                    p += step;
                }
                *cell = trans;
            }
        });
        Some(ShadowGrid { dims, t })
    }

    /// Transmittance at `uvw` (`[0, 1]³`), trilinear between texel centres, clamped to
    /// the edge.
    pub fn sample(&self, uvw: Vec3) -> f32 {
        let [nx, ny, nz] = self.dims;
        let q = uvw * Vec3::new(nx as f32, ny as f32, nz as f32) - 0.5;
        let i0 = q.floor();
        let f = q - i0;
        let at = |d: usize, i: f32| (i.max(0.0) as usize).min(d - 1);
        let mut v = 0.0;
        for (dz, wz) in [(0.0, 1.0 - f.z), (1.0, f.z)] {
            for (dy, wy) in [(0.0, 1.0 - f.y), (1.0, f.y)] {
                for (dx, wx) in [(0.0, 1.0 - f.x), (1.0, f.x)] {
                    let (x, y, z) = (at(nx, i0.x + dx), at(ny, i0.y + dy), at(nz, i0.z + dz));
                    v += wx * wy * wz * self.t[(z * ny + y) * nx + x];
                }
            }
        }
        v
    }
}
