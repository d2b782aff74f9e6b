//! Normal moments (format 1.4, SPEC.md §8.4a): the frozen 1.4 fixture, round trips of
//! moments volumes (raw, with LOD bands), the header rules (mean normals or moments, not
//! both) and the chunk rules (no mean-normal chunk in a moments volume, nor the reverse).
//! The BC7 round trip (`VMB7`/`BMB7`) is in tests/blocks.rs, next to its encoder.
//!
//! To generate the fixture — only ever for a NEW fixture file, never to "fix" one:
//! `cargo test -p billow-format --test moments -- --ignored generate_v1_4`

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow_format::*;
use common::*;

const MOMENTS_FIXTURE: &str = "v1_4_volume_moments.billow";
const MOMENTS_FIXTURE_LEN: usize = 816;
const MOMENTS_FIXTURE_CRC: u32 = 0x6473_7942;

fn moments_fixture_path() -> PathBuf {
    fixture_path().with_file_name(MOMENTS_FIXTURE)
}

fn minor(bytes: &[u8]) -> u16 {
    u16::from_le_bytes([bytes[10], bytes[11]])
}

fn tags(bytes: &[u8]) -> String {
    let c = from_bytes(bytes).unwrap();
    let mut t = vec!["HEAD".to_string()];
    t.extend(c.chunks.iter().map(|ch| tag_str(&ch.tag)));
    t.push("END ".into());
    t.join(" ")
}

/// The fixture's level 0 moments, 3×2×1 texels (x fastest): a flat patch facing +z; a
/// flat patch with normal (0.6, 0, 0.8) (x = 0.36·127 = 45.72, z = 0.64·127 = 81.28); an
/// empty texel; isotropic normals (1/3 each, 42.33); a flat patch facing +y; a thin
/// sheet seen from both sides, normals +x and −x (mean normal 0, moments x = 1).
const MOMENTS_0: [[u8; 4]; 6] = [
    [0, 0, 127, 0],
    [46, 0, 81, 0],
    [0, 0, 0, 0],
    [42, 42, 42, 0],
    [0, 127, 0, 0],
    [127, 0, 0, 0],
];
/// Level 1 (1×1×1): the mean of level 0's five full texels (equal alpha):
/// x = 215/5 = 43, y = 169/5 = 33.8, z = 250/5 = 50.
const MOMENTS_1: [u8; 4] = [43, 34, 50, 0];

/// The content written by the generator; the decode test spells out the values itself.
fn generator_asset() -> VolumeAsset {
    let mut params = BTreeMap::new();
    params.insert("res".to_string(), "3x2x1".to_string());
    let mut header = Header {
        bounds: Bounds {
            min: [0.0; 3],
            max: [1.5, 1.0, 0.5],
        },
        params,
        ..Header::volume(
            "billow 0.1.0",
            ColourSpace::SrgbPremultiplied,
            [3, 2, 1],
            2,
            false,
        )
    };
    header
        .volume
        .as_mut()
        .unwrap()
        .set_normal_kind(Some(NormalKind::Moments));
    let level0 = [
        [200, 150, 100, 255],
        [120, 160, 60, 255],
        [0, 0, 0, 0],
        [90, 90, 90, 255],
        [30, 140, 40, 255],
        [180, 180, 170, 255],
    ]
    .concat();
    let level1 = vec![110, 128, 86, 213];
    VolumeAsset {
        header,
        levels: vec![level0, level1],
        normals: Some(vec![MOMENTS_0.concat(), MOMENTS_1.to_vec()]),
        cells: vec![Prism {
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
        }],
        bands: Vec::new(),
    }
}

/// The generator's asset with mean normals instead (the same bytes, other meaning).
fn as_mean(mut a: VolumeAsset) -> VolumeAsset {
    let v = a.header.volume.as_mut().unwrap();
    v.set_normal_kind(Some(NormalKind::Mean));
    a
}

