//! Accuracy evaluation: a reference ray tracer of the source scene, a CPU slicer for
//! volume assets (VB paper §3.3), image metrics and image output.
//!
//! Every image here is **premultiplied linear RGBA, f32**, transparent background
//! ([`image::ImageF32`]). The camera conventions are in [`billow_core::camera`].
//!
//! `billow eval` as one call is [`evaluate()`] ([`evaluate::EvaluateOptions`] in, an
//! [`evaluate::Evaluation`] out); [`suite`] holds its parts.

pub mod banding;
pub mod cloud_render;
pub mod error;
pub mod evaluate;
pub mod image;
pub mod lighting;
pub mod limits;
pub mod lod_sweep;
pub mod metrics;
pub mod reference;
mod slice_raster;
pub mod slicer;
pub mod ssim;
pub mod suite;
pub mod volume_sampler;
pub mod volume_shadow;

pub use error::EvalError;
pub use evaluate::evaluate;
pub use image::ImageF32;
