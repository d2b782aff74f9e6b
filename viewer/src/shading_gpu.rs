//! Runs the light models of `shaders/shading.wgsl` — the mesh and cloud passes'
//! `diffuse_factor`, the volume pass's `moments_cosine_of` — in a compute pass and reads
//! the results back, for testing them against the billow-core functions they copy
//! (`viewer/tests/shading_gpu.rs`), as [`crate::volume_math_gpu`] does for the volume
//! pass's other functions.

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

/// One set of arguments of `moments_cosine_of(m, light, axis)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MomentsCase {
    /// `[m.x, m.y, m.z, 0]`: filtered moments, any trace.
    pub m: [f32; 4],
    /// `[light.x, light.y, light.z, 0]`, unit.
    pub light: [f32; 4],
    /// `[axis.x, axis.y, axis.z, 0]`: the view axis, any length.
    pub axis: [f32; 4],
}

/// `moments_cosine_of` of each case, computed on the GPU.
pub fn moments_cosine_on_gpu(gpu: &Gpu, cases: &[MomentsCase]) -> Result<Vec<f32>, ViewError> {
    let out: Vec<[f32; 4]> = run_cases(
        gpu,
        "moments_check.wgsl",
        &[
            include_str!("shaders/shading.wgsl"),
            include_str!("shaders/moments_check.wgsl"),
        ],
        cases,
    )?;
    Ok(out.iter().map(|o| o[0]).collect())
}
