//! `formats/SPEC.md` is enough to write a reader: `tests/spec_reader/read_billow.py` was
//! written from it alone (its author read no Rust), and here it must agree with the Rust
//! reader — kind, version, chunk sequence, volume dimensions and MIP count, cloud level
//! and billboard counts — on the four frozen fixtures and on real assets the binary bakes
//! now (a volume with normals, its pruned copy with LOD bands, a billboard cloud with
//! normal maps, a shell), and refuse what the Rust reader refuses (a truncated file, a
//! flipped payload byte, a newer major version).
//!
//! Needs `python3` (standard library only); without it the test says it skips.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use billow_format::{read_file, tag_str, CloudAsset};
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
    assert_eq!(paths.len(), 7, "{paths:?}");
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
        assert!(read_file(path).is_err(), "{}", path.display());
    }
    let errors: Vec<&str> = lines.iter().map(|l| l["error"].as_str().unwrap()).collect();
    assert!(errors[0].contains("truncated"), "{errors:?}");
    assert!(errors[1].contains("CRC"), "{errors:?}");
    assert!(errors[2].contains("newer"), "{errors:?}");
}
