//! Block-compressed texel payloads (format 1.2, SPEC.md §12).
//!
//! A compressed level holds BC7 blocks instead of raw RGBA8 texels: 16 bytes per 4×4
//! block, blocks row by row (x fastest), each z slice of a 3D level its own blocks (the
//! layout of a `BC7` 3D texture in Vulkan, WebGPU and KTX2). Sides that are not a multiple
//! of 4 end in partial blocks whose texels beyond the level are ignored.
//!
//! Blocks whose 16 texels are all zero bytes (empty space: most of a volume, most of an
//! atlas) are not stored: the chunk starts with a mask of one bit per block (set: stored),
//! padded to 16 bytes, followed by the stored blocks in order ([`sparse_len`]).
//!
//! The reader decodes every compressed level into the raw texels of the 1.0 chunks, so
//! the typed assets ([`crate::VolumeAsset`], [`crate::CloudAsset`]) look the same whether
//! the file was compressed or not; [`VolumeBlocks`] and [`CloudBlocks`] keep the blocks
//! for a renderer that uploads them as they are.

/// Bytes of one BC7 block (4×4 texels).
pub const BC7_BLOCK_BYTES: usize = 16;
pub use crate::normal_tags::{TAG_BMB7, TAG_BNB7, TAG_VMB7, TAG_VNB7};
/// Volume colour level, BC7 (replaces `VLEV`).
pub const TAG_VLB7: [u8; 4] = *b"VLB7";
/// Cloud atlas MIP level, BC7 (replaces `ATEX`).
pub const TAG_ATB7: [u8; 4] = *b"ATB7";
/// Cloud atlas normal-map MIP level, BC7 (replaces `ANRM`).
pub const TAG_ANB7: [u8; 4] = *b"ANB7";
/// Cloud mesh texture, BC7 (replaces `MTEX`).
pub const TAG_MTB7: [u8; 4] = *b"MTB7";
/// LOD band colour level, BC7 (format 1.3; replaces `BLEV`).
pub const TAG_BLB7: [u8; 4] = *b"BLB7";

/// A BC7 block that decodes to 16 zero texels (mode 6, every endpoint, p-bit and index
/// zero): what an omitted block of a colour stream is, for a renderer that needs every
/// block ([`expand_blocks`]).
pub const ZERO_BLOCK: [u8; 16] = [0x40, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];

/// A BC7 block that decodes to 16 texels `80 80 80 80` (mode 6, every 7-bit endpoint 64,
/// p-bits and indices zero): what an omitted block of a normal or normal-moment stream is
/// (`VNB7`, `BNB7`, `VMB7`, `BMB7`: the signed zero, SPEC §12.2), for a renderer that
/// samples those blocks as they are.
pub const SIGNED_ZERO_BLOCK: [u8; 16] = [
    0x40, 0x20, 0x10, 0x08, 0x04, 0x02, 0x81, 0x40, 0, 0, 0, 0, 0, 0, 0, 0,
];

/// Bytes of all the BC7 blocks of a `w`×`h`×`d` level, dense.
pub fn bc7_len(w: u32, h: u32, d: u32) -> u64 {
    block_count([w, h, d]) * BC7_BLOCK_BYTES as u64
}

/// Number of 4×4 blocks of a `dims` level: `⌈w/4⌉·⌈h/4⌉·d`.
pub fn block_count(dims: [u32; 3]) -> u64 {
    u64::from(dims[0].div_ceil(4)) * u64::from(dims[1].div_ceil(4)) * u64::from(dims[2])
}

/// Bytes of the block mask of `n` blocks: one bit each, padded to a multiple of 16.
pub fn mask_len(n: u64) -> u64 {
    n.div_ceil(8).next_multiple_of(BC7_BLOCK_BYTES as u64)
}

/// Checks a compressed chunk payload of a `dims` level (SPEC §12.1): the mask, no bit set
/// beyond the last block, and exactly 16 bytes per set bit after it. Returns the number
/// of stored blocks.
pub fn sparse_len(payload: &[u8], dims: [u32; 3]) -> Result<u64, String> {
    let n = block_count(dims);
    let m = mask_len(n);
    if (payload.len() as u64) < m {
        return Err(format!(
            "{} bytes, shorter than the {m}-byte block mask of {n} blocks",
            payload.len()
        ));
    }
    let mask = &payload[..m as usize];
    let stored: u64 = mask.iter().map(|b| u64::from(b.count_ones())).sum();
    let beyond = (n..m * 8).any(|i| mask[(i / 8) as usize] >> (i % 8) & 1 == 1);
    if beyond {
        return Err(format!("block mask has bits set beyond its {n} blocks"));
    }
    let want = m + stored * BC7_BLOCK_BYTES as u64;
    if payload.len() as u64 != want {
        return Err(format!(
            "{} bytes, expected {want} (a {m}-byte mask and {stored} stored blocks)",
            payload.len()
        ));
    }
    Ok(stored)
}

/// Packs dense blocks (`stored[i]`: block `i` is kept) into a chunk payload.
pub fn pack_blocks(dense: &[u8], stored: &[bool]) -> Vec<u8> {
    let n = stored.len() as u64;
    let mut out = vec![0u8; mask_len(n) as usize];
    for (i, (&s, b)) in stored
        .iter()
        .zip(dense.chunks_exact(BC7_BLOCK_BYTES))
        .enumerate()
    {
        if s {
            out[i / 8] |= 1 << (i % 8);
            out.extend_from_slice(b);
        }
    }
    out
}

