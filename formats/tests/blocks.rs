//! Block-compressed texels (format 1.2, SPEC.md §12): the two frozen 1.2 fixtures, round
//! trips, what a reader refuses, and the decoder checked against a second, independent
//! BC7 decoder (the `block_compression` crate's).
//!
//! To generate a fixture — only ever for a NEW fixture file, never to "fix" one:
//! `cargo test -p billow-format --test blocks -- --ignored generate_v1_2`

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow_format::*;
use block_compression::{encode::compress_rgba8, BC7Settings, CompressionVariant};
use common::*;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/format")
        .join(name)
}

const BANDS_FIXTURE_LEN: usize = 1384;
const BANDS_FIXTURE_CRC: u32 = 0x7e6e_4f9e;
const BANDS_TEXEL_1: [u8; 4] = [66, 44, 26, 131];
const VOLUME_FIXTURE: &str = "v1_2_volume_bc7.billow";
const CLOUD_FIXTURE: &str = "v1_2_cloud_bc7.billow";
const CLOUD_1_1: &str = "v1_1_cloud_normals.billow";
const BANDS_FIXTURE: &str = "v1_3_volume_bands_bc7.billow";

/// The compressed payload of a `dims` level (the generator's encoder: edge texels
/// repeated, tiles of all-`omit` texels omitted).
fn encode(texels: &[u8], dims: [u32; 3], omit: u8) -> Vec<u8> {
    let [w, h, d] = dims.map(|v| v as usize);
    let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
    let (pw, ph) = (bw * 4, bh * 4);
    let mut out = Vec::new();
    let mut keep = Vec::new();
    for z in 0..d {
        let mut padded = vec![0u8; pw * ph * 4];
        for y in 0..ph {
            for x in 0..pw {
                let s = ((z * h + y.min(h - 1)) * w + x.min(w - 1)) * 4;
                padded[(y * pw + x) * 4..][..4].copy_from_slice(&texels[s..s + 4]);
            }
        }
        let v = CompressionVariant::BC7(BC7Settings::alpha_basic());
        let mut b = vec![0u8; bw * bh * 16];
        compress_rgba8(v, &padded, &mut b, pw as u32, ph as u32, (pw * 4) as u32);
        out.extend(b);
        for by in 0..bh {
            for bx in 0..bw {
                let tile = (0..4).flat_map(|ty| {
                    let o = ((by * 4 + ty) * pw + bx * 4) * 4;
                    padded[o..o + 16].to_vec()
                });
                keep.push(tile.collect::<Vec<u8>>().iter().any(|&b| b != omit));
            }
        }
    }
    pack_blocks(&out, &keep)
}

/// The second decoder: `block_compression`'s, on the same blocks (omitted ones as
/// [`ZERO_BLOCK`], which decodes to zero).
fn other_decoder(payload: &[u8], dims: [u32; 3]) -> Vec<u8> {
    let blocks = expand_blocks(payload, dims, ZERO_BLOCK);
    let [w, h, d] = dims.map(|v| v as usize);
    let (bw, bh) = (w.div_ceil(4), h.div_ceil(4));
    let mut out = vec![0u8; w * h * d * 4];
    for z in 0..d {
        let slice = &blocks[z * bw * bh * 16..(z + 1) * bw * bh * 16];
        let mut full = vec![0u8; bw * bh * 64];
        block_compression::decode::decompress_blocks_as_rgba8(
            CompressionVariant::BC7(BC7Settings::alpha_basic()),
            (bw * 4) as u32,
            (bh * 4) as u32,
            slice,
            &mut full,
        );
        for y in 0..h {
            let s = y * bw * 4 * 4;
            let o = (z * h + y) * w * 4;
            out[o..o + w * 4].copy_from_slice(&full[s..s + w * 4]);
        }
    }
    out
}

