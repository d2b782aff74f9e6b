//! KTX 2.0 export: read back with the `ktx2` crate and check every field.

use std::path::Path;

mod common;

use billow::export::{ktx2_bytes, write_ktx2, ExportError};
use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, Prism, VolumeAsset};
use ktx2::dfd::{Basic, ChannelTypeQualifiers, DataFormatFlags};

/// A valid asset with distinct, deterministic bytes per level.
fn asset(dims: [u32; 3], mip_count: u32, cs: ColourSpace) -> VolumeAsset {
    let mut seed = 0x9E37_79B9u32;
    let levels = (0..mip_count)
        .map(|i| {
            let d = mip_dims(dims, i);
            let n = (d[0] * d[1] * d[2]) as usize;
            let mut v = Vec::with_capacity(4 * n);
            for _ in 0..n {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let a = (seed >> 24) as u8;
                v.extend_from_slice(&[a / 2, a / 3, a, a]); // premultiplied-valid
            }
            v
        })
        .collect();
    VolumeAsset {
        header: Header::volume("test", cs, dims, mip_count, false),
        levels,
        normals: None,
        bands: Vec::new(),
        cells: vec![Prism {
            pos: [[0.0; 3]; 6],
            uvw: [[0.0; 3]; 6],
        }],
    }
}

