//! LOD bands (format 1.1, SPEC.md §8.6): round trips, the frozen 1.1 fixture, the
//! validation rules, and what a reader that does not know bands sees.

mod common;

use std::collections::BTreeMap;

use billow_format::*;
use common::*;

const BANDS_FIXTURE: &str = "v1_1_volume_bands.billow";

fn bands_fixture_path() -> std::path::PathBuf {
    fixture_path().with_file_name(BANDS_FIXTURE)
}

fn prism(lo: [f32; 3], hi: [f32; 3], uvw_hi: [f32; 3]) -> Prism {
    let c = |t: [f32; 3]| [0, 1, 2].map(|a| if t[a] > 0.5 { hi[a] } else { lo[a] });
    let u = |t: [f32; 3]| [0, 1, 2].map(|a| t[a] * uvw_hi[a]);
    let t = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 1.0],
        [1.0, 1.0, 0.0],
    ];
    Prism {
        pos: t.map(c),
        uvw: t.map(u),
    }
}

/// A 4×2×2 base texture (2 levels, with normals) and one band from level 1: 2×1×1, 2
/// levels, one prism.
fn banded() -> VolumeAsset {
    let mut params = BTreeMap::new();
    params.insert("emptyspace".to_string(), "fixture".to_string());
    let header = Header {
        kind: AssetKind::Volume,
        tool: "billow 0.1.0".into(),
        source: None,
        bounds: Bounds {
            min: [0.0; 3],
            max: [2.0, 1.0, 1.0],
        },
        colour_space: ColourSpace::SrgbPremultiplied,
        seed: None,
        params,
        volume: Some(VolumeHeader {
            dims: [4, 2, 2],
            mip_count: 2,
            texel: TexelFormat::Rgba8Unorm,
            normals: Some(NormalEncoding::Rgba8Snorm),
            moments: None,
        }),
    };
    let ramp = |n: usize, k: u8| {
        (0..n as u8)
            .flat_map(|i| [i, k, 0, 10 + i])
            .collect::<Vec<_>>()
    };
    VolumeAsset {
        header,
        levels: vec![ramp(16, 1), ramp(2, 2)],
        normals: Some(vec![vec![0; 64], vec![0; 8]]),
        cells: vec![prism([0.0; 3], [2.0, 1.0, 1.0], [0.5, 1.0, 1.0])],
        bands: vec![LodBand {
            first_level: 1,
            dims: [2, 1, 1],
            levels: vec![ramp(2, 3), ramp(1, 4)],
            normals: Some(vec![vec![0, 127, 0, 0, 0, 0, 127, 0], vec![0, 0, 0, 0]]),
            cells: vec![prism([0.0; 3], [2.0, 1.0, 1.0], [1.0; 3])],
        }],
    }
}

#[test]
fn banded_assets_round_trip_as_format_1_1() {
    let a = banded();
    let bytes = a.to_bytes().unwrap();
    assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 1, "minor 1");
    let back = VolumeAsset::from_bytes(&bytes).unwrap();
    assert_eq!(back, a);
    assert_eq!(back.max_lod(), 2);
    assert_eq!(back.to_bytes().unwrap(), bytes);
    // Written straight to a file: the same bytes.
    let dir = tempfile::tempdir().unwrap();
    a.write(&dir.path().join("a.billow")).unwrap();
    assert_eq!(std::fs::read(dir.path().join("a.billow")).unwrap(), bytes);
    // The same asset without bands is a 1.0 file.
    let plain = VolumeAsset {
        bands: Vec::new(),
        ..a.clone()
    };
    let b = plain.to_bytes().unwrap();
    assert_eq!(u16::from_le_bytes([b[10], b[11]]), 0, "minor 0");
    assert_eq!(plain.max_lod(), 1);
    // Texel bytes count every band.
    assert_eq!(a.texel_bytes(), plain.texel_bytes() + 2 * (8 + 4));
}

#[test]
#[ignore = "writes the frozen 1.1 fixture; run by hand only for a new format version"]
fn generate_v1_1_fixture() {
    banded().write(&bands_fixture_path()).unwrap();
}

/// FROZEN. Decodes the 1.1 fixture; never regenerate the file to make this pass.
#[test]
fn decodes_frozen_v1_1_fixture() {
    let bytes =
        std::fs::read(bands_fixture_path()).expect("fixtures/format/v1_1_volume_bands.billow");
    assert_eq!(bytes.len(), 1232);
    assert_eq!(crc(&bytes), 0x4506_ef1d, "fixture file changed on disk");
    assert_eq!(&bytes[8..12], &[1, 0, 1, 0], "version 1.1");
    let a = VolumeAsset::from_bytes(&bytes).unwrap();
    assert_eq!(a.levels[1], vec![0, 2, 0, 10, 1, 2, 0, 11]);
    assert_eq!(a.bands.len(), 1);
    let b = &a.bands[0];
    assert_eq!((b.first_level, b.dims, b.mip_count()), (1, [2, 1, 1], 2));
    assert_eq!(b.levels[0], vec![0, 3, 0, 10, 1, 3, 0, 11]);
    assert_eq!(b.levels[1], vec![0, 4, 0, 10]);
    assert_eq!(
        b.normals.as_ref().unwrap()[0],
        vec![0, 127, 0, 0, 0, 0, 127, 0]
    );
    assert_eq!(b.cells.len(), 1);
    assert_eq!(b.cells[0].pos[4], [2.0, 1.0, 1.0]);
    assert_eq!(b.cells[0].uvw[4], [1.0, 1.0, 1.0]);
    assert_eq!(a.max_lod(), 2);
}

