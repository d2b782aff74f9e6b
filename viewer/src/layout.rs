//! The bind-group-layout entries and shader modules the passes declare, in one place: each
//! pass lists its bindings as `entry(binding, stages, kind)` with the kinds below.

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
