//! The Cloud kind: frozen fixture, round trip, validation on read.
//!
//! `decodes_frozen_v1_cloud_fixture` must stay forever and never regenerate the file.
//! To generate (only for a NEW fixture file):
//! `cargo test -p billow-format --test cloud_format -- --ignored generate_v1_cloud_fixture`
//! (`generate_v1_1_cloud_fixture` for the 1.1 fixture with normal maps).

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow_format::*;
use common::{crc, spec_chunk, split_chunks};

fn fixture_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/format/v1_cloud_tiny.billow")
}

fn fixture_1_1_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/format/v1_1_cloud_normals.billow")
}

fn rect(atlas: u32, uv: [f32; 4]) -> AtlasRect {
    AtlasRect { atlas, uv }
}

fn board(
    z: f32,
    front: AtlasRect,
    back: AtlasRect,
    parent: Option<u32>,
    elements: u32,
) -> Billboard {
    let c = [[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]];
    Billboard {
        plane: [0.0, 0.0, 1.0, z],
        corners: c,
        parent_corners: c.map(|p| [p[0], p[1], 0.0]),
        front,
        back,
        parent,
        elements,
    }
}

fn v(p: [f32; 3], uv: [f32; 2]) -> MeshVertex {
    MeshVertex {
        position: p,
        normal: [0.0, 0.0, 1.0],
        uv,
    }
}

/// Two levels: two billboards on a 4x2 atlas (3 MIPs), then one on a 2x2 atlas (2 MIPs).
fn generator_asset() -> CloudAsset {
    let mut params = BTreeMap::new();
    params.insert("epsilon".to_string(), "0.04".to_string());
    params.insert("samples".to_string(), "500".to_string());
    let header = Header {
        kind: AssetKind::Cloud,
        tool: "billow 0.1.0".into(),
        source: None,
        bounds: Bounds {
            min: [0.0, 0.0, 0.0],
            max: [1.0, 1.0, 0.5],
        },
        colour_space: ColourSpace::SrgbPremultiplied,
        seed: Some(7),
        params,
        volume: None,
    };
    let a0: Vec<u8> = (0..32).map(|i| (i * 8) as u8).collect();
    CloudAsset {
        header,
        levels: vec![
            CloudLevel {
                first_billboard: 0,
                billboard_count: 2,
                first_atlas: 0,
                atlas_count: 1,
                epsilon: 0.5,
                texel_density: 2.0,
            },
            CloudLevel {
                first_billboard: 2,
                billboard_count: 1,
                first_atlas: 1,
                atlas_count: 1,
                epsilon: 1.0,
                texel_density: 1.0,
            },
        ],
        billboards: vec![
            board(
                0.0,
                rect(0, [0.0, 0.0, 0.25, 0.5]),
                rect(0, [0.25, 0.0, 0.5, 0.5]),
                Some(2),
                2,
            ),
            board(
                0.5,
                rect(0, [0.5, 0.0, 0.75, 0.5]),
                rect(0, [0.75, 0.0, 1.0, 0.5]),
                Some(2),
                1,
            ),
            board(
                0.25,
                rect(1, [0.0, 0.0, 0.5, 0.5]),
                rect(1, [0.5, 0.5, 1.0, 1.0]),
                None,
                2,
            ),
        ],
        atlases: vec![
            Atlas {
                width: 4,
                height: 2,
                mips: vec![a0, vec![10, 20, 30, 40, 50, 60, 70, 80], vec![1, 2, 3, 4]],
                normals: None,
            },
            Atlas {
                width: 2,
                height: 2,
                mips: vec![vec![255; 16], vec![128, 64, 32, 128]],
                normals: None,
            },
        ],
        materials: vec![
            MeshMaterial {
                base_color_factor: [1.0, 0.5, 0.25, 1.0],
                alpha_cutoff: 0.5,
                texture: None,
                alpha_mode: 0,
                double_sided: false,
            },
            MeshMaterial {
                base_color_factor: [0.5, 1.0, 0.5, 1.0],
                alpha_cutoff: 0.5,
                texture: Some(0),
                alpha_mode: 1,
                double_sided: true,
            },
        ],
        textures: vec![MeshTexture {
            width: 1,
            height: 1,
            wrap: [0, 1],
            texels: vec![40, 200, 40, 255],
        }],
        trunk: Mesh {
            vertices: vec![
                v([0.0, 0.0, 0.0], [0.0, 0.0]),
                v([0.1, 0.0, 0.0], [1.0, 0.0]),
                v([0.0, 1.0, 0.0], [0.0, 1.0]),
            ],
            triangles: vec![[0, 1, 2]],
            materials: vec![0],
            ..Mesh::default()
        },
        foliage: Mesh {
            vertices: vec![
                v([0.0, 0.0, 0.1], [0.0, 0.0]),
                v([1.0, 0.0, 0.1], [1.0, 0.0]),
                v([0.0, 1.0, 0.1], [0.0, 1.0]),
                v([0.0, 0.0, 0.4], [0.0, 0.0]),
            ],
            triangles: vec![[0, 1, 2], [3, 1, 2]],
            materials: vec![1, 1],
            morph: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 0.5],
            ],
            billboard: vec![0, 0],
        },
    }
}

