//! KTX 2.0 export: the asset's colour MIP chain as one 3D texture.
//!
//! Layout (KTX 2.0 specification, Khronos; all integers little-endian):
//!
//! | part | content |
//! |------|---------|
//! | identifier | `«KTX 20»\r\n\x1A\n` (12 bytes) |
//! | header | `vkFormat` 43 `R8G8B8A8_SRGB` (`SrgbPremultiplied`) or 37 `R8G8B8A8_UNORM` (`LinearPremultiplied`); `typeSize` 1; `pixelWidth/Height/Depth` = level-0 dims x, y, z (a 3D texture); `layerCount` 0; `faceCount` 1; `levelCount` = the asset's `mip_count`; `supercompressionScheme` 0 (none; 2 with Zstandard, below) |
//! | index | DFD, KVD offsets/lengths; SGD 0/0 |
//! | level index | one `{byteOffset, byteLength, uncompressedByteLength}` per level, level 0 first |
//! | DFD | `dfdTotalSize` + one Basic Data Format Descriptor block (88 bytes) |
//! | KVD | `KTXorientation` = `"ruo"`, `KTXwriter` = `"billow <version>"`, sorted by key, each entry padded to 4 bytes |
//! | levels | level data, **smallest level first** (level `mip_count − 1` … level 0), each level's offset aligned to `lcm(4, texel size 4) = 4` (`mipPadding` zero bytes, never needed for RGBA8 but computed; none when supercompressed) |
//!
//! **Block-compressed** (the asset's `VolumeBlocks`, `billow voxelize --compress bc`, the
//! default): `vkFormat` 146 `BC7_SRGB_BLOCK` or 145 `BC7_UNORM_BLOCK`, `typeSize` 1, the
//! level data the asset's BC7 blocks, every block (the omitted empty ones as a block that
//! decodes to zero, SPEC §12.1; each z slice's 4×4 blocks, rows of blocks
//! top to bottom: KTX's order for a block-compressed 3D image), levels aligned to
//! `lcm(16, 4) = 16`; the DFD's colour model is `KHR_DF_MODEL_BC7` with a 4×4×1×1 texel
//! block of 16 bytes and one 128-bit sample (channel 0, lower 0, upper `0xFFFFFFFF`).
//!
//! **Zstandard supercompression** ([`Supercompression::Zstd`], `billow voxelize --ktx2-zstd
//! LEVEL`, off by default): `supercompressionScheme` 2, each level's bytes (the same bytes as
//! without it) one Zstandard frame of its own at the given level, compressed on one thread
//! (no `zstdmt`), so the same asset and level give the same file; `byteLength` is the
//! frame's length and `uncompressedByteLength` the level's, the levels follow each other
//! with no `mipPadding` (the required alignment of a supercompressed level is 1) and the
//! DFD is the one of the uncompressed data, `bytesPlane0` included (KTX-Software's `ktx
//! deflate` keeps it too, and its validator warns when a supercompressed file's is 0; an
//! older revision of the KTX 2.0 text asked for 0). SGD stays empty (Zstandard needs none).
//!
//! The level bytes are the asset's bytes unchanged: texel `(x, y, z)` at `4·(x + w·(y + h·z))`,
//! which is KTX's row-major, slice-by-slice image order.
//!
//! The Basic DFD: colour model `KHR_DF_MODEL_RGBSDA`, primaries `BT709`, transfer `SRGB`
//! (or `LINEAR`), flags **`KHR_DF_FLAG_ALPHA_PREMULTIPLIED`**, texel block 1×1×1×1, 4 bytes
//! in plane 0, four 8-bit samples R (bits 0..8), G (8..16), B (16..24), A (24..32) with
//! `sampleLower` 0 and `sampleUpper` 255; with the sRGB transfer the alpha sample carries the
//! `KHR_DF_SAMPLE_DATATYPE_LINEAR` qualifier (alpha is stored linear). So a GPU sampling the
//! `_SRGB` format decodes rgb with the sRGB EOTF to *linear premultiplied* colour before
//! filtering — exactly the asset's meaning (SPEC §8.3: the premultiplication happened in
//! linear space).
//!
//! `KTXorientation` `"ruo"`: x increases to the right, y **up**, z **out** of the screen
//! (billow is Y-up and right-handed; row 0 of each image is the *bottom* of the volume).
//! Loaders that ignore the key (most GPU uploads) are unaffected: texture coordinates map
//! to texels exactly as the asset's uvw do.

