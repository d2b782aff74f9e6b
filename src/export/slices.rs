//! Slice export: every z-slice of one MIP level as an image, for looking at the volume.
//!
//! Files are `slice_0000.png`, `slice_0001.png`, … (or `.exr`), one per z from 0 to
//! `depth − 1` of the level, 4 digits at least (more when depth exceeds 10 000, which the
//! format's 4096 limit rules out). The image shows the slice seen from +z (x to the right,
//! **y up**): image row 0 is the top row `y = h − 1`, so the volume appears upright
//! (billow is Y-up). Pixel `(px, row)` of slice `z` is texel `(px, h − 1 − row, z)`.
//!
//! - [`SliceFormat::Png8`]: 8-bit RGBA, **straight** (not premultiplied) alpha, sRGB —
//!   what image viewers expect. Each texel is decoded to linear premultiplied colour,
//!   divided by alpha *in linear space*, clamped to [0, 1] (premultiplied colour above
//!   alpha, which a valid bake does not produce, saturates), sRGB-encoded and rounded;
//!   alpha is copied. Texels with alpha 0 become transparent black `(0, 0, 0, 0)`.
//! - [`SliceFormat::Exr`]: 32-bit float RGBA, **linear premultiplied** (OpenEXR's own
//!   convention), the decoded texel values exactly (no clamping needed).

use std::path::{Path, PathBuf};

use billow_format::{write_atomic, VolumeAsset};

use super::{check_asset, decode_texel, srgb_oetf, to_u8, ExportError};

/// Image format of exported slices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SliceFormat {
    /// 8-bit RGBA PNG, straight alpha, sRGB.
    Png8,
    /// 32-bit float RGBA OpenEXR, linear premultiplied.
    Exr,
}

impl SliceFormat {
    /// File extension without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            SliceFormat::Png8 => "png",
            SliceFormat::Exr => "exr",
        }
    }
}

/// `slice_0007.png` for `z = 7`.
pub fn slice_file_name(z: u32, format: SliceFormat) -> String {
    format!("slice_{z:04}.{}", format.extension())
}

/// Writes every z-slice of MIP level `level` of `asset` into `dir` (created if missing),
/// each file atomically, and returns their paths in z order. A level beyond the asset's
/// `mip_count` is refused before anything is written.
pub fn write_slices(
    asset: &VolumeAsset,
    level: u32,
    dir: &Path,
    format: SliceFormat,
) -> Result<Vec<PathBuf>, ExportError> {
    let depth = check_slices(asset, level, dir)?;
    std::fs::create_dir_all(dir).map_err(|source| ExportError::CreateDir {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut paths = Vec::with_capacity(depth as usize);
    for z in 0..depth {
        let path = dir.join(slice_file_name(z, format));
        let bytes = slice_bytes(asset, level, z, format, &path)?;
        write_atomic(&path, &bytes).map_err(ExportError::Write)?;
        paths.push(path);
    }
    Ok(paths)
}

/// Checks that `asset` can be exported and has MIP level `level` (`dir` names the output in
/// errors); the number of slices (the level's depth).
pub fn check_slices(asset: &VolumeAsset, level: u32, dir: &Path) -> Result<u32, ExportError> {
    check_asset(asset, dir)?;
    let mip_count = asset.levels.len() as u32;
    if level >= mip_count {
        return Err(ExportError::NoSuchLevel {
            path: dir.to_path_buf(),
            level,
            mip_count,
        });
    }
    Ok(asset.level_dims(level)[2])
}

/// The file [`write_slices`] writes for slice `z` of MIP level `level` (checked with
/// [`check_slices`] first), in memory; `path` only names it in errors.
pub fn slice_bytes(
    asset: &VolumeAsset,
    level: u32,
    z: u32,
    format: SliceFormat,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    let [w, h, _] = asset.level_dims(level);
    let texels = &asset.levels[level as usize];
    let slice_bytes = (w * h) as usize * 4;
    let slice = &texels[z as usize * slice_bytes..(z as usize + 1) * slice_bytes];
    match format {
        SliceFormat::Png8 => png_bytes(asset, slice, w, h, path),
        SliceFormat::Exr => exr_bytes(asset, slice, w, h, path),
    }
}

/// The texel shown at image pixel `(px, row)` of a `w × h` slice.
fn texel(slice: &[u8], w: u32, h: u32, px: u32, row: u32) -> [u8; 4] {
    let i = 4 * (px + w * (h - 1 - row)) as usize;
    [slice[i], slice[i + 1], slice[i + 2], slice[i + 3]]
}

/// Straight-alpha sRGB RGBA8 of one stored texel (see the module docs).
pub fn straight_srgb8(colour_space: billow_format::ColourSpace, t: [u8; 4]) -> [u8; 4] {
    if t[3] == 0 {
        return [0; 4];
    }
    let [r, g, b, a] = decode_texel(colour_space, t);
    let s = |c: f32| to_u8(srgb_oetf((c / a).clamp(0.0, 1.0)));
    [s(r), s(g), s(b), t[3]]
}

fn png_bytes(
    asset: &VolumeAsset,
    slice: &[u8],
    w: u32,
    h: u32,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    use image::ImageEncoder;
    let cs = asset.header.colour_space;
    let mut rgba = Vec::with_capacity(slice.len());
    for row in 0..h {
        for px in 0..w {
            rgba.extend_from_slice(&straight_srgb8(cs, texel(slice, w, h, px, row)));
        }
    }
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(&rgba, w, h, image::ExtendedColorType::Rgba8)
        .map_err(|e| ExportError::Encode {
            path: path.to_path_buf(),
            format: "PNG",
            message: e.to_string(),
        })?;
    Ok(out)
}

fn exr_bytes(
    asset: &VolumeAsset,
    slice: &[u8],
    w: u32,
    h: u32,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    use exr::prelude::*;
    let cs = asset.header.colour_space;
    let channels = SpecificChannels::rgba(|Vec2(px, row): Vec2<usize>| {
        let [r, g, b, a] = decode_texel(cs, texel(slice, w, h, px as u32, row as u32));
        (r, g, b, a)
    });
    let image = Image::from_channels((w as usize, h as usize), channels);
    let mut cursor = std::io::Cursor::new(Vec::new());
    image
        .write()
        .non_parallel()
        .to_buffered(&mut cursor)
        .map_err(|e| ExportError::Encode {
            path: path.to_path_buf(),
            format: "EXR",
            message: e.to_string(),
        })?;
    Ok(cursor.into_inner())
}