/// The volume fixture's source texels: level 0 is 5×4×2, level 1 2×2×1.
fn volume_source() -> VolumeAsset {
    let mut params = BTreeMap::new();
    params.insert("compress".to_string(), "bc7".to_string());
    params.insert("res".to_string(), "5x4x2".to_string());
    let header = Header {
        kind: AssetKind::Volume,
        tool: "billow 0.1.0".into(),
        source: None,
        bounds: Bounds {
            min: [0.0; 3],
            max: [1.25, 1.0, 0.5],
        },
        colour_space: ColourSpace::SrgbPremultiplied,
        seed: None,
        params,
        volume: Some(VolumeHeader {
            dims: [5, 4, 2],
            mip_count: 2,
            texel: TexelFormat::Rgba8Unorm,
            normals: Some(NormalEncoding::Rgba8Snorm),
            moments: None,
        }),
    };
    let colour = |n: usize, s: usize| -> Vec<u8> {
        (0..n)
            .flat_map(|i| {
                let a = (40 + 50 * ((i + s) % 5)) as u8;
                [a / 2, a / 3, (i * 7 % 32) as u8, a]
            })
            .collect()
    };
    let normal = |n: usize| -> Vec<u8> {
        (0..n)
            .flat_map(|i| {
                let v: [i8; 4] = [(i as i8 % 5) * 20 - 40, 60, 100 - (i as i8 % 3) * 30, 0];
                v.map(|c| c as u8)
            })
            .collect()
    };
    let cells = vec![Prism {
        pos: [
            [0.0, 0.0, 0.0],
            [1.25, 0.0, 0.0],
            [1.25, 0.0, 0.5],
            [0.0, 1.0, 0.0],
            [1.25, 1.0, 0.0],
            [1.25, 1.0, 0.5],
        ],
        uvw: [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 1.0, 1.0],
        ],
    }];
    // Slice z = 1's partial block (x = 4) is empty: omitted from both chunks.
    let (mut c0, mut n0) = (colour(40, 0), normal(40));
    for y in 0..4 {
        let i = 4 * (4 + 5 * (y + 4));
        c0[i..i + 4].fill(0);
        n0[i..i + 4].fill(0);
    }
    VolumeAsset {
        header,
        levels: vec![c0, colour(4, 3)],
        normals: Some(vec![n0, normal(4)]),
        cells,
        bands: Vec::new(),
    }
}

/// [`volume_source`] with one LOD band (first level 1, 3×2×1 with two levels, normals).
fn bands_source() -> VolumeAsset {
    let mut a = volume_source();
    let colour = |n: usize| -> Vec<u8> {
        (0..n)
            .flat_map(|i| {
                let a = if i % 3 == 0 {
                    0
                } else {
                    90 + 40 * (i as u8 % 4)
                };
                [a / 2, a / 3, a / 5, a]
            })
            .collect()
    };
    let normal =
        |n: usize| -> Vec<u8> { (0..n).flat_map(|i| [i as u8 * 9, 20, 0x90, 0]).collect() };
    let cells = a.cells.clone();
    a.bands.push(LodBand {
        first_level: 1,
        dims: [3, 2, 1],
        levels: vec![colour(6), colour(1)],
        normals: Some(vec![normal(6), normal(1)]),
        cells,
    });
    a
}

/// [`compress_volume`] and every band: `a` then holds the decoded texels.
fn compress_volume_bands(a: &mut VolumeAsset) -> VolumeBlocks {
    let mut b = compress_volume(a);
    for band in &mut a.bands {
        let mut bb = BandBlocks::default();
        for (i, l) in band.levels.iter_mut().enumerate() {
            let d = mip_dims(band.dims, i as u32);
            bb.colour.push(encode(l, d, 0));
            *l = decode_bc7(bb.colour.last().unwrap(), d, 0);
        }
        let mut nb = Vec::new();
        for (i, l) in band.normals.iter_mut().flatten().enumerate() {
            let d = mip_dims(band.dims, i as u32);
            nb.push(encode(&snorm_to_unorm(l), d, 0x80));
            *l = decode_bc7(nb.last().unwrap(), d, 0x80);
            unorm_to_snorm_in_place(l);
        }
        bb.normals = Some(nb);
        b.bands.push(bb);
    }
    b
}

