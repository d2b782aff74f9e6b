//! The volume pass: GPU slicing of volumetric billboards (VB §3.3).
//!
//! Per volume asset a 3D texture with its MIP chain, stored in **extinction space**
//! ([`VolumeStorage::Extinction`]: each texel `(σ·c, σ)` in `Rgba16Float`, made on load
//! from the asset's RGBA8 texels by `billow_core::extinction::extinction_texel`, sRGB
//! decoded first), so the texture unit's trilinear filter *is* the extinction-space
//! filter of the CPU sampler (`billow::eval::volume_sampler`): one hardware sample per
//! fragment instead of eight loads and conversions per MIP level. On hardware adapters a
//! BC7-compressed asset keeps its blocks instead ([`VolumeStorage::Blocks`], 1 byte per
//! texel against 8; [`Gpu::sample_blocks`]), filtered by loads in the shader
//! ([`shader_source`]). Up to [`batch_size`] textures (the device's
//! limit, at most [`MAX_TEXTURES_PER_BATCH`]) are bound at once (a *batch*), so one draw covers cells of several assets and a slice keeps its
//! cells in ID order whatever their texture; each cell names its asset (and so its
//! texture slot, sampler and `v₀`).
//!
//! The pipelines are made on first use ([`VolumePass::pipeline`],
//! [`VolumePass::shadow_pipeline`]): a scene without shadows never builds the shadow
//! pipeline, and the shader holds the filter by loads only when a block texture is bound.
//!
//! Per frame: every cell of every instance goes to one storage buffer in camera space,
//! the slices (back to front) to another, and the slabs' cell lists to a third
//! ([`crate::slab`]). A draw covers a run of slices × a list of cells: instance `i` is
//! slice `first + i div n`, cell `list[offset + i mod n]`, so within a draw slices go
//! back to front and, within a slice, cells by ascending ID. The vertex shader
//! intersects its prism with its slice plane in WGSL (`prism_plane.wgsl`, a port of the
//! Rust reference) with a budget of 9 vertices (a fan of 3 triangles covers the ≤ 5-gon).
//! Blending is premultiplied "over" into Rgba16Float. Slices do not write depth; they
//! read the opaque meshes' depth (group 3, bound read-only) and fade where a surface cuts
//! the slab they stand for (`depth ± d/2`), as spherical billboards clip a particle's
//! path at the scene depth; a hard depth test would end every slice on a line and leave
//! terraces where volumes meet opaque surfaces. The same pipeline with depth writes and an
//! alpha test renders volumes into the shadow map ([`VolumePass::shadow_pipeline`]).
//!
//! **Runtime shading** (VB §3.2 "Reflectance"): an asset that stores normals (SPEC §8.4)
//! gets a second 3D texture per band, in the normal slot of the same batch slot, holding
//! `(α·n̄, α)` in `Rgba8Snorm` (the Toksvig normal weighted by the texel's colour alpha,
//! so the sampler's filtering is the alpha-weighted mean the voxelizer's MIP levels use;
//! src/eval/volume_sampler.rs decodes the same texels). The fragment shader multiplies
//! the albedo by `ambient + (1 − ambient) · shadow · max(n̄·L, 0)` with the normal taken to
//! view space by the cell's normal matrix (src/eval/lighting.rs::volume_diffuse_factor,
//! src/eval/slicer.rs::normal_matrix). Assets without normals keep their baked colour.
//!
//! This file holds the pipelines, layouts and bind groups; `gpu_types.rs` the records
//! the shader reads ([`GpuCell`], [`GpuVolumeParams`], …) and `textures.rs` the uploads
//! ([`VolumePass::upload_with`], [`extinction_levels`]); textures → gpu_types, one way.

mod gpu_types;
mod textures;

pub use gpu_types::{
    FrameUniform, GpuCell, GpuDraw, GpuSlice, GpuVolume, GpuVolumeParams, VolumeStorage,
};
pub use textures::{extinction_levels, repeat_axes, EXTINCTION_FORMAT, NORMAL_FORMAT};

use std::cell::OnceCell;

use billow_format::{VolumeAsset, VolumeBlocks};

use crate::layout::{
    color_target, depth_texture, entry, sampler, shader, storage, texture, uniform, Pipeline,
};
use crate::target::COLOR_FORMAT;
use crate::{Gpu, ViewError};

/// Most textures bound at once (the shaders switch over this many slots at most).
pub const MAX_TEXTURES_PER_BATCH: usize = 32;

