//! Block compression of an asset's textures (format 1.2, SPEC.md §12): BC7, the successor
//! of the S3TC/DXT5 the volumetric billboards paper shipped its volumes in (§5, Table 1).
//!
//! Every colour, normal, atlas and mesh texture level becomes 4×4 blocks of 16 bytes (one
//! byte per texel instead of four). The encoder is the `block_compression` crate's CPU BC7
//! encoder — a pure-Rust port of Intel's ISPC texture compressor (the kernel `intel_tex_2`
//! binds): the same blocks' quality, safe code, no prebuilt native library and, because
//! it is scalar Rust without fused or reordered float operations, the same bytes on every
//! machine. docs/accuracy.md ("Compressed textures") compares the two crates.
//!
//! Determinism: every block depends only on its 16 texels, so the rows of blocks are
//! encoded in parallel and the output is byte-identical at any thread count. Texels beyond
//! a side that is not a multiple of 4 repeat the last row or column (clamp-to-edge).
//!
//! After compressing ([`compress_volume`], [`compress_cloud`]), the asset's texels are
//! replaced by the decoded blocks: the asset in memory is then exactly what a reader of the
//! file gets back. [`encode_volume`] only encodes, for a caller that writes the file and
//! reads no texel after.

use billow_format::{
    bc7_len, decode_bc7, decode_bc7_block, mip_dims, pack_blocks, snorm_to_unorm,
    unorm_to_snorm_in_place, BandBlocks, CloudAsset, CloudBlocks, ColourSpace, VolumeAsset,
    VolumeBlocks, BC7_BLOCK_BYTES,
};
use block_compression::{encode::compress_rgba8, BC7Settings, CompressionVariant};
use rayon::prelude::*;

mod anchored;
use anchored::zero_anchored_block;

/// What the bakers write texels as (`--compress`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Compression {
    /// BC7 blocks (format 1.2).
    #[default]
    Bc,
    /// Raw RGBA8 texels, byte for byte what billow wrote before compression existed.
    None,
}

impl std::str::FromStr for Compression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bc" => Ok(Compression::Bc),
            "none" => Ok(Compression::None),
            other => Err(format!("expected bc or none, got '{other}'")),
        }
    }
}

/// How the tiles of a level are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Kind {
    /// The ISPC kernel's "alpha ultra fast" profile; with `opaque_fast`, tiles whose alpha
    /// is all 255 with "opaque ultra fast": the same RGB error, about 5× faster (it may
    /// decode alpha 255 as 254; used for the cloud's alpha-tested or opaque textures, not
    /// for volumes, whose opacity accumulates).
    Alpha { opaque_fast: bool },
    /// Volume colour under the exact-zero constraint ([`encode_keep_zero`]).
    KeepZero,
    /// Volume normals (unsigned, w unused and 0x80): [`encode_normal_tile`].
    Normals,
}

/// Tiles already encoded on this thread, by texels and kind. The encoders are pure
/// functions of the tile, so the cache changes no byte (and a volume repeats many tiles:
/// constant ones, and the spot cow's colour a quarter of its tiles). Bounded: cleared
/// when it holds [`CACHE_MAX`] tiles.
type TileCache = std::collections::HashMap<([u8; 64], Kind), [u8; 16]>;
const CACHE_MAX: usize = 1 << 16;

thread_local! {
    static CACHE: std::cell::RefCell<TileCache> =
        std::cell::RefCell::new(std::collections::HashMap::new());
}

fn bc7(tile: &[u8; 64], settings: BC7Settings) -> [u8; 16] {
    let mut b = [0u8; 16];
    compress_rgba8(CompressionVariant::BC7(settings), tile, &mut b, 4, 4, 16);
    b
}