#[test]
#[ignore = "writes the frozen fixture; run by hand only for a new fixture"]
fn generate_v1_cloud_fixture() {
    generator_asset().write(&fixture_path()).unwrap();
}

/// FROZEN: decode the fixture and check values spelled out here, independently of the generator.
#[test]
fn decodes_frozen_v1_cloud_fixture() {
    let bytes = std::fs::read(fixture_path()).expect("fixtures/format/v1_cloud_tiny.billow");
    assert_eq!(bytes.len(), 1888);
    assert_eq!(crc(&bytes), 0x383d_01ee, "fixture file changed on disk");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 0, 0, 2, 0, 0, 0],
        "version 1.0, kind Cloud"
    );
    let a = CloudAsset::from_bytes(&bytes).expect("decodes");
    assert_eq!(a.header.kind, AssetKind::Cloud);
    assert_eq!(a.header.seed, Some(7));
    assert_eq!(a.levels.len(), 2);
    assert_eq!(
        (
            a.levels[1].first_billboard,
            a.levels[1].billboard_count,
            a.levels[1].epsilon
        ),
        (2, 1, 1.0)
    );
    assert_eq!(a.billboards.len(), 3);
    let b1 = &a.billboards[1];
    assert_eq!(b1.plane, [0.0, 0.0, 1.0, 0.5]);
    assert_eq!(b1.corners[2], [1.0, 1.0, 0.5]);
    assert_eq!(b1.parent_corners[2], [1.0, 1.0, 0.0]);
    assert_eq!((b1.front.atlas, b1.front.uv), (0, [0.5, 0.0, 0.75, 0.5]));
    assert_eq!((b1.back.atlas, b1.back.uv), (0, [0.75, 0.0, 1.0, 0.5]));
    assert_eq!((b1.parent, b1.elements), (Some(2), 1));
    assert_eq!(a.billboards[2].parent, None);
    assert_eq!(
        (
            a.atlases[0].width,
            a.atlases[0].height,
            a.atlases[0].mips.len()
        ),
        (4, 2, 3)
    );
    assert_eq!(a.atlases[0].mips[0][31], 248);
    assert_eq!(a.atlases[0].mips[2], [1, 2, 3, 4]);
    assert_eq!(a.atlases[1].mips[1], [128, 64, 32, 128]);
    assert_eq!(a.materials[1].texture, Some(0));
    assert_eq!(
        (a.materials[1].alpha_mode, a.materials[1].double_sided),
        (1, true)
    );
    assert_eq!(a.textures[0].texels, [40, 200, 40, 255]);
    assert_eq!(a.textures[0].wrap, [0, 1]);
    assert_eq!(a.trunk.triangles, [[0, 1, 2]]);
    assert_eq!(a.trunk.vertices[1].position, [0.1, 0.0, 0.0]);
    assert_eq!(a.foliage.triangles[1], [3, 1, 2]);
    assert_eq!(a.foliage.morph[3], [0.0, 0.0, 0.5]);
    assert_eq!(a.foliage.billboard, [0, 0]);
    let tags: Vec<String> = split_chunks(&bytes).iter().map(|c| tag_str(&c.0)).collect();
    assert_eq!(
        tags.join(" "),
        "HEAD CLVL CLVF BBRD BBIX ATLS ATEX ATEX ATEX ATEX ATEX MMAT MMAI MTXI MTEX TVTX TIDX FVTX FIDX END "
    );
    assert_eq!(
        a.to_bytes().unwrap(),
        bytes,
        "re-encoding reproduces the file"
    );
    assert_eq!(
        generator_asset().to_bytes().unwrap(),
        bytes,
        "the writer is stable"
    );
}

