//! Block-compressed textures (format 1.2, SPEC §12): a BC7 MIP chain uploaded as its
//! blocks, one byte per texel of GPU memory instead of four. Used only where
//! [`Gpu::block_upload`] allows it; otherwise the callers upload the decoded texels the
//! asset reader already produced (the decode-on-load path).

use crate::Gpu;

/// Uploads the BC7 `levels` (`levels[l]`: the compressed chunk payload of
/// `mip_dims(dims0, l)`, SPEC §12.1: omitted blocks are uploaded as a block of zeros) as a `dimension` texture of `Bc7RgbaUnormSrgb` (`srgb`) or
/// `Bc7RgbaUnorm`. The caller checked [`Gpu::block_upload`].
pub fn upload_bc7(
    gpu: &Gpu,
    label: &str,
    dims0: [u32; 3],
    dimension: wgpu::TextureDimension,
    levels: &[Vec<u8>],
    srgb: bool,
) -> wgpu::Texture {
    upload_bc7_filled(
        gpu,
        label,
        dims0,
        dimension,
        levels,
        srgb,
        billow_format::ZERO_BLOCK,
    )
}

/// [`upload_bc7`] with `fill` for the omitted blocks: [`billow_format::ZERO_BLOCK`] for
/// colour, [`billow_format::SIGNED_ZERO_BLOCK`] for normal moments (SPEC §12.2).
pub fn upload_bc7_filled(
    gpu: &Gpu,
    label: &str,
    dims0: [u32; 3],
    dimension: wgpu::TextureDimension,
    levels: &[Vec<u8>],
    srgb: bool,
    fill: [u8; 16],
) -> wgpu::Texture {
    let format = if srgb {
        wgpu::TextureFormat::Bc7RgbaUnormSrgb
    } else {
        wgpu::TextureFormat::Bc7RgbaUnorm
    };
    let texture = gpu.asset_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: dims0[0],
            height: dims0[1],
            depth_or_array_layers: dims0[2],
        },
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (l, payload) in levels.iter().enumerate() {
        let d = billow_format::mip_dims(dims0, l as u32);
        let blocks = billow_format::expand_blocks(payload, d, fill);
        let (bw, bh) = (d[0].div_ceil(4), d[1].div_ceil(4));
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: l as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &blocks,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(bw * billow_format::BC7_BLOCK_BYTES as u32),
                rows_per_image: Some(bh),
            },
            // Copies of block-compressed levels cover whole blocks (the physical size).
            wgpu::Extent3d {
                width: bw * 4,
                height: bh * 4,
                depth_or_array_layers: d[2],
            },
        );
    }
    texture
}