/// [`generator_asset`] with one LOD band from level 1 (1×1×1, one level).
fn banded() -> VolumeAsset {
    let mut a = generator_asset();
    a.bands.push(LodBand {
        first_level: 1,
        dims: [1, 1, 1],
        levels: vec![vec![10, 20, 30, 40]],
        normals: Some(vec![vec![0, 64, 63, 0]]),
        cells: a.cells.clone(),
    });
    a
}

#[test]
#[ignore = "writes the frozen 1.4 fixture; only for a new fixture file"]
fn generate_v1_4() {
    generator_asset().write(&moments_fixture_path()).unwrap();
}

/// FROZEN. Decodes the 1.4 fixture; never regenerate the file to make this pass.
#[test]
fn decodes_frozen_v1_4_moments_fixture() {
    let bytes =
        std::fs::read(moments_fixture_path()).expect("fixtures/format/v1_4_volume_moments.billow");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 4, 0, 1, 0, 0, 0],
        "format 1.4, Volume"
    );
    assert_eq!(bytes.len(), MOMENTS_FIXTURE_LEN);
    assert_eq!(
        crc(&bytes),
        MOMENTS_FIXTURE_CRC,
        "fixture file changed on disk"
    );
    assert_eq!(tags(&bytes), "HEAD VLEV VLEV VMOM VMOM CELL END ");
    let a = VolumeAsset::from_bytes(&bytes).unwrap();
    let v = a.header.volume.unwrap();
    assert_eq!((v.dims, v.mip_count), ([3, 2, 1], 2));
    assert_eq!(v.normals, None);
    assert_eq!(v.moments, Some(NormalEncoding::Rgba8Snorm));
    assert_eq!(v.normal_kind(), Some(NormalKind::Moments));
    assert!(a
        .header
        .to_ron()
        .unwrap()
        .contains("moments: Some(Rgba8Snorm)"));
    let n = a.normals.as_ref().expect("moments");
    #[rustfmt::skip]
    assert_eq!(n[0], [
        0, 0, 127, 0,   46, 0, 81, 0,    0, 0, 0, 0,      // y = 0, x = 0..3
        42, 42, 42, 0,  0, 127, 0, 0,    127, 0, 0, 0,    // y = 1
    ]);
    assert_eq!(n[1], [43, 34, 50, 0]);
    // Every texel with surface has x + y + z within rounding of 127, the empty one 0.
    for t in n[0].chunks_exact(4).chain(n[1].chunks_exact(4)) {
        let s: i32 = t[..3].iter().map(|&b| i32::from(b as i8)).sum();
        assert!(s == 0 || (126..=128).contains(&s), "{t:?}");
        assert!(t[..3].iter().all(|&b| (b as i8) >= 0) && t[3] == 0, "{t:?}");
    }
    assert_eq!(a.levels[1], [110, 128, 86, 213]);
    assert_eq!(a.cells.len(), 1);
    assert_eq!(a.cells[0].pos[5], [1.5, 1.0, 0.5]);
    // The file is what the writer writes, through either path.
    assert_eq!(a.to_bytes().unwrap(), bytes);
    assert_eq!(to_bytes(&a.to_container().unwrap()).unwrap(), bytes);
}

/// The generator still produces exactly the frozen bytes.
#[test]
fn generator_matches_frozen_v1_4_fixture() {
    let bytes = std::fs::read(moments_fixture_path()).unwrap();
    assert_eq!(generator_asset().to_bytes().unwrap(), bytes);
    assert_eq!(generator_asset(), VolumeAsset::from_bytes(&bytes).unwrap());
}

/// The spec-level reference writer (tests/common) reproduces the fixture from its chunks.
#[test]
fn spec_reference_writer_reproduces_v1_4_fixture() {
    let bytes = std::fs::read(moments_fixture_path()).unwrap();
    assert_eq!(join_chunks(1, 4, 1, &split_chunks(&bytes)), bytes);
}

