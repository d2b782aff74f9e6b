//! Where the slices go: the CPU side of the slicing, a port of `billow::eval::slicer`
//! (same formulas, same f32 operations, so the GPU draws the same slices).
//!
//! - `v₀` ([`voxel_size`]): the world size of a level-0 voxel, minimum over the cells.
//! - Adaptive spacing at depth `z`: `d(z) = bias · max(pixel_size(z), v₀)`; uniform: `d`.
//! - Slices front to back from the nearest cell depth: `z₀ = z_min + d(z_min)/2`,
//!   `z_{i+1} = z_i + d(z_i)` while `z < z_max`, then drawn back to front.
//! - Per slice (on the GPU, per texture): `lod = clamp(log2(d/v₀), 0, levels−1)`,
//!   opacity correction ratio `d / (v₀·2^lod)`.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use billow_format::Prism;
use glam::{Mat3, Vec3};

use crate::{ViewCamera, ViewError};

/// Slice spacing mode (as `billow::eval::slicer::Spacing`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spacing {
    /// The paper's adaptive spacing scaled by `bias` (1 = paper).
    Adaptive { bias: f32 },
    /// Constant world-space spacing.
    Uniform { spacing: f32 },
}

impl Spacing {
    /// The same mode with slices `f` times farther apart.
    pub fn scaled(self, f: f32) -> Spacing {
        match self {
            Spacing::Adaptive { bias } => Spacing::Adaptive { bias: bias * f },
            Spacing::Uniform { spacing } => Spacing::Uniform {
                spacing: spacing * f,
            },
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceParams {
    pub spacing: Spacing,
    /// Refuse to render more slices than this.
    pub max_slices: usize,
    /// Slab partitioning ([`crate::slab`]); off: every cell meets every slice (the
    /// paper's plain slicing).
    pub partition: bool,
    /// Fewest slices a slab holds.
    pub slab_min_slices: u32,
}

impl Default for SliceParams {
    fn default() -> Self {
        SliceParams {
            spacing: Spacing::Adaptive { bias: 1.0 },
            max_slices: 100_000,
            partition: true,
            slab_min_slices: 16,
        }
    }
}

impl SliceParams {
    pub fn validate(&self) -> Result<(), ViewError> {
        match self.spacing {
            Spacing::Adaptive { bias } if !(bias > 0.0 && bias.is_finite()) => Err(
                ViewError::InvalidParam(format!("spacing bias {bias} must be > 0")),
            ),
            Spacing::Uniform { spacing } if !(spacing > 0.0 && spacing.is_finite()) => Err(
                ViewError::InvalidParam(format!("spacing {spacing} must be > 0")),
            ),
            _ => Ok(()),
        }
    }
}

/// World size of a level-0 voxel (`billow::eval::slicer::voxel_size`): per cell
/// `cbrt(|det P| / |det T| / (w·h·d))`, the minimum over the cells.
pub fn voxel_size(cells: &[Prism], dims: [u32; 3]) -> Option<f32> {
    let n = f64::from(dims[0]) * f64::from(dims[1]) * f64::from(dims[2]);
    let mut best: Option<f32> = None;
    for c in cells {
        let p = |i: usize| Vec3::from(c.pos[i]) - Vec3::from(c.pos[0]);
        let t = |i: usize| Vec3::from(c.uvw[i]) - Vec3::from(c.uvw[0]);
        let pm = Mat3::from_cols(p(1), p(2), p(3));
        let tm = Mat3::from_cols(t(1), t(2), t(3));
        let dt = f64::from(tm.determinant());
        if dt.abs() < 1e-12 {
            continue;
        }
        let v = (f64::from(pm.determinant()) / dt).abs() / n;
        let s = v.cbrt() as f32;
        if s > 0.0 && s.is_finite() {
            best = Some(best.map_or(s, |b| b.min(s)));
        }
    }
    best
}

/// Slice depths and spacings `(depth, d)`, **front to back**, over `[z_min, z_max]`.
pub fn slice_depths(
    camera: &ViewCamera,
    spacing: Spacing,
    v0: f32,
    z_min: f32,
    z_max: f32,
    limit: usize,
) -> Result<Vec<(f32, f32)>, ViewError> {
    let d_at = |z: f32| match spacing {
        Spacing::Adaptive { bias } => bias * camera.pixel_size_at(z).max(v0),
        Spacing::Uniform { spacing } => spacing,
    };
    let mut out = Vec::new();
    let mut z = z_min + 0.5 * d_at(z_min);
    while z < z_max {
        if out.len() >= limit {
            let needed = ((z_max - z_min) / d_at(z_min).max(f32::MIN_POSITIVE)) as usize;
            return Err(ViewError::TooManySlices {
                needed: needed.max(limit + 1),
                limit,
            });
        }
        let d = d_at(z);
        out.push((z, d));
        let next = z + d;
        if !(next > z) {
            break;
        }
        z = next;
    }
    Ok(out)
}
