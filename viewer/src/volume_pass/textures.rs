//! The volume pass's textures: an asset's base texture and LOD bands uploaded with their
//! MIP chains, in extinction space or as BC7 blocks, and their normal textures (the
//! volume pass's module docs).

use billow_core::slicing::level_size_ratio;
use billow_format::{ColourSpace, VolumeAsset, VolumeBlocks};

use super::gpu_types::{GpuVolume, VolumeStorage};
use crate::texture_bc::{upload_bc7, upload_bc7_filled};
use crate::{Gpu, ViewError};

/// The addressing of `asset` (SPEC §8.5): repeat in x and z for shells (header param
/// `shell`), clamp everywhere otherwise.
pub fn repeat_axes(asset: &VolumeAsset) -> [bool; 3] {
    let shell = asset.header.is_shell();
    [shell, false, shell]
}

/// [`super::VolumePass::upload_with`]: `asset`'s base texture, then one per LOD band,
/// each as its BC7 `blocks` where given and the device allows it, else as the decoded
/// texels.
pub(super) fn upload(
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
        .filter(|b| b.colour.len() == asset.levels.len() && gpu.block_upload(dims0, true))
        .map(|b| (&b.colour[..], b.normals.as_deref()));
    let base = Texels {
        dims: dims0,
        levels: &asset.levels,
        normals: asset.normals.as_deref(),
    };
    let mut out = vec![upload_texture(
        gpu,
        "volume (BC7)",
        base,
        direct,
        (cs, moments),
        repeat,
    )?];
    // Compressed bands (format 1.3): uploaded as their blocks where the device allows it.
    let band_blocks = blocks
        .map(|b| b.bands.as_slice())
        .filter(|bb| bb.len() == asset.bands.len());
    for (i, b) in asset.bands.iter().enumerate() {
        let direct = band_blocks
            .map(|bb| &bb[i])
            .filter(|bb| bb.colour.len() == b.levels.len() && gpu.block_upload(b.dims, true))
            .map(|bb| (&bb.colour[..], bb.normals.as_deref()));
        let band = Texels {
            dims: b.dims,
            levels: &b.levels,
            normals: b.normals.as_deref(),
        };
        // Bands address their textures with clamp-to-edge (SPEC §8.6).
        out.push(upload_texture(
            gpu,
            "volume band (BC7)",
            band,
            direct,
            (cs, moments),
            false,
        )?);
    }
    Ok(out)
}

/// The MIP levels of a texture, one byte vector each (texels or BC7 blocks).
type Levels<'a> = &'a [Vec<u8>];

/// One texture of an asset (its base or a band) as the reader decoded it: level-0 size,
/// RGBA8 levels and the stored normals.
struct Texels<'a> {
    dims: [u32; 3],
    levels: Levels<'a>,
    normals: Option<Levels<'a>>,
}

/// Uploads `t` as its BC7 `blocks` where given (colour, and the normals' blocks; `label`
/// names the texture), else as its decoded texels in extinction space ([`upload_levels`]);
/// `(cs, moments)`: the asset's colour space, and whether its normals are moments.
fn upload_texture(
    gpu: &Gpu,
    label: &str,
    t: Texels,
    blocks: Option<(Levels, Option<Levels>)>,
    (cs, moments): (ColourSpace, bool),
    repeat: bool,
) -> Result<GpuVolume, ViewError> {
    let Some((colour, normal_blocks)) = blocks else {
        return upload_levels(gpu, t.dims, t.levels, (t.normals, moments), cs, repeat);
    };
    check_3d(gpu, t.dims, colour.len() as u32)?;
    let texture = upload_bc7(
        gpu,
        label,
        t.dims,
        wgpu::TextureDimension::D3,
        colour,
        cs == ColourSpace::SrgbPremultiplied,
    );
    let view = texture.create_view(&Default::default());
    let (normals, moments_bc) = normal_slot(
        gpu,
        t.dims,
        t.levels,
        t.normals,
        moments.then_some(normal_blocks).flatten(),
    );
    Ok(GpuVolume {
        dims0: t.dims,
        levels: colour.len() as u32,
        repeat,
        texture,
        view,
        normals,
        moments,
        moments_bc,
        storage: VolumeStorage::Blocks,
    })
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

/// The `(α·n̄, α)` normal texture of a volume that stores normals (the volume pass's
/// module docs), in
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
}
