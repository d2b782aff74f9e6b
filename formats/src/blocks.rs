//! Block-compressed texel payloads (format 1.2, SPEC.md §12).
//!
//! A compressed level holds BC7 blocks instead of raw RGBA8 texels: 16 bytes per 4×4
//! block, blocks row by row (x fastest), each z slice of a 3D level its own blocks (the
//! layout of a `BC7` 3D texture in Vulkan, WebGPU and KTX2). Sides that are not a multiple
//! of 4 end in partial blocks whose texels beyond the level are ignored.
//!
//! The reader decodes every compressed level into the raw texels of the 1.0 chunks, so
//! the typed assets ([`crate::VolumeAsset`], [`crate::CloudAsset`]) look the same whether
//! the file was compressed or not; [`VolumeBlocks`] and [`CloudBlocks`] keep the blocks
//! for a renderer that uploads them as they are.

/// Bytes of one BC7 block (4×4 texels).
pub const BC7_BLOCK_BYTES: usize = 16;
/// Volume colour level, BC7 (replaces `VLEV`).
pub const TAG_VLB7: [u8; 4] = *b"VLB7";
/// Volume normal level, BC7 of the normal bytes XOR 0x80 (replaces `VNRM`).
pub const TAG_VNB7: [u8; 4] = *b"VNB7";
/// Cloud atlas MIP level, BC7 (replaces `ATEX`).
pub const TAG_ATB7: [u8; 4] = *b"ATB7";
/// Cloud atlas normal-map MIP level, BC7 (replaces `ANRM`).
pub const TAG_ANB7: [u8; 4] = *b"ANB7";
/// Cloud mesh texture, BC7 (replaces `MTEX`).
pub const TAG_MTB7: [u8; 4] = *b"MTB7";

/// Bytes of the BC7 blocks of a `w`×`h`×`d` level.
pub fn bc7_len(w: u32, h: u32, d: u32) -> u64 {
    u64::from(w.div_ceil(4)) * u64::from(h.div_ceil(4)) * u64::from(d) * BC7_BLOCK_BYTES as u64
}

/// Decodes the BC7 blocks of a `dims` level into RGBA8 texels, x fastest, then y, then z.
/// `blocks` must be exactly [`bc7_len`] bytes (callers check it first).
pub fn decode_bc7(blocks: &[u8], dims: [u32; 3]) -> Vec<u8> {
    let [w, h, d] = dims.map(|v| v as usize);
    let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
    debug_assert_eq!(blocks.len(), bw * bh * d * BC7_BLOCK_BYTES);
    let mut out = vec![0u8; w * h * d * 4];
    let mut tile = [0u8; 64];
    for (i, b) in blocks.chunks_exact(BC7_BLOCK_BYTES).enumerate() {
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
/// encode the normal bytes XOR 0x80.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeBlocks {
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

/// Checks that `levels[i]` is exactly the blocks of `dims_of(i)`.
pub(crate) fn check_block_levels(
    what: &str,
    levels: &[Vec<u8>],
    dims_of: impl Fn(u32) -> [u32; 3],
) -> Result<(), String> {
    for (i, l) in levels.iter().enumerate() {
        let [w, h, d] = dims_of(i as u32);
        let want = bc7_len(w, h, d);
        if l.len() as u64 != want {
            return Err(format!(
                "{what} level {i} is {} bytes, expected {want} (BC7 blocks of {w}x{h}x{d} texels)",
                l.len()
            ));
        }
    }
    Ok(())
}

/// Decodes a whole chain (`levels[i]` of `dims_of(i)`).
pub(crate) fn decode_levels(levels: &[Vec<u8>], dims_of: impl Fn(u32) -> [u32; 3]) -> Vec<Vec<u8>> {
    levels
        .iter()
        .enumerate()
        .map(|(i, l)| decode_bc7(l, dims_of(i as u32)))
        .collect()
}