/// Compresses `a`'s base texture; `a` then holds the decoded texels.
fn compress_volume(a: &mut VolumeAsset) -> VolumeBlocks {
    let dims = a.level_dims(0);
    let mut b = VolumeBlocks::default();
    for (i, l) in a.levels.iter_mut().enumerate() {
        let d = mip_dims(dims, i as u32);
        b.colour.push(encode(l, d, 0));
        *l = decode_bc7(b.colour.last().unwrap(), d, 0);
    }
    let mut nb = Vec::new();
    for (i, l) in a.normals.iter_mut().flatten().enumerate() {
        let d = mip_dims(dims, i as u32);
        nb.push(encode(&snorm_to_unorm(l), d, 0x80));
        *l = decode_bc7(nb.last().unwrap(), d, 0x80);
        unorm_to_snorm_in_place(l);
    }
    b.normals = Some(nb);
    b
}

fn compress_cloud(a: &mut CloudAsset) -> CloudBlocks {
    let mut b = CloudBlocks::default();
    let chain = |levels: &mut Vec<Vec<u8>>, w: u32, h: u32| -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        for (k, l) in levels.iter_mut().enumerate() {
            let d = mip_dims([w, h, 1], k as u32);
            out.push(encode(l, d, 0));
            *l = decode_bc7(out.last().unwrap(), d, 0);
        }
        out
    };
    let mut normals = Vec::new();
    for at in &mut a.atlases {
        b.atlases.push(chain(&mut at.mips, at.width, at.height));
        normals.push(chain(at.normals.as_mut().unwrap(), at.width, at.height));
    }
    b.atlas_normals = Some(normals);
    for t in &mut a.textures {
        let d = [t.width, t.height, 1];
        b.textures.push(encode(&t.texels, d, 0));
        t.texels = decode_bc7(b.textures.last().unwrap(), d, 0);
    }
    b
}

#[test]
#[ignore = "writes the frozen fixtures; only for new fixture files"]
fn generate_v1_2() {
    let mut v = volume_source();
    let vb = compress_volume(&mut v);
    v.write_with(&path(VOLUME_FIXTURE), Some(&vb)).unwrap();
    let mut c = CloudAsset::read(&path(CLOUD_1_1)).unwrap();
    c.header.params.insert("compress".into(), "bc7".into());
    let cb = compress_cloud(&mut c);
    c.write_with(&path(CLOUD_FIXTURE), Some(&cb)).unwrap();
}

#[test]
#[ignore = "writes the frozen fixture; only for new fixture files"]
fn generate_v1_3() {
    let mut v = bands_source();
    let vb = compress_volume_bands(&mut v);
    v.write_with(&path(BANDS_FIXTURE), Some(&vb)).unwrap();
}

/// Compressed bands (format 1.3): written as BLB7/BNB7, read back as the same blocks and
/// decoded texels; a raw-banded volume with a compressed base stays 1.2.
#[test]
fn compressed_bands_round_trip_as_1_3() {
    let mut a = bands_source();
    let b = compress_volume_bands(&mut a);
    let bytes = a.to_bytes_with(Some(&b)).unwrap();
    assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 3);
    assert_eq!(
        tags(&bytes),
        "HEAD VLB7 VLB7 VNB7 VNB7 CELL VBND BLB7 BLB7 BNB7 BNB7 BCEL END "
    );
    let (back, bb) = VolumeAsset::from_bytes_with_blocks(&bytes).unwrap();
    assert_eq!(back, a);
    assert_eq!(bb.as_ref(), Some(&b));
    let base_only = VolumeBlocks {
        bands: Vec::new(),
        ..b.clone()
    };
    let raw_bands = a.to_bytes_with(Some(&base_only)).unwrap();
    assert_eq!(u16::from_le_bytes([raw_bands[10], raw_bands[11]]), 2);
    assert!(tags(&raw_bands).contains("BLEV BLEV BNRM BNRM"));
    // A wrong number of band block sets is refused by the writer.
    let mut two = b.clone();
    two.bands.push(b.bands[0].clone());
    assert!(a.to_bytes_with(Some(&two)).is_err());
}

