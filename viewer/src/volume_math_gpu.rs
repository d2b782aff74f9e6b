//! Runs the volume pass's pure WGSL functions (`shaders/volume_math.wgsl`: the slice LOD,
//! the depth fade, the slab's conversion out of extinction space; and
//! `shaders/volume_loads.wgsl`'s conversion into it) in a compute pass and reads the
//! results back — for testing them against the billow-core functions they copy
//! (`viewer/tests/volume_math_gpu.rs`), as [`crate::prism_plane_gpu`] does for the
//! prism/plane intersection.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::layout::shader;
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
}

/// Evaluates each case on the GPU.
pub fn volume_math_on_gpu(gpu: &Gpu, cases: &[MathCase]) -> Result<Vec<MathOut>, ViewError> {
    if cases.is_empty() {
        return Ok(Vec::new());
    }
    let device = &gpu.device;
    let module = shader(
        device,
        "volume_math_check.wgsl",
        &[
            include_str!("shaders/volume_math.wgsl"),
            include_str!("shaders/volume_loads.wgsl"),
            include_str!("shaders/volume_math_check.wgsl"),
        ],
    );
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("volume math check"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let inb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("cases"),
        contents: bytemuck::cast_slice(cases),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (cases.len() * std::mem::size_of::<MathOut>()) as u64;
    let outb = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readb = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results read-back"),
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
    let out: Vec<MathOut> = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| ViewError::Gpu(format!("read-back: {e}")))?;
        bytemuck::cast_slice(&view).to_vec()
    };
    readb.unmap();
    Ok(out)
}
