//! `make batch` (the Makefile's batch rules) with the depfiles billow writes: on a tiny mesh
//! set (a glTF with a separate .bin and a texture, with foliage; an OBJ + MTL + texture
//! without), one batch makes everything, `make -q batch` is then true, touching one texture
//! rebakes exactly its mesh's outputs, a mesh without foliage is not baked again, and a mesh
//! path with a space is refused loudly. Runs the already built binary (`BILLOW=`), so it
//! never runs cargo; needs GNU make (the test says SKIP without it).

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, SystemTime};

use common::*;

/// A leaf cluster: 6 textured quads (alpha MASK) in a glTF with its buffer in `leaves.bin`
/// and its texture in `leaf.png`.
fn write_leaves(d: &Path) {
    let mut pos: Vec<f32> = Vec::new();
    let mut uv: Vec<f32> = Vec::new();
    let mut idx: Vec<u16> = Vec::new();
    for k in 0..6u16 {
        let a = f32::from(k) * 0.5;
        let (c, s) = (a.cos(), a.sin());
        let y = f32::from(k) * 0.3;
        let base = (pos.len() / 3) as u16;
        for (u, v) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            pos.extend([c * (u - 0.5), y + v * 0.8, s * (u - 0.5)]);
            uv.extend([u, 1.0 - v]);
        }
        idx.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let mut bin: Vec<u8> = Vec::new();
    pos.iter().for_each(|f| bin.extend(f.to_le_bytes()));
    let uv_off = bin.len();
    uv.iter().for_each(|f| bin.extend(f.to_le_bytes()));
    let idx_off = bin.len();
    idx.iter().for_each(|i| bin.extend(i.to_le_bytes()));
    let n = pos.len() / 3;
    std::fs::write(d.join("leaves.bin"), &bin).unwrap();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in pos.chunks(3) {
        for ((l, h), &x) in lo.iter_mut().zip(hi.iter_mut()).zip(p) {
            *l = l.min(x);
            *h = h.max(x);
        }
    }
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
"materials":[{{"name":"leaf","alphaMode":"MASK","doubleSided":true,"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":"leaf.png"}}],
"buffers":[{{"uri":"leaves.bin","byteLength":{len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{uv_off}}},{{"buffer":0,"byteOffset":{uv_off},"byteLength":{uvl}}},{{"buffer":0,"byteOffset":{idx_off},"byteLength":{il}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{n},"type":"VEC3","min":[{l0},{l1},{l2}],"max":[{h0},{h1},{h2}]}},
{{"bufferView":1,"componentType":5126,"count":{n},"type":"VEC2"}},
{{"bufferView":2,"componentType":5123,"count":{ni},"type":"SCALAR"}}]}}"#,
        len = bin.len(),
        uvl = idx_off - uv_off,
        il = bin.len() - idx_off,
        ni = idx.len(),
        l0 = lo[0],
        l1 = lo[1],
        l2 = lo[2],
        h0 = hi[0],
        h1 = hi[1],
        h2 = hi[2],
    );
    std::fs::write(d.join("leaves.gltf"), gltf).unwrap();
    let img = image::RgbaImage::from_fn(16, 16, |x, y| {
        let inside = (x as i32 - 8).pow(2) + (y as i32 - 8).pow(2) < 40;
        image::Rgba([40, 140, 30, if inside { 255 } else { 0 }])
    });
    img.save(d.join("leaf.png")).unwrap();
}

