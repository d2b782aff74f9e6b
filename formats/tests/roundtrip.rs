//! Round trips, determinism and atomic writes.

mod common;

use std::collections::BTreeMap;

use billow_format::*;
use proptest::prelude::*;

fn finite() -> impl Strategy<Value = f32> {
    use proptest::num::f32::*;
    NORMAL | SUBNORMAL | ZERO | NEGATIVE | POSITIVE
}

fn vec3() -> impl Strategy<Value = [f32; 3]> {
    [finite(), finite(), finite()]
}

fn prism() -> impl Strategy<Value = Prism> {
    (
        [vec3(), vec3(), vec3(), vec3(), vec3(), vec3()],
        [vec3(), vec3(), vec3(), vec3(), vec3(), vec3()],
    )
        .prop_map(|(pos, uvw)| Prism { pos, uvw })
}

fn header() -> impl Strategy<Value = Header> {
    let source = proptest::option::of(("[^/\\\\]{0,12}", "[0-9a-f]{64}", any::<u64>()).prop_map(
        |(file_name, sha256, bytes)| SourceInfo {
            file_name,
            sha256,
            bytes,
        },
    ));
    (
        ".{0,20}",
        source,
        vec3(),
        vec3(),
        any::<bool>(),
        proptest::option::of(any::<u64>()),
        proptest::collection::btree_map(".{0,8}", ".{0,16}", 0..4),
    )
        .prop_map(|(tool, source, a, b, linear, seed, params)| Header {
            kind: AssetKind::Volume,
            tool,
            source,
            bounds: Bounds {
                min: std::array::from_fn(|i| a[i].min(b[i])),
                max: std::array::from_fn(|i| a[i].max(b[i])),
            },
            colour_space: if linear {
                ColourSpace::LinearPremultiplied
            } else {
                ColourSpace::SrgbPremultiplied
            },
            seed,
            params,
            volume: None,
        })
}

fn volume_asset() -> impl Strategy<Value = VolumeAsset> {
    ([1u32..10, 1u32..10, 1u32..10], any::<bool>(), any::<u32>()).prop_flat_map(
        |(dims, with_normals, pick)| {
            let mips = 1 + pick % full_mip_count(dims);
            let level_strategy = move || {
                (0..mips)
                    .map(|i| {
                        let n = mip_dims(dims, i).iter().product::<u32>() as usize * 4;
                        proptest::collection::vec(any::<u8>(), n)
                    })
                    .collect::<Vec<_>>()
            };
            let normals = if with_normals {
                level_strategy().prop_map(Some).boxed()
            } else {
                Just(None).boxed()
            };
            (
                header(),
                level_strategy(),
                normals,
                proptest::collection::vec(prism(), 0..4),
            )
                .prop_map(move |(mut header, levels, normals, cells)| {
                    header.volume = Some(VolumeHeader {
                        dims,
                        mip_count: mips,
                        texel: TexelFormat::Rgba8Unorm,
                        normals: normals.as_ref().map(|_| NormalEncoding::Rgba8Snorm),
                        moments: None,
                    });
                    VolumeAsset {
                        header,
                        levels,
                        normals,
                        bands: Vec::new(),
                        cells,
                    }
                })
        },
    )
}

/// Bitwise float comparison (PartialEq treats -0.0 == 0.0).
fn bits(a: &VolumeAsset) -> Vec<u32> {
    let b = &a.header.bounds;
    let mut v: Vec<u32> = b.min.iter().chain(&b.max).map(|f| f.to_bits()).collect();
    for p in &a.cells {
        v.extend(p.pos.iter().chain(&p.uvw).flatten().map(|f| f.to_bits()));
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn random_volume_assets_round_trip(asset in volume_asset()) {
        let bytes = asset.to_bytes().unwrap();
        prop_assert_eq!(bytes.len() % 8, 0);
        prop_assert_eq!(&to_bytes(&asset.to_container().unwrap()).unwrap(), &bytes);
        let back = VolumeAsset::from_bytes(&bytes).unwrap();
        prop_assert_eq!(&back, &asset);
        prop_assert_eq!(bits(&back), bits(&asset));
        prop_assert_eq!(back.to_bytes().unwrap(), bytes);
    }

    /// `write` streams the payloads to the file: the same bytes as `to_bytes`.
    #[test]
    fn write_gives_the_encoded_bytes(asset in volume_asset()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.billow");
        asset.write(&path).unwrap();
        prop_assert_eq!(std::fs::read(&path).unwrap(), asset.to_bytes().unwrap());
    }
}

#[test]
fn mip_chain_rules() {
    assert_eq!(full_mip_count([1, 1, 1]), 1);
    assert_eq!(full_mip_count([3, 2, 1]), 2);
    assert_eq!(full_mip_count([4, 1, 1]), 3);
    assert_eq!(full_mip_count([5, 7, 9]), 4);
    assert_eq!(full_mip_count([4096, 4096, 4096]), 13);
    assert_eq!(mip_dims([5, 7, 9], 0), [5, 7, 9]);
    assert_eq!(mip_dims([5, 7, 9], 1), [2, 3, 4]);
    assert_eq!(mip_dims([5, 7, 9], 2), [1, 1, 2]);
    assert_eq!(mip_dims([5, 7, 9], 3), [1, 1, 1]);
    assert_eq!(mip_dims([5, 7, 9], 40), [1, 1, 1]);
}

#[test]
fn writing_twice_gives_identical_bytes() {
    let asset = VolumeAsset::from_bytes(&common::fixture_bytes()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.billow"), dir.path().join("b.billow"));
    asset.write(&a).unwrap();
    asset.clone().write(&b).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // HashMap-free: params inserted in another order encode the same.
    let mut h2 = asset.clone();
    let mut p = BTreeMap::new();
    for (k, v) in asset.header.params.iter().rev() {
        p.insert(k.clone(), v.clone());
    }
    h2.header.params = p;
    assert_eq!(h2.to_bytes().unwrap(), asset.to_bytes().unwrap());
}

fn dir_names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn write_atomic_leaves_no_temp_and_replaces() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.billow");
    write_atomic(&p, b"first").unwrap();
    write_atomic(&p, b"second").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"second");
    assert_eq!(dir_names(dir.path()), ["out.billow"]);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&p).unwrap().permissions().mode();
        assert_ne!(
            mode & 0o044,
            0,
            "readable like a normally created file: {mode:o}"
        );
    }
}

