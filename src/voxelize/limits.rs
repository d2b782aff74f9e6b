//! The ranges of [`VoxelizeOptions`](super::VoxelizeOptions)' fields beside the grid's
//! resolution and margin ([`super::grid`]), each declared once:
//! [`VoxelizeOptions::validate`](super::VoxelizeOptions::validate) (and so
//! [`super::voxelize`] and [`super::bake()`]) refuses a value outside them with an
//! [`OptionError`] that names the field, and `billow voxelize` checks its flags with the
//! same functions, printing the error after the flag's name
//! (`--align: must be between 1 and 2048 voxels, got 0`).

use billow_core::Aabb;

/// Largest number of voxels along one axis, and the largest
/// [`VoxelizeOptions::align`](super::VoxelizeOptions::align).
pub const MAX_AXIS: u32 = 2048;
/// Largest number of AO rays per voxel ([`super::Bake::Ao`]).
pub const MAX_AO_RAYS: u32 = 4096;

/// An option outside its range. The message says the problem only; [`OptionError::option`]
/// names the field it is about, so a caller can put its own name for it in front.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum OptionError {
    /// `align` outside `1..=`[`MAX_AXIS`].
    #[error("must be between 1 and {MAX_AXIS} voxels, got {0}")]
    Align(u32),
    /// A memory limit that is not a positive number of GiB ([`memory_limit_bytes`]), or
    /// a `memory_limit` of 0 bytes.
    #[error("must be a positive number of GiB, got {0}")]
    MemoryLimit(f64),
    /// AO rays outside `1..=`[`MAX_AO_RAYS`].
    #[error("must be between 1 and {MAX_AO_RAYS}, got {0}")]
    AoRays(u32),
    /// An AO distance that is not a positive number.
    #[error("must be a positive number, got {0}")]
    AoDistance(f32),
    /// Explicit bounds with a corner that is not finite.
    #[error("expected six finite numbers minx,miny,minz,maxx,maxy,maxz")]
    BoundsNotFinite,
    /// Explicit bounds whose min is not below their max on every axis.
    #[error("min must be below max on every axis")]
    BoundsEmpty,
}

impl OptionError {
    /// The field of [`VoxelizeOptions`](super::VoxelizeOptions) at fault (`bake.rays` for
    /// [`super::Bake::Ao`]'s `rays`).
    pub fn option(&self) -> &'static str {
        match self {
            OptionError::Align(_) => "align",
            OptionError::MemoryLimit(_) => "memory_limit",
            OptionError::AoRays(_) => "bake.rays",
            OptionError::AoDistance(_) => "bake.distance",
            OptionError::BoundsNotFinite | OptionError::BoundsEmpty => "bounds",
        }
    }
}

/// An alignment is `1..=`[`MAX_AXIS`] voxels.
pub fn check_align(align: u32) -> Result<(), OptionError> {
    if (1..=MAX_AXIS).contains(&align) {
        Ok(())
    } else {
        Err(OptionError::Align(align))
    }
}

/// A memory limit given in GiB (`--memory-limit`) as the bytes of
/// [`VoxelizeOptions::memory_limit`](super::VoxelizeOptions::memory_limit): it must be a
/// positive number; at least 1 byte, at most `u64::MAX`.
pub fn memory_limit_bytes(gib: f64) -> Result<u64, OptionError> {
    if !(gib.is_finite() && gib > 0.0) {
        return Err(OptionError::MemoryLimit(gib));
    }
    Ok(((gib * (1u64 << 30) as f64).min(u64::MAX as f64) as u64).max(1))
}

/// A memory limit in bytes is positive (what [`memory_limit_bytes`] gives).
pub fn check_memory_limit(bytes: u64) -> Result<(), OptionError> {
    if bytes > 0 {
        Ok(())
    } else {
        Err(OptionError::MemoryLimit(0.0))
    }
}

/// AO rays per voxel are `1..=`[`MAX_AO_RAYS`].
pub fn check_ao_rays(rays: u32) -> Result<(), OptionError> {
    if (1..=MAX_AO_RAYS).contains(&rays) {
        Ok(())
    } else {
        Err(OptionError::AoRays(rays))
    }
}

/// An AO distance is a positive number (scene units).
pub fn check_ao_distance(distance: f32) -> Result<(), OptionError> {
    if distance.is_finite() && distance > 0.0 {
        Ok(())
    } else {
        Err(OptionError::AoDistance(distance))
    }
}

/// Explicit bounds are finite, their min below their max on every axis.
pub fn check_bounds(b: &Aabb) -> Result<(), OptionError> {
    if !(b.min.is_finite() && b.max.is_finite()) {
        Err(OptionError::BoundsNotFinite)
    } else if !b.min.cmplt(b.max).all() {
        Err(OptionError::BoundsEmpty)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn align_is_one_to_max_axis() {
        assert_eq!(check_align(0), Err(OptionError::Align(0)));
        assert_eq!(
            check_align(MAX_AXIS + 1),
            Err(OptionError::Align(MAX_AXIS + 1))
        );
        assert_eq!(check_align(1), Ok(()));
        assert_eq!(check_align(MAX_AXIS), Ok(()));
    }

    #[test]
    fn memory_limit_is_positive() {
        for gib in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                memory_limit_bytes(gib),
                Err(OptionError::MemoryLimit(_))
            ));
        }
        assert_eq!(memory_limit_bytes(0.5), Ok(1 << 29));
        assert_eq!(memory_limit_bytes(1e-30), Ok(1));
        assert_eq!(check_memory_limit(0), Err(OptionError::MemoryLimit(0.0)));
        assert_eq!(check_memory_limit(1), Ok(()));
    }

    #[test]
    fn ao_rays_and_distance() {
        assert_eq!(check_ao_rays(0), Err(OptionError::AoRays(0)));
        assert_eq!(
            check_ao_rays(MAX_AO_RAYS + 1),
            Err(OptionError::AoRays(MAX_AO_RAYS + 1))
        );
        assert_eq!(check_ao_rays(1), Ok(()));
        assert_eq!(check_ao_distance(0.0), Err(OptionError::AoDistance(0.0)));
        assert!(check_ao_distance(f32::NAN).is_err());
        assert!(check_ao_distance(f32::INFINITY).is_err());
        assert_eq!(check_ao_distance(0.25), Ok(()));
    }

    #[test]
    fn bounds_are_finite_and_not_empty() {
        let b = |min: [f32; 3], max: [f32; 3]| Aabb {
            min: Vec3::from(min),
            max: Vec3::from(max),
        };
        assert_eq!(
            check_bounds(&b([0.0; 3], [1.0, 1.0, f32::INFINITY])),
            Err(OptionError::BoundsNotFinite)
        );
        assert_eq!(
            check_bounds(&b([f32::NAN, 0.0, 0.0], [1.0; 3])),
            Err(OptionError::BoundsNotFinite)
        );
        assert_eq!(
            check_bounds(&b([0.0; 3], [1.0, 1.0, 0.0])),
            Err(OptionError::BoundsEmpty)
        );
        assert_eq!(
            check_bounds(&b([1.0; 3], [0.0; 3])),
            Err(OptionError::BoundsEmpty)
        );
        assert_eq!(check_bounds(&b([0.0; 3], [1.0; 3])), Ok(()));
    }

    #[test]
    fn messages_name_the_problem() {
        assert_eq!(
            OptionError::Align(0).to_string(),
            "must be between 1 and 2048 voxels, got 0"
        );
        assert_eq!(OptionError::AoRays(0).option(), "bake.rays");
    }
}