/// One tile's block.
fn encode_tile(tile: &[u8; 64], kind: Kind) -> [u8; 16] {
    match kind {
        Kind::Alpha { opaque_fast } => {
            if opaque_fast && tile.chunks_exact(4).all(|t| t[3] == 255) {
                bc7(tile, BC7Settings::opaque_ultra_fast())
            } else {
                bc7(tile, BC7Settings::alpha_ultrafast())
            }
        }
        Kind::KeepZero => encode_keep_zero(tile),
        Kind::Normals => encode_normal_tile(tile),
    }
}

/// The compressed chunk payload (SPEC §12.1) of a `dims` level of RGBA8 texels (x fastest,
/// then y, then z; each z slice its own blocks): the block mask and the BC7 blocks of
/// every 4×4 tile that is not all `omit` bytes (0 for colour; 0x80, the unsigned form of
/// a zero normal, for normals). Omitted tiles cost no encoding: volumes and atlases are
/// mostly empty (the oak at 128³: 4 % of its voxels are not).
pub fn encode_bc7(texels: &[u8], dims: [u32; 3], omit: u8) -> Vec<u8> {
    encode_bc7_with(texels, dims, omit, false, false)
}

/// [`encode_bc7`]; `opaque_fast`: encode tiles of alpha 255 with the opaque profile
/// (`Kind::Alpha`); `keep_zero`: texels that are all zero bytes (empty space) decode to
/// all zero bytes exactly (`encode_keep_zero`; `opaque_fast` is then not used), so that
/// a volume's empty space stays empty after compression and `billow emptyspace` can still
/// prune it.
pub fn encode_bc7_with(
    texels: &[u8],
    dims: [u32; 3],
    omit: u8,
    opaque_fast: bool,
    keep_zero: bool,
) -> Vec<u8> {
    let kind = if keep_zero {
        Kind::KeepZero
    } else {
        Kind::Alpha { opaque_fast }
    };
    encode_level(texels, dims, omit, kind)
}

/// The payload of a volume normal level in its unsigned form ([`snorm_to_unorm`]; tiles
/// all 0x80 omitted), encoded by `encode_normal_tile`.
pub fn encode_bc7_normals(texels: &[u8], dims: [u32; 3]) -> Vec<u8> {
    encode_level(texels, dims, 0x80, Kind::Normals)
}

fn encode_level(texels: &[u8], dims: [u32; 3], omit: u8, kind: Kind) -> Vec<u8> {
    let [w, h, d] = dims.map(|v| v as usize);
    assert_eq!(texels.len(), w * h * d * 4, "texels of a {dims:?} level");
    let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
    let mut out = vec![0u8; bc7_len(dims[0], dims[1], dims[2]) as usize];
    let mut stored = vec![false; out.len() / BC7_BLOCK_BYTES];
    let row_bytes = bw * BC7_BLOCK_BYTES;
    let rows = out.par_chunks_mut(row_bytes).zip(stored.par_chunks_mut(bw));
    rows.enumerate().for_each(|(r, (dst, keep))| {
        let (by, z) = (r % bh, r / bh);
        // One row of blocks: 4 texel rows of bw·4 texels, edges clamped.
        let sw = bw * 4;
        let mut strip = vec![0u8; sw * 4 * 4];
        for ty in 0..4 {
            let y = (by * 4 + ty).min(h - 1);
            for x in 0..sw {
                let s = ((z * h + y) * w + x.min(w - 1)) * 4;
                let o = (ty * sw + x) * 4;
                strip[o..o + 4].copy_from_slice(&texels[s..s + 4]);
            }
        }
        let mut tile = [0u8; 64];
        for (bx, out) in dst.chunks_exact_mut(BC7_BLOCK_BYTES).enumerate() {
            for ty in 0..4 {
                let s = (ty * sw + bx * 4) * 4;
                tile[ty * 16..ty * 16 + 16].copy_from_slice(&strip[s..s + 16]);
            }
            // Omitted tiles are skipped before any encoding.
            keep[bx] = !tile.iter().all(|&b| b == omit);
            if !keep[bx] {
                continue;
            }
            let b = CACHE.with(|c| c.borrow().get(&(tile, kind)).copied());
            let b = b.unwrap_or_else(|| {
                let b = encode_tile(&tile, kind);
                CACHE.with(|c| {
                    let mut c = c.borrow_mut();
                    if c.len() >= CACHE_MAX {
                        c.clear();
                    }
                    c.insert((tile, kind), b);
                });
                b
            });
            out.copy_from_slice(&b);
        }
    });
    pack_blocks(&out, &stored)
}

