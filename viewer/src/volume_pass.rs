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

use std::cell::OnceCell;

use billow_core::slicing::level_size_ratio;
use billow_format::{ColourSpace, VolumeAsset, VolumeBlocks};
use bytemuck::{Pod, Zeroable};
use glam::Mat3;

use crate::layout::{
    color_target, depth_texture, entry, sampler, shader, storage, texture, uniform, Pipeline,
};
use crate::target::COLOR_FORMAT;
use crate::texture_bc::{upload_bc7, upload_bc7_filled};
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
        include_str!("shaders/volume_loads.wgsl")
    } else {
        ""
    };
    format!(
        "{}\n{}\n{}\n{}\n{}\n{}",
        include_str!("shaders/prism_plane.wgsl"),
        include_str!("shaders/shadow_lookup.wgsl"),
        include_str!("shaders/volume_math.wgsl"),
        loads_src,
        sampler,
        include_str!("shaders/volume.wgsl")
    )
}

/// One cell in camera space, as the shaders read it (vec4-padded). `pos[0].w` holds the
/// index of its instance's [`GpuVolumeParams`] ([`GpuCell::with_volume`]), as raw bits.
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
    /// The cell drawn with the texture and parameters of params entry `volume`.
    pub fn with_volume(mut self, volume: u32) -> Self {
        self.pos[0][3] = f32::from_bits(volume);
        self
    }
    /// The cell's normal matrix (stored normals → view space), row by row in the free
    /// `w` components: row 0 in `uvw[0..3].w`, row 1 in `uvw[3..6].w`, row 2 in
    /// `pos[1..4].w` (`volume.wgsl`'s `normal_matrix`).
    pub fn with_normal_matrix(mut self, m: Mat3) -> Self {
        for r in 0..3 {
            let row = m.row(r);
            for c in 0..3 {
                match r {
                    0 => self.uvw[c][3] = row[c],
                    1 => self.uvw[3 + c][3] = row[c],
                    _ => self.pos[1 + c][3] = row[c],
                }
            }
        }
        self
    }
}

/// Per-frame uniform of the volume pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameUniform {
    pub proj: [[f32; 4]; 4],
    /// Camera view space → the shadow map's clip space (unused without shadows).
    pub view_to_shadow: [[f32; 4]; 4],
    /// x: 1 = receive shadows, y: alpha cut-off of the shadow pipeline.
    pub flags: [f32; 4],
    /// xyz: unit direction towards the light in view space (shading of volumes with
    /// normals), w: ambient (the unshadowed fraction of the light).
    pub light: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuSlice {
    /// view z (−depth), spacing d, the thickness of the slab the slice stands for (`d`,
    /// more for the farthest: `billow_core::slicing::far_slab`), 0
    pub zd: [f32; 4],
}

/// Per (volume instance, LOD band): `p` = (the band's `v₀·2^f`, its max lod, texture
/// slot, flags: 1 = repeat addressing in x and z, + 2 = shaded from normals, + 4 = BC7
/// blocks filtered by loads, [`VolumeStorage::Blocks`], + 8 = the normals are moments,
/// [`GpuVolume::moments`]); `q` = (the instance's asset-wide `v₀`, the
/// asset's largest LOD `L`, and the slice-LOD range `[f_b, f_{b+1})` the band draws).
/// Without bands: `q = (v₀, levels − 1, −∞, ∞)` (SPEC §8.6).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuVolumeParams {
    pub p: [f32; 4],
    pub q: [f32; 4],
    /// x: the world size of a level-0 texel of the band's texture
    /// (`billow_core::slicing::voxel_size` on the instance's cells): the textures hold
    /// optical depths per level-0 texel ([`extinction_levels`]), and a slab takes its
    /// thickness over this of them.
    pub r: [f32; 4],
}

/// One draw: slices `first_slice..first_slice + slice_count` × the `cell_count` cells at
/// `list[list_offset..]` (one dynamic-offset uniform per draw, padded to 256 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuDraw {
    pub first_slice: u32,
    pub slice_count: u32,
    pub list_offset: u32,
    pub cell_count: u32,
    pub pad: [u32; 60],
}

