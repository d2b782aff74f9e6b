//! What a new user broke in one afternoon (issue 24): crashes, closed pipes, real
//! exporters' OBJ files, exit codes that disagreed with docs/cli.md, unbounded inputs and
//! interface details. Each test fails on the build before its fix.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use common::{bin, repo, run, run_limited};

/// A closed tetrahedron.
const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) {
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// A small volume asset baked from [`TETRA`] in `dir`.
fn tiny_asset(dir: &Path) -> String {
    write(dir, "t.obj", TETRA);
    let r = run(
        &["voxelize", "t.obj", "-o", "t.billow", "--res", "8", "-q"],
        dir,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    "t.billow".into()
}

/// Runs billow with stdout a pipe whose reading end is already closed: every write to
/// stdout fails with EPIPE. Returns (exit code, stderr).
fn with_closed_stdout(args: &[&str], dir: &Path) -> (Option<i32>, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(bin())
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_long_flat_combine_expression_is_refused_not_a_stack_overflow() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TETRA);
    // 20,000 terms: nesting depth 1, but a left-deep tree 20,000 nodes high. Before the
    // fix this overflowed the stack (SIGABRT, no exit code).
    let expr = format!("expr:px{}", "+px".repeat(20_000));
    let r = run_limited(
        &[
            "voxelize",
            "t.obj",
            "-o",
            "x.billow",
            "--res",
            "8",
            "--combine",
            &expr,
        ],
        dir.path(),
        Duration::from_secs(60),
        4 << 20,
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.contains("--combine") && line.contains("1024 tokens"),
        "{line}"
    );
    assert!(!dir.path().join("x.billow").exists());
    // A long but reasonable expression still works.
    let expr = format!("expr:(px{})/100", "+px".repeat(99));
    let r = run(
        &[
            "voxelize",
            "t.obj",
            "-o",
            "x.billow",
            "--res",
            "8",
            "--combine",
            &expr,
        ],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

#[test]
fn a_closed_stdout_ends_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let asset = tiny_asset(d);
    // Before the fix: a panic ("failed printing to stdout: Broken pipe"), exit 101.
    for args in [
        vec!["info", asset.as_str()],
        vec!["info", asset.as_str(), "--json"],
        vec!["inspect", "t.obj"],
        vec!["inspect", "t.obj", "--json"],
    ] {
        let (code, stderr) = with_closed_stdout(&args, d);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
        assert!(stderr.is_empty(), "{args:?}: {stderr}");
    }
    // A command with outputs still writes them.
    let (code, stderr) = with_closed_stdout(
        &[
            "voxelize", "t.obj", "-o", "y.billow", "--res", "8", "--json",
        ],
        d,
    );
    assert_eq!(code, Some(0), "{stderr}");
    assert!(d.join("y.billow").is_file());
}

#[test]
fn a_full_stdout_is_an_output_error() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        common::skip(
            "a_full_stdout_is_an_output_error",
            "no /dev/full on this system",
        );
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let asset = tiny_asset(dir.path());
    let out = Command::new(bin())
        .args(["info", &asset])
        .current_dir(dir.path())
        .stdout(full)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(7), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: stdout: cannot write"),
        "{stderr}"
    );
}

