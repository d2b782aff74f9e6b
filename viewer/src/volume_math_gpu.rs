//! Runs the volume pass's pure WGSL functions (`shaders/volume_math.wgsl`: the slice LOD,
//! the band a slice draws, the depth fade, the slab's conversion out of extinction space; and
//! `shaders/volume_loads.wgsl`'s conversion into it) in a compute pass and reads the
//! results back — for testing them against the billow-core functions they copy
//! (`viewer/tests/volume_math_gpu.rs`), as [`crate::prism_plane_gpu`] does for the
//! prism/plane intersection.

use bytemuck::{Pod, Zeroable};

use crate::compute_check::run_cases;
use crate::{Gpu, ViewError};

/// One set of arguments.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MathCase {
    /// `slice_lod(d, v0, max_lod)`: `[d, v0, max_lod, ratio]`; `ratio` is the slab
    /// thickness of `slab_sample` and the texel size of `to_extinction`.
    pub lod: [f32; 4],
    /// `depth_fade(z, slab0, thickness)`: `[z, slab0, thickness, _]` (z ≥ 3e38: no surface).
    pub fade: [f32; 4],
    /// `slab_sample`'s filtered extinction-space sample `(σ·c, σ)`.
    pub e: [f32; 4],
    /// `to_extinction`'s premultiplied RGBA texel.
    pub c: [f32; 4],
    /// `band_holds(range, lambda)`: `[lo, hi, lambda, _]`.
    pub band: [f32; 4],
}

/// What the GPU computed for one [`MathCase`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MathOut {
    /// `[slice_lod, depth_fade, MAX_OPTICAL_DEPTH, OPAQUE_OPTICAL_DEPTH]`.
    pub scalars: [f32; 4],
    /// `slab_sample(e, ratio)`: premultiplied RGBA.
    pub slab: [f32; 4],
    /// `to_extinction(c, ratio)`: `(σ·c, σ)`, σ per level-0 texel.
    pub extinction: [f32; 4],
    /// x: `band_holds` (1 or 0).
    pub band: [f32; 4],
}

/// Evaluates each case on the GPU.
pub fn volume_math_on_gpu(gpu: &Gpu, cases: &[MathCase]) -> Result<Vec<MathOut>, ViewError> {
    run_cases(
        gpu,
        "volume_math_check.wgsl",
        &[
            include_str!("shaders/volume_math.wgsl"),
            include_str!("shaders/volume_loads.wgsl"),
            include_str!("shaders/volume_math_check.wgsl"),
        ],
        cases,
    )
}
