//! Runs the mesh and cloud passes' light model (`shaders/shading.wgsl`'s
//! `diffuse_factor`) in a compute pass and reads the results back — for testing it
//! against the billow-core function it copies (`viewer/tests/shading_gpu.rs`), as
//! [`crate::volume_math_gpu`] does for the volume pass's functions.

use bytemuck::{Pod, Zeroable};

use crate::compute_check::run_cases;
use crate::{Gpu, ViewError};

/// One set of arguments of `diffuse_factor(n, light, ambient, visibility)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadingCase {
    /// `[n.x, n.y, n.z, ambient]`, `n` unit.
    pub n: [f32; 4],
    /// `[light.x, light.y, light.z, visibility]`, `light` unit.
    pub light: [f32; 4],
}

/// `diffuse_factor` of each case, computed on the GPU.
pub fn diffuse_factor_on_gpu(gpu: &Gpu, cases: &[ShadingCase]) -> Result<Vec<f32>, ViewError> {
    let out: Vec<[f32; 4]> = run_cases(
        gpu,
        "shading_check.wgsl",
        &[
            include_str!("shaders/shading.wgsl"),
            include_str!("shaders/shading_check.wgsl"),
        ],
        cases,
    )?;
    Ok(out.iter().map(|o| o[0]).collect())
}