/// Normal texels made moment-like (format 1.4, SPEC §8.4a): each texel's |x|, |y|, |z|
/// scaled to sum to 127, w = 0; all-zero texels (empty) stay zero.
fn as_moments(texels: &mut [u8]) {
    for t in texels.chunks_exact_mut(4) {
        let a = [0, 1, 2].map(|i| u32::from((t[i] as i8).unsigned_abs()));
        let s: u32 = a.iter().sum();
        if s == 0 {
            t.fill(0);
            continue;
        }
        let x = (a[0] * 127 + s / 2) / s;
        let y = ((a[0] + a[1]) * 127 + s / 2) / s - x;
        t.copy_from_slice(&[x as u8, y as u8, (127 - x - y) as u8, 0]);
    }
}

/// Normal moments (format 1.4) compress like mean normals, the bytes XOR 0x80: stored as
/// VMB7 (base) and BMB7 (bands) instead of VNB7/BNB7, read back as the same blocks and
/// texels; with raw bands, BMOM.
#[test]
fn compressed_moments_round_trip_as_vmb7_and_bmb7() {
    let mut a = bands_source();
    a.header
        .volume
        .as_mut()
        .unwrap()
        .set_normal_kind(Some(NormalKind::Moments));
    a.normals.iter_mut().flatten().for_each(|l| as_moments(l));
    for band in &mut a.bands {
        band.normals
            .iter_mut()
            .flatten()
            .for_each(|l| as_moments(l));
    }
    let b = compress_volume_bands(&mut a);
    let bytes = a.to_bytes_with(Some(&b)).unwrap();
    assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 4);
    assert_eq!(
        tags(&bytes),
        "HEAD VLB7 VLB7 VMB7 VMB7 CELL VBND BLB7 BLB7 BMB7 BMB7 BCEL END "
    );
    let (back, bb) = VolumeAsset::from_bytes_with_blocks(&bytes).unwrap();
    assert_eq!(back, a);
    assert_eq!(bb.as_ref(), Some(&b));
    // The empty texel (4, 3, 1) of the source decodes to exactly zero moments.
    assert_eq!(&back.normals.as_ref().unwrap()[0][156..160], &[0; 4]);
    let base_only = VolumeBlocks {
        bands: Vec::new(),
        ..b.clone()
    };
    let raw_bands = a.to_bytes_with(Some(&base_only)).unwrap();
    assert_eq!(u16::from_le_bytes([raw_bands[10], raw_bands[11]]), 4);
    assert!(tags(&raw_bands).contains("VMB7 VMB7 CELL VBND BLEV BLEV BMOM BMOM BCEL"));
    assert_eq!(VolumeAsset::from_bytes(&raw_bands).unwrap(), a);
    // Mean-normal blocks in a moments volume are refused, not skipped.
    let mut chunks = split_chunks(&bytes);
    for c in chunks.iter_mut().filter(|c| &c.0 == b"VMB7") {
        c.0 = *b"VNB7";
    }
    let e = VolumeAsset::from_bytes(&join_chunks(1, 4, 1, &chunks))
        .unwrap_err()
        .to_string();
    assert!(e.contains("VNB7") && e.contains("volume.moments"), "{e}");
}

/// FROZEN: the 1.3 fixture: the 1.2 volume fixture's source with one compressed band.
#[test]
fn decodes_frozen_v1_3_bands_fixture() {
    let bytes =
        std::fs::read(path(BANDS_FIXTURE)).expect("fixtures/format/v1_3_volume_bands_bc7.billow");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 3, 0, 1, 0, 0, 0],
        "format 1.3, Volume"
    );
    assert_eq!(bytes.len(), BANDS_FIXTURE_LEN);
    assert_eq!(
        crc(&bytes),
        BANDS_FIXTURE_CRC,
        "fixture file changed on disk"
    );
    assert_eq!(
        tags(&bytes),
        "HEAD VLB7 VLB7 VNB7 VNB7 CELL VBND BLB7 BLB7 BNB7 BNB7 BCEL END "
    );
    let (a, blocks) = VolumeAsset::from_bytes_with_blocks(&bytes).unwrap();
    let blocks = blocks.expect("a compressed volume");
    assert_eq!(blocks.bands.len(), 1);
    let band = &a.bands[0];
    assert_eq!((band.first_level, band.dims), (1, [3, 2, 1]));
    // Texels 0 and 3 of the band's level 0 are empty in the source: exactly zero.
    assert_eq!(&band.levels[0][0..4], &[0; 4]);
    assert_eq!(&band.levels[0][12..16], &[0; 4]);
    assert_eq!(&band.levels[0][4..8], &BANDS_TEXEL_1);
    for (i, (b, l)) in blocks.bands[0].colour.iter().zip(&band.levels).enumerate() {
        assert_eq!(
            &other_decoder(b, mip_dims([3, 2, 1], i as u32)),
            l,
            "level {i}"
        );
    }
    let src = bands_source();
    for (l, s) in band.levels.iter().zip(&src.bands[0].levels) {
        assert!(max_diff(l, s) <= 12, "{}", max_diff(l, s));
    }
    assert_eq!(a.to_bytes_with(Some(&blocks)).unwrap(), bytes);
}

