//! billow: bakes meshes into image-based level-of-detail assets.
pub mod bbcloud;
pub mod bvh;
pub mod camera;
pub mod compress;
pub mod emptyspace;
pub mod eval;
pub mod export;
pub mod import;
pub mod inspect;
pub mod noise_volume;
pub mod presets;
pub mod procgen;
pub mod provenance;
pub mod rng;
pub mod scene;
pub(crate) mod shade;
pub mod shell;
pub mod texture;
pub mod voxelize;

/// The one skip rule for checks that cannot run here (feature `test-support`).
#[cfg(any(test, feature = "test-support"))]
pub mod test_support;
