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

#[test]
fn batch_is_up_to_date_after_a_batch_and_rebakes_exactly_what_changed() {
    if Command::new("make").arg("--version").output().is_err() {
        common::skip(
            "batch_is_up_to_date_after_a_batch_and_rebakes_exactly_what_changed",
            "GNU make not found",
        );
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
    // The volume's depfile names every file the bake read.
    let dep = std::fs::read_to_string(out.join("tree/leaves.gltf.volume.billow.d")).unwrap();
    for f in ["leaves.gltf", "leaves.bin", "leaf.png"] {
        assert!(dep.contains(f), "{dep}");
    }
    let dep = std::fs::read_to_string(out.join("crate/box.obj.volume.billow.d")).unwrap();
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
        !text(&again).contains("billow"),
        "nothing to do, but: {}",
        text(&again)
    );

    // A touched texture rebakes exactly the mesh that reads it, each of its outputs.
    touch(&src.join("crate/wood.png"));
    let n = make(&["-n", "batch"], &src, &out);
    let plan = text(&n);
    assert!(!plan.contains("leaves.gltf"), "only the box: {plan}");
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
        plan.contains("leaves.gltf") && !plan.contains("box.obj"),
        "{plan}"
    );
    make(&["batch"], &src, &out);
    touch(&src.join("crate/box.mtl"));
    let plan = text(&make(&["-n", "batch"], &src, &out));
    assert!(
        plan.contains("box.obj") && !plan.contains("leaves.gltf"),
        "{plan}"
    );

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