/// The texture batch a renderer on `gpu` starts with ([`crate::Renderer::texture_batch`]):
/// [`MAX_TEXTURES_PER_BATCH`] (clamped to [`batch_size`]) on hardware adapters, where the
/// fragment's switch over its cell's texture slot runs one case; **1** on software
/// adapters (`DeviceType::Cpu`, lavapipe), whose SIMD fragment code runs every case of a
/// switch under a mask, so each bound slot costs every fragment a trilinear fetch: the
/// asteroid belt (18 textures) at 320×240 drew its frame in 2.2 s with one texture per
/// batch (6,587 draws) and in 18.2 s with 18 per batch (699 draws), the same picture
/// (docs/performance.md).
pub fn preferred_batch(gpu: &Gpu) -> usize {
    if gpu.info.device_type == wgpu::DeviceType::Cpu {
        1
    } else {
        MAX_TEXTURES_PER_BATCH
    }
}

/// Textures per batch on `gpu`: as many colour + normal pairs as the fragment stage may
/// sample, keeping two for the shadow map and a spare, at most [`MAX_TEXTURES_PER_BATCH`].
pub fn batch_size(gpu: &Gpu) -> usize {
    let n = gpu.device.limits().max_sampled_textures_per_shader_stage as usize;
    (n.saturating_sub(2) / 2).clamp(1, MAX_TEXTURES_PER_BATCH)
}

/// The WGSL of the volume pass for `n` texture slots (prism/plane intersection +
/// slicing shaders + the texture-slot switch). `sample_volume` returns the sample in
/// extinction space (`billow_core::extinction`), filtered trilinearly within a level and
/// linearly between levels, not the hardware's filter on alpha, which would leave thin
/// opaque layers see-through:
/// - a texture of [`VolumeStorage::Extinction`] holds extinction-space texels and is
///   filtered by the texture unit, one `textureSampleLevel`;
/// - with `loads` (some texture is [`VolumeStorage::Blocks`], flag 4 of its params) the
///   shader also has the filter by loads (`volume_loads.wgsl`: eight texel loads per
///   level, each converted, as `billow::eval::volume_sampler` filters), used for those
///   textures only.
pub fn shader_source(n: usize, loads: bool) -> String {
    let mut bindings = String::new();
    let mut switch = String::new();
    let mut nswitch = String::new();
    let sample = |t: &str| {
        format!(
            "if rep {{ return textureSampleLevel({t}, smp_repeat, uvw, lod); }} \
             return textureSampleLevel({t}, smp_clamp, uvw, lod);"
        )
    };
    for i in 0..n {
        let j = n + i;
        bindings += &format!("@group(1) @binding({i}) var vol_tex{i}: texture_3d<f32>;\n");
        bindings += &format!("@group(1) @binding({j}) var vol_nrm{i}: texture_3d<f32>;\n");
        let by_loads = if loads {
            format!("if by_loads {{ return sample_extinction(vol_tex{i}, rep, uvw, lod); }} ")
        } else {
            String::new()
        };
        switch += &format!(
            "        case {i}u: {{ {by_loads}{} }}\n",
            sample(&format!("vol_tex{i}"))
        );
        nswitch += &format!(
            "        case {i}u: {{ {} }}\n",
            sample(&format!("vol_nrm{i}"))
        );
    }
    let sampler = format!(
        "{bindings}@group(1) @binding({}) var smp_clamp: sampler;\n\
         @group(1) @binding({}) var smp_repeat: sampler;\n\
         fn sample_volume(slot: u32, flags: u32, uvw: vec3<f32>, lod: f32) -> vec4<f32> {{\n\
             let rep = (flags & 1u) != 0u;\n\
             let by_loads = (flags & 4u) != 0u;\n\
             switch slot {{\n{switch}        default: {{ return vec4<f32>(0.0); }}\n    }}\n}}\n\
         fn sample_normals(slot: u32, rep: bool, uvw: vec3<f32>, lod: f32) -> vec4<f32> {{\n\
             switch slot {{\n{nswitch}        default: {{ return vec4<f32>(0.0); }}\n    }}\n}}\n",
        2 * n,
        2 * n + 1
    );
    let loads_src = if loads {
        include_str!("../shaders/volume_loads.wgsl")
    } else {
        ""
    };
    format!(
        "{}\n{}\n{}\n{}\n{}\n{}\n{}",
        include_str!("../shaders/prism_plane.wgsl"),
        include_str!("../shaders/shadow_lookup.wgsl"),
        include_str!("../shaders/shading.wgsl"),
        include_str!("../shaders/volume_math.wgsl"),
        loads_src,
        sampler,
        include_str!("../shaders/volume.wgsl")
    )
}