/// What a reader that does not know bands (1.0) does: skip the band chunks, see the base.
#[test]
fn a_reader_without_bands_sees_the_base_texture() {
    let bytes = banded().to_bytes().unwrap();
    let c = from_bytes(&bytes).unwrap();
    let tags: Vec<String> = c.chunks.iter().map(|ch| tag_str(&ch.tag)).collect();
    assert_eq!(
        tags,
        ["VLEV", "VLEV", "VNRM", "VNRM", "CELL", "VBND", "BLEV", "BLEV", "BNRM", "BNRM", "BCEL"]
    );
    let base = Container {
        header: c.header.clone(),
        chunks: c
            .chunks
            .iter()
            .filter(|ch| [TAG_VLEV, TAG_VNRM, TAG_CELL].contains(&ch.tag))
            .cloned()
            .collect(),
    };
    let a = VolumeAsset::from_container(base).unwrap();
    assert!(a.bands.is_empty());
    assert_eq!(a.levels, banded().levels);
}

fn rejected(a: &VolumeAsset, what: &str) {
    let e = a.validate().expect_err(what).to_string();
    assert!(e.contains("band"), "{what}: {e}");
    assert!(
        a.to_bytes().is_err(),
        "{what}: the writer must refuse it too"
    );
}

#[test]
fn band_rules_are_enforced() {
    let mut a = banded();
    a.bands[0].first_level = 0;
    rejected(&a, "first level not above the base's");
    let mut a = banded();
    a.bands[0].first_level = 2;
    rejected(&a, "the base (2 levels) cannot reach level 2");
    let mut a = banded();
    a.bands[0].levels[1] = vec![0; 8];
    rejected(&a, "level 1 of a 2×1×1 band is 1 texel");
    let mut a = banded();
    a.bands[0].levels.push(vec![0; 4]);
    a.bands[0].normals.as_mut().unwrap().push(vec![0; 4]);
    rejected(&a, "more levels than 2×1×1 has");
    let mut a = banded();
    a.bands[0].normals = None;
    rejected(&a, "normals missing in a band of an asset with normals");
    let mut a = banded();
    a.bands[0].cells[0].uvw[2][1] = f32::NAN;
    rejected(&a, "non-finite band cell");
    let mut a = banded();
    let second = LodBand {
        first_level: 1,
        ..a.bands[0].clone()
    };
    a.bands.push(second);
    rejected(&a, "first levels must increase");
}

/// Rebuilds `banded()`'s file with its chunks transformed, with the spec-level writer.
fn rebuilt(f: impl Fn(Vec<(String, u32, Vec<u8>)>) -> Vec<(String, u32, Vec<u8>)>) -> Vec<u8> {
    let c = from_bytes(&banded().to_bytes().unwrap()).unwrap();
    let chunks: Vec<(String, u32, Vec<u8>)> = c
        .chunks
        .iter()
        .map(|ch| (tag_str(&ch.tag), ch.elem.code(), ch.data.clone()))
        .collect();
    let mut body = vec![spec_chunk(
        b"HEAD",
        0,
        c.header.to_ron().unwrap().as_bytes(),
    )];
    for (tag, elem, data) in f(chunks) {
        let t: [u8; 4] = tag.as_bytes().try_into().unwrap();
        body.push(spec_chunk(&t, elem, &data));
    }
    body.push(spec_chunk(b"END ", 0, &[]));
    spec_file(1, 1, 1, &body)
}

#[test]
fn inconsistent_band_chunks_are_refused() {
    let drop = |tag: &'static str| {
        move |v: Vec<(String, u32, Vec<u8>)>| {
            let mut seen = false;
            v.into_iter()
                .filter(|c| {
                    let hit = c.0 == tag && !seen;
                    seen |= hit;
                    !hit
                })
                .collect()
        }
    };
    for (tag, why) in [
        ("VBND", "VBND"),
        ("BLEV", "BLEV"),
        ("BNRM", "BNRM"),
        ("BCEL", "BCEL"),
    ] {
        let e = VolumeAsset::from_bytes(&rebuilt(drop(tag))).expect_err(tag);
        assert!(e.to_string().contains(why), "{tag}: {e}");
    }
    // A reserved field set in the band table.
    let bytes = rebuilt(|mut v| {
        let t = v.iter_mut().find(|c| c.0 == "VBND").unwrap();
        t.2[28] = 1;
        v
    });
    let e = VolumeAsset::from_bytes(&bytes).unwrap_err().to_string();
    assert!(e.contains("reserved"), "{e}");
    // Wrong element type.
    let bytes = rebuilt(|mut v| {
        v.iter_mut().find(|c| c.0 == "BCEL").unwrap().1 = 3;
        v
    });
    assert!(VolumeAsset::from_bytes(&bytes).is_err());
    // The untouched rebuild reads back.
    assert_eq!(VolumeAsset::from_bytes(&rebuilt(|v| v)).unwrap(), banded());
}
