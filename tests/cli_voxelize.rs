//! `billow voxelize` and `billow shell` driven as real binaries in a temp dir.

mod common;

use std::path::Path;
use std::time::Duration;

use common::*;

fn oak() -> String {
    repo()
        .join("fixtures/oak/eztree_oak_medium.gltf")
        .to_str()
        .unwrap()
        .to_string()
}

fn voxelize_oak(dir: &Path, out: &str, threads: &str) -> Run {
    run_with(
        &[
            "voxelize",
            &oak(),
            "-o",
            out,
            "--res",
            "40",
            "--normals",
            "--json",
        ],
        dir,
        Duration::from_secs(300),
        8 << 20,
        &[("RAYON_NUM_THREADS", threads)],
    )
}

#[test]
fn bakes_the_oak_with_a_json_summary_and_exports() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        &[
            "voxelize",
            &oak(),
            "-o",
            "oak.billow",
            "--res",
            "32",
            "--json",
            "--ktx2",
            "oak.ktx2",
            "--slices",
            "slices",
            "--slice-level",
            "1",
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("one JSON document");
    let dims: Vec<u64> = v["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .collect();
    assert_eq!(dims.iter().max(), Some(&32));
    assert_eq!(v["mip_count"], 6);
    assert_eq!(v["triangles"], 13806);
    assert!(v["non_empty_voxels"].as_u64().unwrap() > 1000);
    assert!(v["seconds"]["total"].as_f64().unwrap() > 0.0);
    assert!(v["peak_memory_bytes"].as_u64().unwrap() > 0);
    let bytes = std::fs::metadata(dir.path().join("oak.billow"))
        .unwrap()
        .len();
    assert_eq!(v["bytes"].as_u64().unwrap(), bytes);

    let info = run(&["info", "--json", "oak.billow"], dir.path());
    assert_eq!(info.code, Some(0), "{}", info.stderr);
    let i: serde_json::Value = serde_json::from_str(&info.stdout).unwrap();
    assert_eq!(i["header"]["source"]["file_name"], "eztree_oak_medium.gltf");
    assert_eq!(i["header"]["params"]["combine"], "opaque");

    let ktx = std::fs::read(dir.path().join("oak.ktx2")).unwrap();
    assert_eq!(&ktx[..12], b"\xABKTX 20\xBB\r\n\x1A\n");
    let slices = std::fs::read_dir(dir.path().join("slices"))
        .unwrap()
        .count() as u64;
    assert_eq!(
        slices,
        (dims[2] / 2).max(1),
        "one PNG per z-slice of level 1"
    );
    // No temporary files left behind.
    for e in std::fs::read_dir(dir.path()).unwrap().flatten() {
        assert!(
            !e.file_name().to_string_lossy().contains(".tmp"),
            "{:?}",
            e.path()
        );
    }
}

#[test]
fn output_is_byte_identical_with_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let a = voxelize_oak(dir.path(), "one.billow", "1");
    assert_eq!(a.code, Some(0), "{}", a.stderr);
    let b = voxelize_oak(dir.path(), "two.billow", "2");
    assert_eq!(b.code, Some(0), "{}", b.stderr);
    let (x, y) = (
        std::fs::read(dir.path().join("one.billow")).unwrap(),
        std::fs::read(dir.path().join("two.billow")).unwrap(),
    );
    assert!(x == y, "1-thread and 2-thread bakes differ");
}

#[test]
fn absurd_resolutions_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (res, code) in [
        ("0", 8),
        ("100000", 8),
        ("64x0x64", 8),
        ("big", 2),
        ("2048", 8),
    ] {
        // 2048 passes the per-axis check but not the memory estimate (the oak is not cubic,
        // so it is ~1680x2048x1710): refused before allocating. "big" does not parse: a
        // usage error (docs/cli.md: 2 or 8).
        let r = run_limited(
            &["voxelize", &oak(), "-o", "x.billow", "--res", res],
            dir.path(),
            Duration::from_secs(30),
            2 << 20,
        );
        assert_eq!(r.code, Some(code), "--res {res}: {}", r.stderr);
        let line = r.error_line().unwrap();
        assert!(
            line.contains("res") || line.contains("memory"),
            "--res {res}: {line}"
        );
        assert!(!dir.path().join("x.billow").exists());
    }
    let r = run(
        &[
            "voxelize",
            &oak(),
            "-o",
            "x.billow",
            "--combine",
            "expr:max(px, qq)",
        ],
        dir.path(),
    );
    // An expression that does not parse: a usage error.
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("qq"));
}

