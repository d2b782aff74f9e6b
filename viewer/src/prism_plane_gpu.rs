//! Runs the WGSL prism/plane intersection (shaders/prism_plane.wgsl, the one the volume
//! pass uses) in a compute pass and reads the polygons back — for testing it against
//! the Rust reference (`billow_core::prism_plane`).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::layout::shader;
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
    if cases.is_empty() {
        return Ok(Vec::new());
    }
    let device = &gpu.device;
    let module = shader(
        device,
        "prism_plane_check.wgsl",
        &[
            include_str!("shaders/prism_plane.wgsl"),
            include_str!("shaders/prism_plane_check.wgsl"),
        ],
    );
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("prism/plane check"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input: Vec<Case> = cases
        .iter()
        .map(|(p, t, z)| Case {
            cell: GpuCell::new(p, t),
            z: [*z, 0.0, 0.0, 0.0],
        })
        .collect();
    let inb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cases"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (cases.len() * std::mem::size_of::<OutPoly>()) as u64;
    let outb = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("polygons"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readb = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("polygons read-back"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: inb.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: outb.as_entire_binding(),
            },
        ],
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut cp = enc.begin_compute_pass(&Default::default());
        cp.set_pipeline(&pipeline);
        cp.set_bind_group(0, &bind, &[]);
        cp.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&outb, 0, &readb, 0, size);
    gpu.queue.submit([enc.finish()]);
    let slice = readb.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|e| ViewError::Gpu(e.to_string()))?
        .map_err(|e| ViewError::Gpu(format!("read-back: {e}")))?;
    let out: Vec<OutPoly> = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| ViewError::Gpu(format!("read-back: {e}")))?;
        bytemuck::cast_slice(&view).to_vec()
    };
    readb.unmap();
    Ok(out
        .iter()
        .map(|o| GpuPolygon {
            count: o.count[0] as usize,
            pos: o.pos.map(|p| [p[0], p[1], p[2]]),
            uvw: o.uvw.map(|p| [p[0], p[1], p[2]]),
        })
        .collect())
}