#[test]
fn unknown_chunks_are_skipped_and_container_round_trips() {
    let a = generator_asset();
    let mut c = a.to_container().unwrap();
    c.chunks.insert(
        3,
        Chunk {
            tag: *b"ZZZZ",
            elem: ElemType::F16,
            data: vec![0; 4],
        },
    );
    let bytes = to_bytes(&c).unwrap();
    assert_eq!(CloudAsset::from_bytes(&bytes).unwrap(), a);
    assert!(VolumeAsset::from_bytes(&bytes).is_err());
    let _ = spec_chunk; // helper shared with the other tests
}

fn rejects(what: &str, f: impl FnOnce(&mut CloudAsset)) {
    let mut a = generator_asset();
    f(&mut a);
    let e = a.to_bytes().expect_err(what);
    assert!(
        matches!(e, CloudError::Invalid(_) | CloudError::Format(_)),
        "{what}: {e}"
    );
}

/// Patch one u32/f32 of a chunk's payload in a valid file's container and decode it.
fn read_patched(tag: &[u8; 4], word: usize, value: [u8; 4]) -> Result<CloudAsset, CloudError> {
    let mut c = generator_asset().to_container().unwrap();
    let ch = c.chunks.iter_mut().find(|ch| &ch.tag == tag).unwrap();
    ch.data[4 * word..4 * word + 4].copy_from_slice(&value);
    CloudAsset::from_bytes(&to_bytes(&c).unwrap())
}

#[test]
fn invalid_content_is_refused_on_read() {
    assert!(
        read_patched(b"BBIX", 2, 1u32.to_le_bytes()).is_err(),
        "parent in own level"
    );
    assert!(
        read_patched(b"BBIX", 0, 1u32.to_le_bytes()).is_err(),
        "atlas of another level"
    );
    assert!(
        read_patched(b"BBRD", 30, 1.5f32.to_le_bytes()).is_err(),
        "uv > 1"
    );
    assert!(
        read_patched(b"BBRD", 4, f32::INFINITY.to_le_bytes()).is_err(),
        "inf corner"
    );
    assert!(
        read_patched(b"ATLS", 0, 8u32.to_le_bytes()).is_err(),
        "atlas size vs MIP bytes"
    );
    assert!(
        read_patched(b"ATLS", 2, u32::MAX.to_le_bytes()).is_err(),
        "hostile MIP count"
    );
    assert!(
        read_patched(b"MTXI", 0, u32::MAX.to_le_bytes()).is_err(),
        "hostile texture width"
    );
    assert!(
        read_patched(b"TIDX", 2, 9u32.to_le_bytes()).is_err(),
        "vertex index"
    );
    assert!(
        read_patched(b"FIDX", 4, 5u32.to_le_bytes()).is_err(),
        "billboard index"
    );
    assert!(
        read_patched(b"CLVL", 1, 5u32.to_le_bytes()).is_err(),
        "level count"
    );
    assert!(
        read_patched(b"MMAI", 1, 7u32.to_le_bytes()).is_err(),
        "alpha mode"
    );
    assert!(
        read_patched(b"BBIX", 3, 9u32.to_le_bytes()).is_ok(),
        "elements is free"
    );
}