/// Volume colour under the exact-zero constraint (SPEC §12.3): a tile without empty
/// texels is the kernel's "alpha ultra fast" block; a tile with some (most of a volume's
/// stored tiles: a surface's voxels border empty space) is [`zero_anchored_block`], which
/// keeps them zero by construction and costs a fraction of the kernel's mode 4/5 search.
/// (Until 2026-12-03 the kernel's block was tried too and taken where it kept the empty
/// texels zero with less error: the spot cow's bake took 2.25 G instructions against
/// 1.66 G now, for a rendered error within ±3 % of this one; docs/accuracy.md, "Encoder
/// speed".)
fn encode_keep_zero(tile: &[u8; 64]) -> [u8; 16] {
    if tile.chunks_exact(4).any(|t| t == [0; 4]) {
        zero_anchored_block(tile)
    } else {
        bc7(tile, BC7Settings::alpha_ultrafast())
    }
}

/// A volume normal tile (unsigned bytes, w = 0x80 as every normal's unused w is 0): the
/// kernel's "opaque ultra fast" block of its xyz (3 channels, mode 6: the same xyz error
/// as "alpha ultra fast", about 3× faster), its alpha endpoints then set to 0x80's 7 bits,
/// so that w decodes to 0x80, or 0x81 where the endpoint's p-bit (shared with xyz) is 1:
/// w, which nothing reads, is then 0 or 1/127. A tile whose w is not all 0x80, a block
/// that is not mode 6, or one that would decode a zero normal (all 0x80: an empty voxel's)
/// as anything else, keeps "alpha ultra fast".
fn encode_normal_tile(tile: &[u8; 64]) -> [u8; 16] {
    let fallback = || bc7(tile, BC7Settings::alpha_ultrafast());
    if !tile.chunks_exact(4).all(|t| t[3] == 0x80) {
        return fallback();
    }
    let zero = [0x80u8; 4];
    let mut opaque = *tile;
    opaque.chunks_exact_mut(4).for_each(|t| t[3] = 255);
    let b = bc7(&opaque, BC7Settings::opaque_ultra_fast());
    if b[0] & 0x7F != 0x40 {
        return fallback();
    }
    // Mode 6: 7 mode bits, then R0 R1 G0 G1 B0 B1 A0 A1 of 7 bits each: A0 at bit 49,
    // A1 at bit 56.
    let mut bits = u128::from_le_bytes(b);
    let a7 = u128::from(0x80u8 >> 1);
    for at in [49, 56] {
        bits = (bits & !(0x7F << at)) | (a7 << at);
    }
    let b = bits.to_le_bytes();
    // A zero normal (an empty voxel's) must stay exactly zero, or `billow emptyspace`
    // would see data there: where this block changes one, the alpha profile it is.
    if !keeps_value(tile, &b, zero) {
        return fallback();
    }
    b
}

/// Whether every texel of `tile` equal to `v` decodes from `block` to `v` exactly.
fn keeps_value(tile: &[u8; 64], block: &[u8; 16], v: [u8; 4]) -> bool {
    if !tile.chunks_exact(4).any(|t| t == v) {
        return true;
    }
    let dec = decode_bc7_block(block);
    tile.chunks_exact(4)
        .zip(dec.chunks_exact(4))
        .all(|(t, d)| t != v || d == v)
}

