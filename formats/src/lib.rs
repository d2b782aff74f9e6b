//! The billow asset container, format v1: the only contract between baker and viewer.
//!
//! A file is a 32-byte preamble (magic, version, kind, total length, CRC),
//! then 8-byte-aligned chunks (tag, element type, length, CRC, payload):
//! `HEAD` (RON header) first, `END ` last. `SPEC.md` next to this crate
//! describes every byte.
//!
//! - [`to_bytes`] / [`from_bytes`]: the untyped [`Container`].
//! - [`VolumeAsset`]: the typed volumetric billboard on top of it.
//! - [`write_atomic`] / [`read_file`]: files.
//! - [`inspect_bytes`]: a structural [`Report`] for `billow info`.

#![forbid(unsafe_code)]

mod bands;
mod blocks;
mod cloud;
mod container;
mod error;
mod grid;
mod header;
mod inspect;
mod normal_tags;
mod volume;

pub use bands::{
    LodBand, BAND_RECORD_BYTES, MAX_FIRST_LEVEL, TAG_BCEL, TAG_BLEV, TAG_BMOM, TAG_BNRM, TAG_VBND,
};
pub use blocks::{
    bc7_len, block_count, decode_bc7, decode_bc7_block, expand_blocks, mask_len, pack_blocks,
    snorm_to_unorm, sparse_len, unorm_to_snorm_in_place, BandBlocks, CloudBlocks, VolumeBlocks,
    BC7_BLOCK_BYTES, SIGNED_ZERO_BLOCK, TAG_ANB7, TAG_ATB7, TAG_BLB7, TAG_BMB7, TAG_BNB7, TAG_MTB7,
    TAG_VLB7, TAG_VMB7, TAG_VNB7, ZERO_BLOCK,
};
pub use cloud::{
    Atlas, AtlasRect, Billboard, CloudAsset, CloudError, CloudLevel, Mesh, MeshMaterial,
    MeshTexture, MeshVertex, MAX_TEXTURE_SIDE, NO_INDEX,
};
pub use container::{
    from_bytes, read_file, read_regular, to_bytes, valid_tag, write_atomic, write_atomic_parts,
    Chunk, Container, ElemType, CHUNK_HEADER_LEN, MAX_ASSET_BYTES, TAG_END, TAG_HEAD,
};
pub use error::{tag_str, FormatError};
pub use grid::{full_mip_count, mip_dims, Prism, MAX_DIM, PRISM_BYTES, TEXEL_BYTES};
pub use header::{
    param, AssetKind, BakedLight, Bounds, ColourSpace, Header, NormalEncoding, NormalKind,
    SourceInfo, TexelFormat, VolumeBake, VolumeHeader, DEFAULT_AMBIENT,
};
pub use inspect::{inspect_bytes, ChunkInfo, Report};
pub use volume::{VolumeAsset, TAG_CELL, TAG_VLEV, TAG_VMOM, TAG_VNRM};

/// Major format version: a reader refuses files with a different major.
pub const FORMAT_MAJOR: u16 = 1;
/// Minor format version implemented: additive changes (new chunks, new optional header
/// fields). 1.1 added LOD bands to Volume assets (SPEC §8.6) and normal maps to Cloud
/// atlases (`ANRM`, §9); 1.2 block-compressed (BC7) texel chunks (§12); 1.3 BC7 chunks for LOD bands (`BLB7`/`BNB7`, §12.4); 1.4 volumes of normal moments
/// (`volume.moments`, chunks `VMOM`/`BMOM`/`VMB7`/`BMB7`, §8.4a). A writer writes the lowest
/// minor version whose features the file uses (SPEC §5).
pub const FORMAT_MINOR: u16 = 4;
/// The minor version written for files that use no 1.1 feature (SPEC §5).
pub const FORMAT_MINOR_BASE: u16 = 0;
/// The first 8 bytes of every billow asset.
pub const MAGIC: [u8; 8] = *b"\x89BLW\r\n\x1a\n";
/// Size of the fixed preamble in bytes.
pub const PREAMBLE_LEN: usize = 32;
/// Conventional file extension.
pub const EXTENSION: &str = "billow";