#[test]
fn invalid_content_is_refused() {
    rejects("parent in the same level", |a| {
        a.billboards[0].parent = Some(1)
    });
    rejects("last level with a parent", |a| {
        a.billboards[2].parent = Some(0)
    });
    rejects("uv outside", |a| a.billboards[0].front.uv[2] = 1.5);
    rejects("atlas of another level", |a| {
        a.billboards[2].front.atlas = 0
    });
    rejects("non-unit normal", |a| a.billboards[0].plane[2] = 2.0);
    rejects("NaN corner", |a| a.billboards[1].corners[0][0] = f32::NAN);
    rejects("wrong MIP size", |a| a.atlases[0].mips[1].push(0));
    rejects("too many MIPs", |a| a.atlases[1].mips.push(vec![0; 4]));
    rejects("level gap", |a| a.levels[1].first_billboard = 3);
    rejects("zero epsilon", |a| a.levels[0].epsilon = 0.0);
    rejects("vertex index", |a| a.trunk.triangles[0][2] = 3);
    rejects("material index", |a| a.foliage.materials[0] = 2);
    rejects("billboard index", |a| a.foliage.billboard[1] = 2);
    rejects("morph count", |a| {
        a.foliage.morph.pop();
    });
    rejects("texture index", |a| a.materials[1].texture = Some(1));
    rejects("alpha mode", |a| a.materials[0].alpha_mode = 3);
    rejects("texture size", |a| a.textures[0].texels.push(0));
    rejects("volume kind", |a| a.header.kind = AssetKind::Volume);
}

/// Byte-level hostility: every chunk removed, duplicated or cut short is refused.
#[test]
fn structural_damage_is_refused() {
    let good = generator_asset().to_container().unwrap();
    for i in 0..good.chunks.len() {
        let mut c = good.clone();
        let removed = c.chunks.remove(i);
        if let Ok(bytes) = to_bytes(&c) {
            assert!(
                CloudAsset::from_bytes(&bytes).is_err(),
                "without {}",
                tag_str(&removed.tag)
            );
        }
        let mut c = good.clone();
        c.chunks.insert(i, good.chunks[i].clone());
        let bytes = to_bytes(&c).unwrap();
        assert!(
            CloudAsset::from_bytes(&bytes).is_err(),
            "duplicated {}",
            tag_str(&good.chunks[i].tag)
        );
        let mut c = good.clone();
        let size = c.chunks[i].elem.size() as usize;
        if c.chunks[i].data.len() >= size {
            let n = c.chunks[i].data.len() - size;
            c.chunks[i].data.truncate(n);
            let bytes = to_bytes(&c).unwrap();
            assert!(
                CloudAsset::from_bytes(&bytes).is_err(),
                "short {}",
                tag_str(&good.chunks[i].tag)
            );
        }
    }
    let bytes = generator_asset().to_bytes().unwrap();
    for cut in (0..bytes.len()).step_by(7) {
        assert!(CloudAsset::from_bytes(&bytes[..cut]).is_err());
    }
}

/// The 1.0 generator's asset with normal maps (format 1.1): atlas 0 with a tilted normal in
/// its first texel and flat elsewhere, atlas 1 flat.
fn generator_asset_1_1() -> CloudAsset {
    let mut a = generator_asset();
    let flat = |n: usize| [128u8, 128, 255, 255].repeat(n);
    let mut n0 = flat(8);
    n0[..4].copy_from_slice(&[218, 128, 218, 255]);
    a.atlases[0].normals = Some(vec![n0, flat(2), vec![200, 100, 230, 180]]);
    a.atlases[1].normals = Some(vec![flat(4), flat(1)]);
    a.header
        .params
        .insert("normal_map".to_string(), "tangent".to_string());
    a
}

#[test]
#[ignore = "writes the frozen 1.1 fixture; run by hand only for a new fixture"]
fn generate_v1_1_cloud_fixture() {
    generator_asset_1_1().write(&fixture_1_1_path()).unwrap();
}

