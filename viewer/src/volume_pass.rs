//! The volume pass: GPU slicing of volumetric billboards (VB §3.3).
//!
//! One pipeline; per volume asset a 3D texture with its MIP chain (`Rgba8UnormSrgb`
//! for sRGB-premultiplied assets, so filtering happens on linear premultiplied values,
//! as the CPU sampler decodes before filtering), a trilinear sampler (clamp, or repeat
//! in x and z for shells, SPEC §8.5) and a bind group. Per frame every cell of every
//! instance goes to one storage buffer, in camera space, and the slices to another;
//! instance `i` of a draw is cell `i mod N` on slice `i div N`, so a single draw covers
//! all cells of a texture on a run of slices in the fixed order (slice back to front,
//! then cell ID). Blending is premultiplied "over" into Rgba16Float; slices test
//! against the depth of the opaque meshes but do not write it.

use billow_format::{ColourSpace, VolumeAsset};
use bytemuck::{Pod, Zeroable};

use crate::target::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::{Gpu, ViewError};

/// The WGSL of the volume pass (prism/plane intersection + slicing shaders).
pub fn shader_source() -> String {
    format!(
        "{}\n{}",
        include_str!("shaders/prism_plane.wgsl"),
        include_str!("shaders/volume.wgsl")
    )
}

/// One cell in camera space, as the shaders read it (vec4-padded).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuCell {
    pub pos: [[f32; 4]; 6],
    pub uvw: [[f32; 4]; 6],
}

impl GpuCell {
    pub fn new(pos: &[[f32; 3]; 6], uvw: &[[f32; 3]; 6]) -> Self {
        GpuCell {
            pos: pos.map(|p| [p[0], p[1], p[2], 0.0]),
            uvw: uvw.map(|p| [p[0], p[1], p[2], 0.0]),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameUniform {
    pub proj: [[f32; 4]; 4],
    pub counts: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuSlice {
    /// view z (−depth), spacing d, 0, 0
    pub zd: [f32; 4],
}

/// An asset's texture on the GPU, shared by all its instances.
pub struct GpuVolume {
    pub dims0: [u32; 3],
    pub levels: u32,
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
    /// Group uniform (v₀, max lod), rewritten every frame.
    pub params: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
}

/// Volume pipeline and layouts.
pub struct VolumePass {
    pub pipeline: wgpu::RenderPipeline,
    pub frame_layout: wgpu::BindGroupLayout,
    pub group_layout: wgpu::BindGroupLayout,
}

/// The addressing of `asset` (SPEC §8.5): repeat in x and z for shells (header param
/// `shell`), clamp everywhere otherwise.
pub fn repeat_axes(asset: &VolumeAsset) -> [bool; 3] {
    let shell = asset.header.params.contains_key("shell");
    [shell, false, shell]
}

impl VolumePass {
    pub fn new(gpu: &Gpu) -> VolumePass {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("volume.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty,
            count: None,
        };
        let storage = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let uniform = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let vs = wgpu::ShaderStages::VERTEX;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume frame"),
            entries: &[
                entry(0, vs, uniform),
                entry(1, vs, storage),
                entry(2, vs, storage),
            ],
        });
        let group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume texture"),
            entries: &[
                entry(0, vs, uniform),
                entry(
                    1,
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    },
                ),
                entry(
                    2,
                    wgpu::ShaderStages::FRAGMENT,
                    wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                ),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume"),
            bind_group_layouts: &[Some(&frame_layout), Some(&group_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("volume slices"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        VolumePass {
            pipeline,
            frame_layout,
            group_layout,
        }
    }

    /// Uploads `asset`'s colour levels as a 3D texture with its MIP chain.
    pub fn upload(&self, gpu: &Gpu, asset: &VolumeAsset) -> Result<GpuVolume, ViewError> {
        asset
            .validate()
            .map_err(|e| ViewError::InvalidAsset(e.to_string()))?;
        let dims0 = asset.level_dims(0);
        let levels = asset.levels.len() as u32;
        let max3d = gpu.device.limits().max_texture_dimension_3d;
        if dims0.iter().any(|&d| d > max3d) || levels == 0 {
            return Err(ViewError::InvalidAsset(format!(
                "volume {}x{}x{} with {levels} levels does not fit a 3D texture (max {max3d})",
                dims0[0], dims0[1], dims0[2]
            )));
        }
        let format = match asset.header.colour_space {
            ColourSpace::SrgbPremultiplied => wgpu::TextureFormat::Rgba8UnormSrgb,
            ColourSpace::LinearPremultiplied => wgpu::TextureFormat::Rgba8Unorm,
        };
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("volume"),
            size: wgpu::Extent3d {
                width: dims0[0],
                height: dims0[1],
                depth_or_array_layers: dims0[2],
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (l, bytes) in asset.levels.iter().enumerate() {
            let d = asset.level_dims(l as u32);
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: l as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * d[0]),
                    rows_per_image: Some(d[1]),
                },
                wgpu::Extent3d {
                    width: d[0],
                    height: d[1],
                    depth_or_array_layers: d[2],
                },
            );
        }
        let view = texture.create_view(&Default::default());
        let mode = |r: bool| {
            if r {
                wgpu::AddressMode::Repeat
            } else {
                wgpu::AddressMode::ClampToEdge
            }
        };
        let rep = repeat_axes(asset);
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("volume trilinear"),
            address_mode_u: mode(rep[0]),
            address_mode_v: mode(rep[1]),
            address_mode_w: mode(rep[2]),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("volume params"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume"),
            layout: &self.group_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        Ok(GpuVolume {
            dims0,
            levels,
            texture,
            view,
            sampler,
            params,
            bind_group,
        })
    }
}
