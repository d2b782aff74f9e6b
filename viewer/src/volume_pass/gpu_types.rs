//! The volume pass's GPU-side records, laid out as `volume.wgsl` reads them: the cells,
//! slices, per-instance parameters and draws of a frame, the frame uniform, and the
//! uploaded textures of an asset ([`GpuVolume`], made by the textures module).

use bytemuck::{Pod, Zeroable};
use glam::Mat3;

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
    /// optical depths per level-0 texel ([`super::extinction_levels`]), and a slab takes its
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
    /// The `(α·n̄, α)` normal texture (the volume pass's module docs), when the asset stores normals.
    pub normals: Option<(wgpu::Texture, wgpu::TextureView)>,
    /// `normals` holds the normals' moments as stored, `(E[n∘n], 0)` (SPEC §8.4a; not
    /// weighted by alpha: the shader divides by their trace), lit two-sided
    /// (`volume.wgsl`'s `moments_cosine`).
    pub moments: bool,
    /// The moments are the file's BC7 blocks, sampled as `Bc7RgbaUnorm` of the snorm
    /// bytes XOR 0x80 (SPEC §12.2): one byte a texel where the colour is sampled as blocks.
    pub moments_bc: bool,
    /// Extinction-space texels, or BC7 blocks (format 1.2, [`crate::Gpu::block_upload`],
    /// [`crate::Gpu::sample_blocks`]).
    pub storage: VolumeStorage,
}

/// How a volume texture stores its texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeStorage {
    /// `(σ·c, σ)` per texel in `Rgba16Float` (the volume pass's module docs), filtered by the texture unit.
    Extinction,
    /// The asset's BC7 blocks of premultiplied colour (format 1.2), filtered in extinction
    /// space by eight loads per level in the shader.
    Blocks,
}