#[test]
fn real_exporters_obj_files_import() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 3ds Max: a Latin-1 '©' in the header comment (not UTF-8), a bare `g`, a bare
    // `usemtl`. Before: "parse error: read error" (exit 4).
    let mut max = b"# 3ds Max Wavefront OBJ Exporter v0.97b - \xa9 2007 guruware\n".to_vec();
    max.extend_from_slice(b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\ng\r\nusemtl\r\nf 1 2 3\r\n");
    write(d, "max.obj", &max);
    let r = run(&["inspect", "max.obj", "--json"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(j["triangles"], 1, "{}", r.stdout);

    // Blender 2.61: an unnamed `newmtl`; also a texture statement without a file.
    // Before: the library was dropped with "material parse error".
    write(
        d,
        "b.obj",
        "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl\nf 1 2 3\nusemtl leaf\nf 1 2 4\n",
    );
    write(
        d,
        "b.mtl",
        "# Blender MTL File\nnewmtl\nKd 0.8 0.1 0.1\nmap_Kd\n\nnewmtl leaf\nKd 0.1 0.8 0.1\nd 0.5\n",
    );
    let r = run(&["inspect", "b.obj", "--json", "--strict"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let j: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let names: Vec<&str> = j["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"(unnamed)") && names.contains(&"leaf"),
        "{names:?}"
    );
}

#[test]
fn malformed_obj_and_mtl_lines_are_named_with_their_line_number() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "bad.obj",
        "# header\nv 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n",
    );
    let r = run(&["inspect", "bad.obj"], d);
    assert_eq!(r.code, Some(4), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.contains("bad.obj") && line.contains("line 4") && line.contains("v 1 x 0"),
        "{line}"
    );
    // A malformed MTL: a warning (the default material is used) naming the library, the
    // line and the problem; an error under --strict.
    write(
        d,
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    write(d, "m.mtl", "newmtl a\nKd 1 0 0\nKd x y z\n");
    let r = run(&["inspect", "m.obj"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stderr.contains("m.mtl") && r.stderr.contains("line 3") && r.stderr.contains("Kd x y z"),
        "{}",
        r.stderr
    );
    let r = run(&["inspect", "m.obj", "--strict"], d);
    assert_eq!(r.code, Some(6), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("line 3"), "{}", r.stderr);
}

#[test]
fn gltf_1_is_unsupported_not_malformed() {
    let dir = tempfile::tempdir().unwrap();
    // The shape of a glTF 1.0 file: objects where 2.0 has arrays. Before: a JSON type
    // error, exit 4.
    write(
        dir.path(),
        "old.gltf",
        r#"{"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}}, "scene": "s",
            "scenes": {"s": {"nodes": []}}}"#,
    );
    let r = run(&["inspect", "old.gltf"], dir.path());
    assert_eq!(r.code, Some(5), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.contains("old.gltf") && line.contains("glTF version 1.0"),
        "{line}"
    );
}

#[test]
fn no_foliage_exits_nothing_to_bake() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TETRA);
    let r = run(&["bbcloud", "t.obj", "-o", "x.billow"], dir.path());
    assert_eq!(r.code, Some(9), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("no foliage"));
}

#[test]
fn the_resolution_limit_is_the_documented_one() {
    let doc = std::fs::read_to_string(repo().join("docs/cli.md")).unwrap();
    let max = billow::voxelize::MAX_AXIS;
    assert!(
        doc.contains(&format!("each axis 1–{max}")),
        "docs/cli.md must give --res axes 1–{max}"
    );
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TETRA);
    let over = (max + 1).to_string();
    let r = run(
        &["voxelize", "t.obj", "-o", "x.billow", "--res", &over],
        dir.path(),
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains(&max.to_string()));
    let help = run(&["voxelize", "--help"], dir.path());
    assert!(
        help.stdout.contains(&format!("1–{max}")),
        "voxelize --help gives --res's range: {}",
        help.stdout
    );
}

#[cfg(unix)]
#[test]
fn non_regular_inputs_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    if !Path::new("/dev/zero").exists() {
        common::skip(
            "non_regular_inputs_are_refused_before_reading",
            "no /dev/zero on this system",
        );
        return;
    }
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.obj")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.gltf")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.billow")).unwrap();
    // Before: read until killed (4 GB RSS). The memory limit (1 GiB of address space)
    // and the timeout make a regression fail instead of eating the machine.
    for args in [
        vec!["inspect", "zero.obj"],
        vec!["inspect", "zero.gltf"],
        vec!["voxelize", "zero.obj", "-o", "x.billow"],
        vec!["info", "zero.billow"],
    ] {
        let r = run_limited(&args, d, Duration::from_secs(30), 1 << 20);
        assert_eq!(r.code, Some(3), "{args:?}: {}", r.stderr);
        let line = r.error_line().unwrap();
        assert!(
            line.contains("zero.") && line.contains("not a regular file"),
            "{line}"
        );
    }
    // A FIFO: opening it would block until a writer comes; it is refused first.
    let fifo = d.join("pipe.obj");
    match Command::new("mkfifo").arg(&fifo).status() {
        Ok(s) if s.success() => {
            let r = run_limited(
                &["inspect", "pipe.obj"],
                d,
                Duration::from_secs(30),
                1 << 20,
            );
            assert!(!r.timed_out, "blocked on the FIFO");
            assert_eq!(r.code, Some(3), "{}", r.stderr);
            assert!(r.error_line().unwrap().contains("not a regular file"));
        }
        _ => common::skip(
            "non_regular_inputs_are_refused_before_reading",
            "mkfifo not available; FIFO case not run",
        ),
    }
}

#[test]
fn text_output_ends_with_a_newline() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TETRA);
    let r = run(&["inspect", "t.obj"], dir.path());
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.ends_with('\n'), "{:?}", r.stdout);
    let r = run(&["view", "t.obj", "--print-passes"], dir.path());
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.ends_with('\n'), "{:?}", r.stdout);
}

