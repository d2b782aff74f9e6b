//! The directional shadow map, built only when a scene asks for shadows.
//!
//! The light's camera is orthographic, looking along the light, fitted to the bounding
//! sphere of everything that casts or receives. Into its depth map go the meshes (depth
//! only), the billboard clouds (alpha-tested) and the volumes, sliced from the light
//! with [`SHADOW_SPACING_BIAS`]× the viewer's spacing — fewer slices whose opacity is
//! corrected for the larger spacing, the paper's opacity scaling (§4, Optimizations) —
//! each slice occluding where its opacity reaches [`SHADOW_ALPHA_CUTOFF`]. Receivers
//! (meshes, clouds, volume slices) look the map up with 3×3 PCF
//! (`shaders/shadow_lookup.wgsl`) and scale the light by `ambient + (1 − ambient)·vis`.

use glam::{Mat4, Vec3};

use crate::layout::{comparison_sampler, depth_texture, entry};
use crate::target::DEPTH_FORMAT;
use crate::texture::desc_2d;
use crate::{Gpu, ViewCamera};

/// Side of the shadow map in texels.
pub const SHADOW_MAP_SIZE: u32 = 1024;
/// Shadow slices are this many times farther apart than the viewer's.
pub const SHADOW_SPACING_BIAS: f32 = 4.0;
/// Opacity at which a shadow slice occludes.
pub const SHADOW_ALPHA_CUTOFF: f32 = 0.5;

/// Group 2 of every receiving pipeline: the depth map and its comparison sampler.
pub fn receiver_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadow receiver"),
        entries: &[
            entry(0, wgpu::ShaderStages::FRAGMENT, depth_texture()),
            entry(1, wgpu::ShaderStages::FRAGMENT, comparison_sampler()),
        ],
    })
}

/// A depth map and the bind group that lets receivers read it.
pub struct ShadowMap {
    pub size: u32,
    pub view: wgpu::TextureView,
    pub bind_group: wgpu::BindGroup,
}

impl ShadowMap {
    /// A `size`² map (`size = 1`: the stand-in bound when a scene has no shadows).
    pub fn new(gpu: &Gpu, layout: &wgpu::BindGroupLayout, size: u32) -> ShadowMap {
        let tex = gpu.device.create_texture(&desc_2d(
            "shadow map",
            size,
            size,
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        ));
        let view = tex.create_view(&Default::default());
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow compare"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow receiver"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        ShadowMap {
            size,
            view,
            bind_group,
        }
    }
}

/// The light's orthographic camera covering the sphere (`centre`, `radius`), looking
/// along `-towards_light`.
pub fn light_camera(towards_light: Vec3, centre: Vec3, radius: f32, size: u32) -> ViewCamera {
    let l = towards_light.normalize_or(Vec3::Y);
    let r = radius.max(1e-6);
    let eye = centre + l * (2.0 * r);
    let up = if l.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    ViewCamera::orthographic(eye, -l, up, r, size, size, r * 0.5, r * 3.5)
}

/// Camera view space → the shadow map's clip space.
pub fn view_to_shadow(camera: &ViewCamera, light: &ViewCamera) -> Mat4 {
    light.projection() * light.view * camera.view.inverse()
}

/// Depth bias in the shadow map's depth units: about two texels of the map's extent.
pub fn depth_bias(light: &ViewCamera) -> f32 {
    let texel = light.pixel_size_at(1.0);
    2.0 * texel / (light.far - light.near)
}
