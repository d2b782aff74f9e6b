//! Where the slices go: the CPU side of the slicing. The planning itself (spacing, `v₀`,
//! slice depths) is the shared core's ([`billow_core::slicing`]), the one the CPU slicer
//! `billow::eval::slicer` uses, so the GPU draws the same slices; this module adds the
//! viewer's parameters ([`SliceParams`]).
//!
//! - `v₀` ([`billow_core::slicing::voxel_size`]): the world size of a level-0 voxel, minimum over the cells.
//! - Adaptive spacing at depth `z`: `d(z) = bias · max(pixel_size(z), v₀)`; uniform: `d`.
//! - Slices front to back from the nearest cell depth: `z₀ = z_min + d(z_min)/2`,
//!   `z_{i+1} = z_i + d(z_i)` while `z < z_max`, then drawn back to front.
//! - Per slice (on the GPU, per texture): `lod = clamp(log2(d/v₀), 0, levels−1)`,
//!   opacity correction ratio `d / (v₀·2^lod)`.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use billow_core::slicing::Spacing;

use crate::ViewError;

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
            Spacing::Adaptive { bias } if !crate::limits::spacing_factor_ok(bias) => Err(
                ViewError::InvalidParam(format!("spacing bias {bias} must be > 0")),
            ),
            Spacing::Uniform { spacing } if !crate::limits::spacing_factor_ok(spacing) => Err(
                ViewError::InvalidParam(format!("spacing {spacing} must be > 0")),
            ),
            _ => Ok(()),
        }?;
        crate::limits::check_slab_min_slices(self.slab_min_slices)
            .map_err(|e| ViewError::InvalidParam(format!("slab_min_slices: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_without_slices_is_refused() {
        let zero = SliceParams {
            slab_min_slices: 0,
            ..SliceParams::default()
        };
        assert!(
            matches!(zero.validate(), Err(ViewError::InvalidParam(m)) if m == "slab_min_slices: must be at least 1")
        );
        let one = SliceParams {
            slab_min_slices: 1,
            ..SliceParams::default()
        };
        assert!(one.validate().is_ok());
    }
}