impl Default for GpuDraw {
    fn default() -> Self {
        Self::zeroed()
    }
}

/// An asset's texture on the GPU, shared by all its instances.
pub struct GpuVolume {
    pub dims0: [u32; 3],
    pub levels: u32,
    pub repeat: bool,
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    /// The `(α·n̄, α)` normal texture (module docs), when the asset stores normals.
    pub normals: Option<(wgpu::Texture, wgpu::TextureView)>,
    /// `normals` holds the normals' moments as stored, `(E[n∘n], 0)` (SPEC §8.4a; not
    /// weighted by alpha: the shader divides by their trace), lit two-sided
    /// (`volume.wgsl`'s `moments_cosine`).
    pub moments: bool,
    /// The moments are the file's BC7 blocks, sampled as `Bc7RgbaUnorm` of the snorm
    /// bytes XOR 0x80 (SPEC §12.2): one byte a texel where the colour is sampled as blocks.
    pub moments_bc: bool,
    /// Extinction-space texels, or BC7 blocks (format 1.2, [`Gpu::block_upload`],
    /// [`Gpu::sample_blocks`]).
    pub storage: VolumeStorage,
}

/// How a volume texture stores its texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeStorage {
    /// `(σ·c, σ)` per texel in `Rgba16Float` (module docs), filtered by the texture unit.
    Extinction,
    /// The asset's BC7 blocks of premultiplied colour (format 1.2), filtered in extinction
    /// space by eight loads per level in the shader.
    Blocks,
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

/// The addressing of `asset` (SPEC §8.5): repeat in x and z for shells (header param
/// `shell`), clamp everywhere otherwise.
pub fn repeat_axes(asset: &VolumeAsset) -> [bool; 3] {
    let shell = asset.header.is_shell();
    [shell, false, shell]
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
    /// whose blocks are given, format 1.3) is uploaded as its BC7 `blocks` when the device allows it ([`Gpu::block_upload`]), else as the decoded
    /// texels in `asset.levels` (what the reader decoded on load).
    pub fn upload_with(
        &self,
        gpu: &Gpu,
        asset: &VolumeAsset,
        blocks: Option<&VolumeBlocks>,
    ) -> Result<Vec<GpuVolume>, ViewError> {
        asset
            .validate()
            .map_err(|e| ViewError::InvalidAsset(e.to_string()))?;
        let rep = repeat_axes(asset);
        let repeat = rep[0] || rep[2];
        let cs = asset.header.colour_space;
        let dims0 = asset.level_dims(0);
        let moments = asset.has_moments();
        let direct = blocks
            .filter(|b| b.colour.len() == asset.levels.len() && gpu.block_upload(dims0, true));
        let mut out = vec![match direct {
            Some(b) => {
                check_3d(gpu, dims0, b.colour.len() as u32)?;
                let texture = upload_bc7(
                    gpu,
                    "volume (BC7)",
                    dims0,
                    wgpu::TextureDimension::D3,
                    &b.colour,
                    cs == ColourSpace::SrgbPremultiplied,
                );
                let view = texture.create_view(&Default::default());
                let (normals, moments_bc) = normal_slot(
                    gpu,
                    dims0,
                    &asset.levels,
                    asset.normals.as_deref(),
                    moments.then_some(b.normals.as_deref()).flatten(),
                );
                GpuVolume {
                    dims0,
                    levels: b.colour.len() as u32,
                    repeat,
                    texture,
                    view,
                    normals,
                    moments,
                    moments_bc,
                    storage: VolumeStorage::Blocks,
                }
            }
            None => upload_levels(
                gpu,
                dims0,
                &asset.levels,
                (asset.normals.as_deref(), moments),
                cs,
                repeat,
            )?,
        }];
        // Compressed bands (format 1.3): uploaded as their blocks where the device allows it.
        let band_blocks = blocks
            .map(|b| b.bands.as_slice())
            .filter(|bb| bb.len() == asset.bands.len());
        for (i, b) in asset.bands.iter().enumerate() {
            let direct = band_blocks
                .map(|bb| &bb[i])
                .filter(|bb| bb.colour.len() == b.levels.len() && gpu.block_upload(b.dims, true));
            // Bands address their textures with clamp-to-edge (SPEC §8.6).
            out.push(match direct {
                Some(bb) => {
                    check_3d(gpu, b.dims, bb.colour.len() as u32)?;
                    let texture = upload_bc7(
                        gpu,
                        "volume band (BC7)",
                        b.dims,
                        wgpu::TextureDimension::D3,
                        &bb.colour,
                        cs == ColourSpace::SrgbPremultiplied,
                    );
                    let view = texture.create_view(&Default::default());
                    let (normals, moments_bc) = normal_slot(
                        gpu,
                        b.dims,
                        &b.levels,
                        b.normals.as_deref(),
                        moments.then_some(bb.normals.as_deref()).flatten(),
                    );
                    GpuVolume {
                        dims0: b.dims,
                        levels: bb.colour.len() as u32,
                        repeat: false,
                        texture,
                        view,
                        normals,
                        moments,
                        moments_bc,
                        storage: VolumeStorage::Blocks,
                    }
                }
                None => upload_levels(
                    gpu,
                    b.dims,
                    &b.levels,
                    (b.normals.as_deref(), moments),
                    cs,
                    false,
                )?,
            });
        }
        Ok(out)
    }
}

