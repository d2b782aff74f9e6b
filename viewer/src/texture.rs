//! 2D textures: RGBA8 with RGB sRGB-encoded, uploaded as `Rgba8UnormSrgb` with a MIP
//! chain built on the CPU (2×2 box filter of linear values; straight-alpha textures are
//! weighted by alpha so transparent texels do not darken their neighbours).
//!
//! Computed levels are plain averages, alpha-tested textures too: a level's alpha is then
//! the share of its area that is covered, which the meshes' hashed alpha test
//! (`shaders/alpha_hash.wgsl`) draws in expectation. Until 2026-12-06 each level's alpha
//! was instead scaled so that the share of texels passing a fixed cut-off stayed level 0's
//! (Castaño, "Computing alpha mipmaps", 2010); a leaf smaller than a pixel then drew all of
//! itself or nothing, and the oak's mesh drew −3 / −18 / +18 % of the ray-traced mesh's
//! coverage at 1× / 4× / 16× (640×480; docs/viewer.md, "Alpha-tested meshes at a
//! distance").

use crate::Gpu;

/// A `width`×`height` 2D texture of `format` with one level and one sample (render
/// targets, look-up tables, the shadow map).
pub fn desc_2d<'a>(
    label: &'a str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureDescriptor<'a> {
    wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    }
}

/// The sampler of the mesh and cloud materials: repeating, trilinear.
pub fn repeat_sampler(device: &wgpu::Device, label: &str) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

/// An RGBA8 image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureData {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<u8>,
    /// Colour premultiplied by alpha (atlases) or straight (authored textures).
    pub premultiplied: bool,
    /// MIP levels 1.. when the asset brings its own (level 0 is `texels`).
    pub mips: Vec<Vec<u8>>,
}

impl TextureData {
    /// A straight-alpha texture without stored MIPs.
    pub fn straight(width: u32, height: u32, texels: Vec<u8>) -> Self {
        TextureData {
            width,
            height,
            texels,
            premultiplied: false,
            mips: Vec::new(),
        }
    }

    /// A 1×1 white texel.
    pub fn white() -> Self {
        Self::straight(1, 1, vec![255; 4])
    }
}

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The next MIP level of `src` (`w`×`h`), 2×2 box (a last odd row/column is folded in).
fn downsample(src: &[u8], w: u32, h: u32, premultiplied: bool) -> Vec<u8> {
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let mut lut = [0f32; 256];
    for (i, l) in lut.iter_mut().enumerate() {
        *l = srgb_to_linear(i as f32 / 255.0);
    }
    let mut out = vec![0u8; (nw * nh * 4) as usize];
    for y in 0..nh {
        for x in 0..nw {
            let (x0, x1) = (2 * x, if x + 1 == nw { w - 1 } else { 2 * x + 1 });
            let (y0, y1) = (2 * y, if y + 1 == nh { h - 1 } else { 2 * y + 1 });
            let mut acc = [0f64; 4];
            let mut n = 0.0;
            for sy in y0..=y1.max(y0) {
                for sx in x0..=x1.max(x0) {
                    let i = ((sy * w + sx) * 4) as usize;
                    let a = f64::from(src[i + 3]) / 255.0;
                    let wgt = if premultiplied { 1.0 } else { a };
                    for c in 0..3 {
                        acc[c] += f64::from(lut[src[i + c] as usize]) * wgt;
                    }
                    acc[3] += a;
                    n += 1.0;
                }
            }
            let a = acc[3] / n;
            let o = ((y * nw + x) * 4) as usize;
            for c in 0..3 {
                let lin = if premultiplied {
                    acc[c] / n
                } else if acc[3] > 0.0 {
                    acc[c] / acc[3]
                } else {
                    0.0
                };
                out[o + c] = (linear_to_srgb(lin.clamp(0.0, 1.0) as f32) * 255.0).round() as u8;
            }
            out[o + 3] = (a * 255.0).round() as u8;
        }
    }
    out
}

/// Writes level `level` (`w`×`h` RGBA8 texels, tightly packed) of a 2D texture.
pub fn write_level(gpu: &Gpu, tex: &wgpu::Texture, level: u32, texels: &[u8], (w, h): (u32, u32)) {
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: tex,
            mip_level: level,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * w),
            rows_per_image: Some(h),
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
}

/// Uploads `t` as an `Rgba8UnormSrgb` texture: with its stored MIP chain when it brings
/// one (premultiplied atlases cap their chain where coarser levels would mix
/// neighbouring billboards, SPEC §9.4: sampling clamps to the last stored level), else
/// a full computed chain.
pub fn upload_rgba8_mips(gpu: &Gpu, t: &TextureData, label: &str) -> wgpu::Texture {
    let full = 32 - t.width.max(t.height).max(1).leading_zeros();
    let levels = if t.mips.is_empty() {
        full
    } else {
        (1 + t.mips.len() as u32).min(full)
    };
    let tex = gpu.asset_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: t.width,
            height: t.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut level = t.texels.clone();
    let (mut w, mut h) = (t.width, t.height);
    for l in 0..levels {
        write_level(gpu, &tex, l, &level, (w, h));
        if l + 1 == levels {
            break;
        }
        let next = match t.mips.get(l as usize) {
            Some(m) => m.clone(),
            None => downsample(&level, w, h, t.premultiplied),
        };
        (w, h) = ((w / 2).max(1), (h / 2).max(1));
        level = next;
    }
    tex
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_alpha_mips_keep_the_colour_of_opaque_texels() {
        // A red opaque texel beside three transparent black ones: the straight-alpha MIP
        // stays red (a plain average would darken it), alpha is the mean.
        let src = [255, 0, 0, 255, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        let m = downsample(&src, 2, 2, false);
        assert_eq!(m, vec![255, 0, 0, 64]);
        // Premultiplied: the colour is averaged with the transparent texels.
        let p = downsample(&src, 2, 2, true);
        assert_eq!(p[3], 64);
        assert!(p[0] < 255 && p[0] > 64, "{p:?}");
        // Odd sizes fold the last row and column in.
        let odd = vec![200u8; 3 * 3 * 4];
        assert_eq!(downsample(&odd, 3, 3, false), vec![200; 4]);
    }
}
