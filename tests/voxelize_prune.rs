//! `billow voxelize --prune` (issue 26) as the real binary: the pruned asset written
//! straight from the brick-sparse working set equals `voxelize --compress none` (same
//! options) followed by `billow emptyspace` with its other defaults and the same
//! `--compress` (raw bricks, or the default BC7 bricks), byte for byte.

mod common;

use std::path::Path;
use std::time::Duration;

use common::*;

fn oak() -> String {
    repo()
        .join("fixtures/oak/eztree_oak_medium.gltf")
        .display()
        .to_string()
}

fn ok(r: &Run, what: &str) {
    assert_eq!(r.code, Some(0), "{what}: {}", r.stderr);
}

fn billow(dir: &Path, args: &[&str], threads: &str) -> Run {
    run_with(
        args,
        dir,
        Duration::from_secs(300),
        8 << 20,
        &[("RAYON_NUM_THREADS", threads)],
    )
}

/// `voxelize --compress none` + `emptyspace --compress C` against `voxelize --prune
/// --compress C` for one set of options (`C` = `compress`).
fn same_bytes(dir: &Path, opts: &[&str], threads: &str) -> serde_json::Value {
    same_bytes_as(dir, opts, threads, "none")
}

fn same_bytes_as(dir: &Path, opts: &[&str], threads: &str, compress: &str) -> serde_json::Value {
    let oak = oak();
    let mut dense = vec!["voxelize", &oak, "-o", "dense.billow", "--compress", "none"];
    dense.extend_from_slice(opts);
    ok(&billow(dir, &dense, threads), "voxelize");
    let es = [
        "emptyspace",
        "dense.billow",
        "-o",
        "pruned.billow",
        "--compress",
        compress,
    ];
    ok(&billow(dir, &es, threads), "emptyspace");
    let mut direct = vec![
        "voxelize",
        &oak,
        "-o",
        "direct.billow",
        "--compress",
        compress,
        "--prune",
        "--json",
    ];
    direct.extend_from_slice(opts);
    let r = billow(dir, &direct, threads);
    ok(&r, "voxelize --prune");
    let a = std::fs::read(dir.join("pruned.billow")).unwrap();
    let b = std::fs::read(dir.join("direct.billow")).unwrap();
    assert!(
        a == b,
        "{opts:?}: voxelize --prune differs from voxelize + emptyspace"
    );
    serde_json::from_str(&r.stdout).expect("one JSON document")
}

#[test]
fn prune_equals_voxelize_then_emptyspace_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // Pruned into bands (the oak at 64: sides multiples of 8).
    let v = same_bytes(dir.path(), &["--res", "64"], "2");
    let p = &v["prune"];
    assert_eq!(p["kept_whole"], false, "{p}");
    assert!(p["tail_level"].as_u64().unwrap() >= 1, "{p}");
    assert!(p["texel_bytes_after"].as_u64() < p["texel_bytes_before"].as_u64());
    // The default --compress bc: BC7 bricks on the 4×4 grid, the same bytes either way (at
    // 128: at 64 the 4×4 layout saves nothing and the volume is kept whole, which
    // `emptyspace` writes raw for a raw input and `--prune --compress bc` compresses).
    let v = same_bytes_as(dir.path(), &["--res", "128"], "2", "bc");
    assert_eq!(v["prune"]["kept_whole"], false, "{v}");
    let pruned = billow_format::VolumeAsset::read(&dir.path().join("direct.billow")).unwrap();
    assert_eq!(
        pruned.header.params.get("compress").map(String::as_str),
        Some("bc7")
    );
    let d = pruned.level_dims(0);
    assert!(
        d[0].is_multiple_of(4) && d[1].is_multiple_of(4),
        "a BC7 atlas is whole 4×4 blocks: {d:?}"
    );
    // Normals kept, another preset, one thread.
    same_bytes(
        dir.path(),
        &["--res", "48", "--normals", "on", "--combine", "min"],
        "1",
    );
    // The presets whose level-0 normal sums share the colour's alpha sum (opaque) or keep
    // their own (max), with normals.
    same_bytes(
        dir.path(),
        &["--res", "48", "--normals", "on", "--combine", "opaque"],
        "2",
    );
    same_bytes(
        dir.path(),
        &["--res", "40", "--normals", "on", "--combine", "max"],
        "2",
    );
    // Odd sides: emptyspace keeps the volume whole.
    let v = same_bytes(dir.path(), &["--res", "40x24x33"], "2");
    assert_eq!(v["prune"]["kept_whole"], true);
    // An expression keeps dense pyramids; --prune prunes them all the same.
    same_bytes(
        dir.path(),
        &[
            "--res",
            "32",
            "--combine",
            "expr:max(px,nx)",
            "--supersample",
            "1",
        ],
        "2",
    );
}