/// A `dims0` volume with `count` levels fits a 3D texture of the device.
fn check_3d(gpu: &Gpu, dims0: [u32; 3], count: u32) -> Result<(), ViewError> {
    let max3d = gpu.device.limits().max_texture_dimension_3d;
    if dims0.iter().any(|&d| d > max3d) || count == 0 {
        return Err(ViewError::InvalidAsset(format!(
            "volume {}x{}x{} with {count} levels does not fit a 3D texture (max {max3d})",
            dims0[0], dims0[1], dims0[2]
        )));
    }
    Ok(())
}

/// One 3D texture in extinction space with its MIP chain (`levels[l]` is
/// `mip_dims(dims0, l)` RGBA8 texels; [`extinction_levels`]).
fn upload_levels(
    gpu: &Gpu,
    dims0: [u32; 3],
    levels: &[Vec<u8>],
    (normals, moments): (Option<&[Vec<u8>]>, bool),
    colour_space: ColourSpace,
    repeat: bool,
) -> Result<GpuVolume, ViewError> {
    let count = levels.len() as u32;
    check_3d(gpu, dims0, count)?;
    let ratios: Vec<f32> = (0..count)
        .map(|l| level_size_ratio(dims0, billow_format::mip_dims(dims0, l)))
        .collect();
    let texels = extinction_levels(
        levels,
        &ratios,
        colour_space == ColourSpace::SrgbPremultiplied,
    );
    let (texture, view) = texture_3d(
        gpu,
        "volume (extinction)",
        dims0,
        EXTINCTION_FORMAT,
        texels.iter().map(|b| &b[..]),
    );
    let normals = if moments {
        moments_texture(gpu, dims0, normals)
    } else {
        normal_texture(gpu, dims0, levels, normals)
    };
    Ok(GpuVolume {
        dims0,
        levels: count,
        repeat,
        texture,
        view,
        normals,
        moments,
        moments_bc: false,
        storage: VolumeStorage::Extinction,
    })
}

