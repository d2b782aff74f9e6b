//! `formats/SPEC.md` is enough to write a reader: `tests/spec_reader/read_billow.py` was
//! written from it alone (its author read no Rust), and here it must agree with the Rust
//! reader — kind, version, chunk sequence, volume dimensions and MIP count, mean normals
//! or normal moments, cloud level and billboard counts — on the frozen fixtures (the 1.4
//! moments volume among them) and on real assets the binary bakes now (a volume with
//! normals, its pruned copy with LOD bands, a billboard cloud with normal maps, a shell),
//! and refuse what the Rust reader refuses (a truncated file, a flipped payload byte, a
//! newer major version, a moments volume with a VNRM chunk or with both header fields).
//!
//! Needs `python3` (standard library only); without it the test says it skips.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use billow_format::{read_file, tag_str, CloudAsset, VolumeAsset};
use common::{repo, run};
use serde_json::Value;

fn python() -> Option<&'static str> {
    let ok = Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        common::skip("spec_reader", "python3 not found");
    }
    ok.then_some("python3")
}

/// The Python reader's JSON line for each of `paths`, and its exit status.
fn read_py(py: &str, paths: &[PathBuf]) -> (Vec<Value>, i32) {
    let out = Command::new(py)
        .arg(repo().join("tests/spec_reader/read_billow.py"))
        .env("PYTHONDONTWRITEBYTECODE", "1") // no __pycache__ in the checkout
        .args(paths)
        .output()
        .expect("run read_billow.py");
    let stdout = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        out.stderr.is_empty(),
        "read_billow.py wrote to stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert_eq!(lines.len(), paths.len(), "{stdout}");
    (lines, out.status.code().expect("exit code"))
}

/// What the Rust reader says of `path`, in the Python reader's terms.
fn read_rust(path: &Path) -> Value {
    let c = read_file(path).unwrap_or_else(|e| panic!("{e}"));
    let bytes = std::fs::read(path).unwrap();
    let minor = u16::from_le_bytes([bytes[10], bytes[11]]);
    let mut tags = vec!["HEAD".to_string()];
    tags.extend(c.chunks.iter().map(|ch| tag_str(&ch.tag)));
    tags.push("END ".to_string());
    let mut v = serde_json::json!({
        "major": 1,
        "minor": minor,
        "kind": format!("{:?}", c.header.kind),
        "chunks": tags.clone(),
    });
    // Block-compressed texel chunks (format 1.2, SPEC §12).
    v["compressed"] = serde_json::json!(tags.iter().any(|t| t.ends_with("B7")));
    if let Some(vol) = &c.header.volume {
        v["dims"] = serde_json::json!(vol.dims);
        v["mip_levels"] = serde_json::json!(vol.mip_count);
        // Mean normals or normal moments (format 1.4, SPEC §8.4a).
        v["normals"] = serde_json::json!(vol.normals.is_some());
        v["moments"] = serde_json::json!(vol.moments.is_some());
    } else {
        let cloud = CloudAsset::read(path).unwrap_or_else(|e| panic!("{e}"));
        v["levels"] = serde_json::json!(cloud.levels.len());
        v["billboards"] = serde_json::json!(cloud.billboards.len());
    }
    v
}

fn assert_agree(py: &Value, path: &Path) {
    assert_eq!(py["ok"], true, "{}: {py}", path.display());
    let rust = read_rust(path);
    for (k, want) in rust.as_object().unwrap() {
        assert_eq!(&py[k], want, "{}: {k} (python {py})", path.display());
    }
}