use std::path::Path;

use billow_format::{
    bc7_len, expand_blocks, mip_dims, write_atomic, ColourSpace, VolumeAsset, VolumeBlocks,
    ZERO_BLOCK,
};

use rayon::prelude::*;

use super::{check_asset, ExportError};

/// The 12-byte KTX 2.0 file identifier.
pub const KTX2_IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];
/// `VK_FORMAT_R8G8B8A8_UNORM`.
pub const VK_FORMAT_R8G8B8A8_UNORM: u32 = 37;
/// `VK_FORMAT_R8G8B8A8_SRGB`.
pub const VK_FORMAT_R8G8B8A8_SRGB: u32 = 43;
/// `VK_FORMAT_BC7_UNORM_BLOCK`.
pub const VK_FORMAT_BC7_UNORM_BLOCK: u32 = 145;
/// `VK_FORMAT_BC7_SRGB_BLOCK`.
pub const VK_FORMAT_BC7_SRGB_BLOCK: u32 = 146;
/// `KHR_DF_MODEL_BC7`.
pub const KHR_DF_MODEL_BC7: u8 = 134;
/// `KHR_DF_MODEL_RGBSDA`.
pub const KHR_DF_MODEL_RGBSDA: u8 = 1;
/// `KHR_DF_PRIMARIES_BT709`.
pub const KHR_DF_PRIMARIES_BT709: u8 = 1;
/// `KHR_DF_TRANSFER_LINEAR`.
pub const KHR_DF_TRANSFER_LINEAR: u8 = 1;
/// `KHR_DF_TRANSFER_SRGB`.
pub const KHR_DF_TRANSFER_SRGB: u8 = 2;
/// `KHR_DF_FLAG_ALPHA_PREMULTIPLIED`.
pub const KHR_DF_FLAG_ALPHA_PREMULTIPLIED: u8 = 1;
/// `KHR_DF_SAMPLE_DATATYPE_LINEAR` (in the 8-bit channel-type field of a sample).
pub const KHR_DF_SAMPLE_DATATYPE_LINEAR: u8 = 0x10;
/// The value written for `KTXorientation`.
pub const ORIENTATION: &str = "ruo";

/// Header (48 bytes after the identifier) plus index (32 bytes): the level index starts here.
const LEVEL_INDEX_OFFSET: usize = 12 + 36 + 32;
const LEVEL_INDEX_ENTRY: usize = 24;
const TEXEL_BYTES: usize = 4;
const SAMPLES: usize = 4;
/// Basic descriptor block: 24 bytes of header + 16 per sample.
const BASIC_BLOCK_BYTES: usize = 24 + 16 * SAMPLES;

/// `supercompressionScheme` 2, `KTX_SS_ZSTD`.
pub const KTX_SS_ZSTD: u32 = 2;
/// The Zstandard levels [`Supercompression::Zstd`] takes (those of `ktx deflate --zstd`).
pub const ZSTD_LEVELS: std::ops::RangeInclusive<i32> = 1..=22;

/// Supercompression of a KTX2 file's level data (`billow voxelize --ktx2-zstd LEVEL`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Supercompression {
    /// None (`supercompressionScheme` 0): the levels as a GPU uploads them.
    #[default]
    None,
    /// Zstandard (`supercompressionScheme` 2) at this level, one of [`ZSTD_LEVELS`]: each
    /// MIP level one frame, compressed single-threaded (deterministic).
    Zstd(i32),
}

/// A Zstandard level outside [`ZSTD_LEVELS`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("must be a Zstandard level {lo}–{hi}, got {0}", lo = ZSTD_LEVELS.start(), hi = ZSTD_LEVELS.end())]
pub struct ZstdLevelError(pub i32);

impl Supercompression {
    /// [`Supercompression::Zstd`] at `level`, one of [`ZSTD_LEVELS`].
    pub fn zstd(level: i32) -> Result<Self, ZstdLevelError> {
        if ZSTD_LEVELS.contains(&level) {
            Ok(Supercompression::Zstd(level))
        } else {
            Err(ZstdLevelError(level))
        }
    }
}