/// The same texels as mean normals are a 1.0 file with VNRM chunks and a header without
/// `moments`; as moments a 1.4 file with VMOM chunks. Both read back as written.
#[test]
fn moments_round_trip_and_write_minor_4_only_when_used() {
    let m = generator_asset();
    let bytes = m.to_bytes().unwrap();
    assert_eq!(minor(&bytes), 4);
    assert_eq!(tags(&bytes), "HEAD VLEV VLEV VMOM VMOM CELL END ");
    assert_eq!(VolumeAsset::from_bytes(&bytes).unwrap(), m);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.billow");
    m.write(&p).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), bytes);
    assert_eq!(VolumeAsset::read(&p).unwrap(), m);

    let mean = as_mean(generator_asset());
    let b = mean.to_bytes().unwrap();
    assert_eq!(minor(&b), 0);
    assert_eq!(tags(&b), "HEAD VLEV VLEV VNRM VNRM CELL END ");
    assert!(!mean.header.to_ron().unwrap().contains("moments"));
    assert_eq!(VolumeAsset::from_bytes(&b).unwrap(), mean);

    let mut none = generator_asset();
    none.normals = None;
    none.header.volume.as_mut().unwrap().set_normal_kind(None);
    let b = none.to_bytes().unwrap();
    assert_eq!(
        (minor(&b), tags(&b).as_str()),
        (0, "HEAD VLEV VLEV CELL END ")
    );
}

/// LOD bands of a moments volume store their levels as BMOM (a 1.4 file); a mean-normal
/// volume's as BNRM (1.1).
#[test]
fn banded_moments_round_trip_as_bmom() {
    let a = banded();
    let bytes = a.to_bytes().unwrap();
    assert_eq!(minor(&bytes), 4);
    assert_eq!(
        tags(&bytes),
        "HEAD VLEV VLEV VMOM VMOM CELL VBND BLEV BMOM BCEL END "
    );
    let back = VolumeAsset::from_bytes(&bytes).unwrap();
    assert_eq!(back, a);
    assert_eq!(back.bands[0].normals.as_ref().unwrap()[0], [0, 64, 63, 0]);
    let mean = as_mean(banded());
    let b = mean.to_bytes().unwrap();
    assert_eq!(minor(&b), 1);
    assert!(tags(&b).contains("BLEV BNRM BCEL"));
    // A band without its moments is refused like one without normals.
    let mut bad = banded();
    bad.bands[0].normals = None;
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("band 1") && e.contains("volume.moments"), "{e}");
}

#[test]
fn normal_kind_follows_the_header_fields() {
    let mut h = Header::volume("t", ColourSpace::SrgbPremultiplied, [1, 1, 1], 1, true);
    let v = h.volume.as_mut().unwrap();
    assert_eq!(v.normal_kind(), Some(NormalKind::Mean));
    v.set_normal_kind(Some(NormalKind::Moments));
    assert_eq!(
        (v.normals, v.moments),
        (None, Some(NormalEncoding::Rgba8Snorm))
    );
    assert_eq!(v.normal_kind(), Some(NormalKind::Moments));
    v.set_normal_kind(None);
    assert_eq!((v.normals, v.moments, v.normal_kind()), (None, None, None));
    v.set_normal_kind(Some(NormalKind::Mean));
    assert_eq!(
        (v.normals, v.moments),
        (Some(NormalEncoding::Rgba8Snorm), None)
    );
    // A header without `moments` (every file before 1.4) reads as None.
    let ron = h.to_ron().unwrap();
    assert!(!ron.contains("moments"), "{ron}");
    assert_eq!(Header::from_ron(&ron).unwrap(), h);
}

/// Mean normals and moments both set: refused by the validator, the writer and the reader.
#[test]
fn normals_and_moments_both_set_are_refused() {
    let mut a = generator_asset();
    a.header.volume.as_mut().unwrap().normals = Some(NormalEncoding::Rgba8Snorm);
    let e = a.validate().unwrap_err().to_string();
    assert!(e.contains("normals") && e.contains("moments"), "{e}");
    assert!(a.to_bytes().is_err());
    assert!(a.header.validate().is_err());
    // The same header written by the spec-level writer with VMOM chunks: the reader
    // refuses the header.
    let good = generator_asset().to_bytes().unwrap();
    let mut chunks = split_chunks(&good);
    chunks[0].2 = a.header.to_ron().unwrap().into_bytes();
    let e = VolumeAsset::from_bytes(&join_chunks(1, 4, 1, &chunks)).unwrap_err();
    assert!(e.to_string().contains("moments"), "{e}");
}