fn check(a: &VolumeAsset, path: &Path) {
    write_ktx2(a, None, path).unwrap();
    let bytes = std::fs::read(path).unwrap();
    // For checking with outside tools: BILLOW_KTX2_DUMP=DIR keeps a copy of each file.
    if let Some(dump) = std::env::var_os("BILLOW_KTX2_DUMP") {
        std::fs::copy(path, Path::new(&dump).join(path.file_name().unwrap())).unwrap();
    }
    assert_eq!(
        bytes,
        ktx2_bytes(a, None, path).unwrap(),
        "write_ktx2 writes ktx2_bytes"
    );
    let r = ktx2::Reader::new(&bytes[..]).expect("ktx2 crate parses the file");
    let h = r.header();
    let v = a.header.volume.unwrap();
    let srgb = a.header.colour_space == ColourSpace::SrgbPremultiplied;
    let format = if srgb {
        ktx2::Format::R8G8B8A8_SRGB
    } else {
        ktx2::Format::R8G8B8A8_UNORM
    };
    assert_eq!(h.format, Some(format));
    assert_eq!(u32::from(bytes[12]), if srgb { 43 } else { 37 }, "vkFormat");
    assert_eq!(h.type_size, 1);
    assert_eq!([h.pixel_width, h.pixel_height, h.pixel_depth], v.dims);
    assert_eq!(h.layer_count, 0);
    assert_eq!(h.face_count, 1);
    assert_eq!(h.level_count, v.mip_count);
    assert_eq!(h.supercompression_scheme, None);
    assert_eq!((h.index.sgd_byte_offset, h.index.sgd_byte_length), (0, 0));

    // DFD: exactly what the crate generates for the format, plus the premultiplied flag.
    assert_eq!(r.is_alpha_premultiplied(), Some(true));
    let dfd = r.basic_dfd().unwrap();
    assert!(dfd.flags.contains(DataFormatFlags::ALPHA_PREMULTIPLIED));
    assert_eq!(dfd.color_model, Some(ktx2::ColorModel::RGBSDA));
    assert_eq!(dfd.color_primaries, Some(ktx2::ColorPrimaries::BT709));
    let tf = if srgb {
        ktx2::TransferFunction::SRGB
    } else {
        ktx2::TransferFunction::Linear
    };
    assert_eq!(dfd.transfer_function, Some(tf));
    let s = &dfd.sample_information;
    assert_eq!(s.len(), 4);
    for (k, (sample, channel)) in s.iter().zip([0u8, 1, 2, 15]).enumerate() {
        assert_eq!(sample.bit_offset, 8 * k as u16);
        assert_eq!(sample.bit_length.get(), 8);
        assert_eq!(sample.channel_type, channel);
        assert_eq!((sample.lower, sample.upper), (0, 255));
        let linear = sample
            .channel_type_qualifiers
            .contains(ChannelTypeQualifiers::LINEAR);
        assert_eq!(
            linear,
            srgb && channel == 15,
            "alpha sample LINEAR qualifier iff sRGB"
        );
    }
    let (reference, type_size) = Basic::from_format_with(format, true, None, None, None).unwrap();
    assert_eq!(type_size, 1);
    let (o, l) = (
        h.index.dfd_byte_offset as usize,
        h.index.dfd_byte_length as usize,
    );
    assert_eq!(
        u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize,
        l
    );
    // Block header: vendor 0 / type 0, version 2, block size 88 (the crate's `to_vec` omits it).
    assert_eq!(&bytes[o + 4..o + 12], &[0, 0, 0, 0, 2, 0, 88, 0]);
    assert_eq!(
        &bytes[o + 12..o + l],
        &reference.to_vec()[..],
        "DFD equals the crate's for {format:?}"
    );

    // Key/value data.
    let kv: Vec<(String, Vec<u8>)> = r
        .key_value_data()
        .map(|(k, v)| (k.to_string(), v.to_vec()))
        .collect();
    assert_eq!(kv[0], ("KTXorientation".to_string(), b"ruo\0".to_vec()));
    assert_eq!(kv[1].0, "KTXwriter");
    assert!(r.writer().unwrap().starts_with("billow "));
    assert_eq!(h.index.kvd_byte_length % 4, 0);

    // Levels: sizes, contents, file order smallest first, 4-byte alignment.
    let levels: Vec<_> = r.levels().collect();
    assert_eq!(levels.len(), v.mip_count as usize);
    for (i, l) in levels.iter().enumerate() {
        let d = mip_dims(v.dims, i as u32);
        assert_eq!(
            l.data.len(),
            (d[0] * d[1] * d[2] * 4) as usize,
            "level {i} size"
        );
        assert_eq!(l.uncompressed_byte_length, l.data.len() as u64);
        assert_eq!(l.data, &a.levels[i][..], "level {i} bytes");
    }
    let idx = |i: usize| {
        let o = 80 + 24 * i;
        let f = |k: usize| u64::from_le_bytes(bytes[o + 8 * k..o + 8 * k + 8].try_into().unwrap());
        (f(0), f(1))
    };
    let data_start = u64::from(h.index.kvd_byte_offset + h.index.kvd_byte_length);
    let last = v.mip_count as usize - 1;
    assert_eq!(
        idx(last).0,
        data_start.next_multiple_of(4),
        "smallest level comes first"
    );
    for i in 0..last {
        assert_eq!(idx(i).0 % 4, 0);
        assert_eq!(
            idx(i).0,
            idx(i + 1).0 + idx(i + 1).1,
            "level {i} follows level {}",
            i + 1
        );
    }
    assert_eq!(
        idx(0).0 + idx(0).1,
        bytes.len() as u64,
        "level 0 ends the file"
    );
}

#[test]
fn srgb_full_chain_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [5, 3, 9];
    check(
        &asset(dims, full_mip_count(dims), ColourSpace::SrgbPremultiplied),
        &dir.path().join("a.ktx2"),
    );
}

#[test]
fn linear_partial_chain_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    check(
        &asset([16, 8, 4], 2, ColourSpace::LinearPremultiplied),
        &dir.path().join("b.ktx2"),
    );
    check(
        &asset([1, 1, 1], 1, ColourSpace::SrgbPremultiplied),
        &dir.path().join("c.ktx2"),
    );
}

#[test]
fn invalid_asset_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.ktx2");
    let mut a = asset([4, 4, 4], 3, ColourSpace::SrgbPremultiplied);
    a.levels[1].pop();
    let e = write_ktx2(&a, None, &path).unwrap_err();
    assert!(matches!(e, ExportError::InvalidAsset { .. }));
    assert!(e.to_string().contains("bad.ktx2"), "{e}");
    assert!(!path.exists());
}

#[test]
fn unwritable_destination_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("missing-dir").join("x.ktx2");
    let e = write_ktx2(
        &asset([2, 2, 2], 1, ColourSpace::SrgbPremultiplied),
        None,
        &path,
    )
    .unwrap_err();
    assert!(e.to_string().contains("x.ktx2"), "{e}");
}