/// Writes `asset`'s colour levels as a KTX 2.0 3D texture at `path`, atomically: its BC7
/// `blocks` when given (the asset's compressed colour levels), else the raw texels.
/// Normals and cells are not part of the KTX file.
pub fn write_ktx2(
    asset: &VolumeAsset,
    blocks: Option<&VolumeBlocks>,
    path: &Path,
) -> Result<(), ExportError> {
    let bytes = ktx2_bytes(asset, blocks, path)?;
    write_atomic(path, &bytes).map_err(ExportError::Write)
}

/// The KTX 2.0 file [`write_ktx2`] writes, in memory. `path` only names the file in errors.
pub fn ktx2_bytes(
    asset: &VolumeAsset,
    blocks: Option<&VolumeBlocks>,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    ktx2_bytes_with(asset, blocks, Supercompression::None, path)
}

/// [`ktx2_bytes`] with the level data supercompressed as `supercompression` says; with
/// [`Supercompression::None`] exactly [`ktx2_bytes`]. A Zstandard level outside
/// [`ZSTD_LEVELS`] is refused ([`ExportError::Encode`]).
pub fn ktx2_bytes_with(
    asset: &VolumeAsset,
    blocks: Option<&VolumeBlocks>,
    supercompression: Supercompression,
    path: &Path,
) -> Result<Vec<u8>, ExportError> {
    let dims = check_asset(asset, path)?;
    if let Supercompression::Zstd(level) = supercompression {
        Supercompression::zstd(level).map_err(|e| ExportError::Encode {
            path: path.to_path_buf(),
            format: "KTX2 (zstd)",
            message: format!("level {e}"),
        })?;
    }
    let bc = blocks.is_some();
    // The dense blocks: a GPU texture has every block (omitted ones decode to zero).
    let dense: Option<Vec<Vec<u8>>> = blocks.map(|b| {
        b.colour
            .iter()
            .enumerate()
            .map(|(i, p)| expand_blocks(p, mip_dims(dims, i as u32), ZERO_BLOCK))
            .collect()
    });
    let levels = dense.as_ref().unwrap_or(&asset.levels);
    let level_count = levels.len();
    let srgb = asset.header.colour_space == ColourSpace::SrgbPremultiplied;
    let vk_format = match (bc, srgb) {
        (false, true) => VK_FORMAT_R8G8B8A8_SRGB,
        (false, false) => VK_FORMAT_R8G8B8A8_UNORM,
        (true, true) => VK_FORMAT_BC7_SRGB_BLOCK,
        (true, false) => VK_FORMAT_BC7_UNORM_BLOCK,
    };

    let dfd = if bc { bc7_dfd(srgb) } else { basic_dfd(srgb) };
    let kvd = key_value_data(&[
        ("KTXorientation", ORIENTATION),
        ("KTXwriter", &writer_name()),
    ]);
    let dfd_offset = LEVEL_INDEX_OFFSET + LEVEL_INDEX_ENTRY * level_count;
    let kvd_offset = dfd_offset + dfd.len();
    let data_start = kvd_offset + kvd.len();

    // Level placement: smallest (last) level first, each aligned (a supercompressed level
    // needs no alignment).
    let zstd = match supercompression {
        Supercompression::None => None,
        Supercompression::Zstd(level) => Some(level),
    };
    let align = if zstd.is_some() {
        1
    } else {
        lcm(if bc { 16 } else { TEXEL_BYTES }, 4)
    };
    for (i, l) in levels.iter().enumerate() {
        let d = mip_dims(dims, i as u32);
        let want = if bc {
            bc7_len(d[0], d[1], d[2]) as usize
        } else {
            d.iter().map(|&v| v as usize).product::<usize>() * TEXEL_BYTES
        };
        if l.len() != want {
            return Err(ExportError::InvalidAsset {
                path: path.to_path_buf(),
                source: billow_format::FormatError::Volume(format!(
                    "level {i} is {} bytes, expected {want}",
                    l.len()
                )),
            });
        }
    }
    // The bytes stored for each level: the level itself, or its Zstandard frame (levels
    // in parallel, each frame single-threaded: the same bytes at any thread count).
    let packed: Option<Vec<Vec<u8>>> = match zstd {
        None => None,
        Some(level) => Some(
            levels
                .par_iter()
                .map(|l| zstd::bulk::compress(l, level))
                .collect::<Result<_, _>>()
                .map_err(|e| ExportError::Encode {
                    path: path.to_path_buf(),
                    format: "KTX2 (zstd)",
                    message: e.to_string(),
                })?,
        ),
    };
    let stored = packed.as_ref().unwrap_or(levels);
    let mut placement = vec![(0usize, 0usize); level_count];
    let mut end = data_start;
    for i in (0..level_count).rev() {
        let offset = end.next_multiple_of(align);
        placement[i] = (offset, stored[i].len());
        end = offset + stored[i].len();
    }

    let mut out = Vec::with_capacity(end);
    out.extend_from_slice(&KTX2_IDENTIFIER);
    for v in [
        vk_format,
        1,
        dims[0],
        dims[1],
        dims[2],
        0,
        1,
        level_count as u32,
        if zstd.is_some() { KTX_SS_ZSTD } else { 0 },
    ] {
        put_u32(&mut out, v);
    }
    put_u32(&mut out, dfd_offset as u32);
    put_u32(&mut out, dfd.len() as u32);
    put_u32(&mut out, if kvd.is_empty() { 0 } else { kvd_offset as u32 });
    put_u32(&mut out, kvd.len() as u32);
    put_u64(&mut out, 0); // sgdByteOffset
    put_u64(&mut out, 0); // sgdByteLength
    debug_assert_eq!(out.len(), LEVEL_INDEX_OFFSET);
    for (&(offset, len), level) in placement.iter().zip(levels) {
        put_u64(&mut out, offset as u64);
        put_u64(&mut out, len as u64);
        put_u64(&mut out, level.len() as u64); // uncompressedByteLength
    }
    debug_assert_eq!(out.len(), dfd_offset);
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    for i in (0..level_count).rev() {
        out.resize(placement[i].0, 0); // mipPadding
        out.extend_from_slice(&stored[i]);
    }
    debug_assert_eq!(out.len(), end);
    Ok(out)
}