#[test]
fn prune_refuses_the_outputs_of_the_dense_volume() {
    let dir = tempfile::tempdir().unwrap();
    let oak = oak();
    for extra in [&["--ktx2", "x.ktx2"][..], &["--slices", "sl"][..]] {
        let mut args = vec!["voxelize", &oak, "-o", "x.billow", "--res", "16", "--prune"];
        args.extend_from_slice(extra);
        let r = run(&args, dir.path());
        assert_eq!(r.code, Some(2), "{extra:?}: {}", r.stderr);
        let line = r.error_line().unwrap();
        assert!(line.contains("--prune"), "{line}");
        assert!(!dir.path().join("x.billow").exists());
    }
}

/// The memory limit with `--prune`: its own estimate (in `--json`), normals dropped by
/// `--normals auto` when only they pass the limit (a warning, and the same file as
/// `--normals off`), and a refusal before any work, exit 8, below the estimate. On a
/// torus, whose normals `auto` would keep (the oak's it drops for their coherence). At
/// 48³ `auto` judges on the bake itself (grids under 256³), so a bake that never had
/// normals records no coherence: none is reported, none written.
#[test]
fn prune_memory_limit_drops_optional_normals_then_refuses() {
    let dir = tempfile::tempdir().unwrap();
    billow::procgen::write_obj(
        &billow::procgen::torus(1.0, 0.4, 48, 24),
        &dir.path().join("torus.obj"),
    )
    .unwrap();
    let bake = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "voxelize",
            "torus.obj",
            "-o",
            out,
            "--res",
            "48",
            "--prune",
            "--json",
        ];
        args.extend_from_slice(extra);
        billow(dir.path(), &args, "2")
    };
    let estimate = |r: &Run| -> (u64, serde_json::Value) {
        ok(r, "voxelize --prune");
        let j: serde_json::Value = serde_json::from_str(&r.stdout).expect("one JSON document");
        (j["estimated_peak_memory_bytes"].as_u64().unwrap(), j)
    };
    let (off, _) = estimate(&bake("off.billow", &["--normals", "off"]));
    let (on, _) = estimate(&bake("on.billow", &["--normals", "on"]));
    assert!(off < on, "{off} {on}");
    let gib = |b: u64| format!("{:.9}", b as f64 / (1u64 << 30) as f64);
    let (_, j) = estimate(&bake("kept.billow", &[]));
    assert_eq!(j["normals"], true, "{j}");
    let between = gib((off + on) / 2);
    let (_, j) = estimate(&bake("auto.billow", &["--memory-limit", &between]));
    assert_eq!(j["normals"], false, "{j}");
    // Given up: baked as `--normals off` bakes, the coarse judgement forgotten.
    assert!(j["normal_coherence"].is_null(), "{j}");
    let w = j["warnings"].to_string();
    assert!(
        w.contains("without normals") && w.contains("--memory-limit"),
        "{w}"
    );
    let read = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
    assert!(
        read("auto.billow") == read("off.billow"),
        "auto without normals differs from off"
    );
    let r = bake(
        "below.billow",
        &["--normals", "off", "--memory-limit", &gib(off / 2)],
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("memory"), "{}", r.stderr);
    assert!(!dir.path().join("below.billow").exists());
}
