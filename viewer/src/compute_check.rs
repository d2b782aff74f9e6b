//! The compute pass behind the WGSL-against-core checks ([`crate::prism_plane_gpu`],
//! [`crate::shading_gpu`], [`crate::volume_math_gpu`]): one storage buffer of cases in
//! (binding 0), one of results out (binding 1), one invocation per case in workgroups of
//! 64, read back.

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use wgpu::ShaderStages;

use crate::layout::{entry, shader, storage};
use crate::{Gpu, ViewError};

/// Runs the check made of `sources` (named `name`: WGSL declaring `Case`, `Out` and
/// `fn check(k: Case) -> Out`) over `cases`, with the entry point of
/// `shaders/compute_check.wgsl` appended, and returns one `Out` per case.
pub(crate) fn run_cases<In: Pod, Out: Pod>(
    gpu: &Gpu,
    name: &str,
    sources: &[&str],
    cases: &[In],
) -> Result<Vec<Out>, ViewError> {
    run_cases_with(gpu, name, sources, cases, None)
}

/// [`run_cases`] with `group2` (its layout, and the bind group) bound at group 2, where
/// the passes bind the shadow receiver's ([`crate::shadow::receiver_layout`]).
pub(crate) fn run_cases_with<In: Pod, Out: Pod>(
    gpu: &Gpu,
    name: &str,
    sources: &[&str],
    cases: &[In],
    group2: Option<(&wgpu::BindGroupLayout, &wgpu::BindGroup)>,
) -> Result<Vec<Out>, ViewError> {
    if cases.is_empty() {
        return Ok(Vec::new());
    }
    let device = &gpu.device;
    let mut all = sources.to_vec();
    all.push(include_str!("shaders/compute_check.wgsl"));
    let module = shader(device, name, &all);
    // Derived from the shader without group 2; declared with it (group 1 left empty).
    let explicit = group2.map(|(g2, _)| {
        let g0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("check cases"),
            entries: &[
                entry(0, ShaderStages::COMPUTE, storage()),
                entry(
                    1,
                    ShaderStages::COMPUTE,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &[Some(&g0), None, Some(g2)],
            immediate_size: 0,
        });
        (g0, layout)
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(name),
        layout: explicit.as_ref().map(|(_, l)| l),
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
    let size = (cases.len() * std::mem::size_of::<Out>()) as u64;
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
        layout: &explicit
            .as_ref()
            .map_or_else(|| pipeline.get_bind_group_layout(0), |(g0, _)| g0.clone()),
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
        if let Some((_, g2)) = group2 {
            cp.set_bind_group(2, g2, &[]);
        }
        cp.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&outb, 0, &readb, 0, size);
    gpu.queue.submit([enc.finish()]);
    gpu.read_mapped(&readb, |bytes| bytemuck::cast_slice(bytes).to_vec())
}
