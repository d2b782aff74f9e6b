//! Parameters that used to run away or give a result without a word (docs/cli.md,
//! "Estimates and limits", "Silent results"): oversized cloud atlases and eval references
//! are refused up front with exit 8 and the estimate; a slow plane search is announced with
//! its expected time; `--bounds` that miss the mesh warn; `--ao-distance` without
//! `--bake ao` is refused; eval warns when the source is not the one the asset was baked
//! from; and the recorded source hash covers the textures and material libraries read.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::*;

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0.2\nvn 0 0 1\nf 1//1 2//1 3//1\n";

fn oak_dir(d: &Path) {
    let oak = repo().join("fixtures/oak");
    for f in [
        "eztree_oak_medium.gltf",
        "eztree_oak_medium.bin",
        "oak_color.png",
        "oak_color_1k.jpg",
    ] {
        std::fs::copy(oak.join(f), d.join(f)).unwrap();
    }
}

/// Runs `args`, asserting exit 8, a message containing each of `needles`, no output file
/// `out`, and that it took less than `within` (the refusal comes before the heavy work).
fn refused_fast(d: &Path, args: &[&str], needles: &[&str], out: &str, within: Duration) {
    let t = Instant::now();
    let r = run(args, d);
    let took = t.elapsed();
    assert_eq!(r.code, Some(8), "{args:?}: {}", r.stderr);
    let line = r.error_line().unwrap();
    for n in needles {
        assert!(line.contains(n), "{args:?}: {line}");
    }
    assert!(!d.join(out).exists(), "{args:?} wrote {out}");
    assert!(took < within, "{args:?} took {took:?} before refusing");
}

#[test]
fn oversized_cloud_atlases_and_eval_references_are_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    oak_dir(d);
    let oak = "eztree_oak_medium.gltf";
    // Today: 112 s at 5.2 GB RSS and a 1.73 GB file.
    refused_fast(
        d,
        &["bbcloud", oak, "-o", "c.billow", "--atlas-size", "16384"],
        &["--atlas-size", "MiB", "limit of 1024 MiB"],
        "c.billow",
        Duration::from_secs(20),
    );
    refused_fast(
        d,
        &["bbcloud", oak, "-o", "c.billow", "--texel-density", "1e30"],
        &["--texel-density", "MiB"],
        "c.billow",
        Duration::from_secs(20),
    );
    std::fs::write(d.join("tri.obj"), TRIANGLE).unwrap();
    let r = run(&["voxelize", "tri.obj", "-o", "v.billow", "--res", "8"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    refused_fast(
        d,
        &[
            "eval",
            "tri.obj",
            "v.billow",
            "--size",
            "4096x4096",
            "--spp",
            "256",
            "--out",
            "ev",
        ],
        &["--size", "reference samples", "min"],
        "ev",
        Duration::from_secs(5),
    );
}

#[test]
fn a_slow_plane_search_is_announced_with_its_expected_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    oak_dir(d);
    for flag in ["--epsilon", "--max-extent"] {
        // Today: 73 s (--epsilon) and 60 s (--max-extent) without a word.
        let mut c = Command::new(bin())
            .args([
                "bbcloud",
                "eztree_oak_medium.gltf",
                "-o",
                "c.billow",
                flag,
                "1e-30",
            ])
            .current_dir(d)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut line = String::new();
        let t = Instant::now();
        BufReader::new(c.stderr.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let took = t.elapsed();
        let _ = c.kill();
        let _ = c.wait();
        assert!(
            line.starts_with("warning:") && line.contains("roughly") && line.contains(" s "),
            "{flag}: {line:?}"
        );
        assert!(line.contains("billboards"), "{line}");
        assert!(
            took < Duration::from_secs(20),
            "{flag}: warned after {took:?}"
        );
    }
}

#[test]
fn silent_results_now_say_something() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.obj"), TRIANGLE).unwrap();

    // --bounds that miss the mesh: a warning, also in --json; the volume is still written.
    let r = run(
        &[
            "voxelize",
            "tri.obj",
            "-o",
            "v.billow",
            "--res",
            "8",
            "--bounds",
            "5,5,5,6,6,6",
            "--json",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stderr.contains("warning:") && r.stderr.contains("misses the mesh"),
        "{}",
        r.stderr
    );
    let json: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(json["non_empty_voxels"], 0);
    assert!(json["warnings"].to_string().contains("misses the mesh"));
    // Bounds around the mesh: no warning.
    let r = run(
        &[
            "voxelize",
            "tri.obj",
            "-o",
            "v.billow",
            "--res",
            "8",
            "--bounds",
            "0,0,0,1,1,1",
        ],
        d,
    );
    assert_eq!(r.code, Some(0));
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);

    // --ao-distance without --bake ao: refused before the bake.
    let r = run(
        &[
            "voxelize",
            "tri.obj",
            "-o",
            "ao.billow",
            "--ao-distance",
            "1",
        ],
        d,
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.contains("--ao-distance") && line.contains("--bake ao"),
        "{line}"
    );
    assert!(!d.join("ao.billow").exists());

    // eval with another source than the asset's: a warning and a JSON note; none with the
    // right one.
    let r = run(&["voxelize", "tri.obj", "-o", "t.billow", "--res", "8"], d);
    assert_eq!(r.code, Some(0));
    std::fs::write(
        d.join("other.obj"),
        "v 0 0 0\nv 2 0 0\nv 0 2 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
    )
    .unwrap();
    let eval = |src: &str| {
        run(
            &[
                "eval",
                src,
                "t.billow",
                "--views=+z",
                "--distances",
                "1",
                "--size",
                "16x16",
                "--spp",
                "1",
                "--json",
            ],
            d,
        )
    };
    let wrong = eval("other.obj");
    assert_eq!(wrong.code, Some(0), "{}", wrong.stderr);
    assert!(
        wrong.stderr.contains("warning:") && wrong.stderr.contains("is not the source"),
        "{}",
        wrong.stderr
    );
    let json: serde_json::Value = serde_json::from_str(&wrong.stdout).unwrap();
    assert!(json["notes"].to_string().contains("is not the source"));
    let right = eval("tri.obj");
    assert_eq!(right.code, Some(0));
    assert!(
        !right.stderr.contains("is not the source"),
        "{}",
        right.stderr
    );
}