fn tags(bytes: &[u8]) -> String {
    let c = from_bytes(bytes).unwrap();
    let mut t = vec!["HEAD".to_string()];
    t.extend(c.chunks.iter().map(|ch| tag_str(&ch.tag)));
    t.push("END ".into());
    t.join(" ")
}

fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// FROZEN: the 1.2 volume fixture, with values spelled out here.
#[test]
fn decodes_frozen_v1_2_volume_fixture() {
    let bytes =
        std::fs::read(path(VOLUME_FIXTURE)).expect("fixtures/format/v1_2_volume_bc7.billow");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 2, 0, 1, 0, 0, 0],
        "format 1.2, Volume"
    );
    assert_eq!(bytes.len(), VOLUME_FIXTURE_LEN);
    assert_eq!(
        crc(&bytes),
        VOLUME_FIXTURE_CRC,
        "fixture file changed on disk"
    );
    assert_eq!(tags(&bytes), "HEAD VLB7 VLB7 VNB7 VNB7 CELL END ");
    let c = from_bytes(&bytes).unwrap();
    let lens: Vec<usize> = c.chunks.iter().map(|ch| ch.data.len()).collect();
    // 5×4×2: 2 blocks per slice, 2 slices, one omitted: a 16-byte mask and 3 blocks;
    // 2×2×1: the mask and one block.
    assert_eq!(lens, [64, 32, 64, 32, 144]);
    assert_eq!(c.chunks[0].data[0], 0b0111, "the block mask of level 0");
    let (a, blocks) = VolumeAsset::from_bytes_with_blocks(&bytes).unwrap();
    let blocks = blocks.expect("a compressed volume");
    assert_eq!(blocks.colour.len(), 2);
    assert_eq!(a.level_dims(0), [5, 4, 2]);
    assert_eq!(a.levels[0].len(), 5 * 4 * 2 * 4);
    assert_eq!(a.levels[1].len(), 2 * 2 * 4);
    // Decoded texels: (0,0,0), (4,3,0) (in a partial block) and level 1's first; (4,3,1)
    // is in the omitted block: zero.
    assert_eq!(&a.levels[0][0..4], &VOLUME_TEXEL_000);
    assert_eq!(&a.levels[0][76..80], &VOLUME_TEXEL_430);
    assert_eq!(&a.levels[0][156..160], &[0; 4]);
    assert_eq!(&a.normals.as_ref().unwrap()[0][156..160], &[0; 4]);
    assert_eq!(&a.levels[1][0..4], &VOLUME_LEVEL1_TEXEL_0);
    // The normals' first texel, as signed bytes.
    let n = a.normals.as_ref().unwrap();
    assert_eq!(&n[0][0..4], &VOLUME_NORMAL_000.map(|v: i8| v as u8));
    // A second decoder agrees on every texel.
    for (i, (b, l)) in blocks.colour.iter().zip(&a.levels).enumerate() {
        assert_eq!(
            &other_decoder(b, mip_dims([5, 4, 2], i as u32)),
            l,
            "level {i}"
        );
    }
    // And the blocks are close to the source texels (lossy, within a few steps).
    let src = volume_source();
    for (l, s) in a.levels.iter().zip(&src.levels) {
        assert!(max_diff(l, s) <= 12, "{}", max_diff(l, s));
    }
    // The file is what the writer writes for this asset and its blocks.
    assert_eq!(a.to_bytes_with(Some(&blocks)).unwrap(), bytes);
}

