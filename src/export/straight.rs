//! Straight-alpha atlases for viewers that filter straight colour (glTF viewers, image
//! tools): un-premultiply, and dilate colour into transparent texels by pull-push.
//!
//! The asset stores atlases premultiplied (`SrgbPremultiplied`), so its own MIPs never
//! darken. A straight-alpha consumer builds its MIPs (and bilinear taps) by averaging
//! straight colour with no regard to alpha: a transparent texel's colour leaks into its
//! neighbours. Exported as black (what un-premultiplying a transparent texel gives), it
//! darkens every leaf edge at a distance. So each transparent texel (alpha byte 0) gets
//! the straight colour of the nearest coarser MIP level of the *premultiplied* chain that
//! has coverage there (pull: the asset's MIPs; push: fill from coarse to fine): the
//! alpha-weighted mean colour of the surrounding leaves. Alpha is never changed.
//!
//! Output: 8-bit RGBA, RGB sRGB-encoded straight colour, alpha linear: what PNG and glTF
//! (`baseColorTexture`) expect.

use billow_format::Atlas;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// sRGB byte → linear.
fn lut() -> &'static [f32; 256] {
    crate::texture::srgb_to_linear_lut()
}

/// Straight linear colour of a premultiplied sRGB texel (`None` when transparent).
fn unpremultiply(p: &[u8]) -> Option<Vec3> {
    if p[3] == 0 {
        return None;
    }
    let l = lut();
    let a = f32::from(p[3]) / 255.0;
    let c = Vec3::new(l[p[0] as usize], l[p[1] as usize], l[p[2] as usize]) / a;
    Some(c.clamp(Vec3::ZERO, Vec3::ONE))
}

fn mip_dims(a: &Atlas, k: usize) -> (usize, usize) {
    let d = |x: u32| (x >> k.min(31)).max(1) as usize;
    (d(a.width), d(a.height))
}

/// One pyramid level: size and straight colour per texel (`None` where transparent).
type Level = ((usize, usize), Vec<Option<Vec3>>);

/// The straight colour of every texel of MIP `level`, transparent texels filled from the
/// coarser levels (pull-push). Colours linear. The asset stores a capped chain (SPEC §9.4);
/// for the pull the pyramid is continued below its last stored level, down to 1×1, by the
/// same premultiplied box filter (those levels are only used here, never exported).
pub fn dilated_colour(atlas: &Atlas, level: usize) -> Vec<Vec3> {
    let last = atlas.mips.len().saturating_sub(1);
    let level = level.min(last);
    // Straight colour per level, finest first: stored levels, then the continuation.
    let mut pyramid: Vec<Level> = (level..=last)
        .map(|k| {
            let straight = atlas.mips[k]
                .par_chunks_exact(4)
                .map(unpremultiply)
                .collect();
            (mip_dims(atlas, k), straight)
        })
        .collect();
    let l = lut();
    let (mut w, mut h) = mip_dims(atlas, last);
    let mut pm: Vec<Vec4> = atlas.mips[last]
        .chunks_exact(4)
        .map(|p| {
            Vec4::new(
                l[p[0] as usize],
                l[p[1] as usize],
                l[p[2] as usize],
                f32::from(p[3]) / 255.0,
            )
        })
        .collect();
    while w > 1 || h > 1 {
        let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
        let get = |x: usize, y: usize| pm[y.min(h - 1) * w + x.min(w - 1)];
        pm = (0..w2 * h2)
            .map(|i| {
                let (x, y) = (2 * (i % w2), 2 * (i / w2));
                0.25 * (get(x, y) + get(x + 1, y) + get(x, y + 1) + get(x + 1, y + 1))
            })
            .collect();
        (w, h) = (w2, h2);
        let straight = pm
            .iter()
            .map(|p| (p.w > 0.0).then(|| (p.truncate() / p.w).clamp(Vec3::ZERO, Vec3::ONE)))
            .collect();
        pyramid.push(((w, h), straight));
    }
    // Push, coarsest first: a texel with no coverage anywhere is mid grey (never seen).
    let mut fill: Vec<Vec3> = Vec::new();
    let mut fill_dims = (1usize, 1usize);
    for ((w, h), straight) in pyramid.into_iter().rev() {
        let coarse = &fill;
        let (cw, ch) = fill_dims;
        let next: Vec<Vec3> = straight
            .into_par_iter()
            .enumerate()
            .map(|(i, c)| {
                c.unwrap_or_else(|| {
                    if coarse.is_empty() {
                        Vec3::splat(0.5)
                    } else {
                        let (x, y) = ((i % w) / 2, (i / w) / 2);
                        coarse[y.min(ch - 1) * cw + x.min(cw - 1)]
                    }
                })
            })
            .collect();
        fill = next;
        fill_dims = (w, h);
    }
    fill
}

/// MIP `level` of `atlas` as straight-alpha RGBA8 (sRGB colour), transparent texels
/// dilated.
pub fn straight_rgba8(atlas: &Atlas, level: usize) -> Vec<u8> {
    let level = level.min(atlas.mips.len().saturating_sub(1));
    let colour = dilated_colour(atlas, level);
    let alpha = &atlas.mips[level];
    let enc = |c: f32| crate::texture::encode_srgb(c.clamp(0.0, 1.0));
    colour
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, c)| [enc(c.x), enc(c.y), enc(c.z), alpha[4 * i + 3]])
        .collect()
}

/// MIP `level` of `atlas` as straight alpha with transparent texels left black: what a
/// naive un-premultiply gives (for comparison in tests and docs).
pub fn straight_rgba8_undilated(atlas: &Atlas, level: usize) -> Vec<u8> {
    let level = level.min(atlas.mips.len().saturating_sub(1));
    let enc = |c: f32| crate::texture::encode_srgb(c.clamp(0.0, 1.0));
    atlas.mips[level]
        .chunks_exact(4)
        .flat_map(|p| {
            let c = unpremultiply(p).unwrap_or(Vec3::ZERO);
            [enc(c.x), enc(c.y), enc(c.z), p[3]]
        })
        .collect()
}

/// Encode RGBA8 as PNG (8-bit, straight alpha).
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Encode RGB8 as PNG (8-bit, no colour-space conversion: used for normal maps).
pub fn encode_png_rgb(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Level 0 of an atlas as a straight-alpha, dilated PNG.
pub fn atlas_png(atlas: &Atlas) -> Result<Vec<u8>, String> {
    encode_png(atlas.width, atlas.height, &straight_rgba8(atlas, 0))
}

/// File name of atlas `i` of LOD `level` in an `--atlas` dump.
pub fn atlas_file_name(level: usize, i: usize) -> String {
    format!("lod{level}_atlas{i}.png")
}

/// Every atlas of `asset` as (file name, PNG bytes), in level then atlas order.
pub fn atlas_pngs(asset: &billow_format::CloudAsset) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut out = Vec::new();
    for (l, lv) in asset.levels.iter().enumerate() {
        for k in 0..lv.atlas_count as usize {
            let a = &asset.atlases[lv.first_atlas as usize + k];
            out.push((atlas_file_name(l, k), atlas_png(a)?));
        }
    }
    Ok(out)
}