/// Validates with Khronos' `ktx` tool (KTX-Software) when it is installed; skips otherwise.
#[test]
fn khronos_ktx_validate_if_installed() {
    let available = std::process::Command::new("ktx")
        .args(["validate", "--help"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !available {
        common::skip_tool(
            "khronos_ktx_validate_if_installed",
            "ktx",
            "Khronos `ktx` tool (KTX-Software) not installed; `ktx validate` not run",
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (name, cs) in [
        ("s.ktx2", ColourSpace::SrgbPremultiplied),
        ("l.ktx2", ColourSpace::LinearPremultiplied),
    ] {
        let path = dir.path().join(name);
        write_ktx2(&asset([8, 4, 6], 4, cs), None, &path).unwrap();
        let out = std::process::Command::new("ktx")
            .arg("validate")
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "ktx validate {name}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// A compressed volume's KTX2 (`voxelize --compress bc`) carries its BC7
/// blocks: `BC7_UNORM_BLOCK` (the writer's linear colour) or `BC7_SRGB_BLOCK` (an older
/// sRGB file), a BC7 DFD, each level every block of each z
/// slice (the omitted empty blocks as a block that decodes to zero).
#[test]
fn compressed_volumes_export_their_bc7_blocks() {
    let dir = tempfile::tempdir().unwrap();
    for (cs, vk, fmt) in [
        (
            ColourSpace::SrgbPremultiplied,
            146u32,
            ktx2::Format::BC7_SRGB_BLOCK,
        ),
        (
            ColourSpace::LinearPremultiplied,
            145,
            ktx2::Format::BC7_UNORM_BLOCK,
        ),
    ] {
        let mut a = asset([10, 6, 3], 4, cs);
        // An empty corner: its block is omitted in the asset and a zero block in the KTX2.
        for y in 0..4 {
            for x in 0..4 {
                let i = 4 * (x + 10 * y);
                a.levels[0][i..i + 4].fill(0);
            }
        }
        let blocks = billow::compress::compress_volume(&mut a);
        // The writer compresses linear colour; an sRGB-encoded compressed volume is a file
        // written before 2026-12-06 (its blocks hold sRGB bytes), labelled as it says.
        assert_eq!(a.header.colour_space, ColourSpace::LinearPremultiplied);
        a.header.colour_space = cs;
        let path = dir.path().join(format!("bc{vk}.ktx2"));
        let bytes = ktx2_bytes(&a, Some(&blocks), &path).unwrap();
        let r = ktx2::Reader::new(&bytes[..]).expect("ktx2 crate parses the file");
        let h = r.header();
        assert_eq!(h.format, Some(fmt));
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), vk);
        assert_eq!([h.pixel_width, h.pixel_height, h.pixel_depth], [10, 6, 3]);
        assert_eq!(h.level_count, 4);
        assert_eq!(h.supercompression_scheme, None);
        assert_eq!(r.is_alpha_premultiplied(), Some(true));
        let dfd = r.basic_dfd().unwrap();
        assert_eq!(dfd.color_model, Some(ktx2::ColorModel::BC7));
        assert_eq!(dfd.texel_block_dimensions.map(|d| d.get()), [4, 4, 1, 1]);
        for (i, l) in r.levels().enumerate() {
            let d = mip_dims([10, 6, 3], i as u32);
            let dense =
                billow_format::expand_blocks(&blocks.colour[i], d, billow_format::ZERO_BLOCK);
            assert_eq!(l.data, &dense[..], "level {i}: the asset's blocks");
            assert_eq!(
                l.data.len() as u64,
                billow_format::bc7_len(d[0], d[1], d[2])
            );
            // And they decode to the asset's texels.
            let packed = billow_format::pack_blocks(l.data, &vec![true; l.data.len() / 16]);
            assert_eq!(billow_format::decode_bc7(&packed, d, 0), a.levels[i]);
        }
        assert_eq!(
            &bytes[..],
            &ktx2_bytes(&a, Some(&blocks), &path).unwrap()[..]
        );
        // The first level-0 block (the empty corner) is the zero block.
        let l0 = r.levels().next().unwrap();
        assert_eq!(&l0.data[..16], &billow_format::ZERO_BLOCK);
    }
}

/// `--ktx2-zstd`: Zstandard supercompression (`supercompressionScheme` 2). The `ktx2` crate
/// reads the file; each level inflates to exactly the level of the plain export, raw and
/// BC7; the rest of the file (header but the scheme, DFD, KVD) is the plain file's; the
/// levels follow each other without padding, and the bytes are the same at any thread
/// count.
#[test]
fn zstd_supercompressed_levels_inflate_to_the_plain_export() {
    use billow::export::{ktx2_bytes_with, Supercompression};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("z.ktx2");
    let mut bc = asset([12, 9, 5], 4, ColourSpace::SrgbPremultiplied);
    // An empty region, so that the BC7 levels have omitted (zero) blocks.
    for z in 0..5 {
        for y in 0..8 {
            for x in 0..8 {
                let i = 4 * (x + 12 * (y + 9 * z));
                bc.levels[0][i..i + 4].fill(0);
            }
        }
    }
    let blocks = billow::compress::compress_volume(&mut bc);
    let raw = asset([7, 5, 3], 3, ColourSpace::LinearPremultiplied);
    for (a, b) in [(&raw, None), (&bc, Some(&blocks))] {
        let plain = ktx2_bytes(a, b, &path).unwrap();
        assert_eq!(
            ktx2_bytes_with(a, b, Supercompression::None, &path).unwrap(),
            plain
        );
        let z = ktx2_bytes_with(a, b, Supercompression::Zstd(19), &path).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| ktx2_bytes_with(a, b, Supercompression::Zstd(19), &path).unwrap());
        assert_eq!(one, z, "same bytes on one thread");
        let p = ktx2::Reader::new(&plain[..]).unwrap();
        let r = ktx2::Reader::new(&z[..]).expect("ktx2 crate parses the zstd file");
        assert_eq!(
            r.header().supercompression_scheme,
            Some(ktx2::SupercompressionScheme::Zstandard)
        );
        assert_eq!(u32::from_le_bytes(z[44..48].try_into().unwrap()), 2);
        // Header (but the scheme), index, DFD and KVD as in the plain file.
        assert_eq!(z[..44], plain[..44]);
        assert_eq!(z[48..80], plain[48..80]);
        let n = a.levels.len();
        let meta = 80 + 24 * n;
        let dfd_kvd =
            (p.header().index.kvd_byte_offset + p.header().index.kvd_byte_length) as usize;
        assert_eq!(z[meta..dfd_kvd], plain[meta..dfd_kvd]);
        let (pl, zl): (Vec<_>, Vec<_>) = (p.levels().collect(), r.levels().collect());
        assert_eq!(zl.len(), n);
        let mut packed = 0;
        for (i, (pl, zl)) in pl.iter().zip(&zl).enumerate() {
            assert_eq!(
                zl.uncompressed_byte_length,
                pl.data.len() as u64,
                "level {i}"
            );
            let inflated = zstd::decode_all(zl.data).expect("a Zstandard frame");
            assert_eq!(inflated, pl.data, "level {i} inflates to the plain level");
            packed += zl.data.len();
        }
        // No mipPadding: the smallest level starts right after the KVD, level 0 ends the
        // file, and the frames are all there is.
        assert_eq!(z.len(), dfd_kvd + packed);
        let off = |i: usize| u64::from_le_bytes(z[80 + 24 * i..88 + 24 * i].try_into().unwrap());
        assert_eq!(off(n - 1), dfd_kvd as u64);
        if b.is_some() {
            // Its empty blocks shrink (the raw test texels are noise: no gain there).
            assert!(z.len() < plain.len(), "{} !< {}", z.len(), plain.len());
        }
    }
    // A level out of range is refused, naming the file.
    let e = ktx2_bytes_with(&raw, None, Supercompression::Zstd(23), &path).unwrap_err();
    assert!(matches!(e, ExportError::Encode { .. }), "{e}");
    assert!(e.to_string().contains("z.ktx2"), "{e}");
}