/// The squared error of `block` against `tile`, or `None` if an empty texel of `tile`
/// does not decode to zero (the tests' check of [`zero_anchored_block`]).
#[cfg(test)]
fn keeps_zero(tile: &[u8; 64], block: &[u8; 16]) -> Option<u64> {
    let dec = decode_bc7_block(block);
    let mut sse = 0u64;
    for (s, d) in tile.chunks_exact(4).zip(dec.chunks_exact(4)) {
        if s == [0; 4] && d != [0; 4] {
            return None;
        }
        sse += s
            .iter()
            .zip(d)
            .map(|(a, b)| u64::from(a.abs_diff(*b)).pow(2))
            .sum::<u64>();
    }
    Some(sse)
}

/// Encodes one level and returns its payload and its decoding.
fn round_trip(
    texels: &[u8],
    dims: [u32; 3],
    omit: u8,
    opaque_fast: bool,
    keep_zero: bool,
) -> (Vec<u8>, Vec<u8>) {
    let blocks = encode_bc7_with(texels, dims, omit, opaque_fast, keep_zero);
    let decoded = decode_bc7(&blocks, dims, omit);
    (blocks, decoded)
}

/// The blocks of one MIP chain of a volume texture (colour, and normals when present).
/// Colour keeps its empty texels exactly empty (`keep_zero`, `encode_keep_zero`).
fn encode_chain(dims: [u32; 3], levels: &[Vec<u8>], normals: Option<&Vec<Vec<u8>>>) -> BandBlocks {
    let colour = levels
        .iter()
        .enumerate()
        .map(|(i, l)| encode_bc7_with(l, mip_dims(dims, i as u32), 0, false, true))
        .collect();
    let normals = normals.map(|ls| {
        ls.iter()
            .enumerate()
            .map(|(i, l)| encode_bc7_normals(&snorm_to_unorm(l), mip_dims(dims, i as u32)))
            .collect()
    });
    BandBlocks { colour, normals }
}

/// Replaces one MIP chain's texels with the decoding of its blocks ([`encode_chain`]'s:
/// `colour`, and `normal_blocks` when present).
fn decode_chain(
    dims: [u32; 3],
    colour: &[Vec<u8>],
    normal_blocks: Option<&Vec<Vec<u8>>>,
    levels: &mut [Vec<u8>],
    normals: Option<&mut Vec<Vec<u8>>>,
) {
    for (i, (l, b)) in levels.iter_mut().zip(colour).enumerate() {
        *l = decode_bc7(b, mip_dims(dims, i as u32), 0);
    }
    if let (Some(ls), Some(bs)) = (normals, normal_blocks) {
        for (i, (l, b)) in ls.iter_mut().zip(bs).enumerate() {
            let mut dec = decode_bc7(b, mip_dims(dims, i as u32), 0x80);
            unorm_to_snorm_in_place(&mut dec);
            *l = dec;
        }
    }
}

/// Makes `asset`'s colour (base texture and every LOD band) linear premultiplied
/// (`ColourSpace::LinearPremultiplied`, SPEC §12.2) if it is sRGB-encoded: what a volume's
/// BC7 blocks hold. A BC7 block interpolates its 16 colours on a straight line between two
/// endpoints in the stored bytes, and a volume's blocks that border empty space
/// (`anchored::zero_anchored_block`) start that line at zero: the premultiplied texels of one
/// albedo with varying alpha lie on it in linear bytes, not in sRGB-encoded ones
/// (`srgb(α·c)` is not proportional to `α`). Encoded as sRGB, a closed surface's partly
/// covered voxels lost up to 30 levels of alpha, and their errors drew contour bands along
/// the slice planes (docs/accuracy.md, "Compressed volumes are linear"). Each texel is
/// decoded once (a table) and rounded; a linear asset is left as it is.
pub fn linear_colour(asset: &mut VolumeAsset) {
    if asset.header.colour_space == ColourSpace::LinearPremultiplied {
        return;
    }
    let lut = crate::texture::srgb_to_linear_lut();
    let table: [u8; 256] = std::array::from_fn(|b| (lut[b] * 255.0).round() as u8);
    let linear = |level: &mut Vec<u8>| {
        for t in level.chunks_exact_mut(4) {
            for c in &mut t[..3] {
                *c = table[*c as usize];
            }
        }
    };
    asset.levels.iter_mut().for_each(linear);
    for b in &mut asset.bands {
        b.levels.iter_mut().for_each(linear);
    }
    asset.header.colour_space = ColourSpace::LinearPremultiplied;
}