/// The dense blocks of a checked payload ([`sparse_len`]), omitted blocks as `fill`.
pub fn expand_blocks(payload: &[u8], dims: [u32; 3], fill: [u8; 16]) -> Vec<u8> {
    let n = block_count(dims) as usize;
    let m = mask_len(n as u64) as usize;
    let mut stored = payload[m..].chunks_exact(BC7_BLOCK_BYTES);
    let mut out = Vec::with_capacity(n * BC7_BLOCK_BYTES);
    for i in 0..n {
        if payload[i / 8] >> (i % 8) & 1 == 1 {
            out.extend_from_slice(stored.next().expect("checked payload"));
        } else {
            out.extend_from_slice(&fill);
        }
    }
    out
}

/// Decodes a checked compressed payload ([`sparse_len`]) of a `dims` level into RGBA8
/// texels, x fastest, then y, then z; the texels of omitted blocks are `omitted` bytes
/// (0, or 0x80 for normals before [`unorm_to_snorm_in_place`]).
pub fn decode_bc7(payload: &[u8], dims: [u32; 3], omitted: u8) -> Vec<u8> {
    let [w, h, d] = dims.map(|v| v as usize);
    let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
    let n = bw * bh * d;
    let m = mask_len(n as u64) as usize;
    let mut out = vec![omitted; w * h * d * 4];
    let mut tile = [0u8; 64];
    let mut stored = payload[m..].chunks_exact(BC7_BLOCK_BYTES);
    for i in 0..n {
        if payload[i / 8] >> (i % 8) & 1 == 0 {
            continue;
        }
        let b = stored.next().expect("checked payload");
        let (bx, by, z) = (i % bw, (i / bw) % bh, i / (bw * bh));
        bcdec_rs::bc7(b, &mut tile, 16);
        for ty in 0..4 {
            let y = by * 4 + ty;
            if y >= h {
                break;
            }
            let x0 = bx * 4;
            let n = (w - x0).min(4);
            let o = ((z * h + y) * w + x0) * 4;
            out[o..o + 4 * n].copy_from_slice(&tile[ty * 16..ty * 16 + 4 * n]);
        }
    }
    out
}

/// Decodes one BC7 block into its 16 RGBA8 texels, row by row.
pub fn decode_bc7_block(block: &[u8; 16]) -> [u8; 64] {
    let mut tile = [0u8; 64];
    bcdec_rs::bc7(block, &mut tile, 16);
    tile
}

/// Normal texels (`Rgba8Snorm` bytes) to the unsigned bytes BC7 encodes: each byte XOR
/// 0x80, i.e. `v + 128` (SPEC §12.2).
pub fn snorm_to_unorm(texels: &[u8]) -> Vec<u8> {
    texels.iter().map(|b| b ^ 0x80).collect()
}

/// The inverse of [`snorm_to_unorm`], in place.
pub fn unorm_to_snorm_in_place(texels: &mut [u8]) {
    texels.iter_mut().for_each(|b| *b ^= 0x80);
}

/// The BC7 blocks of a volume's base texture, as stored in `VLB7`/`VNB7` chunks: one
/// entry per MIP level, [`bc7_len`] of `mip_dims(dims, i)` bytes each. The normal blocks
/// encode the normal bytes XOR 0x80. `bands`: the blocks of each LOD band (`BLB7`/`BNB7`,
/// format 1.3), in band order, or empty when the bands are stored raw (`BLEV`/`BNRM`) or
/// the asset has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeBlocks {
    pub colour: Vec<Vec<u8>>,
    pub normals: Option<Vec<Vec<u8>>>,
    pub bands: Vec<BandBlocks>,
}

/// The BC7 blocks of one LOD band: one entry per MIP level of the band, as
/// [`VolumeBlocks::colour`] and [`VolumeBlocks::normals`] are for the base texture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BandBlocks {
    pub colour: Vec<Vec<u8>>,
    pub normals: Option<Vec<Vec<u8>>>,
}

/// The BC7 blocks of a cloud's textures: per atlas its MIP levels (`ATB7`), per atlas its
/// normal-map levels when the asset has normal maps (`ANB7`), per mesh texture its single
/// level (`MTB7`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CloudBlocks {
    pub atlases: Vec<Vec<Vec<u8>>>,
    pub atlas_normals: Option<Vec<Vec<Vec<u8>>>>,
    pub textures: Vec<Vec<u8>>,
}

/// Checks that `levels[i]` is a valid compressed payload of `dims_of(i)` ([`sparse_len`]).
pub(crate) fn check_block_levels(
    what: &str,
    levels: &[Vec<u8>],
    dims_of: impl Fn(u32) -> [u32; 3],
) -> Result<(), String> {
    for (i, l) in levels.iter().enumerate() {
        let [w, h, d] = dims_of(i as u32);
        sparse_len(l, [w, h, d])
            .map_err(|e| format!("{what} level {i} ({w}x{h}x{d} texels): {e}"))?;
    }
    Ok(())
}

/// Decodes a whole checked chain (`levels[i]` of `dims_of(i)`).
pub(crate) fn decode_levels(
    levels: &[Vec<u8>],
    dims_of: impl Fn(u32) -> [u32; 3],
    omitted: u8,
) -> Vec<Vec<u8>> {
    levels
        .iter()
        .enumerate()
        .map(|(i, l)| decode_bc7(l, dims_of(i as u32), omitted))
        .collect()
}

#[cfg(test)]
mod zero_block_tests {
    use super::*;

    #[test]
    fn the_zero_blocks_decode_to_their_zeros() {
        assert_eq!(decode_bc7_block(&ZERO_BLOCK), [0u8; 64]);
        assert_eq!(decode_bc7_block(&SIGNED_ZERO_BLOCK), [0x80u8; 64]);
    }
}
