//! The frozen v1 fixture. `decodes_frozen_v1_fixture` must stay forever and
//! must never regenerate the file: a v1 reader has to decode it bit for bit.
//!
//! To (re)generate — only ever for a NEW fixture file of a new version, never
//! to "fix" this one:
//! `cargo test -p billow-format --test fixture -- --ignored generate_v1_fixture`

mod common;

use std::collections::BTreeMap;

use billow_format::*;
use common::*;

/// The content written by the generator. The decode test below does NOT use
/// this: it spells out every value on its own.
fn generator_asset() -> VolumeAsset {
    let mut params = BTreeMap::new();
    params.insert("res".to_string(), "3x2x1".to_string());
    params.insert("normals".to_string(), "on".to_string());
    let header = Header {
        kind: AssetKind::Volume,
        tool: "billow 0.1.0".into(),
        source: Some(SourceInfo {
            file_name: "tiny.obj".into(),
            sha256: "eaa82642f6a440f3891be5defe9d61cfd88a3e326eeee54fede4a77d4944febd".into(),
            bytes: 45,
        }),
        bounds: Bounds {
            min: [0.0, 0.0, 0.0],
            max: [1.5, 1.0, 0.5],
        },
        colour_space: ColourSpace::SrgbPremultiplied,
        seed: Some(42),
        params,
        volume: Some(VolumeHeader {
            dims: [3, 2, 1],
            mip_count: 2,
            texel: TexelFormat::Rgba8Unorm,
            normals: Some(NormalEncoding::Rgba8Snorm),
            moments: None,
        }),
    };
    let level0 = vec![
        255, 0, 0, 255, 0, 128, 0, 128, 0, 0, 64, 64, //
        32, 32, 32, 255, 0, 0, 0, 0, 200, 100, 50, 200,
    ];
    let level1 = vec![60, 40, 20, 150];
    let n = |v: [i8; 4]| v.map(|c| c as u8);
    let normals0 = [
        n([0, 0, 127, 0]),
        n([127, 0, 0, 0]),
        n([0, -127, 0, 0]),
        n([64, 64, 0, 0]),
        n([0, 0, 0, 0]),
        n([-90, 0, 90, 0]),
    ]
    .concat();
    let normals1 = n([10, 20, 30, 0]).to_vec();
    let cells = vec![
        Prism {
            pos: [
                [0.0, 0.0, 0.0],
                [1.5, 0.0, 0.0],
                [1.5, 1.0, 0.0],
                [0.0, 0.0, 0.5],
                [1.5, 0.0, 0.5],
                [1.5, 1.0, 0.5],
            ],
            uvw: [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
        },
        Prism {
            pos: [
                [0.0, 0.0, 0.0],
                [1.5, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 0.5],
                [1.5, 1.0, 0.5],
                [0.0, 1.0, 0.5],
            ],
            uvw: [
                [0.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
                [0.0, 1.0, 1.0],
            ],
        },
    ];
    VolumeAsset {
        header,
        levels: vec![level0, level1],
        normals: Some(vec![normals0, normals1]),
        bands: Vec::new(),
        cells,
    }
}

#[test]
#[ignore = "writes the frozen fixture; run by hand only for a new format version"]
fn generate_v1_fixture() {
    let path = fixture_path();
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    generator_asset().write(&path).unwrap();
    eprintln!("wrote {}", path.display());
}

/// FROZEN. Decodes the v1 fixture and checks every value. Never regenerate
/// the file to make this pass: if it fails, the reader broke compatibility.
#[test]
fn decodes_frozen_v1_fixture() {
    let bytes = fixture_bytes();
    assert_eq!(bytes.len(), 1112);
    assert_eq!(crc(&bytes), 0x4d65_6ae8, "fixture file changed on disk");

    let asset = VolumeAsset::from_bytes(&bytes).expect("v1 fixture decodes");
    let h = &asset.header;
    assert_eq!(h.kind, AssetKind::Volume);
    assert_eq!(h.tool, "billow 0.1.0");
    let src = h.source.as_ref().expect("source");
    assert_eq!(src.file_name, "tiny.obj");
    assert_eq!(
        src.sha256,
        "eaa82642f6a440f3891be5defe9d61cfd88a3e326eeee54fede4a77d4944febd"
    );
    assert_eq!(src.bytes, 45);
    assert_eq!(h.bounds.min, [0.0, 0.0, 0.0]);
    assert_eq!(h.bounds.max, [1.5, 1.0, 0.5]);
    assert_eq!(h.colour_space, ColourSpace::SrgbPremultiplied);
    assert_eq!(h.seed, Some(42));
    let params: Vec<(&str, &str)> = h
        .params
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    assert_eq!(params, [("normals", "on"), ("res", "3x2x1")]);
    let v = h.volume.expect("volume header");
    assert_eq!(v.dims, [3, 2, 1]);
    assert_eq!(v.mip_count, 2);
    assert_eq!(v.texel, TexelFormat::Rgba8Unorm);
    assert_eq!(v.normals, Some(NormalEncoding::Rgba8Snorm));
    assert_eq!(asset.level_dims(0), [3, 2, 1]);
    assert_eq!(asset.level_dims(1), [1, 1, 1]);

    assert_eq!(asset.levels.len(), 2);
    #[rustfmt::skip]
    assert_eq!(asset.levels[0], [
        255, 0, 0, 255,   0, 128, 0, 128,   0, 0, 64, 64,       // y = 0, x = 0..3
        32, 32, 32, 255,  0, 0, 0, 0,       200, 100, 50, 200,  // y = 1
    ]);
    assert_eq!(asset.levels[1], [60, 40, 20, 150]);

    let normals = asset.normals.as_ref().expect("normals");
    assert_eq!(normals.len(), 2);
    let as_i8 = |l: &Vec<u8>| l.iter().map(|&b| b as i8).collect::<Vec<i8>>();
    #[rustfmt::skip]
    assert_eq!(as_i8(&normals[0]), [
        0, 0, 127, 0,   127, 0, 0, 0,   0, -127, 0, 0,
        64, 64, 0, 0,   0, 0, 0, 0,     -90, 0, 90, 0,
    ]);
    assert_eq!(as_i8(&normals[1]), [10, 20, 30, 0]);

    assert_eq!(asset.cells.len(), 2);
    let (z, t, w) = (0.0, 0.5, 1.5);
    assert_eq!(
        asset.cells[0].pos,
        [
            [z, z, z],
            [w, z, z],
            [w, 1.0, z],
            [z, z, t],
            [w, z, t],
            [w, 1.0, t]
        ]
    );
    assert_eq!(
        asset.cells[0].uvw,
        [
            [z, z, z],
            [1.0, z, z],
            [1.0, 1.0, z],
            [z, z, 1.0],
            [1.0, z, 1.0],
            [1.0, 1.0, 1.0]
        ]
    );
    assert_eq!(
        asset.cells[1].pos,
        [
            [z, z, z],
            [w, 1.0, z],
            [z, 1.0, z],
            [z, z, t],
            [w, 1.0, t],
            [z, 1.0, t]
        ]
    );
    assert_eq!(
        asset.cells[1].uvw,
        [
            [z, z, z],
            [1.0, 1.0, z],
            [z, 1.0, z],
            [z, z, 1.0],
            [1.0, 1.0, 1.0],
            [z, 1.0, 1.0]
        ]
    );

    // Re-encoding the decoded asset reproduces the file byte for byte, both
    // through the typed fast path and through the container.
    assert_eq!(asset.to_bytes().unwrap(), bytes);
    assert_eq!(to_bytes(&asset.to_container().unwrap()).unwrap(), bytes);
    assert_eq!(
        VolumeAsset::from_container(read_file(&fixture_path()).unwrap()).unwrap(),
        asset
    );
}

/// FROZEN. The chunk layout of the fixture, as `billow info` shows it.
#[test]
fn inspects_frozen_v1_fixture() {
    let r = inspect_bytes(&fixture_bytes()).unwrap();
    assert_eq!(
        (r.major, r.minor, r.kind, r.file_len),
        (1, 0, AssetKind::Volume, 1112)
    );
    assert!(r.is_ok());
    let layout: Vec<(&[u8; 4], ElemType, u64, u64)> = r
        .chunks
        .iter()
        .map(|c| (&c.tag, c.elem, c.offset, c.len))
        .collect();
    assert_eq!(
        layout,
        [
            (b"HEAD", ElemType::Opaque, 32, 553),
            (b"VLEV", ElemType::U8, 616, 24),
            (b"VLEV", ElemType::U8, 664, 4),
            (b"VNRM", ElemType::I8, 696, 24),
            (b"VNRM", ElemType::I8, 744, 4),
            (b"CELL", ElemType::F32, 776, 288),
            (b"END ", ElemType::Opaque, 1088, 0),
        ]
    );
    assert!(r.header_ron.starts_with("(\n    kind: Volume,\n"));
    let text = r.to_string();
    assert!(text.contains("'CELL'") && text.contains("ok"), "{text}");
}

/// The independent reference writer in tests/common (straight from SPEC.md)
/// reproduces the fixture from its chunks, so SPEC.md and the code agree.
#[test]
fn spec_reference_writer_reproduces_fixture() {
    let bytes = fixture_bytes();
    let chunks = split_chunks(&bytes);
    assert_eq!(join_chunks(1, 0, 1, &chunks), bytes);
}

/// The generator still produces exactly the frozen bytes (so the writer is
/// stable). If this fails but the decode test passes, the writer changed
/// its output; that is allowed only with care, since old files stay valid.
#[test]
fn generator_matches_frozen_fixture() {
    assert_eq!(generator_asset().to_bytes().unwrap(), fixture_bytes());
}

/// The hex dump lines in SPEC.md §10 match the fixture, and the CRC check
/// value quoted in §1 holds.
#[test]
fn spec_hex_dump_matches_fixture() {
    assert_eq!(crc(b"123456789"), 0xcbf4_3926);
    let spec = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/SPEC.md")).unwrap();
    let f = fixture_bytes();
    let mut checked = 0;
    for line in spec.lines() {
        let Some((addr, rest)) = line.split_once(": ") else {
            continue;
        };
        if addr.len() != 8 || !addr.bytes().all(|b| b.is_ascii_hexdigit()) {
            continue;
        }
        let off = usize::from_str_radix(addr, 16).unwrap();
        let hex: String = rest.get(..39).unwrap_or(rest).split_whitespace().collect();
        for (i, pair) in hex.as_bytes().chunks(2).enumerate() {
            let b = u8::from_str_radix(std::str::from_utf8(pair).unwrap(), 16).unwrap();
            assert_eq!(f[off + i], b, "SPEC.md dump byte at {:#x}", off + i);
            checked += 1;
        }
    }
    assert!(checked > 200, "only {checked} bytes of hex dump found");
}
