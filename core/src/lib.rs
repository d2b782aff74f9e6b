//! billow-core: the pure rendering math that billow's CPU evaluator (`billow::eval`, the
//! reference renderers) and its GPU viewer (`billow-view`) both use, written once so the
//! two cannot drift apart:
//!
//! - [`camera`]: the pinhole camera, its view and projection matrices, primary rays,
//!   framing and the evaluation view set;
//! - [`slicing`]: slice planning of volumetric billboards (voxel size, adaptive slice
//!   depths, the per-cell normal matrix);
//! - [`compositing`]: premultiplied "over"/"under" and opacity correction;
//! - [`extinction`]: the extinction space volume texels are filtered in (thin layers
//!   stay opaque);
//! - [`prism_plane`]: the prism/plane intersection (VB paper Appendix A);
//! - [`ray_triangle`]: the watertight ray/triangle test;
//! - [`cells`]: a box as the two prism cells of a volumetric billboard;
//! - [`shading`]: the two Lambert lighting models (leaf cards/meshes, volume voxels);
//! - [`Aabb`]: the axis-aligned box the camera frames.
//!
//! **This is not a second contract between baker and viewer.** The asset contract stays
//! the format crate (`billow-format`, `formats/SPEC.md`): what a file holds and means.
//! This crate holds only math, no I/O, no GPU, no images; it depends on glam and on the
//! format crate for its cell type ([`billow_format::Prism`]) alone. The viewer's WGSL
//! shaders keep their own GPU code (tested against these functions).
//!
//! The library and the viewer call these by their paths here (`billow_core::camera`,
//! `crate::prism_plane`, `billow_core::Aabb`, …); the library keeps no re-exports
//! of them.

pub mod aabb;
pub mod camera;
pub mod cells;
pub mod compositing;
pub mod extinction;
pub mod gpu_memory;
pub mod prism_plane;
pub mod ray_triangle;
pub mod shading;
pub mod slicing;

pub use aabb::Aabb;
