//! `billow info` driven as a real binary over the frozen v1 fixture and damaged copies of it.

mod common;

use std::path::Path;

use common::*;

const FIXTURE: &str = "fixtures/format/v1_volume_3x2x1.billow";

fn fixture_bytes() -> Vec<u8> {
    std::fs::read(repo().join(FIXTURE)).unwrap()
}

#[test]
fn describes_the_frozen_fixture() {
    let dir = tempfile::tempdir().unwrap();
    let path = repo().join(FIXTURE);
    let text = run(&["info", path.to_str().unwrap()], dir.path());
    assert_eq!(text.code, Some(0), "{}", text.stderr);
    for needle in [
        "billow 1.0",
        "Volume",
        "VLEV",
        "VNRM",
        "CELL",
        "HEAD",
        "res",
        "3x2x1",
    ] {
        assert!(
            text.stdout.contains(needle),
            "missing {needle:?} in:\n{}",
            text.stdout
        );
    }
    let json = run(&["info", "--json", path.to_str().unwrap()], dir.path());
    assert_eq!(json.code, Some(0), "{}", json.stderr);
    let v: serde_json::Value = serde_json::from_str(&json.stdout).unwrap();
    assert_eq!(v["format_version"], "1.0");
    assert_eq!(v["kind"], "Volume");
    assert_eq!(v["checksums_ok"], true);
    assert_eq!(v["file_bytes"], 1112);
    assert_eq!(v["header"]["volume"]["dims"], serde_json::json!([3, 2, 1]));
    let chunks: Vec<&str> = v["chunks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["tag"].as_str().unwrap())
        .collect();
    assert_eq!(
        chunks,
        ["HEAD", "VLEV", "VLEV", "VNRM", "VNRM", "CELL", "END "]
    );
    assert_eq!(v["normals"], "mean");
    assert!(text.stdout.contains("normals:  mean"), "{}", text.stdout);
}

/// The 1.4 fixture: a volume of normal moments (SPEC §8.4a), named as such.
#[test]
fn describes_the_moments_fixture() {
    let dir = tempfile::tempdir().unwrap();
    let path = repo().join("fixtures/format/v1_4_volume_moments.billow");
    let text = run(&["info", path.to_str().unwrap()], dir.path());
    assert_eq!(text.code, Some(0), "{}", text.stderr);
    for needle in [
        "billow 1.4",
        "normals:  moments",
        "VMOM",
        "moments: Some(Rgba8Snorm)",
    ] {
        assert!(
            text.stdout.contains(needle),
            "missing {needle:?} in:\n{}",
            text.stdout
        );
    }
    let json = run(&["info", "--json", path.to_str().unwrap()], dir.path());
    assert_eq!(json.code, Some(0), "{}", json.stderr);
    let v: serde_json::Value = serde_json::from_str(&json.stdout).unwrap();
    assert_eq!(v["format_version"], "1.4");
    assert_eq!(v["normals"], "moments");
    assert_eq!(v["header"]["volume"]["moments"], "Rgba8Snorm");
    assert_eq!(v["header"]["volume"]["normals"], serde_json::Value::Null);
}

fn assert_rejected(dir: &Path, name: &str, bytes: &[u8], what: &str) {
    std::fs::write(dir.join(name), bytes).unwrap();
    let r = run(&["info", name], dir);
    assert!(
        matches!(r.code, Some(3..=8)),
        "{what}: expected a clean failure, got exit {:?}\nstdout: {}\nstderr: {}",
        r.code,
        r.stdout,
        r.stderr
    );
    let line = r.error_line().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        line.contains(name),
        "{what}: error does not name the file: {line}"
    );
}

/// Every strict prefix of the fixture (0 bytes included) is refused with one error line.
#[test]
fn every_strict_prefix_is_rejected() {
    let bytes = fixture_bytes();
    let dir = tempfile::tempdir().unwrap();
    for len in 0..bytes.len() {
        assert_rejected(
            dir.path(),
            "prefix.billow",
            &bytes[..len],
            &format!("prefix of {len} bytes"),
        );
    }
}

/// Flipping every bit of any single byte is caught (the library tests also cover xor 0x01
/// and 0x80 at every offset; the binary is driven for 0xFF at every offset).
#[test]
fn every_single_byte_flip_is_rejected() {
    let bytes = fixture_bytes();
    let dir = tempfile::tempdir().unwrap();
    for i in 0..bytes.len() {
        let mut b = bytes.clone();
        b[i] ^= 0xFF;
        assert_rejected(
            dir.path(),
            "flipped.billow",
            &b,
            &format!("byte {i} flipped"),
        );
    }
}

#[test]
fn newer_major_is_refused_with_both_versions_named() {
    let mut bytes = fixture_bytes();
    bytes[8..10].copy_from_slice(&2u16.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("future.billow"), &bytes).unwrap();
    let r = run(&["info", "future.billow"], dir.path());
    assert_eq!(r.code, Some(5), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(line.contains("2.0") && line.contains("1.x"), "{line}");
}

#[test]
fn a_mesh_given_to_info_is_not_an_asset() {
    let dir = tempfile::tempdir().unwrap();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let r = run(&["info", oak.to_str().unwrap()], dir.path());
    assert_eq!(r.code, Some(4), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("not a billow asset"));
}