#[test]
fn independent_reader_agrees_with_the_rust_reader() {
    let Some(py) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let oak = oak.to_str().unwrap();
    for args in [
        vec![
            "voxelize",
            oak,
            "-o",
            "vol.billow",
            // 80 (72×80×72): at 64 the 4×4 brick layout of a compressed prune saves
            // nothing and the volume is kept whole, with no bands to read.
            "--res",
            "80",
            "--align",
            "8",
            "--normals",
            "--compress",
            "bc",
        ],
        // Raw texels (--compress none).
        vec![
            "voxelize",
            oak,
            "-o",
            "raw.billow",
            "--res",
            "64",
            "--align",
            "8",
            "--normals",
            "--compress",
            "none",
        ],
        vec![
            "emptyspace",
            "raw.billow",
            "-o",
            "pruned.billow",
            "--compress",
            "none",
        ],
        // The compressed volume prunes too (its empty texels stay exactly empty), into
        // compressed bands (format 1.3, emptyspace's default --compress bc).
        vec!["emptyspace", "vol.billow", "-o", "pruned_bc.billow"],
        vec![
            "shell",
            oak,
            "vol.billow",
            "-o",
            "shell.billow",
            "--height",
            "0.1",
        ],
        vec![
            "bbcloud",
            oak,
            "-o",
            "cloud.billow",
            "--lods",
            "2",
            "--normal-map",
            "--samples",
            "50",
        ],
    ] {
        let r = run(&args, d);
        assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
    }
    let mut paths: Vec<PathBuf> = std::fs::read_dir(repo().join("fixtures/format"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "billow"))
        .collect();
    paths.sort();
    assert_eq!(paths.len(), 8, "{paths:?}");
    assert!(paths
        .iter()
        .any(|p| p.ends_with("v1_4_volume_moments.billow")));
    let f = paths.len();
    paths.extend(
        ["vol", "pruned", "cloud", "shell", "raw", "pruned_bc"]
            .map(|n| d.join(format!("{n}.billow"))),
    );
    let (lines, code) = read_py(py, &paths);
    for (line, path) in lines.iter().zip(&paths) {
        assert_agree(line, path);
    }
    assert_eq!(code, 0);
    let moments = &lines[paths
        .iter()
        .position(|p| p.ends_with("v1_4_volume_moments.billow"))
        .unwrap()];
    assert_eq!(
        (&moments["moments"], &moments["normals"], &moments["minor"]),
        (&Value::from(true), &Value::from(false), &Value::from(4)),
        "{moments}"
    );
    // The baked assets exercise what the fixtures are too small to: normals, bands, ANRM,
    // block compression (`--compress bc`, the default) and raw texels (--compress none).
    assert_eq!(lines[f]["normals"], true, "{}", lines[f]);
    assert!(
        lines[f + 1]["bands"].as_u64().unwrap() >= 1,
        "{}",
        lines[f + 1]
    );
    assert_eq!(lines[f + 2]["normal_maps"], true, "{}", lines[f + 2]);
    for (i, compressed) in [
        (f, true),
        (f + 1, false),
        (f + 2, true),
        (f + 3, true),
        (f + 4, false),
        (f + 5, true),
    ] {
        assert_eq!(lines[i]["compressed"], compressed, "{}", lines[i]);
    }
    assert!(
        lines[f + 5]["bands"].as_u64().unwrap() >= 1,
        "{}",
        lines[f + 5]
    );
    assert_eq!(lines[f + 5]["compressed_bands"], true, "{}", lines[f + 5]);
    assert_eq!(lines[f + 5]["minor"], 3, "{}", lines[f + 5]);
}

