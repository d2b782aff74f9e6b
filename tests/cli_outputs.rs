//! No command writes over its own input (the mesh or asset it was given, or a file the
//! import read beside it: glTF buffers and images, MTL libraries, textures), and no two
//! outputs of one command share a file: each is refused before baking with exit code 8, a
//! line naming the file, and nothing written. Real binaries in a temp dir.

mod common;

use std::path::Path;

use common::*;

/// A triangle every baking command accepts (so without the check, each would succeed
/// and replace its input).
const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0.2\nvn 0 0 1\nf 1//1 2//1 3//1\n";

fn refused(dir: &Path, args: &[&str], names: &str) {
    refused_with(dir, args, 8, names);
}

/// Asserts that `args` exits with `code` and a one-line error containing `names`; returns
/// that line.
fn refused_with(dir: &Path, args: &[&str], code: i32, names: &str) -> String {
    let r = run(args, dir);
    assert_eq!(r.code, Some(code), "{args:?}: {}", r.stderr);
    let line = r.error_line().unwrap().to_string();
    assert!(line.contains(names), "{args:?}: {line}");
    line
}

#[test]
fn outputs_never_replace_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.obj"), TRIANGLE).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let tri = sha256(&d.join("tri.obj"));

    // The control: an ordinary bake, twice to the same output (replacing an old output
    // is allowed).
    for _ in 0..2 {
        let r = run(&["voxelize", "tri.obj", "-o", "v.billow", "--res", "8"], d);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
    }
    let vol = sha256(&d.join("v.billow"));

    refused(d, &["voxelize", "tri.obj", "-o", "tri.obj"], "tri.obj");
    refused(
        d,
        &["voxelize", "tri.obj", "-o", "sub/../tri.obj"],
        "is the input",
    );
    #[cfg(unix)]
    {
        std::fs::hard_link(d.join("tri.obj"), d.join("link.obj")).unwrap();
        refused(d, &["voxelize", "tri.obj", "-o", "link.obj"], "link.obj");
    }
    refused(d, &["emptyspace", "v.billow", "-o", "v.billow"], "v.billow");
    refused(d, &["bbcloud", "tri.obj", "-o", "tri.obj"], "tri.obj");
    refused(
        d,
        &[
            "shell", "tri.obj", "v.billow", "-o", "v.billow", "--height", "0.1",
        ],
        "v.billow",
    );
    refused(
        d,
        &["view", "v.billow", "--headless", "--screenshot", "v.billow"],
        "v.billow",
    );
    assert_eq!(sha256(&d.join("tri.obj")), tri);
    assert_eq!(sha256(&d.join("v.billow")), vol);

    image::RgbaImage::new(4, 4).save(d.join("a.png")).unwrap();
    let png = sha256(&d.join("a.png"));
    refused(
        d,
        &["compare", "a.png", "a.png", "--diff", "a.png"],
        "a.png",
    );
    assert_eq!(sha256(&d.join("a.png")), png);
}

#[test]
fn two_outputs_of_one_command_cannot_share_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.obj"), TRIANGLE).unwrap();
    refused(
        d,
        &[
            "voxelize", "tri.obj", "-o", "a.billow", "--ktx2", "a.billow",
        ],
        "--ktx2 a.billow",
    );
    // (`--gltf` takes only a .glb or .gltf name, so -o is named like one here.)
    refused(
        d,
        &["bbcloud", "tri.obj", "-o", "c.glb", "--gltf", "./c.glb"],
        "-o writes that file too",
    );
    assert!(!d.join("a.billow").exists());
    assert!(!d.join("c.glb").exists());
}

#[test]
fn outputs_never_replace_the_files_a_mesh_refers_to() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let oak = repo().join("fixtures/oak");
    let files = [
        "eztree_oak_medium.gltf",
        "eztree_oak_medium.bin",
        "eztree_oak_medium.obj",
        "eztree_oak_medium.mtl",
        "oak_color.png",
        "oak_color_1k.jpg",
    ];
    for f in files {
        std::fs::copy(oak.join(f), d.join(f)).unwrap();
    }
    let before: Vec<String> = files.iter().map(|f| sha256(&d.join(f))).collect();
    let gltf = "eztree_oak_medium.gltf";
    let obj = "eztree_oak_medium.obj";
    refused(
        d,
        &[
            "voxelize",
            gltf,
            "-o",
            "eztree_oak_medium.bin",
            "--res",
            "8",
        ],
        "eztree_oak_medium.gltf reads that file (eztree_oak_medium.bin)",
    );
    refused(
        d,
        &[
            "voxelize",
            gltf,
            "-o",
            "v.billow",
            "--ktx2",
            "oak_color.png",
            "--res",
            "8",
        ],
        "--ktx2 oak_color.png",
    );
    refused(
        d,
        &["voxelize", obj, "-o", "eztree_oak_medium.mtl", "--res", "8"],
        "eztree_oak_medium.mtl",
    );
    // (`--gltf` takes only a .glb or .gltf name, which no file of the oak has; the depfile
    // is the bbcloud output checked here.)
    refused(
        d,
        &[
            "bbcloud",
            obj,
            "-o",
            "c.billow",
            "--depfile",
            "oak_color_1k.jpg",
        ],
        "oak_color_1k.jpg",
    );
    refused(
        d,
        &["view", gltf, "--headless", "--screenshot", "oak_color.png"],
        "eztree_oak_medium.gltf reads that file (oak_color.png)",
    );
    for (f, want) in files.iter().zip(&before) {
        assert_eq!(&sha256(&d.join(f)), want, "{f} changed");
    }
    assert!(!d.join("v.billow").exists());
    assert!(!d.join("c.billow").exists());
}

/// An output that cannot be written (its folder is missing, it names a folder, or a
/// folder output names a file) is refused before baking with exit code 7, and no other
/// output of the command is written either (they used to be, with the error after the
/// bake).
#[test]
fn unwritable_destinations_are_refused_before_baking() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.obj"), TRIANGLE).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let unwritable = |args: &[&str], names: &str| {
        let line = refused_with(d, args, 7, names);
        assert!(line.contains("nothing was written"), "{args:?}: {line}");
        assert!(!d.join("v.billow").exists(), "{args:?} wrote -o");
    };
    let vox = ["voxelize", "tri.obj", "-o", "v.billow", "--res", "8"];
    let with = |extra: &[&'static str]| [&vox[..], extra].concat();
    unwritable(
        &with(&["--ktx2", "missing/v.ktx2"]),
        "missing does not exist",
    );
    unwritable(&with(&["--ktx2", "sub"]), "is a directory");
    unwritable(
        &with(&["--slices", "tri.obj"]),
        "is a file, not a directory",
    );
    unwritable(
        &["voxelize", "tri.obj", "-o", "missing/v.billow"],
        "missing does not exist",
    );
    unwritable(
        &["bbcloud", "tri.obj", "-o", "v.billow", "--atlas", "tri.obj"],
        "is a file, not a directory",
    );
    // The control: the same bake with writable destinations succeeds.
    let r = run(&with(&["--ktx2", "sub/v.ktx2", "--slices", "slices"]), d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(d.join("v.billow").exists() && d.join("sub/v.ktx2").exists());
}