/// The format of [`VolumeStorage::Extinction`] textures: filterable everywhere; f16
/// keeps σ (at most 6.23) to 2⁻¹¹ of itself, which moves α by at most 1.8·10⁻⁴
/// (`σ·e^−σ·2⁻¹¹ ≤ e⁻¹·2⁻¹¹`), under a twentieth of an 8-bit step.
pub const EXTINCTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// RGBA8 levels (`srgb`: sRGB-encoded premultiplied colour) as little-endian `Rgba16Float`
/// texels in extinction space, `(σ·c, σ)` ([`billow_core::extinction::extinction_texel`],
/// through tables of its per-byte factors: the same f32 operations, so the same values),
/// each level's optical depth divided by the size of its texels in level-0 texels
/// (`ratios[l]`, [`level_size_ratio`]): a density per level-0 texel, so that the texture
/// unit's blend of two levels is the CPU slicer's (`billow_core::slicing::level_weights`),
/// and opaque texels hold [`billow_core::extinction::MAX_OPTICAL_DEPTH`] at every level
/// (`billow_core::slicing::opaque_optical_depth`). A ratio of 1 stores `extinction_texel`.
pub fn extinction_levels(levels: &[Vec<u8>], ratios: &[f32], srgb: bool) -> Vec<Vec<u8>> {
    use billow_core::extinction::{srgb8_to_linear, to_density};
    let lin: [f32; 256] = std::array::from_fn(|v| {
        if srgb {
            srgb8_to_linear(v as u8)
        } else {
            v as f32 / 255.0
        }
    });
    levels
        .iter()
        .enumerate()
        .map(|(l, bytes)| {
            let r = ratios.get(l).copied().filter(|r| *r > 0.0).unwrap_or(1.0);
            // Per alpha byte: the density and the colour factor density/α (0 where α = 0).
            let sigma: [(f32, f32); 256] = std::array::from_fn(|a| {
                let alpha = a as f32 / 255.0;
                let c = glam::Vec4::new(0.0, 0.0, 0.0, alpha);
                let s = to_density(c, r).w;
                (s, if a > 0 { s / alpha } else { 0.0 })
            });
            let mut out = Vec::with_capacity(bytes.len() * 2);
            for t in bytes.chunks_exact(4) {
                let (s, k) = sigma[t[3] as usize];
                for v in [
                    lin[t[0] as usize] * k,
                    lin[t[1] as usize] * k,
                    lin[t[2] as usize] * k,
                    s,
                ] {
                    out.extend_from_slice(&half::f16::from_f32(v).to_le_bytes());
                }
            }
            out
        })
        .collect()
}

/// The `(α·n̄, α)` normal texture of a volume that stores normals (module docs), in
/// [`NORMAL_FORMAT`]: the colour alpha weights the stored snorm8 normal, and the product is
/// rounded to the nearest 1/127 (an opaque texel's normal exactly as stored).
fn normal_texture(
    gpu: &Gpu,
    dims0: [u32; 3],
    levels: &[Vec<u8>],
    normals: Option<&[Vec<u8>]>,
) -> Option<(wgpu::Texture, wgpu::TextureView)> {
    normals.map(|nl| {
        let texels: Vec<Vec<u8>> = nl
            .iter()
            .zip(levels)
            .map(|(n, c)| {
                let mut out = Vec::with_capacity(n.len());
                for (t, c) in n.chunks_exact(4).zip(c.chunks_exact(4)) {
                    let a = f32::from(c[3]) / 255.0;
                    let d = |b: u8| (b as i8 as f32 / 127.0).max(-1.0) * a;
                    out.extend([d(t[0]), d(t[1]), d(t[2]), a].map(snorm8));
                }
                out
            })
            .collect();
        texture_3d(
            gpu,
            "volume normals",
            dims0,
            NORMAL_FORMAT,
            texels.iter().map(|b| &b[..]),
        )
    })
}

/// The normal slot of a BC7-sampled volume whose normals are `moments` given (its `VMB7`
/// blocks; `None` for mean normals): the blocks themselves, sampled as they are
/// (`volume.wgsl` undoes the XOR 0x80: `v = (255·u − 128)/127`, affine, so it commutes
/// with filtering), and `true`; else [`normal_texture`] of the decoded normals.
fn normal_slot(
    gpu: &Gpu,
    dims0: [u32; 3],
    levels: &[Vec<u8>],
    normals: Option<&[Vec<u8>]>,
    moments: Option<&[Vec<u8>]>,
) -> (Option<(wgpu::Texture, wgpu::TextureView)>, bool) {
    match moments {
        Some(blocks) => {
            let texture = upload_bc7_filled(
                gpu,
                "volume moments (BC7)",
                dims0,
                wgpu::TextureDimension::D3,
                blocks,
                false,
                billow_format::SIGNED_ZERO_BLOCK,
            );
            let view = texture.create_view(&Default::default());
            (Some((texture, view)), true)
        }
        None => (normal_texture(gpu, dims0, levels, normals), false),
    }
}