/// The header's source hash covers the files read beside the mesh: a changed texture or
/// material library changes it (and eval then notices).
#[test]
fn the_source_hash_covers_textures_and_material_libraries() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("t.obj"),
        format!("mtllib t.mtl\nusemtl m\nvt 0 0\nvt 1 0\nvt 0 1\n{TRIANGLE}")
            .replace("f 1//1 2//1 3//1", "f 1/1/1 2/2/1 3/3/1"),
    )
    .unwrap();
    std::fs::write(d.join("t.mtl"), "newmtl m\nKd 1 1 1\nmap_Kd t.png\n").unwrap();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 10, 10, 255]))
        .save(d.join("t.png"))
        .unwrap();
    let source = |out: &str| -> serde_json::Value {
        let r = run(&["voxelize", "t.obj", "-o", out, "--res", "8"], d);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let info = run(&["info", out, "--json"], d);
        let v: serde_json::Value = serde_json::from_str(&info.stdout).unwrap();
        v["header"]["source"].clone()
    };
    let a = source("a.billow");
    assert_eq!(a["file_name"], "t.obj");
    let sizes: u64 = ["t.obj", "t.mtl", "t.png"]
        .iter()
        .map(|f| std::fs::metadata(d.join(f)).unwrap().len())
        .sum();
    assert_eq!(a["bytes"], sizes, "bytes counts every file read");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([10, 200, 10, 255]))
        .save(d.join("t.png"))
        .unwrap();
    let b = source("b.billow");
    assert_ne!(a["sha256"], b["sha256"], "a new texture, a new source hash");
    std::fs::write(d.join("t.mtl"), "newmtl m\nKd 1 1 0.5\nmap_Kd t.png\n").unwrap();
    let c = source("c.billow");
    assert_ne!(b["sha256"], c["sha256"], "a new .mtl, a new source hash");
    // eval with the changed source against the old asset notices.
    let r = run(
        &[
            "eval",
            "t.obj",
            "a.billow",
            "--views=+z",
            "--distances",
            "1",
            "--size",
            "8x8",
            "--spp",
            "1",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stderr.contains("is not the source"), "{}", r.stderr);
}