/// `KTXwriter` value: the tool and its version.
fn writer_name() -> String {
    format!("billow {}", env!("CARGO_PKG_VERSION"))
}

/// `dfdTotalSize` followed by one Basic Data Format Descriptor block for RGBA8.
fn basic_dfd(srgb: bool) -> Vec<u8> {
    let mut b = Vec::with_capacity(4 + BASIC_BLOCK_BYTES);
    put_u32(&mut b, (4 + BASIC_BLOCK_BYTES) as u32); // dfdTotalSize
                                                     // vendorId 0 (Khronos, 17 bits) | descriptorType 0 (basic, 15 bits) << 17.
    put_u32(&mut b, 0);
    // versionNumber 2 (KDFS 1.3) | descriptorBlockSize << 16.
    put_u32(&mut b, 2 | ((BASIC_BLOCK_BYTES as u32) << 16));
    let transfer = if srgb {
        KHR_DF_TRANSFER_SRGB
    } else {
        KHR_DF_TRANSFER_LINEAR
    };
    b.extend_from_slice(&[
        KHR_DF_MODEL_RGBSDA,
        KHR_DF_PRIMARIES_BT709,
        transfer,
        KHR_DF_FLAG_ALPHA_PREMULTIPLIED,
    ]);
    b.extend_from_slice(&[0, 0, 0, 0]); // texelBlockDimension0..3: 1×1×1×1 (stored minus one)
    b.extend_from_slice(&[TEXEL_BYTES as u8, 0, 0, 0, 0, 0, 0, 0]); // bytesPlane0..7
                                                                    // Samples: channel ids R 0, G 1, B 2, A 15 (KHR_DF_CHANNEL_RGBSDA_*).
    for (k, channel) in [0u8, 1, 2, 15].into_iter().enumerate() {
        let qualifiers = if srgb && channel == 15 {
            KHR_DF_SAMPLE_DATATYPE_LINEAR
        } else {
            0
        };
        let bit_offset = (8 * k) as u16;
        b.extend_from_slice(&bit_offset.to_le_bytes());
        b.push(8 - 1); // bitLength minus one
        b.push(channel | qualifiers);
        b.extend_from_slice(&[0, 0, 0, 0]); // samplePosition0..3
        put_u32(&mut b, 0); // sampleLower
        put_u32(&mut b, 255); // sampleUpper
    }
    debug_assert_eq!(b.len(), 4 + BASIC_BLOCK_BYTES);
    b
}

