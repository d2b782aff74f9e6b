//! What a new user and a build engineer broke in the first hour, again (issue 37): messages
//! that named the input instead of the flag or took several lines, "nothing to bake" with
//! a different exit code per command, image outputs written as PNG whatever their name,
//! folders and devices taken for meshes, summaries that said too little. Each test fails
//! on the build before its fix.

mod common;

use std::path::Path;

use common::{repo, run, Run};

/// A closed tetrahedron.
const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

fn oak() -> String {
    repo()
        .join("fixtures/oak/eztree_oak_medium.gltf")
        .display()
        .to_string()
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) {
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// The one `error:` line of a failed run with exit `code`.
fn fails(r: &Run, code: i32) -> String {
    assert_eq!(r.code, Some(code), "{}", r.stderr);
    r.error_line().unwrap().to_string()
}

#[test]
fn usage_errors_take_one_line_and_say_where_to_look() {
    let tmp = tempfile::tempdir().unwrap();
    let o = oak();
    let r = run(&["voxelize", &o, "-o", "x.billow", "--bogus"], tmp.path());
    let line = fails(&r, 2);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(
        line.contains("'--bogus'") && line.contains("'billow voxelize --help'"),
        "{line}"
    );
    let r = run(&["voxelize", "-o", "x.billow"], tmp.path());
    fails(&r, 2);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
}

#[test]
fn out_of_range_values_name_the_flag_in_words() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let o = oak();
    write(d, "t.obj", TETRA);
    let r = run(
        &["voxelize", "t.obj", "-o", "t.billow", "--res", "8", "-q"],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for (args, flag, want) in [
        (
            vec!["voxelize", &o, "-o", "x.billow", "--supersample", "9"],
            "--supersample",
            "(1 to 8)",
        ),
        (
            vec!["voxelize", &o, "-o", "x.billow", "--supersample", "-5"],
            "--supersample",
            "(1 to 8)",
        ),
        (
            vec!["voxelize", &o, "-o", "x.billow", "--res", "-5"],
            "--res",
            "negative",
        ),
        (
            vec!["voxelize", &o, "-o", "x.billow", "--margin", "30"],
            "--margin",
            "(0 to 16 voxels)",
        ),
        (
            vec![
                "voxelize", "t.obj", "-o", "x.billow", "--res", "8", "--mips", "9",
            ],
            "--mips",
            "(1 to 4",
        ),
        (
            vec!["bbcloud", &o, "-o", "x.billow", "--samples", "0"],
            "--samples",
            "(1 to 1000000)",
        ),
        (
            vec!["bbcloud", &o, "-o", "x.billow", "--lods", "12"],
            "--lods",
            "(1 to 8)",
        ),
        (
            vec![
                "emptyspace",
                "t.billow",
                "-o",
                "x.billow",
                "--threshold",
                "256",
            ],
            "--threshold",
            "(0 to 255)",
        ),
    ] {
        let line = fails(&run(&args, d), 8);
        assert!(
            line.starts_with(&format!("error: {flag}: ")),
            "{args:?}: {line}"
        );
        assert!(line.contains(want), "{args:?}: {line}");
        assert!(!line.contains("..="), "Rust range syntax: {line}");
        assert!(
            !line.contains("eztree") && !line.contains("t.obj"),
            "names the input: {line}"
        );
    }
}

/// One rule: a valid mesh without a triangle is "nothing to bake", exit 9, for every
/// baking command.
#[test]
fn nothing_to_bake_is_exit_9_for_every_command() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write(d, "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n");
    write(d, "t.obj", TETRA);
    let r = run(
        &["voxelize", "t.obj", "-o", "t.billow", "--res", "8", "-q"],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for args in [
        vec!["voxelize", "points.obj", "-o", "x.billow"],
        vec!["bbcloud", "points.obj", "-o", "x.billow"],
        vec![
            "shell",
            "points.obj",
            "t.billow",
            "-o",
            "x.billow",
            "--height",
            "0.1",
        ],
    ] {
        let line = fails(&run(&args, d), 9);
        assert!(
            line.contains("points.obj: nothing to bake: "),
            "{args:?}: {line}"
        );
    }
    assert!(!d.join("x.billow").exists());
}

#[test]
fn folders_and_devices_are_not_regular_files() {
    let tmp = tempfile::tempdir().unwrap();
    for p in [tmp.path().display().to_string(), "/dev/zero".into()] {
        let line = fails(&run(&["inspect", &p], tmp.path()), 3);
        assert!(line.contains("not a regular file"), "{line}");
    }
}

/// `--diff x.jpg` writes a JPEG, `--diff x.png` a PNG, anything else is refused before
/// any work.
#[test]
fn image_outputs_follow_their_extension() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let img = image::RgbaImage::from_fn(8, 8, |x, y| {
        image::Rgba([x as u8 * 30, y as u8 * 30, 90, 255])
    });
    img.save(d.join("a.png")).unwrap();
    let img2 = image::RgbaImage::from_fn(8, 8, |x, _| image::Rgba([x as u8 * 20, 40, 90, 200]));
    img2.save(d.join("b.png")).unwrap();
    for (name, magic) in [
        ("d.jpg", &b"\xff\xd8\xff"[..]),
        ("d.JPEG", b"\xff\xd8\xff"),
        ("d.png", b"\x89PNG"),
    ] {
        let r = run(&["compare", "a.png", "b.png", "--diff", name], d);
        assert_eq!(r.code, Some(0), "{name}: {}", r.stderr);
        let bytes = std::fs::read(d.join(name)).unwrap();
        assert!(bytes.starts_with(magic), "{name}: {:?}", &bytes[..4]);
    }
    let line = fails(
        &run(&["compare", "a.png", "b.png", "--diff", "d.bmp"], d),
        2,
    );
    assert!(
        line.contains("--diff d.bmp") && line.contains(".png or .jpg"),
        "{line}"
    );
    assert!(!d.join("d.bmp").exists());
}