/// `good`'s chunks with `from` renamed `to` (element types kept), rewritten with the
/// spec-level writer.
fn renamed(good: &[u8], from: &[u8; 4], to: &[u8; 4]) -> Vec<u8> {
    let mut chunks = split_chunks(good);
    let mut hit = false;
    for c in &mut chunks {
        if &c.0 == from {
            c.0 = *to;
            hit = true;
        }
    }
    assert!(hit, "no {} chunk", tag_str(from));
    join_chunks(1, minor(good), 1, &chunks)
}

/// A normal chunk of the kind the header does not declare is an error, not a chunk to
/// skip: VNRM or BNRM in a moments volume, VMOM or BMOM in a mean-normal volume, either
/// in a volume without normals.
#[test]
fn normal_chunks_of_the_other_kind_are_refused() {
    let moments = banded().to_bytes().unwrap();
    for (from, to) in [(b"VMOM", b"VNRM"), (b"BMOM", b"BNRM")] {
        let e = VolumeAsset::from_bytes(&renamed(&moments, from, to))
            .unwrap_err()
            .to_string();
        let t = tag_str(to);
        assert!(e.contains(&t) && e.contains("volume.moments"), "{t}: {e}");
    }
    let mean = as_mean(banded()).to_bytes().unwrap();
    for (from, to) in [(b"VNRM", b"VMOM"), (b"BNRM", b"BMOM")] {
        let e = VolumeAsset::from_bytes(&renamed(&mean, from, to))
            .unwrap_err()
            .to_string();
        let t = tag_str(to);
        assert!(e.contains(&t) && e.contains("volume.normals"), "{t}: {e}");
    }
    // VMOM chunks in a volume whose header declares no normals at all.
    let mut chunks = split_chunks(&moments);
    let mut h = banded().header;
    h.volume.as_mut().unwrap().set_normal_kind(None);
    chunks[0].2 = h.to_ron().unwrap().into_bytes();
    let e = VolumeAsset::from_bytes(&join_chunks(1, 4, 1, &chunks))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("VMOM") && e.contains("volume.moments is None"),
        "{e}"
    );
    // VMOM chunks with the wrong element type.
    let mut chunks = split_chunks(&moments);
    for c in chunks.iter_mut().filter(|c| &c.0 == b"VMOM") {
        c.1 = ElemType::U8.code();
    }
    let e = VolumeAsset::from_bytes(&join_chunks(1, 4, 1, &chunks))
        .unwrap_err()
        .to_string();
    assert!(e.contains("VMOM") && e.contains("element type"), "{e}");
    // One VMOM level missing.
    let mut chunks = split_chunks(&moments);
    let i = chunks.iter().position(|c| &c.0 == b"VMOM").unwrap();
    chunks.remove(i);
    let e = VolumeAsset::from_bytes(&join_chunks(1, 4, 1, &chunks))
        .unwrap_err()
        .to_string();
    assert!(e.contains("1 VMOM levels but mip_count is 2"), "{e}");
}

/// The report of `billow info`: the 1.4 fixture's chunks.
#[test]
fn inspects_the_v1_4_fixture() {
    let bytes = std::fs::read(moments_fixture_path()).unwrap();
    let r = inspect_bytes(&bytes).unwrap();
    assert_eq!((r.major, r.minor, r.kind), (1, 4, AssetKind::Volume));
    assert!(r.is_ok());
    let t: Vec<String> = r.chunks.iter().map(|c| tag_str(&c.tag)).collect();
    assert_eq!(t, ["HEAD", "VLEV", "VLEV", "VMOM", "VMOM", "CELL", "END "]);
    assert!(r
        .chunks
        .iter()
        .filter(|c| &c.tag == b"VMOM")
        .all(|c| c.elem == ElemType::I8));
}