/// Volume pipelines and layouts.
pub struct VolumePass {
    /// The colour and shadow pipelines' layouts.
    layouts: [wgpu::PipelineLayout; 2],
    /// The shader for the textures uploaded so far and its pipelines, made on first use
    /// (made again when a block texture first needs the filter by loads).
    module: OnceCell<wgpu::ShaderModule>,
    pipeline: OnceCell<wgpu::RenderPipeline>,
    shadow_pipeline: OnceCell<wgpu::RenderPipeline>,
    /// Some texture is [`VolumeStorage::Blocks`]: the shader has the filter by loads.
    loads: bool,
    pub frame_layout: wgpu::BindGroupLayout,
    pub batch_layout: wgpu::BindGroupLayout,
    pub samplers: [wgpu::Sampler; 2],
    /// Bound in unused texture slots.
    pub dummy: wgpu::TextureView,
    /// Texture slots per batch.
    pub batch: usize,
    /// Group 3 of [`VolumePass::pipeline`]: the opaque scene's depth the slices fade at.
    pub depth_layout: wgpu::BindGroupLayout,
}

impl VolumePass {
    /// The layouts with `batch` texture slots (at most [`batch_size`]`(gpu)`); the
    /// pipelines are made on first use.
    pub fn new(gpu: &Gpu, shadow_layout: &wgpu::BindGroupLayout, batch: usize) -> VolumePass {
        let batch = batch.clamp(1, batch_size(gpu));
        let device = &gpu.device;
        let vs = wgpu::ShaderStages::VERTEX;
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let fs = wgpu::ShaderStages::FRAGMENT;
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume frame"),
            entries: &[
                entry(0, vf, uniform(false)),
                entry(1, vs, storage()),
                entry(2, vs, storage()),
                entry(3, vs, storage()),
                entry(4, vs, storage()),
                entry(5, vs, uniform(true)),
            ],
        });
        // Colour slots 0..batch, their normal slots batch..2·batch, then the samplers.
        let mut batch_entries: Vec<_> = (0..2 * batch as u32)
            .map(|i| entry(i, fs, texture(wgpu::TextureViewDimension::D3)))
            .collect();
        for i in 0..2 {
            batch_entries.push(entry(2 * batch as u32 + i, fs, sampler()));
        }
        let batch_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume textures"),
            entries: &batch_entries,
        });
        let depth_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("volume scene depth"),
            entries: &[entry(0, fs, depth_texture())],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&batch_layout),
                Some(shadow_layout),
                Some(&depth_layout),
            ],
            immediate_size: 0,
        });
        let shadow_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("volume shadow"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&batch_layout),
                Some(shadow_layout),
            ],
            immediate_size: 0,
        });
        let mode = |r: bool| {
            if r {
                wgpu::AddressMode::Repeat
            } else {
                wgpu::AddressMode::ClampToEdge
            }
        };
        let sampler = |rep: bool| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("volume trilinear"),
                address_mode_u: mode(rep),
                address_mode_v: mode(false),
                address_mode_w: mode(rep),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            })
        };
        let dummy = device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("volume dummy"),
                size: wgpu::Extent3d {
                    width: 1,
                    height: 1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&Default::default());
        VolumePass {
            layouts: [layout, shadow_pl],
            module: OnceCell::new(),
            pipeline: OnceCell::new(),
            shadow_pipeline: OnceCell::new(),
            loads: false,
            frame_layout,
            batch_layout,
            samplers: [sampler(false), sampler(true)],
            dummy,
            batch,
            depth_layout,
        }
    }

    /// Notes textures of `storage` bound from now on: the first block texture drops
    /// the pipelines made without the filter by loads (they are made again on use).
    pub fn note_storage(&mut self, storage: VolumeStorage) {
        if storage == VolumeStorage::Blocks && !self.loads {
            self.loads = true;
            self.module = OnceCell::new();
            self.pipeline = OnceCell::new();
            self.shadow_pipeline = OnceCell::new();
        }
    }

    fn module(&self, gpu: &Gpu) -> &wgpu::ShaderModule {
        self.module.get_or_init(|| {
            shader(
                &gpu.device,
                "volume.wgsl",
                &[&shader_source(self.batch, self.loads)],
            )
        })
    }

    /// The slices' pipeline (premultiplied "over" into the colour target), made on first
    /// use (recorded as `pipeline:volume`).
    pub fn pipeline(&self, gpu: &Gpu) -> &wgpu::RenderPipeline {
        self.pipeline.get_or_init(|| {
            // The slices fade at the opaque depth themselves (`depth_fade` in
            // volume.wgsl), so the colour pipeline does not depth-test: a slice just
            // behind a surface still adds the part of its slab in front of it.
            let p = Pipeline {
                fs: "fs_main",
                depth: Some((false, wgpu::CompareFunction::Always)),
                target: color_target(
                    COLOR_FORMAT,
                    Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                ),
                ..Pipeline::new("volume slices", &self.layouts[0], self.module(gpu))
            }
            .build(&gpu.device);
            gpu.note_built("pipeline:volume");
            p
        })
    }

    /// Depth-only, alpha-tested: the volumes into the shadow map, made on first use
    /// (recorded as `pipeline:volume-shadow`; only scenes with shadows make it).
    pub fn shadow_pipeline(&self, gpu: &Gpu) -> &wgpu::RenderPipeline {
        self.shadow_pipeline.get_or_init(|| {
            let p = Pipeline {
                fs: "fs_shadow",
                depth: Some((true, wgpu::CompareFunction::Less)),
                target: None,
                ..Pipeline::new("volume shadow slices", &self.layouts[1], self.module(gpu))
            }
            .build(&gpu.device);
            gpu.note_built("pipeline:volume-shadow");
            p
        })
    }

    /// Group 3 of [`VolumePass::pipeline`] for the depth buffer `depth` (bound read-only
    /// while the slices are drawn).
    pub fn depth_bind_group(&self, gpu: &Gpu, depth: &wgpu::TextureView) -> wgpu::BindGroup {
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume scene depth"),
            layout: &self.depth_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(depth),
            }],
        })
    }

    /// The bind group of a batch: `views[i]` (colour, normals) in slot `i`, the dummy in
    /// the others and where a texture has no normals.
    pub fn batch_bind_group(
        &self,
        gpu: &Gpu,
        views: &[(&wgpu::TextureView, Option<&wgpu::TextureView>)],
    ) -> wgpu::BindGroup {
        let mut entries: Vec<wgpu::BindGroupEntry> = (0..2 * self.batch)
            .map(|i| {
                let v = views.get(i % self.batch);
                let view = match (i < self.batch, v) {
                    (true, Some(v)) => v.0,
                    (false, Some(v)) => v.1.unwrap_or(&self.dummy),
                    _ => &self.dummy,
                };
                wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: wgpu::BindingResource::TextureView(view),
                }
            })
            .collect();
        for (i, s) in self.samplers.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: (2 * self.batch + i) as u32,
                resource: wgpu::BindingResource::Sampler(s),
            });
        }
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume batch"),
            layout: &self.batch_layout,
            entries: &entries,
        })
    }

    /// Uploads `asset`'s textures: the base texture first, then one per LOD band
    /// (SPEC §8.6), each with its MIP chain.
    pub fn upload(&self, gpu: &Gpu, asset: &VolumeAsset) -> Result<Vec<GpuVolume>, ViewError> {
        self.upload_with(gpu, asset, None)
    }

    /// [`VolumePass::upload`] of a compressed asset: the base texture (and each LOD band
    /// whose blocks are given, format 1.3) is uploaded as its BC7 `blocks` when the device
    /// allows it ([`Gpu::block_upload`]), else as the decoded texels in `asset.levels`
    /// (what the reader decoded on load).
    pub fn upload_with(
        &self,
        gpu: &Gpu,
        asset: &VolumeAsset,
        blocks: Option<&VolumeBlocks>,
    ) -> Result<Vec<GpuVolume>, ViewError> {
        textures::upload(gpu, asset, blocks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without block textures the shader filters by the texture unit alone: no texel
    /// loads of the colour textures; with them, the loads are there for flag 4.
    #[test]
    fn the_filter_by_loads_is_in_the_shader_only_for_block_textures() {
        let plain = shader_source(3, false);
        assert!(!plain.contains("textureLoad(t,"), "no filter by loads");
        assert!(!plain.contains("sample_extinction("));
        assert_eq!(plain.matches("textureSampleLevel(vol_tex").count(), 2 * 3);
        let loads = shader_source(3, true);
        assert_eq!(loads.matches("sample_extinction(vol_tex").count(), 3);
        assert!(loads.contains("textureLoad(t,"));
    }
}
