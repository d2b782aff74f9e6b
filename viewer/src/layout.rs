//! The bind-group layouts, shader modules and render pipelines the passes declare, in one
//! place: each pass lists its bindings as `entry(binding, stages, kind)` with the kinds
//! below, and its pipelines as a [`Pipeline`] that names only what differs from the
//! defaults.

use wgpu::{BindGroupLayoutEntry, BindingType, ShaderStages, TextureSampleType};
use wgpu::{TextureViewDimension as Dim, TextureViewDimension};

/// One binding of a layout (never an array).
pub fn entry(binding: u32, visibility: ShaderStages, ty: BindingType) -> BindGroupLayoutEntry {
    BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

/// A uniform buffer, with a dynamic offset when `dynamic`.
pub fn uniform(dynamic: bool) -> BindingType {
    BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: dynamic,
        min_binding_size: None,
    }
}

/// A read-only storage buffer.
pub fn storage() -> BindingType {
    BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only: true },
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// A filterable float texture of dimension `dim` (single-sampled).
pub fn texture(dim: TextureViewDimension) -> BindingType {
    BindingType::Texture {
        sample_type: TextureSampleType::Float { filterable: true },
        view_dimension: dim,
        multisampled: false,
    }
}

/// A 2D depth texture (single-sampled).
pub fn depth_texture() -> BindingType {
    BindingType::Texture {
        sample_type: TextureSampleType::Depth,
        view_dimension: Dim::D2,
        multisampled: false,
    }
}

/// A filtering sampler.
pub fn sampler() -> BindingType {
    BindingType::Sampler(wgpu::SamplerBindingType::Filtering)
}

/// A depth-comparison sampler.
pub fn comparison_sampler() -> BindingType {
    BindingType::Sampler(wgpu::SamplerBindingType::Comparison)
}

/// A WGSL module from `sources` concatenated in order (shared pieces such as
/// `fullscreen.wgsl` or `shadow_lookup.wgsl` first).
pub fn shader(device: &wgpu::Device, label: &str, sources: &[&str]) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(sources.join("\n").into()),
    })
}

/// The material layout of the mesh and cloud passes (the bind group that
/// [`crate::Gpu::uniform_texture_bind_group`] makes): a uniform, a 2D texture and its sampler,
/// all read by the fragment stage.
pub fn material_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    let fs = ShaderStages::FRAGMENT;
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            entry(0, fs, uniform(false)),
            entry(1, fs, texture(Dim::D2)),
            entry(2, fs, sampler()),
        ],
    })
}

/// A pass's render pipeline: what the passes choose; everything else is wgpu's default
/// (counter-clockwise front faces, no multisampling, no stencil, no depth bias).
pub struct Pipeline<'a> {
    pub label: &'a str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vs: &'a str,
    pub fs: &'a str,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub topology: wgpu::PrimitiveTopology,
    pub cull: Option<wgpu::Face>,
    /// Tested against the shared depth buffer: (write, compare); `None`: no depth.
    pub depth: Option<(bool, wgpu::CompareFunction)>,
    /// The colour target; `None`: no colour attachment (depth only).
    pub target: Option<wgpu::ColorTargetState>,
}

impl<'a> Pipeline<'a> {
    /// `vs_main` / `fs_main` over triangle lists, no vertex buffers, no culling, no depth,
    /// no colour target: the fields a pass sets replace these.
    pub fn new(
        label: &'a str,
        layout: &'a wgpu::PipelineLayout,
        module: &'a wgpu::ShaderModule,
    ) -> Self {
        Pipeline {
            label,
            layout,
            module,
            vs: "vs_main",
            fs: "fs_main",
            buffers: &[],
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull: None,
            depth: None,
            target: None,
        }
    }

    pub fn build(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        let targets = [self.target.clone()];
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.module,
                entry_point: Some(self.vs),
                compilation_options: Default::default(),
                buffers: self.buffers,
            },
            primitive: wgpu::PrimitiveState {
                topology: self.topology,
                cull_mode: self.cull,
                ..Default::default()
            },
            depth_stencil: self.depth.map(|(write, compare)| wgpu::DepthStencilState {
                format: crate::target::DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: self.module,
                entry_point: Some(self.fs),
                compilation_options: Default::default(),
                targets: if self.target.is_some() { &targets } else { &[] },
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// The colour target `format` with `blend`, writing every channel.
pub fn color_target(
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A layout with one uniform buffer at binding 0, read by both stages (the passes' frame
/// uniforms).
pub fn frame_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[entry(0, ShaderStages::VERTEX_FRAGMENT, uniform(false))],
    })
}