/// The BC7 blocks of `asset`'s base texture and every LOD band (colour and normals, every
/// MIP level; bands as `BLB7`/`BNB7`, format 1.3): what [`compress_volume`] returns, without
/// decoding them back into the asset. Its colour is first made linear ([`linear_colour`]:
/// the texels and the header's colour space change, nothing else). For a caller that
/// only writes the file: at 512³ the decoding is a 537 MB level-0 buffer filled on one
/// thread (0.4 s of the bench tree's 2.3 s of compression).
pub fn encode_volume(asset: &mut VolumeAsset) -> VolumeBlocks {
    linear_colour(asset);
    let dims = asset.level_dims(0);
    let base = encode_chain(dims, &asset.levels, asset.normals.as_ref());
    let bands = asset
        .bands
        .iter()
        .map(|b| encode_chain(b.dims, &b.levels, b.normals.as_ref()))
        .collect();
    VolumeBlocks {
        colour: base.colour,
        normals: base.normals,
        bands,
    }
}

/// Compresses `asset`'s base texture and every LOD band ([`encode_volume`]) and replaces
/// its texels with the decoded blocks.
pub fn compress_volume(asset: &mut VolumeAsset) -> VolumeBlocks {
    let blocks = encode_volume(asset);
    let dims = asset.level_dims(0);
    let (levels, normals) = (&mut asset.levels, asset.normals.as_mut());
    decode_chain(
        dims,
        &blocks.colour,
        blocks.normals.as_ref(),
        levels,
        normals,
    );
    for (band, b) in asset.bands.iter_mut().zip(&blocks.bands) {
        let (levels, normals) = (&mut band.levels, band.normals.as_mut());
        decode_chain(band.dims, &b.colour, b.normals.as_ref(), levels, normals);
    }
    blocks
}