/// FROZEN: the format 1.1 fixture with normal maps (`ANRM`), values spelled out here.
#[test]
fn decodes_frozen_v1_1_cloud_normals_fixture() {
    let bytes =
        std::fs::read(fixture_1_1_path()).expect("fixtures/format/v1_1_cloud_normals.billow");
    assert_eq!(bytes.len(), 2112);
    assert_eq!(crc(&bytes), FIXTURE_1_1_CRC, "fixture file changed on disk");
    assert_eq!(
        &bytes[8..16],
        &[1, 0, 1, 0, 2, 0, 0, 0],
        "version 1.1, kind Cloud"
    );
    let a = CloudAsset::from_bytes(&bytes).expect("decodes");
    let n0 = a.atlases[0].normals.as_ref().expect("atlas 0 normal map");
    assert_eq!(n0.len(), 3);
    assert_eq!(n0[0][..8], [218, 128, 218, 255, 128, 128, 255, 255]);
    assert_eq!(n0[1], [128, 128, 255, 255, 128, 128, 255, 255]);
    assert_eq!(n0[2], [200, 100, 230, 180]);
    assert_eq!(
        a.atlases[1].normals.as_ref().unwrap()[1],
        [128, 128, 255, 255]
    );
    // Everything else is the 1.0 fixture's content.
    let mut without = a.clone();
    without.atlases.iter_mut().for_each(|x| x.normals = None);
    without.header.params.remove("normal_map");
    let v1_0 = CloudAsset::from_bytes(&std::fs::read(fixture_path()).unwrap()).unwrap();
    assert_eq!(without, v1_0);
    let tags: Vec<String> = split_chunks(&bytes).iter().map(|c| tag_str(&c.0)).collect();
    assert_eq!(
        tags.join(" "),
        "HEAD CLVL CLVF BBRD BBIX ATLS ATEX ATEX ATEX ATEX ATEX ANRM ANRM ANRM ANRM ANRM \
         MMAT MMAI MTXI MTEX TVTX TIDX FVTX FIDX END "
    );
    assert_eq!(
        a.to_bytes().unwrap(),
        bytes,
        "re-encoding reproduces the file"
    );
    assert_eq!(
        generator_asset_1_1().to_bytes().unwrap(),
        bytes,
        "the writer is stable"
    );
    // What a 1.0 reader does: skip the unknown ANRM chunks (§5) and read the rest.
    let mut c = from_bytes(&bytes).unwrap();
    c.chunks.retain(|ch| &ch.tag != b"ANRM");
    let old = CloudAsset::from_container(c).unwrap();
    assert!(old.atlases.iter().all(|x| x.normals.is_none()));
}

/// CRC of the frozen 1.1 fixture.
const FIXTURE_1_1_CRC: u32 = 0x2287_c5ed;

#[test]
fn normal_maps_are_all_or_nothing_and_match_the_colour_levels() {
    let good = generator_asset_1_1();
    assert_eq!(
        CloudAsset::from_bytes(&good.to_bytes().unwrap()).unwrap(),
        good
    );
    let no_normals = generator_asset().to_bytes().unwrap();
    assert_eq!(&no_normals[8..12], &[1, 0, 0, 0], "no ANRM: written as 1.0");
    let bad = |what: &str, f: &dyn Fn(&mut CloudAsset)| {
        let mut a = generator_asset_1_1();
        f(&mut a);
        assert!(a.to_bytes().is_err(), "{what}");
    };
    bad("one atlas without", &|a| a.atlases[1].normals = None);
    bad("a level missing", &|a| {
        a.atlases[0].normals.as_mut().unwrap().pop();
    });
    bad("wrong size", &|a| {
        a.atlases[0].normals.as_mut().unwrap()[1].push(0)
    });
    // On read: ANRM chunks must be one per ATEX chunk, U8.
    let c = good.to_container().unwrap();
    let mut fewer = c.clone();
    let i = fewer
        .chunks
        .iter()
        .position(|ch| &ch.tag == b"ANRM")
        .unwrap();
    fewer.chunks.remove(i);
    assert!(CloudAsset::from_bytes(&to_bytes(&fewer).unwrap()).is_err());
    let mut typed = c.clone();
    typed.chunks[i].elem = ElemType::I8;
    assert!(CloudAsset::from_bytes(&to_bytes(&typed).unwrap()).is_err());
}
