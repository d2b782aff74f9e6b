//! billow: bakes meshes into image-based level-of-detail assets.
//!
//! What `billow voxelize --prune` does, from Rust ([`voxelize::bake()`]; a full program
//! that also evaluates the result with [`eval::evaluate()`], `billow eval` as one call, is
//! `examples/bake_from_rust.rs`):
//!
//! ```no_run
//! use std::path::Path;
//!
//! use billow::import::{import, ImportOptions};
//! use billow::voxelize::{bake, BakeHooks, BakeOptions, Resolution};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = import(Path::new("tree.gltf"), &ImportOptions::default())?.scene;
//! // `billow voxelize --res 96 --prune`: normals auto (moments), BC7.
//! let opts = BakeOptions {
//!     prune: true,
//!     ..BakeOptions::at(Resolution::Longest(96))
//! };
//! let baked = bake(&scene, &opts, &BakeHooks::default())?;
//! std::fs::write("tree.billow", baked.asset.to_bytes_with(baked.blocks.as_ref())?)?;
//! # Ok(())
//! # }
//! ```
pub mod bbcloud;
pub mod bvh;
pub mod compress;
pub mod emptyspace;
pub mod eval;
pub mod export;
pub mod import;
pub mod inspect;
pub(crate) mod material;
/// Procedural noise volumes for tests and examples (feature `test-support`).
#[cfg(any(test, feature = "test-support"))]
pub mod noise_volume;
pub mod presets;
/// Procedural meshes (trees, tori, fur, trusses) for tests, examples and the gallery
/// (feature `test-support`).
#[cfg(any(test, feature = "test-support"))]
pub mod procgen;
pub mod provenance;
pub mod rng;
pub mod scene;
pub mod shell;
pub mod sparse_level;
pub mod target_error;
pub mod texture;
pub mod voxelize;

/// The one skip rule for checks that cannot run here (feature `test-support`).
#[cfg(any(test, feature = "test-support"))]
pub mod test_support;
