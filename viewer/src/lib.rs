//! `billow-view`: the viewer's renderer (wgpu). Volume assets are drawn with the GPU
//! slicing of Volumetric Billboards (Decaudin & Neyret 2009, §3.3): all cells of all
//! instances at once, slices parallel to the screen back to front, adaptive spacing,
//! opacity correction and slab partitioning, exactly as the CPU slicer of
//! `billow::eval::slicer` (the reference the tests compare with), prism/plane
//! intersection in WGSL. Billboard clouds (Lacewell et al. 2006) morph between their
//! LODs; opaque meshes share the z-buffer; a directional shadow map when asked for.
//!
//! Conventions are those of `billow_core::camera` (view space looks down −Z, wgpu clip
//! space, row 0 at the top). This crate does not depend on the `billow` library (the
//! `billow` binary depends on this crate, and a package cannot depend on itself): the
//! binary converts its camera with [`ViewCamera::from_parts`] and imports meshes itself.
//!
//! Images are premultiplied linear RGBA f32, like `billow::eval::ImageF32`.

pub mod animate;
pub mod camera;
pub mod cloud_pass;
#[cfg(any(test, feature = "test-support"))]
mod compute_check;
pub mod content;
pub mod dolly;
pub mod error;
pub mod frame_stats;
pub mod gpu;
pub mod layout;
pub mod limits;
pub mod lines;
pub mod mesh_pass;
pub mod overlay;
pub mod particle_layer;
pub mod particle_pass;
pub mod particles;
/// Test support (feature `test-support`, on for the viewer's own tests): not part of the API.
#[cfg(any(test, feature = "test-support"))]
pub mod prism_plane_gpu;
pub mod render;
pub mod scene;
/// Test support (feature `test-support`, on for the viewer's own tests): not part of the API.
#[cfg(any(test, feature = "test-support"))]
pub mod shading_gpu;
pub mod shadow;
/// Test support (feature `test-support`, on for the viewer's own tests): not part of the API.
#[cfg(any(test, feature = "test-support"))]
pub mod shadow_gpu;
pub mod slab;
pub mod slice_plan;
pub mod target;
pub mod texture;
pub mod texture_bc;
/// Test support (feature `test-support`, on for the viewer's own tests): not part of the API.
#[cfg(any(test, feature = "test-support"))]
pub mod volume_math_gpu;
pub mod volume_pass;
pub mod volume_plan;
pub mod window;

pub use camera::ViewCamera;
pub use error::ViewError;
pub use frame_stats::FrameStats;
pub use gpu::Gpu;
pub use render::Renderer;
pub use slice_plan::SliceParams;
pub use target::RgbaImage;
