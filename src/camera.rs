//! The camera: moved to the shared rendering core ([`billow_core::camera`], one
//! implementation for the CPU evaluator and the viewer); re-exported here under its old
//! path so that `billow::camera::…` keeps compiling.

pub use billow_core::camera::*;