/// The normal moments of a volume as stored (`Rgba8Snorm` `(E[n∘n], 0)`, SPEC §8.4a), four
/// bytes a texel: the shader normalises by their trace, so they need no alpha.
fn moments_texture(
    gpu: &Gpu,
    dims0: [u32; 3],
    moments: Option<&[Vec<u8>]>,
) -> Option<(wgpu::Texture, wgpu::TextureView)> {
    moments.map(|m| {
        texture_3d(
            gpu,
            "volume moments",
            dims0,
            NORMAL_FORMAT,
            m.iter().map(|b| &b[..]),
        )
    })
}

/// The format of a volume's normal texture, `(α·n̄, α)`: every component is in
/// [−1, 1], and the file's normals are snorm8 already, so four bytes a texel hold them
/// (`billow_core::gpu_memory::VOLUME_NORMAL_TEXEL_BYTES`).
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Snorm;

/// `v` in [−1, 1] as a snorm8 byte (round to nearest; the GPU reads `max(b / 127, −1)`).
fn snorm8(v: f32) -> u8 {
    (v.clamp(-1.0, 1.0) * 127.0).round() as i8 as u8
}

/// A 3D texture of `format` with one MIP level per item of `levels` (tightly packed).
fn texture_3d<'a>(
    gpu: &Gpu,
    label: &str,
    dims0: [u32; 3],
    format: wgpu::TextureFormat,
    levels: impl ExactSizeIterator<Item = &'a [u8]>,
) -> (wgpu::Texture, wgpu::TextureView) {
    let count = levels.len() as u32;
    let bpp = format.block_copy_size(None).unwrap_or(4);
    let texture = gpu.asset_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: dims0[0],
            height: dims0[1],
            depth_or_array_layers: dims0[2],
        },
        mip_level_count: count,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (l, bytes) in levels.enumerate() {
        let d = billow_format::mip_dims(dims0, l as u32);
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
                bytes_per_row: Some(bpp * d[0]),
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
    (texture, view)
}

#[cfg(test)]
mod tests {
    use super::*;
    use billow_core::extinction::extinction_texel;

    /// The tables of [`extinction_levels`] give `extinction_texel` exactly (before the
    /// f16 rounding, which is the format's).
    #[test]
    fn extinction_levels_are_the_core_conversion_rounded_to_f16() {
        for srgb in [false, true] {
            let mut level = Vec::new();
            for a in 0..=255u8 {
                for c in [0u8, 1, 17, 128, 200, 255] {
                    level.extend_from_slice(&[c, c / 2, 255 - c, a]);
                }
            }
            let out = &extinction_levels(std::slice::from_ref(&level), &[1.0], srgb)[0];
            assert_eq!(out.len(), 2 * level.len());
            for (t, h) in level.chunks_exact(4).zip(out.chunks_exact(8)) {
                let want = extinction_texel([t[0], t[1], t[2], t[3]], srgb).to_array();
                for (k, w) in want.iter().enumerate() {
                    let got = half::f16::from_le_bytes([h[2 * k], h[2 * k + 1]]);
                    assert_eq!(got, half::f16::from_f32(*w), "{t:?} srgb {srgb} [{k}]");
                }
            }
        }
    }

    /// A coarser level stores densities per level-0 voxel: half the optical depth of a
    /// texel twice as large, and opaque texels the same as level 0's.
    #[test]
    fn coarse_levels_store_densities_per_level0_voxel() {
        let level = vec![10u8, 20, 30, 128, 40, 50, 60, 255];
        let one = &extinction_levels(std::slice::from_ref(&level), &[1.0], false)[0];
        let two = &extinction_levels(std::slice::from_ref(&level), &[2.0], false)[0];
        let h = |b: &[u8], k: usize| half::f16::from_le_bytes([b[2 * k], b[2 * k + 1]]).to_f32();
        for k in 0..4 {
            let (a, b) = (h(one, k), h(two, k));
            assert!(
                (b - a / 2.0).abs() <= 1e-3 * a.abs().max(1e-3),
                "[{k}] {a} {b}"
            );
        }
        for k in 4..8 {
            assert_eq!(h(one, k), h(two, k), "opaque texel [{k}]");
        }
    }

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
