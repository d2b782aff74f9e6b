//! `billow inspect` driven as a real binary: the bundled oak, and every file of the shared
//! glTF validator suite and bad-input corpus (each imports, or fails with one clear line).

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::*;

#[test]
fn inspects_the_bundled_oak_as_json() {
    let dir = tempfile::tempdir().unwrap();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let before = sha256(&oak);
    let r = run(&["inspect", "--json", oak.to_str().unwrap()], dir.path());
    assert_eq!(r.code, Some(0), "stderr: {}", r.stderr);
    let v: serde_json::Value =
        serde_json::from_str(&r.stdout).expect("stdout is one JSON document");
    assert_eq!(v["triangles"], 13806);
    assert_eq!(v["dropped_triangles"], 0);
    assert_eq!(v["materials"].as_array().unwrap().len(), 2);
    let leaves = &v["materials"][1];
    assert_eq!(leaves["alpha_mode"], "mask");
    assert_eq!(leaves["double_sided"], true);
    // The buffer and both images, each once, as the glTF names them.
    let files: Vec<&str> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(files.len(), 3, "{files:?}");
    for name in ["eztree_oak_medium.bin", "oak_color_1k.jpg", "oak_color.png"] {
        assert!(
            files.iter().any(|f| f.ends_with(name)),
            "{name} in {files:?}"
        );
    }
    assert_eq!(sha256(&oak), before, "input must never be touched");
}

#[test]
fn inspects_the_oak_obj_as_text() {
    let dir = tempfile::tempdir().unwrap();
    let oak = repo().join("fixtures/oak/eztree_oak_medium.obj");
    let r = run(&["inspect", oak.to_str().unwrap()], dir.path());
    assert_eq!(r.code, Some(0), "stderr: {}", r.stderr);
    assert!(
        r.stdout.contains("13806") || r.stdout.contains("13,806"),
        "{}",
        r.stdout
    );
    // The MTL library and the two textures it names.
    assert!(r.stdout.contains("files read 3"), "{}", r.stdout);
    assert!(r.stdout.contains("eztree_oak_medium.mtl"), "{}", r.stdout);
}

#[test]
fn missing_file_is_exit_3_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(&["inspect", "no such file.gltf"], dir.path());
    assert_eq!(r.code, Some(3), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(line.contains("no such file.gltf"), "{line}");
}

#[test]
fn unknown_extension_is_exit_5() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("mesh.fbx"), b"whatever").unwrap();
    let r = run(&["inspect", "mesh.fbx"], dir.path());
    assert_eq!(r.code, Some(5), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("mesh.fbx"));
}

#[test]
fn an_asset_given_as_a_mesh_names_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo().join("fixtures/format/v1_volume_3x2x1.billow"),
        dir.path().join("tree.billow"),
    )
    .unwrap();
    for cmd in ["inspect", "voxelize"] {
        let mut args = vec![cmd, "tree.billow"];
        if cmd == "voxelize" {
            args.extend(["-o", "out.billow"]);
        }
        let r = run(&args, dir.path());
        assert_eq!(r.code, Some(5), "{cmd}: {}", r.stderr);
        let line = r.error_line().unwrap();
        assert!(
            line.contains("tree.billow") && line.contains("baked billow asset, not a mesh"),
            "{cmd}: {line}"
        );
        assert!(line.contains("billow info"), "{cmd}: {line}");
    }
    assert!(!dir.path().join("out.billow").exists());
}

#[test]
fn strict_turns_a_missing_texture_into_exit_6() {
    let dir = tempfile::tempdir().unwrap();
    let src = repo().join("fixtures/oak");
    for f in [
        "eztree_oak_medium.gltf",
        "eztree_oak_medium.bin",
        "oak_color_1k.jpg",
    ] {
        std::fs::copy(src.join(f), dir.path().join(f)).unwrap();
    }
    // oak_color.png (the leaves) is left out on purpose.
    let lenient = run(&["inspect", "eztree_oak_medium.gltf"], dir.path());
    assert_eq!(lenient.code, Some(0), "{}", lenient.stderr);
    assert!(lenient.stderr.contains("warning:") && lenient.stderr.contains("oak_color.png"));
    let strict = run(
        &["inspect", "--strict", "eztree_oak_medium.gltf"],
        dir.path(),
    );
    assert_eq!(strict.code, Some(6), "{}", strict.stderr);
    assert!(strict.error_line().unwrap().contains("oak_color.png"));
}

fn mesh_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            mesh_files(&p, out);
        } else if let Some(ext) = p.extension().and_then(|e| e.to_str()) {
            if ["gltf", "glb", "obj"].contains(&ext.to_ascii_lowercase().as_str()) {
                out.push(p);
            }
        }
    }
}

/// Every validator-suite and bad-input file: exit 0, or a known non-zero code with exactly
/// one `error:` line naming the file. Never a panic (101), a signal, a hang (10 s) or an
/// allocation beyond 2 GiB of address space.
#[test]
fn every_corpus_file_imports_or_fails_cleanly() {
    let Some(assets) = shared_assets("every_corpus_file_imports_or_fails_cleanly") else {
        return;
    };
    let mut files = Vec::new();
    for sub in [
        "gltf_validator_testsuite/test",
        "bad_inputs",
        "tobj_obj_testfiles/obj",
    ] {
        mesh_files(&assets.join(sub), &mut files);
    }
    assert!(
        files.len() > 350,
        "corpus looks incomplete: {} files",
        files.len()
    );
    let dir = tempfile::tempdir().unwrap();
    let (mut ok, mut failed_cleanly, mut offenders) = (0, 0, Vec::new());
    for f in &files {
        let arg = f.to_str().unwrap();
        let r = run_limited(
            &["inspect", arg],
            dir.path(),
            Duration::from_secs(10),
            2 << 20,
        );
        let name = f.file_name().unwrap().to_str().unwrap();
        match r.code {
            Some(0) => ok += 1,
            Some(3..=8) => match r.error_line() {
                Ok(line) if line.contains(name) => failed_cleanly += 1,
                Ok(line) => {
                    offenders.push(format!("{arg}: error line does not name the file: {line}"))
                }
                Err(e) => offenders.push(format!("{arg}: {e}")),
            },
            other => offenders.push(format!(
                "{arg}: exit {other:?} (timed out: {}), stderr: {}",
                r.timed_out,
                r.stderr.trim()
            )),
        }
    }
    println!(
        "{} files: {ok} imported, {failed_cleanly} refused cleanly",
        files.len()
    );
    assert!(
        offenders.is_empty(),
        "{} offenders:\n{}",
        offenders.len(),
        offenders.join("\n")
    );
}