/// A textured box without foliage: box.obj + box.mtl + wood.png.
fn write_box(d: &Path) {
    let mut obj = String::from("mtllib box.mtl\nusemtl wood\n");
    for (x, y, z) in [
        (0, 0, 0),
        (1, 0, 0),
        (1, 1, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (1, 1, 1),
        (0, 1, 1),
    ] {
        obj.push_str(&format!("v {x} {y} {z}\n"));
    }
    obj.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    for f in [
        [1, 4, 3, 2],
        [5, 6, 7, 8],
        [1, 2, 6, 5],
        [2, 3, 7, 6],
        [3, 4, 8, 7],
        [4, 1, 5, 8],
    ] {
        obj.push_str(&format!("f {}/1 {}/2 {}/3 {}/4\n", f[0], f[1], f[2], f[3]));
    }
    std::fs::write(d.join("box.obj"), obj).unwrap();
    std::fs::write(
        d.join("box.mtl"),
        "newmtl wood\nKd 1 1 1\nmap_Kd wood.png\n",
    )
    .unwrap();
    image::RgbaImage::from_pixel(4, 4, image::Rgba([120, 80, 40, 255]))
        .save(d.join("wood.png"))
        .unwrap();
}

fn make(args: &[&str], in_dir: &Path, out_dir: &Path) -> Output {
    Command::new("make")
        .arg("--no-print-directory")
        .arg("-C")
        .arg(repo())
        .args(args)
        .arg(format!("IN_DIR={}", in_dir.display()))
        .arg(format!("OUT_DIR={}", out_dir.display()))
        .arg(format!("BILLOW={}", bin().display()))
        .arg("BATCH_RES=16")
        .arg("BATCH_CLOUD_ARGS=--samples 40 --lods 2 --atlas-size 256")
        .env("RAYON_NUM_THREADS", "2")
        .output()
        .expect("run make")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Sets `p`'s modification time to now (a few ms later than anything older).
fn touch(p: &Path) {
    std::thread::sleep(Duration::from_millis(20));
    let f = std::fs::File::options().append(true).open(p).unwrap();
    f.set_modified(SystemTime::now()).unwrap();
}

/// Whether `make -n`'s `plan` runs a billow command on `mesh` (not the summary's list).
fn bakes(plan: &str, mesh: &str) -> bool {
    plan.lines().any(|l| {
        ["voxelize", "emptyspace", "inspect", "bbcloud"]
            .iter()
            .any(|c| l.contains(&format!("billow {c}")))
            && l.contains(mesh)
    })
}

fn have_make(test: &str) -> bool {
    if Command::new("make").arg("--version").output().is_err() {
        common::skip(test, "GNU make not found");
        return false;
    }
    true
}

#[test]
fn batch_is_up_to_date_after_a_batch_and_rebakes_exactly_what_changed() {
    if !have_make("batch_is_up_to_date_after_a_batch_and_rebakes_exactly_what_changed") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (src, out) = (tmp.path().join("in"), tmp.path().join("out"));
    std::fs::create_dir_all(src.join("tree")).unwrap();
    std::fs::create_dir_all(src.join("crate")).unwrap();
    write_leaves(&src.join("tree"));
    write_box(&src.join("crate"));

    let first = make(&["batch"], &src, &out);
    assert!(first.status.success(), "make batch: {}", text(&first));
    assert!(!text(&first).contains("cargo"), "{}", text(&first));
    for f in [
        "tree/leaves.gltf.volume.billow",
        "tree/leaves.gltf.volume.done",
        "tree/leaves.gltf.pruned.billow",
        "tree/leaves.gltf.inspect.json",
        "tree/leaves.gltf.cloud.billow",
        "tree/leaves.gltf.cloud.done",
        "crate/box.obj.volume.billow",
        "crate/box.obj.cloud.skipped",
        "crate/box.obj.cloud.done",
    ] {
        assert!(out.join(f).is_file(), "{f} missing: {}", text(&first));
    }
    assert!(!out.join("crate/box.obj.cloud.billow").exists());
    let done = std::fs::read_to_string(out.join("crate/box.obj.cloud.done")).unwrap();
    assert!(done.starts_with("skipped: no foliage"), "{done}");
    // The summary counts what happened.
    assert!(
        text(&first).contains(&format!(
            "batch: 2 meshes under {}: 2 baked (1 without foliage: no cloud), 0 skipped (nothing to bake), 0 failed, ",
            src.display()
        )),
        "{}",
        text(&first)
    );
    // The depfiles name every file the bake read.
    let dep = std::fs::read_to_string(out.join("tree/leaves.gltf.volume.done.d")).unwrap();
    for f in ["leaves.gltf", "leaves.bin", "leaf.png"] {
        assert!(dep.contains(f), "{dep}");
    }
    let dep = std::fs::read_to_string(out.join("crate/box.obj.volume.done.d")).unwrap();
    for f in ["box.obj", "box.mtl", "wood.png"] {
        assert!(dep.contains(f), "{dep}");
    }

    // Up to date: `make -q` says so, and a second batch runs nothing (no bbcloud for the
    // mesh without foliage either).
    let q = make(&["-q", "batch"], &src, &out);
    assert_eq!(q.status.code(), Some(0), "make -q batch: {}", text(&q));
    let again = make(&["batch"], &src, &out);
    assert!(again.status.success());
    assert!(
        !["voxelize", "emptyspace", "bbcloud", "inspect"]
            .iter()
            .any(|c| text(&again).contains(c)),
        "nothing to do, but: {}",
        text(&again)
    );

    // A touched texture rebakes exactly the mesh that reads it, each of its outputs.
    touch(&src.join("crate/wood.png"));
    let n = make(&["-n", "batch"], &src, &out);
    let plan = text(&n);
    assert!(!bakes(&plan, "leaves.gltf"), "only the box: {plan}");
    for what in ["voxelize", "emptyspace", "inspect", "bbcloud"] {
        assert!(
            plan.lines()
                .any(|l| l.contains(what) && l.contains("box.obj")),
            "{what} of box.obj: {plan}"
        );
    }
    let re = make(&["batch"], &src, &out);
    assert!(re.status.success(), "{}", text(&re));
    assert_eq!(make(&["-q", "batch"], &src, &out).status.code(), Some(0));

    // The glTF's buffer and the .mtl count too.
    touch(&src.join("tree/leaves.bin"));
    let plan = text(&make(&["-n", "batch"], &src, &out));
    assert!(
        bakes(&plan, "leaves.gltf") && !bakes(&plan, "box.obj"),
        "{plan}"
    );
    make(&["batch"], &src, &out);
    touch(&src.join("crate/box.mtl"));
    let plan = text(&make(&["-n", "batch"], &src, &out));
    assert!(
        bakes(&plan, "box.obj") && !bakes(&plan, "leaves.gltf"),
        "{plan}"
    );

    // The same folder with a trailing slash is the same batch (and up to date).
    make(&["batch"], &src, &out);
    let slash = format!("{}/", src.display());
    let q = Command::new("make")
        .args(["--no-print-directory", "-q", "-C"])
        .arg(repo())
        .arg("batch")
        .arg(format!("IN_DIR={slash}"))
        .arg(format!("OUT_DIR={}", out.display()))
        .arg(format!("BILLOW={}", bin().display()))
        .arg("BATCH_RES=16")
        .output()
        .unwrap();
    assert_eq!(q.status.code(), Some(0), "IN_DIR={slash}: {}", text(&q));

    // A mesh path with a space: refused with a message naming it, nothing baked.
    std::fs::create_dir_all(src.join("odd dir")).unwrap();
    write_box(&src.join("odd dir"));
    let spaced = make(&["batch"], &src, &out);
    assert!(!spaced.status.success());
    assert!(
        text(&spaced).contains("odd dir/box.obj"),
        "{}",
        text(&spaced)
    );
    assert!(!out.join("odd dir").exists());
}

/// A texture missing at bake time: the mesh bakes with its warning kept in a log and
/// counted, the batch is up to date while the texture stays missing, and restoring it
/// (with an old modification time, as a backup restores it) rebakes the mesh. With
/// BATCH_STRICT=1 the same mesh fails instead, and the batch says so.
#[test]
fn a_restored_texture_rebakes_and_warnings_are_kept() {
    if !have_make("a_restored_texture_rebakes_and_warnings_are_kept") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (src, out) = (tmp.path().join("in"), tmp.path().join("out"));
    std::fs::create_dir_all(&src).unwrap();
    write_box(&src);
    let texture = std::fs::read(src.join("wood.png")).unwrap();
    let old = std::fs::metadata(src.join("wood.png"))
        .unwrap()
        .modified()
        .unwrap();
    std::fs::remove_file(src.join("wood.png")).unwrap();

    let first = make(&["batch"], &src, &out);
    assert!(first.status.success(), "{}", text(&first));
    let log = std::fs::read_to_string(out.join("box.obj.volume.log")).unwrap();
    assert!(log.contains("wood.png"), "{log}");
    assert!(
        text(&first).contains("1 with warnings")
            && text(&first).contains("warned:  box.obj")
            && text(&first).contains("wood.png"),
        "{}",
        text(&first)
    );
    // Up to date while the texture is missing.
    assert_eq!(make(&["-q", "batch"], &src, &out).status.code(), Some(0));

    // Restored with its old time: out of date, and the rebake has no warning left.
    std::fs::write(src.join("wood.png"), &texture).unwrap();
    std::fs::File::options()
        .append(true)
        .open(src.join("wood.png"))
        .unwrap()
        .set_modified(old)
        .unwrap();
    assert_eq!(
        make(&["-q", "batch"], &src, &out).status.code(),
        Some(1),
        "a restored texture must rebake"
    );
    let re = make(&["batch"], &src, &out);
    assert!(re.status.success(), "{}", text(&re));
    assert!(text(&re).contains("voxelize"), "{}", text(&re));
    assert!(!out.join("box.obj.volume.log").exists());
    assert!(!text(&re).contains("wood.png"), "{}", text(&re));
    assert_eq!(make(&["-q", "batch"], &src, &out).status.code(), Some(0));

    // Strict: the missing texture fails the mesh (exit 6 from billow), the batch fails.
    std::fs::remove_file(src.join("wood.png")).unwrap();
    let strict = make(&["batch", "BATCH_STRICT=1"], &src, &out);
    assert!(!strict.status.success(), "{}", text(&strict));
    assert!(out.join("box.obj.volume.failed").is_file());
    assert!(text(&strict).contains("1 failed"), "{}", text(&strict));
}

/// Folders the batch cannot use are refused, not silently "nothing to be done"; a mesh
/// with nothing to bake is skipped with its reason; a broken mesh fails alone, is named in
/// the summary and fails the batch; engine-ready copies are written on request.
#[test]
fn batch_refuses_bad_folders_skips_empty_meshes_and_isolates_failures() {
    if !have_make("batch_refuses_bad_folders_skips_empty_meshes_and_isolates_failures") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (src, out) = (tmp.path().join("in"), tmp.path().join("out"));
    let missing = make(&["batch"], &tmp.path().join("nope"), &out);
    assert!(!missing.status.success());
    assert!(
        text(&missing).contains("is not a folder"),
        "{}",
        text(&missing)
    );
    std::fs::create_dir_all(src.join("empty")).unwrap();
    std::fs::write(src.join("empty/readme.txt"), "no meshes here").unwrap();
    let empty = make(&["batch"], &src.join("empty"), &out);
    assert!(!empty.status.success());
    assert!(text(&empty).contains("no meshes"), "{}", text(&empty));
    assert!(!out.exists(), "nothing may be written");

    std::fs::create_dir_all(src.join("set")).unwrap();
    write_leaves(&src.join("set"));
    std::fs::write(
        src.join("set/points.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n",
    )
    .unwrap();
    std::fs::write(src.join("set/broken.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    let set = src.join("set");
    let r = make(&["batch", "BATCH_KTX2=1", "BATCH_GLB=1"], &set, &out);
    let t = text(&r);
    assert!(!r.status.success(), "a failed mesh fails the batch: {t}");
    assert!(
        t.contains(&format!(
            "batch: 3 meshes under {}: 1 baked (0 without foliage: no cloud), 1 skipped (nothing to bake), 1 failed",
            set.display()
        )),
        "{t}"
    );
    assert!(t.contains("failed:  broken.obj: error: "), "{t}");
    assert!(
        t.contains("skipped: points.obj: the scene has no triangles"),
        "{t}"
    );
    for f in [
        "leaves.gltf.volume.billow",
        "leaves.gltf.volume.ktx2",
        "leaves.gltf.cloud.glb",
        "leaves.gltf.pruned.billow",
        "points.obj.volume.done",
        "points.obj.volume.skipped",
        "broken.obj.volume.failed",
    ] {
        assert!(out.join(f).is_file(), "{f}: {t}");
    }
    assert!(!out.join("points.obj.volume.billow").exists());
    assert!(!out.join("broken.obj.volume.done").exists());
    // The failed mesh is tried again; the others are up to date.
    let again = make(&["-n", "batch", "BATCH_KTX2=1", "BATCH_GLB=1"], &set, &out);
    let plan = text(&again);
    let runs = |mesh: &str| {
        plan.lines()
            .any(|l| l.contains("billow voxelize") && l.contains(mesh))
    };
    assert!(
        runs("broken.obj") && !runs("leaves.gltf") && !runs("points.obj"),
        "{plan}"
    );
}