/// FROZEN: the 1.2 cloud fixture: the 1.1 fixture with its textures as blocks.
#[test]
fn decodes_frozen_v1_2_cloud_fixture() {
    let bytes = std::fs::read(path(CLOUD_FIXTURE)).expect("fixtures/format/v1_2_cloud_bc7.billow");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 2, 0, 2, 0, 0, 0],
        "format 1.2, Cloud"
    );
    assert_eq!(bytes.len(), CLOUD_FIXTURE_LEN);
    assert_eq!(
        crc(&bytes),
        CLOUD_FIXTURE_CRC,
        "fixture file changed on disk"
    );
    assert_eq!(
        tags(&bytes),
        "HEAD CLVL CLVF BBRD BBIX ATLS ATB7 ATB7 ATB7 ATB7 ATB7 ANB7 ANB7 ANB7 ANB7 ANB7 \
         MMAT MMAI MTXI MTB7 TVTX TIDX FVTX FIDX END "
    );
    let (a, blocks) = CloudAsset::from_bytes_with_blocks(&bytes).unwrap();
    let blocks = blocks.expect("a compressed cloud");
    let raw = CloudAsset::read(&path(CLOUD_1_1)).unwrap();
    // Everything but the texels is the 1.1 fixture's.
    assert_eq!(a.levels, raw.levels);
    assert_eq!(a.billboards, raw.billboards);
    assert_eq!(a.trunk, raw.trunk);
    assert_eq!(a.foliage, raw.foliage);
    for (x, y) in a.atlases.iter().zip(&raw.atlases) {
        assert_eq!(
            (x.width, x.height, x.mips.len()),
            (y.width, y.height, y.mips.len())
        );
        for (k, (p, q)) in x.mips.iter().zip(&y.mips).enumerate() {
            assert!(max_diff(p, q) <= 16, "atlas level {k}: {}", max_diff(p, q));
        }
    }
    // Each 4×2 level-0 atlas is one block; 2×1 and 1×1 levels one block each: a 16-byte
    // mask and at most one block.
    assert!(blocks
        .atlases
        .iter()
        .flatten()
        .all(|b| b.len() == 16 || b.len() == 32));
    assert_eq!(&a.atlases[0].mips[0][0..4], &CLOUD_ATLAS0_TEXEL0);
    for (i, (b, at)) in blocks.atlases.iter().zip(&a.atlases).enumerate() {
        for (k, (bl, l)) in b.iter().zip(&at.mips).enumerate() {
            let d = mip_dims([at.width, at.height, 1], k as u32);
            assert_eq!(&other_decoder(bl, d), l, "atlas {i} level {k}");
        }
    }
    assert_eq!(a.to_bytes_with(Some(&blocks)).unwrap(), bytes);
}

// Values of the frozen files (set when they were generated, never changed after).
const VOLUME_FIXTURE_LEN: usize = 952;
const VOLUME_FIXTURE_CRC: u32 = 0xd793_b179;
const VOLUME_TEXEL_000: [u8; 4] = [20, 14, 1, 40];
const VOLUME_TEXEL_430: [u8; 4] = [120, 80, 6, 240];
const VOLUME_LEVEL1_TEXEL_0: [u8; 4] = [93, 60, 4, 190];
const VOLUME_NORMAL_000: [i8; 4] = [-38, 61, 103, 4];
const CLOUD_FIXTURE_LEN: usize = 2344;
const CLOUD_FIXTURE_CRC: u32 = 0x6883_1791;
const CLOUD_ATLAS0_TEXEL0: [u8; 4] = [1, 9, 17, 25];

