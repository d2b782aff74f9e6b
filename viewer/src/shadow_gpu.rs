//! Runs the receivers' shadow lookup (`shaders/shadow_lookup.wgsl`'s `shadow_visibility`)
//! in a compute pass over a depth atlas whose texels the caller gives, for testing its
//! filter against an f64 reference (`viewer/tests/shadow_filter_gpu.rs`), as
//! [`crate::shading_gpu`] does for the light models.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;
use wgpu::ShaderStages;

use crate::compute_check::run_cases_with;
use crate::layout::{entry, shader, storage, Pipeline};
use crate::shadow::{receiver_layout, CascadeUniform, ShadowMap, ATLAS_TILES};
use crate::{Gpu, ViewError};

/// One lookup of `shadow_visibility(clip, bias)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VisibilityCase {
    /// `[x, y, z, bias]`: the point in the base shadow camera's NDC (orthographic, w = 1)
    /// and the depth bias.
    pub p: [f32; 4],
}

const CHECK_WGSL: &str = "
struct Case { p: vec4<f32> }
struct Out { v: vec4<f32> }
fn check(k: Case) -> Out {
    return Out(vec4<f32>(shadow_visibility(vec4<f32>(k.p.xyz, 1.0), k.p.w), 0.0, 0.0, 0.0));
}
";

/// Writes each pixel's depth from a storage buffer (row-major, `SIDE` texels a row), over
/// `fullscreen.wgsl`'s triangle.
const FILL_WGSL: &str = "
@group(0) @binding(0) var<storage, read> texels: array<f32>;

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    let q = vec2<u32>(p.xy);
    return texels[q.y * SIDE + q.x];
}
";

/// `shadow_visibility` of each case, computed on the device with one cascade: the
/// atlas's first tile, `size`² texels holding `depth` (row-major, row 0 at the top, as
/// the light camera renders it), the base NDC mapped to itself.
pub fn shadow_visibility_on_gpu(
    gpu: &Gpu,
    size: u32,
    depth: &[f32],
    cases: &[VisibilityCase],
) -> Result<Vec<f32>, ViewError> {
    if size < 2 || depth.len() != (size * size) as usize {
        return Err(ViewError::InvalidParam(format!(
            "a {size}² tile needs {} depth texels, got {}",
            size * size,
            depth.len()
        )));
    }
    let device = &gpu.device;
    let layout = receiver_layout(device);
    let map = ShadowMap::new(gpu, &layout, size);
    let t = 1.0 / ATLAS_TILES as f32;
    let mut uniform = CascadeUniform::default();
    uniform.map[0] = [1.0, 1.0, 0.0, 0.0];
    uniform.tile[0] = [0.0, 0.0, t, t];
    uniform.info[0] = 1.0;
    gpu.queue
        .write_buffer(&map.cascades, 0, bytemuck::bytes_of(&uniform));

    let texels = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("shadow check texels"),
        contents: bytemuck::cast_slice(depth),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let fill_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadow check fill"),
        entries: &[entry(0, ShaderStages::FRAGMENT, storage())],
    });
    let fill_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadow check fill"),
        layout: &fill_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: texels.as_entire_binding(),
        }],
    });
    let side = format!("const SIDE: u32 = {size}u;\n");
    let module = shader(
        device,
        "shadow check fill",
        &[include_str!("shaders/fullscreen.wgsl"), &side, FILL_WGSL],
    );
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadow check fill"),
        bind_group_layouts: &[Some(&fill_layout)],
        immediate_size: 0,
    });
    let fill = Pipeline {
        vs: "vs_full",
        depth: Some((true, wgpu::CompareFunction::Always)),
        ..Pipeline::new("shadow check fill", &pipeline_layout, &module)
    }
    .build(device);
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow check fill"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &map.view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_viewport(0.0, 0.0, size as f32, size as f32, 0.0, 1.0);
        rp.set_scissor_rect(0, 0, size, size);
        rp.set_pipeline(&fill);
        rp.set_bind_group(0, &fill_bind, &[]);
        rp.draw(0..3, 0..1);
    }
    gpu.queue.submit([enc.finish()]);

    let out: Vec<[f32; 4]> = run_cases_with(
        gpu,
        "shadow_visibility check",
        &[include_str!("shaders/shadow_lookup.wgsl"), CHECK_WGSL],
        cases,
        Some((&layout, &map.bind_group)),
    )?;
    Ok(out.iter().map(|o| o[0]).collect())
}
