//! Runs the WGSL prism/plane intersection (shaders/prism_plane.wgsl, the one the volume
//! pass uses) in a compute pass and reads the polygons back — for testing it against
//! the Rust reference (`billow_core::prism_plane`).

use bytemuck::{Pod, Zeroable};

use crate::compute_check::run_cases;
use crate::volume_pass::GpuCell;
use crate::{Gpu, ViewError};

/// A polygon read back from the GPU: `count` ∈ {0, 3, 4, 5} vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuPolygon {
    pub count: usize,
    pub pos: [[f32; 3]; 5],
    pub uvw: [[f32; 3]; 5],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Case {
    cell: GpuCell,
    z: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct OutPoly {
    count: [u32; 4],
    pos: [[f32; 4]; 5],
    uvw: [[f32; 4]; 5],
}

/// One case: prism positions (camera space), their uvw, the plane's z.
pub type PrismCase = ([[f32; 3]; 6], [[f32; 3]; 6], f32);

/// Intersects each `(prism positions, uvw, z_slice)` on the GPU.
pub fn intersect_on_gpu(gpu: &Gpu, cases: &[PrismCase]) -> Result<Vec<GpuPolygon>, ViewError> {
    let input: Vec<Case> = cases
        .iter()
        .map(|(p, t, z)| Case {
            cell: GpuCell::new(p, t),
            z: [*z, 0.0, 0.0, 0.0],
        })
        .collect();
    let out: Vec<OutPoly> = run_cases(
        gpu,
        "prism_plane_check.wgsl",
        &[
            include_str!("shaders/prism_plane.wgsl"),
            include_str!("shaders/prism_plane_check.wgsl"),
        ],
        &input,
    )?;
    Ok(out
        .iter()
        .map(|o| GpuPolygon {
            count: o.count[0] as usize,
            pos: o.pos.map(|p| [p[0], p[1], p[2]]),
            uvw: o.uvw.map(|p| [p[0], p[1], p[2]]),
        })
        .collect())
}