/// Compresses every atlas level, atlas normal map and mesh texture of `asset` and replaces
/// their texels with the decoded blocks.
pub fn compress_cloud(asset: &mut CloudAsset) -> CloudBlocks {
    // Every level of every texture is one job; the jobs run in parallel (small levels
    // alone would leave cores idle) and their results go back by index.
    let mut jobs: Vec<(&mut Vec<u8>, [u32; 3])> = Vec::new();
    let mut normal_jobs: Vec<(&mut Vec<u8>, [u32; 3])> = Vec::new();
    let (mut shape, mut normal_shape) = (Vec::new(), Vec::new());
    for a in &mut asset.atlases {
        let (w, h) = (a.width, a.height);
        shape.push(a.mips.len());
        for (k, l) in a.mips.iter_mut().enumerate() {
            jobs.push((l, mip_dims([w, h, 1], k as u32)));
        }
        if let Some(n) = a.normals.as_mut() {
            normal_shape.push(n.len());
            for (k, l) in n.iter_mut().enumerate() {
                normal_jobs.push((l, mip_dims([w, h, 1], k as u32)));
            }
        }
    }
    jobs.append(&mut normal_jobs);
    for t in &mut asset.textures {
        let d = [t.width, t.height, 1];
        jobs.push((&mut t.texels, d));
    }
    let mut payloads: Vec<Vec<u8>> = jobs
        .into_par_iter()
        .map(|(l, d)| {
            let (b, dec) = round_trip(l, d, 0, true, false);
            *l = dec;
            b
        })
        .collect();
    let mut rest = payloads.drain(..);
    let mut take = |n: usize| rest.by_ref().take(n).collect::<Vec<_>>();
    let atlases: Vec<Vec<Vec<u8>>> = shape.iter().map(|&n| take(n)).collect();
    let normals: Vec<Vec<Vec<u8>>> = normal_shape.iter().map(|&n| take(n)).collect();
    let textures = take(usize::MAX);
    let has_normals = asset.atlases.first().is_some_and(|a| a.normals.is_some());
    CloudBlocks {
        atlases,
        atlas_normals: has_normals.then_some(normals),
        textures,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `encode_volume` gives `compress_volume`'s blocks (base and bands, colour and normals)
    /// and leaves the asset's texels as they were; `compress_volume` then holds their
    /// decoding. On a torus with normals and one band cut from its level-1 texels.
    #[test]
    fn encode_volume_is_compress_volume_without_the_decoding() {
        use crate::voxelize::{voxelize, Resolution, VoxelizeOptions};
        let scene = crate::procgen::torus(1.0, 0.4, 24, 12);
        let opts = VoxelizeOptions {
            resolution: Resolution::Longest(16),
            normals: true,
            ..Default::default()
        };
        let v = voxelize(&scene, &opts, &|_, _| {}).unwrap();
        let mut asset = v.into_asset("test", None, Default::default());
        let dims = asset.level_dims(1);
        asset.bands.push(billow_format::LodBand {
            first_level: 1,
            dims,
            levels: asset.levels[1..].to_vec(),
            normals: asset.normals.as_ref().map(|n| n[1..].to_vec()),
            cells: asset.cells.clone(),
        });
        let mut before = asset.clone();
        let encoded = encode_volume(&mut asset);
        linear_colour(&mut before);
        assert!(
            asset == before,
            "encode_volume changed the asset beyond its colour space"
        );
        let compressed = compress_volume(&mut asset);
        assert_eq!(encoded, compressed);
        assert!(encoded.normals.is_some() && encoded.bands.len() == 1);
        assert!(encoded.bands[0].normals.is_some());
        let d0 = before.level_dims(0);
        assert_eq!(asset.levels[0], decode_bc7(&encoded.colour[0], d0, 0));
        assert_ne!(
            asset.levels[0], before.levels[0],
            "nothing was lossy: a weak test"
        );
        let mut n0 = decode_bc7(&encoded.normals.as_ref().unwrap()[0], d0, 0x80);
        unorm_to_snorm_in_place(&mut n0);
        assert_eq!(asset.normals.as_ref().unwrap()[0], n0);
        assert_eq!(
            asset.bands[0].levels[0],
            decode_bc7(&encoded.bands[0].colour[0], dims, 0)
        );
    }

    #[test]
    fn blocks_round_trip_odd_sizes_and_are_thread_count_independent() {
        // A 6×5×2 gradient: partial blocks on both axes, two slices.
        let dims = [6u32, 5, 2];
        let texels: Vec<u8> = (0..6 * 5 * 2 * 4).map(|i| (i * 7 % 251) as u8).collect();
        let blocks = encode_bc7(&texels, dims, 0);
        // 8 blocks, all stored: a 16-byte mask and 8 blocks.
        assert_eq!(blocks.len(), 16 + 2 * 2 * 2 * 16);
        assert_eq!(billow_format::sparse_len(&blocks, dims), Ok(8));
        let dec = decode_bc7(&blocks, dims, 0);
        assert_eq!(dec.len(), texels.len());
        let err = texels
            .iter()
            .zip(&dec)
            .map(|(a, b)| (i32::from(*a) - i32::from(*b)).abs())
            .max()
            .unwrap();
        assert!(err < 64, "max error {err}");
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| encode_bc7(&texels, dims, 0));
        assert_eq!(one, blocks);
        // Empty tiles are omitted: an empty level is its mask alone and decodes to zero,
        // and the dense form's stand-in block decodes to zero too.
        let empty = encode_bc7(&[0u8; 8 * 4 * 4], [8, 4, 1], 0);
        assert_eq!(empty, vec![0u8; 16]);
        assert_eq!(decode_bc7(&empty, [8, 4, 1], 0), vec![0u8; 128]);
        let dense = billow_format::expand_blocks(&empty, [8, 4, 1], billow_format::ZERO_BLOCK);
        assert_eq!(
            decode_bc7(&pack_blocks(&dense, &[true; 2]), [8, 4, 1], 9),
            vec![0u8; 128]
        );
        // Normals omit their zero (0x80 unsigned).
        let flat = encode_bc7(&[0x80u8; 64], [4, 4, 1], 0x80);
        assert_eq!(flat, vec![0u8; 16]);
        // A constant block decodes within a step or two.
        let flat = [200u8, 100, 50, 255].repeat(16);
        let back = decode_bc7(&encode_bc7(&flat, [4, 4, 1], 0), [4, 4, 1], 0);
        assert!(
            flat.iter().zip(&back).all(|(a, b)| a.abs_diff(*b) <= 2),
            "{back:?}"
        );
    }

    #[test]
    fn empty_texels_of_a_partly_full_block_decode_to_exact_zero() {
        // A surface edge: half the tile empty, half a premultiplied green of varying alpha.
        let mut tile = [0u8; 64];
        for i in 0..16 {
            if i % 4 >= 2 {
                let a = 40 + 12 * i as u8;
                tile[4 * i..4 * i + 4].copy_from_slice(&[a / 5, a / 2, a / 7, a]);
            }
        }
        let z = zero_anchored_block(&tile);
        let dec = decode_bc7_block(&z);
        for (s, d) in tile.chunks_exact(4).zip(dec.chunks_exact(4)) {
            if s == [0; 4] {
                assert_eq!(d, [0; 4]);
            } else {
                assert!(
                    s.iter().zip(d).all(|(a, b)| a.abs_diff(*b) <= 12),
                    "{s:?} -> {d:?}"
                );
            }
        }
        // Texel 0 full: the endpoints swap and the anchor still holds.
        let mut flipped = tile;
        flipped.swap_with_slice(&mut [0u8; 64]);
        for i in 0..16 {
            if i % 4 < 2 {
                flipped[4 * i..4 * i + 4].copy_from_slice(&[30, 90, 10, 120]);
            }
        }
        let dec = decode_bc7_block(&zero_anchored_block(&flipped));
        for (s, d) in flipped.chunks_exact(4).zip(dec.chunks_exact(4)) {
            if s == [0; 4] {
                assert_eq!(d, [0; 4]);
            } else {
                assert!(s.iter().zip(d).all(|(a, b)| a.abs_diff(*b) <= 3), "{d:?}");
            }
        }
        // A tile that leaks under the kernel alone (found by a search over tiles of a few
        // bright opaque texels among empty ones): "alpha ultra fast" decodes its 13 empty
        // texels as (0, 8, 0, 0); the anchored block, which keeps them empty, is poor
        // (one line through zero cannot fit three hues) but is what the volume encoder
        // takes (`encode_keep_zero`).
        let mut tile = [0u8; 64];
        for (i, t) in [
            (4, [39, 66, 16, 255]),
            (9, [49, 110, 70, 255]),
            (13, [198, 0, 197, 255]),
        ] {
            tile[4 * i..4 * i + 4].copy_from_slice(&t);
        }
        let fast = bc7(&tile, BC7Settings::alpha_ultrafast());
        let leaked = decode_bc7_block(&fast);
        let leaks = (0..16)
            .filter(|&i| tile[4 * i..4 * i + 4] == [0; 4] && leaked[4 * i..4 * i + 4] != [0; 4])
            .count();
        assert_eq!(leaks, 13, "the pattern leaks unrepaired: {leaked:?}");
        let anchored = keeps_zero(&tile, &zero_anchored_block(&tile)).unwrap();
        assert!(anchored > 64, "{anchored}");
        let anchored_block = zero_anchored_block(&tile);
        // The encoder with the constraint, on a level of that tile beside an empty one and
        // a full one: every empty texel of the level stays empty, the others stay close.
        let dims = [12u32, 4, 1];
        let mut texels = vec![0u8; 12 * 4 * 4];
        for y in 0..4 {
            for x in 0..4 {
                let o = 4 * (y * 12 + x);
                texels[o..o + 4].copy_from_slice(&tile[4 * (y * 4 + x)..4 * (y * 4 + x) + 4]);
                let o = 4 * (y * 12 + 8 + x);
                let a = (60 + 10 * (x + 4 * y)) as u8;
                texels[o..o + 4].copy_from_slice(&[a / 2, a / 3, a / 4, a]);
            }
        }
        let blocks = encode_bc7_with(&texels, dims, 0, false, true);
        assert_eq!(billow_format::sparse_len(&blocks, dims), Ok(2));
        let dec = decode_bc7(&blocks, dims, 0);
        for (i, (s, d)) in texels.chunks_exact(4).zip(dec.chunks_exact(4)).enumerate() {
            if s == [0; 4] {
                assert_eq!(d, [0; 4], "texel {i}: an empty texel leaks");
            } else if i % 12 >= 8 {
                // The full block, one hue: close.
                assert!(
                    s.iter().zip(d).all(|(a, b)| a.abs_diff(*b) <= 4),
                    "{s:?} -> {d:?}"
                );
            }
        }
        assert_eq!(
            &blocks[16..32],
            &anchored_block[..],
            "the level's block is the zero-anchored one"
        );
    }

    #[test]
    fn normal_tiles_keep_their_unused_w_within_one_step() {
        // A smooth patch of unit normals (snorm bytes, w = 0) and one empty texel.
        let mut texels = Vec::new();
        for i in 0..16 {
            let (x, y) = ((i % 4) as f32 / 8.0 - 0.2, (i / 4) as f32 / 8.0 - 0.2);
            let z = (1.0 - x * x - y * y).sqrt();
            let q = |v: f32| ((v * 127.0).round() as i8) as u8;
            texels.extend_from_slice(&if i == 5 {
                [0; 4]
            } else {
                [q(x), q(y), q(z), 0]
            });
        }
        let unorm = snorm_to_unorm(&texels);
        let blocks = encode_bc7_normals(&unorm, [4, 4, 1]);
        assert_eq!(blocks[16] & 0x7F, 0x40, "mode 6");
        let mut dec = decode_bc7(&blocks, [4, 4, 1], 0x80);
        unorm_to_snorm_in_place(&mut dec);
        let alpha = bc7(
            &unorm.clone().try_into().unwrap(),
            BC7Settings::alpha_ultrafast(),
        );
        let mut dec_alpha = decode_bc7_block(&alpha).to_vec();
        unorm_to_snorm_in_place(&mut dec_alpha);
        let xyz_sse = |dec: &[u8]| -> i64 {
            let e = |a: u8, b: u8| (i64::from(a as i8) - i64::from(b as i8)).pow(2);
            (0..64)
                .filter(|k| k % 4 != 3)
                .map(|k| e(texels[k], dec[k]))
                .sum()
        };
        let (fast, reference) = (xyz_sse(&dec), xyz_sse(&dec_alpha));
        // The xyz error of "alpha ultra fast" (which also picks mode 6 for such a tile).
        assert!(
            fast <= reference + reference / 4 + 16,
            "{fast} vs {reference}"
        );
        for d in dec.chunks_exact(4) {
            assert!(d[3] == 0 || d[3] == 1, "w {}", d[3]);
        }
        // Not all w zero (another use of the encoder): the alpha profile.
        let mut odd = unorm.clone();
        odd[3] = 0x90;
        let b = encode_bc7_normals(&odd, [4, 4, 1]);
        assert_eq!(
            &b[16..],
            &bc7(&odd.try_into().unwrap(), BC7Settings::alpha_ultrafast())
        );
    }
}