#[test]
fn write_atomic_failure_leaves_target_untouched() {
    let dir = tempfile::tempdir().unwrap();
    // Missing directory: error names the path, nothing is created.
    let missing = dir.path().join("no_such_dir").join("out.billow");
    let msg = write_atomic(&missing, b"x").unwrap_err().to_string();
    assert!(msg.starts_with(&missing.display().to_string()), "{msg}");
    // ... and says which directory is missing, without the temporary file's random name.
    let parent = missing.parent().unwrap().display().to_string();
    assert!(
        msg.ends_with(&format!("directory {parent} does not exist")),
        "{msg}"
    );
    assert!(!msg.contains(".billow.tmp"), "{msg}");
    assert!(dir_names(dir.path()).is_empty());
    // Target is a directory: rename fails, existing content untouched, temp removed.
    let target = dir.path().join("occupied");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"keep").unwrap();
    assert!(write_atomic(&target, b"new").is_err());
    assert_eq!(std::fs::read(target.join("keep")).unwrap(), b"keep");
    assert_eq!(dir_names(dir.path()), ["occupied"]);
    // Invalid asset: nothing written, existing file untouched.
    let p = dir.path().join("asset.billow");
    std::fs::write(&p, b"old").unwrap();
    let mut asset = VolumeAsset::from_bytes(&common::fixture_bytes()).unwrap();
    asset.levels.pop();
    assert!(asset.write(&p).is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"old");
    assert_eq!(dir_names(dir.path()), ["asset.billow", "occupied"]);
}

#[test]
fn read_file_errors_carry_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.billow");
    std::fs::write(&p, &common::fixture_bytes()[..100]).unwrap();
    let msg = read_file(&p).unwrap_err().to_string();
    assert_eq!(
        msg,
        format!(
            "{}: truncated: file is 100 bytes but the preamble says 1112",
            p.display()
        )
    );
    let msg = read_file(&dir.path().join("nope.billow"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("nope.billow: "), "{msg}");
}

#[test]
fn encoder_refuses_invalid_containers() {
    let asset = VolumeAsset::from_bytes(&common::fixture_bytes()).unwrap();
    let mut c = asset.to_container().unwrap();
    c.chunks.push(Chunk {
        tag: *b"HEAD",
        elem: ElemType::Opaque,
        data: vec![],
    });
    assert!(to_bytes(&c).is_err());
    c.chunks.pop();
    c.chunks.push(Chunk {
        tag: *b"ODD_",
        elem: ElemType::U32,
        data: vec![1, 2, 3],
    });
    assert!(to_bytes(&c).unwrap_err().to_string().contains("multiple"));
    c.chunks.pop();
    c.header.volume = None;
    assert!(to_bytes(&c).is_err());
    let mut a = asset.clone();
    a.cells[0].pos[0][0] = f32::INFINITY;
    assert!(a.to_bytes().is_err());
    let mut a = asset;
    a.normals = None;
    assert!(a.to_container().is_err());
}

#[test]
fn cloud_kind_container_round_trips() {
    let mut h = VolumeAsset::from_bytes(&common::fixture_bytes())
        .unwrap()
        .header;
    h.kind = AssetKind::Cloud;
    h.volume = None;
    let c = Container {
        header: h,
        chunks: vec![Chunk {
            tag: *b"QUAD",
            elem: ElemType::F16,
            data: vec![0; 6],
        }],
    };
    let bytes = to_bytes(&c).unwrap();
    assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 2);
    assert_eq!(from_bytes(&bytes).unwrap(), c);
    assert!(VolumeAsset::from_bytes(&bytes)
        .unwrap_err()
        .to_string()
        .contains("not Volume"));
}

/// SPEC §6: every non-`Option` field is required, `params` may be the empty map, a field
/// given twice is refused, unknown fields and omitted `Option`s are fine.
#[test]
fn header_required_and_duplicate_fields() {
    let base = "kind: Cloud, tool: \"t\", bounds: (min: (0.0, 0.0, 0.0), max: (1.0, 1.0, 1.0)), \
                colour_space: SrgbPremultiplied";
    let ok = |extra: &str| Header::from_ron(&format!("({base}, {extra})"));
    assert!(ok("params: {}").is_ok());
    assert!(ok("params: {}, future_field: [1, 2], seed: None").is_ok());
    assert!(
        Header::from_ron(&format!("({base})")).is_err(),
        "params missing"
    );
    let twice = ok("params: {}, tool: \"u\"");
    assert!(twice.is_err(), "a field given twice: {twice:?}");
    let no_tool = format!("({}, params: {{}})", base.replace("tool: \"t\", ", ""));
    assert!(Header::from_ron(&no_tool).is_err(), "tool missing");
}