#[test]
fn compressed_volumes_round_trip_as_1_2_and_raw_files_stay_1_0() {
    let src = volume_source();
    let raw = src.to_bytes().unwrap();
    assert_eq!(u16::from_le_bytes([raw[10], raw[11]]), 0, "no blocks: 1.0");
    let mut a = volume_source();
    let b = compress_volume(&mut a);
    let bytes = a.to_bytes_with(Some(&b)).unwrap();
    assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 2);
    let (back, bb) = VolumeAsset::from_bytes_with_blocks(&bytes).unwrap();
    assert_eq!(back, a);
    assert_eq!(bb.as_ref(), Some(&b));
    // Plain `from_bytes` gives the decoded asset too.
    assert_eq!(VolumeAsset::from_bytes(&bytes).unwrap(), a);
    // Streamed and written: the same bytes.
    let parts = a.with_parts_with(Some(&b), |p| p.concat()).unwrap();
    assert_eq!(parts, bytes);
    let dir = tempfile::tempdir().unwrap();
    a.write_with(&dir.path().join("v.billow"), Some(&b))
        .unwrap();
    assert_eq!(std::fs::read(dir.path().join("v.billow")).unwrap(), bytes);
    // 4:1 — the compressed file is smaller than the raw one by the texel bytes' 3/4.
    assert!(bytes.len() < raw.len());
}

#[test]
fn wrong_block_shapes_and_mixed_chunks_are_refused() {
    let mut a = volume_source();
    let b = compress_volume(&mut a);
    // A block level of the wrong size is refused when writing.
    let mut short = b.clone();
    short.colour[1].truncate(8);
    assert!(a.to_bytes_with(Some(&short)).is_err());
    let mut missing = b.clone();
    missing.normals = None;
    assert!(a.to_bytes_with(Some(&missing)).is_err());
    // On read: a file with both VLEV and VLB7, a VLB7 of the wrong length, a missing VNB7.
    let bytes = a.to_bytes_with(Some(&b)).unwrap();
    let c = from_bytes(&bytes).unwrap();
    let rebuilt = |f: &dyn Fn(&mut Vec<Chunk>)| {
        let mut c2 = c.clone();
        f(&mut c2.chunks);
        to_bytes(&c2).unwrap()
    };
    let mixed = rebuilt(&|ch| {
        ch.insert(
            0,
            Chunk {
                tag: TAG_VLEV,
                elem: ElemType::U8,
                data: vec![0; 160],
            },
        )
    });
    let e = VolumeAsset::from_bytes(&mixed).unwrap_err().to_string();
    assert!(e.contains("both raw"), "{e}");
    let bad_len = rebuilt(&|ch| ch[1].data.truncate(8));
    let e = VolumeAsset::from_bytes(&bad_len).unwrap_err().to_string();
    assert!(e.contains("VLB7 level 1"), "{e}");
    let no_normals = rebuilt(&|ch| ch.retain(|c| c.tag != TAG_VNB7));
    assert!(VolumeAsset::from_bytes(&no_normals).is_err());
    // A reader that knows no blocks (1.0/1.1) finds no VLEV chunks: refused, never misread.
    let older = rebuilt(&|ch| ch.retain(|c| c.tag != TAG_VLB7 && c.tag != TAG_VNB7));
    assert!(VolumeAsset::from_bytes(&older).is_err());
}

#[test]
fn cloud_blocks_must_cover_every_texture() {
    let mut c = CloudAsset::read(&path(CLOUD_1_1)).unwrap();
    let b = compress_cloud(&mut c);
    let bytes = c.to_bytes_with(Some(&b)).unwrap();
    let (back, bb) = CloudAsset::from_bytes_with_blocks(&bytes).unwrap();
    assert_eq!(back, c);
    assert_eq!(bb.as_ref(), Some(&b));
    let mut no_tex = b.clone();
    no_tex.textures.clear();
    assert!(c.to_bytes_with(Some(&no_tex)).is_err());
    let mut no_normals = b.clone();
    no_normals.atlas_normals = None;
    assert!(c.to_bytes_with(Some(&no_normals)).is_err());
    // Mixed raw and compressed texture chunks are refused on read.
    let mut cont = from_bytes(&bytes).unwrap();
    let at = cont
        .chunks
        .iter()
        .position(|ch| ch.tag == TAG_ATB7)
        .unwrap();
    cont.chunks.insert(
        at,
        Chunk {
            tag: *b"ATEX",
            elem: ElemType::U8,
            data: vec![0; 32],
        },
    );
    let e = CloudAsset::from_bytes(&to_bytes(&cont).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("both raw"), "{e}");
}