#[test]
fn failures_leave_existing_outputs_and_inputs_alone() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("keep.billow"), b"precious").unwrap();
    std::fs::write(dir.path().join("broken.gltf"), b"{ not json").unwrap();
    let before = sha256(&dir.path().join("broken.gltf"));
    let r = run(
        &["voxelize", "broken.gltf", "-o", "keep.billow"],
        dir.path(),
    );
    assert_eq!(r.code, Some(4), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("broken.gltf"));
    assert_eq!(
        std::fs::read(dir.path().join("keep.billow")).unwrap(),
        b"precious"
    );
    assert_eq!(sha256(&dir.path().join("broken.gltf")), before);

    let r = run(
        &[
            "voxelize",
            &oak(),
            "-o",
            "no/such/dir/x.billow",
            "--res",
            "8",
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(7), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("x.billow"));
    assert!(!dir.path().join("no").exists());
}

#[test]
fn shell_covers_a_torus_with_a_fur_tile() {
    use billow::procgen::{fur_tile, torus, write_obj};
    let dir = tempfile::tempdir().unwrap();
    let surface = torus(1.0, 0.35, 24, 12);
    write_obj(&surface, &dir.path().join("torus.obj")).unwrap();
    write_obj(&fur_tile(60, 1), &dir.path().join("fur.obj")).unwrap();
    let r = run(
        &[
            "voxelize",
            "fur.obj",
            "-o",
            "fur.billow",
            "--res",
            "16x8x16",
            "--bounds",
            "0,0,0,1,1,1",
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let r = run(
        &[
            "shell",
            "torus.obj",
            "fur.billow",
            "-o",
            "furry.billow",
            "--height",
            "0.15",
            "--tiles",
            "8,3",
            "--json",
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(
        v["prisms"].as_u64().unwrap(),
        surface.triangles.len() as u64
    );
    let info = run(&["info", "--json", "furry.billow"], dir.path());
    assert_eq!(info.code, Some(0), "{}", info.stderr);
    let i: serde_json::Value = serde_json::from_str(&info.stdout).unwrap();
    assert!(i["header"]["params"]["shell"]
        .as_str()
        .unwrap()
        .contains("height=0.15"));

    let bad = run(
        &[
            "shell",
            "torus.obj",
            "fur.billow",
            "-o",
            "x.billow",
            "--height",
            "-1",
        ],
        dir.path(),
    );
    assert_eq!(bad.code, Some(8), "{}", bad.stderr);
    let not_volume = run(
        &[
            "shell",
            "torus.obj",
            "torus.obj",
            "-o",
            "x.billow",
            "--height",
            "1",
        ],
        dir.path(),
    );
    assert_eq!(not_volume.code, Some(4), "{}", not_volume.stderr);
    assert!(not_volume.error_line().unwrap().contains("torus.obj"));
}

#[test]
fn align_rounds_the_grid_up_and_bad_alignments_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        &[
            "voxelize",
            &oak(),
            "-o",
            "a.billow",
            "--res",
            "40",
            "--align",
            "8",
            "--json",
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let dims: Vec<u64> = v["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .collect();
    assert_eq!(dims, [40, 40, 40], "33x40x34 rounded up to multiples of 8");
    // Without --align: `--res N` aligns to the largest of 8, 4, 2, 1 dividing N (so
    // `billow emptyspace` can prune it and the longest axis stays N); an exact size stays.
    for (res, want) in [
        ("40", [40, 40, 40]),
        ("36", [32, 36, 32]),
        ("33", [28, 33, 28]),
        ("33x40x34", [33, 40, 34]),
    ] {
        let r = run(
            &["voxelize", &oak(), "-o", "d.billow", "--res", res, "--json"],
            dir.path(),
        );
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        let dims: Vec<u64> = v["dims"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .collect();
        assert_eq!(dims, want, "--res {res}");
    }
    for bad in ["0", "4096"] {
        let r = run(
            &["voxelize", &oak(), "-o", "b.billow", "--align", bad],
            dir.path(),
        );
        assert_eq!(r.code, Some(8), "--align {bad}: {}", r.stderr);
        assert!(r.error_line().unwrap().contains("--align"));
        assert!(!dir.path().join("b.billow").exists());
    }
}