#[test]
fn print_passes_with_json_prints_json() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TETRA);
    let r = run(&["view", "t.obj", "--print-passes", "--json"], dir.path());
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let j: serde_json::Value =
        serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("not JSON ({e}): {}", r.stdout));
    let passes = j["passes"].as_array().expect("a passes array");
    assert!(!passes.is_empty());
    let text = run(&["view", "t.obj", "--print-passes"], dir.path());
    let listed: Vec<&str> = passes.iter().map(|p| p.as_str().unwrap()).collect();
    assert_eq!(text.stdout.lines().collect::<Vec<_>>(), listed);
}

/// Every numeric flag's help gives its range (a default alone does not say what is
/// accepted); `view --help` lists the window's keys.
#[test]
fn help_gives_ranges_and_keys() {
    let dir = tempfile::tempdir().unwrap();
    let help = |cmd: &str| {
        let r = run(&[cmd, "--help"], dir.path());
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        r.stdout
    };
    // Every range below is the library's constant (the one the library refuses by), so the
    // help and the library cannot disagree.
    use billow::bbcloud::{
        LARGEST_MAX_EXTENT, MAX_ATLAS_SIZE, MAX_EPSILON, MAX_LODS, MAX_MIP_LEVELS, MAX_SAMPLES,
        MAX_SUPERSAMPLE as BB_SUPERSAMPLE, MIN_ATLAS_SIZE, UNIT_RANGE,
    };
    let unit = format!("[{}, {}]", UNIT_RANGE.start(), UNIT_RANGE.end());
    let bb_ranges = [
        ("--epsilon", format!("(0, {MAX_EPSILON}]")),
        ("--samples", format!("1–{MAX_SAMPLES}")),
        ("--lods", format!("1–{MAX_LODS}")),
        ("--view-strength", unit.clone()),
        ("--mip-levels", format!("1–{MAX_MIP_LEVELS}")),
        ("--atlas-size", format!("{MIN_ATLAS_SIZE}–{MAX_ATLAS_SIZE}")),
        ("--texel-density", "> 0".to_string()),
        ("--ambient", unit),
        ("--supersample", format!("1–{BB_SUPERSAMPLE}")),
        ("--max-extent", format!("at most {LARGEST_MAX_EXTENT}")),
    ];
    let bb = help("bbcloud");
    for (flag, range) in &bb_ranges {
        let entry = flag_help(&bb, flag);
        assert!(entry.contains(range.as_str()), "bbcloud {flag}: {entry}");
    }
    use billow::emptyspace::{MAX_DEPTH, MIN_CELL_COST, MIN_GAIN_RANGE};
    let es = help("emptyspace");
    for (flag, range) in [
        ("--threshold", format!("0–{}", u8::MAX)),
        ("--max-depth", format!("0–{MAX_DEPTH}")),
        (
            "--min-gain",
            format!("[{}, {})", MIN_GAIN_RANGE.start, MIN_GAIN_RANGE.end),
        ),
        ("--cell-cost", format!("≥ {MIN_CELL_COST}")),
    ] {
        let entry = flag_help(&es, flag);
        assert!(entry.contains(range.as_str()), "emptyspace {flag}: {entry}");
    }
    let vx = help("voxelize");
    // The library's limits, which the help prints from the same constants.
    use billow::voxelize::{MAX_AO_RAYS, MAX_AXIS, MAX_MARGIN, MAX_SUPERSAMPLE};
    let (margin, axis) = (format!("0–{MAX_MARGIN}"), format!("1–{MAX_AXIS}"));
    let (samples, rays) = (format!("1–{MAX_SUPERSAMPLE}"), format!("1–{MAX_AO_RAYS}"));
    for (flag, range) in [
        ("--res", axis.as_str()),
        ("--supersample", samples.as_str()),
        ("--mips", "1–"),
        ("--margin", margin.as_str()),
        ("--align", axis.as_str()),
        ("--ao-rays", rays.as_str()),
        ("--ao-distance", "> 0"),
    ] {
        let entry = flag_help(&vx, flag);
        assert!(entry.contains(range), "voxelize {flag}: {entry}");
    }
    let view = help("view");
    for key in ["Esc", "W ", "drag", "wheel"] {
        assert!(view.contains(key), "view --help lists the key {key:?}");
    }
}

/// The help text of one flag (from its line to the next flag's: `  -x, --long` or
/// `      --long`, whichever comes first).
fn flag_help<'a>(help: &'a str, flag: &str) -> &'a str {
    let start = help
        .find(&format!("      {flag} "))
        .or_else(|| help.find(&format!(", {flag} ")))
        .unwrap_or_else(|| panic!("{flag} not in help"));
    let rest = &help[start + flag.len() + 6..];
    let end = ["\n  -", "\n      -"]
        .iter()
        .filter_map(|next| rest.find(next))
        .min()
        .unwrap_or(rest.len());
    &help[start..start + flag.len() + 6 + end]
}