#[test]
fn compare_says_an_asset_is_not_an_image() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write(d, "t.obj", TETRA);
    assert_eq!(
        run(
            &["voxelize", "t.obj", "-o", "t.billow", "--res", "8", "-q"],
            d
        )
        .code,
        Some(0)
    );
    image::RgbaImage::new(4, 4).save(d.join("a.png")).unwrap();
    let line = fails(&run(&["compare", "a.png", "t.billow"], d), 5);
    assert!(
        line.contains("t.billow: a billow asset, not an image") && line.contains("billow eval"),
        "{line}"
    );
    assert!(!line.contains("was not recognized"), "{line}");
}

/// The plain summary says what the settings resolved to, what `--normals` decided and
/// why, and what `--prune` saved.
#[test]
fn voxelize_summary_says_what_was_chosen() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let o = oak();
    let r = run(
        &[
            "voxelize", &o, "-o", "v.billow", "--preset", "draft", "--prune",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let e = &r.stderr;
    assert!(
        e.contains("settings: --preset draft: --res 32 (preset), --supersample"),
        "{e}"
    );
    assert!(
        e.contains("normals: moments (--normals auto; coherence 0.")
            && e.contains("thin or fuzzy, such as foliage"),
        "{e}"
    );
    assert!(e.contains("prune: "), "{e}");
    write(d, "t.obj", TETRA);
    let r = run(
        &[
            "voxelize",
            "t.obj",
            "-o",
            "t.billow",
            "--res",
            "16",
            "--normals",
            "on",
        ],
        d,
    );
    assert!(
        r.stderr.contains("normals: mean (--normals on"),
        "{}",
        r.stderr
    );
}

/// eval of a pruned volume names the grid, not the atlas, as the asset's size.
#[test]
fn eval_of_a_pruned_volume_names_its_grid() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let o = oak();
    let r = run(
        &[
            "voxelize", &o, "-o", "v.billow", "--res", "128", "--prune", "-q",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let r = run(
        &[
            "eval", &o, "v.billow", "--views", "+x", "--size", "32x32", "--spp", "1",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let first = r.stdout.lines().next().unwrap_or_default();
    assert!(
        first.contains("(grid 112x128x112, pruned into an "),
        "{first}"
    );
}

#[test]
fn help_says_eval_takes_clouds_too() {
    let tmp = tempfile::tempdir().unwrap();
    let r = run(&["--help"], tmp.path());
    let line = r
        .stdout
        .lines()
        .find(|l| l.trim_start().starts_with("eval"))
        .unwrap_or_default()
        .to_string();
    assert!(line.contains("billboard-cloud"), "{line}");
}
