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
//! After compressing, the asset's texels are replaced by the decoded blocks: the asset in
//! memory is then exactly what a reader of the file gets back.

use billow_format::{
    bc7_len, decode_bc7, mip_dims, pack_blocks, snorm_to_unorm, unorm_to_snorm_in_place,
    CloudAsset, CloudBlocks, VolumeAsset, VolumeBlocks, BC7_BLOCK_BYTES,
};
use block_compression::{encode::compress_rgba8, BC7Settings, CompressionVariant};
use rayon::prelude::*;

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

/// The encoder's settings for a tile: the ISPC kernel's "alpha ultra fast" profile (see
/// docs/accuracy.md for the slower profiles' speed and error), or, with `opaque_fast` and
/// a tile whose alpha is all 255, "opaque ultra fast": the same RGB error, about 5× faster
/// (it may decode alpha 255 as 254; used for the cloud's alpha-tested or opaque textures,
/// not for volumes, whose opacity accumulates).
fn settings(tile: &[u8; 64], opaque_fast: bool) -> (CompressionVariant, bool) {
    if opaque_fast && tile.chunks_exact(4).all(|t| t[3] == 255) {
        (
            CompressionVariant::BC7(BC7Settings::opaque_ultra_fast()),
            true,
        )
    } else {
        (
            CompressionVariant::BC7(BC7Settings::alpha_ultrafast()),
            false,
        )
    }
}

/// Constant tiles already encoded on this thread, by texel value and profile.
type ConstantCache = std::collections::HashMap<([u8; 4], bool), [u8; 16]>;

thread_local! {
    static CONSTANT: std::cell::RefCell<ConstantCache> =
        std::cell::RefCell::new(std::collections::HashMap::new());
}

/// The compressed chunk payload (SPEC §12.1) of a `dims` level of RGBA8 texels (x fastest,
/// then y, then z; each z slice its own blocks): the block mask and the BC7 blocks of
/// every 4×4 tile that is not all `omit` bytes (0 for colour; 0x80, the unsigned form of
/// a zero normal, for normals). Omitted tiles cost no encoding: volumes and atlases are
/// mostly empty (the oak at 128³: 4 % of its voxels are not).
pub fn encode_bc7(texels: &[u8], dims: [u32; 3], omit: u8) -> Vec<u8> {
    encode_bc7_with(texels, dims, omit, false)
}

/// [`encode_bc7`]; `opaque_fast`: encode tiles of alpha 255 with the opaque profile
/// ([`settings`]).
pub fn encode_bc7_with(texels: &[u8], dims: [u32; 3], omit: u8, opaque_fast: bool) -> Vec<u8> {
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
            let first: [u8; 4] = tile[0..4].try_into().expect("4 bytes");
            keep[bx] = !tile.iter().all(|&b| b == omit);
            if !keep[bx] {
                continue;
            }
            let (variant, opaque) = settings(&tile, opaque_fast);
            if tile.chunks_exact(4).all(|t| t == first) {
                // Constant tiles (an empty region's normals, a flat colour) recur: the
                // encoder is a pure function, so a per-thread cache changes no byte.
                CONSTANT.with(|c| {
                    let mut c = c.borrow_mut();
                    let b = c.entry((first, opaque)).or_insert_with(|| {
                        let mut b = [0u8; 16];
                        compress_rgba8(variant, &tile, &mut b, 4, 4, 16);
                        b
                    });
                    out.copy_from_slice(b);
                });
            } else {
                compress_rgba8(variant, &tile, out, 4, 4, 16);
            }
        }
    });
    pack_blocks(&out, &stored)
}

/// Encodes one level and returns its payload and its decoding.
fn round_trip(texels: &[u8], dims: [u32; 3], omit: u8, opaque_fast: bool) -> (Vec<u8>, Vec<u8>) {
    let blocks = encode_bc7_with(texels, dims, omit, opaque_fast);
    let decoded = decode_bc7(&blocks, dims, omit);
    (blocks, decoded)
}

/// Compresses `asset`'s base texture (colour and normals, every MIP level) and replaces
/// its texels with the decoded blocks. LOD bands stay raw (`billow emptyspace` writes them).
pub fn compress_volume(asset: &mut VolumeAsset) -> VolumeBlocks {
    let dims = asset.level_dims(0);
    let mut colour = Vec::with_capacity(asset.levels.len());
    for (i, l) in asset.levels.iter_mut().enumerate() {
        let (b, dec) = round_trip(l, mip_dims(dims, i as u32), 0, false);
        colour.push(b);
        *l = dec;
    }
    let normals = asset.normals.as_mut().map(|ls| {
        ls.iter_mut()
            .enumerate()
            .map(|(i, l)| {
                let (b, mut dec) =
                    round_trip(&snorm_to_unorm(l), mip_dims(dims, i as u32), 0x80, false);
                unorm_to_snorm_in_place(&mut dec);
                *l = dec;
                b
            })
            .collect()
    });
    VolumeBlocks { colour, normals }
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
            let (b, dec) = round_trip(l, d, 0, true);
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
}