#[test]
fn independent_reader_refuses_what_the_rust_reader_refuses() {
    let Some(py) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read(repo().join("fixtures/format/v1_volume_3x2x1.billow")).unwrap();
    let mut cases: Vec<(&str, Vec<u8>)> = vec![("truncated", good[..good.len() - 8].to_vec())];
    let mut flipped = good.clone();
    flipped[650] ^= 0x01; // inside the first VLEV payload, 640..664 (SPEC §10)
    cases.push(("flipped", flipped));
    let mut major = good.clone();
    major[8] = 2;
    cases.push(("major2", major));
    // Format 1.4 (SPEC §8.4a): a moments volume with a mean-normal chunk, and a header
    // with both `normals` and `moments`.
    let moments = std::fs::read(repo().join("fixtures/format/v1_4_volume_moments.billow")).unwrap();
    let mut chunks = split(&moments);
    for c in chunks.iter_mut().filter(|c| &c.0 == b"VMOM") {
        c.0 = *b"VNRM";
    }
    cases.push(("moments_vnrm", join(4, &chunks)));
    let mut chunks = split(&moments);
    let head = String::from_utf8(chunks[0].2.clone()).unwrap();
    assert!(head.contains("normals: None,"), "{head}");
    chunks[0].2 = head
        .replace("normals: None,", "normals: Some(Rgba8Snorm),")
        .into_bytes();
    cases.push(("both_set", join(4, &chunks)));
    let paths: Vec<PathBuf> = cases
        .iter()
        .map(|(name, bytes)| {
            let p = dir.path().join(format!("{name}.billow"));
            std::fs::write(&p, bytes).unwrap();
            p
        })
        .collect();
    let (lines, code) = read_py(py, &paths);
    assert_eq!(code, 1);
    for (line, path) in lines.iter().zip(&paths) {
        assert_eq!(line["ok"], false, "{}: {line}", path.display());
        let err = line["error"].as_str().unwrap();
        assert!(!err.is_empty() && !err.contains('\n'), "{err:?}");
        let refused = read_file(path).is_err() || VolumeAsset::read(path).is_err();
        assert!(refused, "{}", path.display());
    }
    let errors: Vec<&str> = lines.iter().map(|l| l["error"].as_str().unwrap()).collect();
    assert!(errors[0].contains("truncated"), "{errors:?}");
    assert!(errors[1].contains("CRC"), "{errors:?}");
    assert!(errors[2].contains("newer"), "{errors:?}");
    assert!(errors[3].contains("VNRM"), "{errors:?}");
    assert!(errors[4].contains("both set"), "{errors:?}");
}

/// A file's chunks, HEAD to END: (tag, element type, payload).
fn split(f: &[u8]) -> Vec<([u8; 4], u32, Vec<u8>)> {
    let mut out = Vec::new();
    let mut off = 32;
    while off < f.len() {
        let tag: [u8; 4] = f[off..off + 4].try_into().unwrap();
        let elem = u32::from_le_bytes(f[off + 4..off + 8].try_into().unwrap());
        let len = u64::from_le_bytes(f[off + 8..off + 16].try_into().unwrap()) as usize;
        out.push((tag, elem, f[off + 24..off + 24 + len].to_vec()));
        off += 24 + len.div_ceil(8) * 8;
    }
    out
}

/// CRC-32/ISO-HDLC (SPEC §1), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A Volume file of format 1.`minor` with `chunks` (HEAD to END), laid out as SPEC §3–§4
/// says, with correct CRCs and length: a file the crate's writer would never write.
fn join(minor: u16, chunks: &[([u8; 4], u32, Vec<u8>)]) -> Vec<u8> {
    let mut body = Vec::new();
    for (tag, elem, payload) in chunks {
        let mut c = Vec::new();
        c.extend_from_slice(tag);
        c.extend_from_slice(&elem.to_le_bytes());
        c.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        c.extend_from_slice(&0u32.to_le_bytes());
        c.extend_from_slice(payload);
        let crc = crc32(&c);
        body.extend_from_slice(&c[..20]);
        body.extend_from_slice(&crc.to_le_bytes());
        body.extend_from_slice(payload);
        body.resize(body.len().next_multiple_of(8), 0);
    }
    let mut f = b"\x89BLW\r\n\x1a\n".to_vec();
    f.extend_from_slice(&1u16.to_le_bytes());
    f.extend_from_slice(&minor.to_le_bytes());
    f.extend_from_slice(&1u32.to_le_bytes());
    f.extend_from_slice(&(32 + body.len() as u64).to_le_bytes());
    f.extend_from_slice(&0u32.to_le_bytes());
    let crc = crc32(&f);
    f.extend_from_slice(&crc.to_le_bytes());
    f.extend(body);
    f
}