/// `dfdTotalSize` followed by one Basic Data Format Descriptor block for BC7: colour model
/// `KHR_DF_MODEL_BC7`, 4×4 texel blocks of 16 bytes, one 128-bit sample.
fn bc7_dfd(srgb: bool) -> Vec<u8> {
    let block = 24 + 16;
    let mut b = Vec::with_capacity(4 + block);
    put_u32(&mut b, (4 + block) as u32);
    put_u32(&mut b, 0);
    put_u32(&mut b, 2 | ((block as u32) << 16));
    let transfer = if srgb {
        KHR_DF_TRANSFER_SRGB
    } else {
        KHR_DF_TRANSFER_LINEAR
    };
    b.extend_from_slice(&[
        KHR_DF_MODEL_BC7,
        KHR_DF_PRIMARIES_BT709,
        transfer,
        KHR_DF_FLAG_ALPHA_PREMULTIPLIED,
    ]);
    b.extend_from_slice(&[3, 3, 0, 0]); // texel block 4×4×1×1, stored minus one
    b.extend_from_slice(&[16, 0, 0, 0, 0, 0, 0, 0]); // bytesPlane0: 16 per block
    b.extend_from_slice(&0u16.to_le_bytes()); // bitOffset
    b.push(127); // bitLength minus one: 128 bits
    b.push(0); // KHR_DF_CHANNEL_BC7_COLOR
    b.extend_from_slice(&[0, 0, 0, 0]);
    put_u32(&mut b, 0);
    put_u32(&mut b, u32::MAX);
    debug_assert_eq!(b.len(), 4 + block);
    b
}

/// Key/value data: entries sorted by key (byte order), each `keyAndValueByteLength`,
/// key, NUL, value, NUL, then zero padding to a multiple of 4.
fn key_value_data(pairs: &[(&str, &str)]) -> Vec<u8> {
    let mut sorted = pairs.to_vec();
    sorted.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let mut out = Vec::new();
    for (k, v) in sorted {
        let len = k.len() + 1 + v.len() + 1;
        put_u32(&mut out, len as u32);
        out.extend_from_slice(k.as_bytes());
        out.push(0);
        out.extend_from_slice(v.as_bytes());
        out.push(0);
        out.resize(out.len().next_multiple_of(4), 0);
    }
    out
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn lcm(a: usize, b: usize) -> usize {
    a / gcd(a, b) * b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zstd_levels_outside_the_range_are_refused() {
        for l in [0, -1, 23] {
            assert_eq!(Supercompression::zstd(l), Err(ZstdLevelError(l)));
        }
        assert_eq!(Supercompression::zstd(1), Ok(Supercompression::Zstd(1)));
        assert_eq!(Supercompression::zstd(22), Ok(Supercompression::Zstd(22)));
        assert_eq!(
            ZstdLevelError(23).to_string(),
            "must be a Zstandard level 1–22, got 23"
        );
    }

    #[test]
    fn kvd_entries_are_padded_and_sorted() {
        let kvd = key_value_data(&[("b", "x"), ("KTXa", "yz")]);
        assert_eq!(kvd.len() % 4, 0);
        assert_eq!(&kvd[4..9], b"KTXa\0");
        assert_eq!(u32::from_le_bytes(kvd[0..4].try_into().unwrap()), 8);
    }

    #[test]
    fn dfd_is_92_bytes_with_premultiplied_flag() {
        let d = basic_dfd(true);
        assert_eq!(d.len(), 92);
        assert_eq!(d[4 + 8 + 3], KHR_DF_FLAG_ALPHA_PREMULTIPLIED);
        // Alpha sample (4th): channel 15 with the linear qualifier.
        assert_eq!(d[4 + 24 + 3 * 16 + 3], 15 | 0x10);
        assert_eq!(basic_dfd(false)[4 + 24 + 3 * 16 + 3], 15);
        assert_eq!(lcm(4, 4), 4);
        assert_eq!(lcm(6, 4), 12);
    }
}
