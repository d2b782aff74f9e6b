//! OBJ and MTL files as real tools write them: other text encodings (UTF-16 with or
//! without a byte-order mark, UTF-8 with one), MTL colours with one value, `p` and `l`
//! statements, and files that hold nothing billow understands — never a silent empty or
//! default-material import. Also the report's account of the files the import read and of
//! those it looked for and could not read.

use std::path::Path;

use billow::import::{import, ImportOptions, Imported};

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) {
    std::fs::write(dir.join(name), bytes).unwrap();
}

fn strict() -> ImportOptions {
    ImportOptions { strict: true }
}

/// Two triangles (a quad) with the material `leaf` from `quad.mtl`.
const QUAD_OBJ: &str = "# exported\nmtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl leaf\nf 1/1 2/2 3/3 4/4\n";
const QUAD_MTL: &str = "newmtl leaf\nKd 0.25 0.5 0.75\n";

fn utf16(text: &str, big_endian: bool, bom: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let units = bom.then_some(0xFEFF).into_iter().chain(text.encode_utf16());
    for u in units {
        out.extend(if big_endian {
            u.to_be_bytes()
        } else {
            u.to_le_bytes()
        });
    }
    out
}

fn assert_quad(i: &Imported, what: &str) {
    assert_eq!(i.scene.triangles.len(), 2, "{what}: {:?}", i.report);
    let m = i.scene.material(&i.scene.triangles[0]);
    assert_eq!(m.name, "leaf", "{what}");
    assert_eq!(m.base_color_factor.truncate().to_array(), [0.25, 0.5, 0.75]);
    assert!(i.report.warnings.is_empty(), "{what}: {:?}", i.report);
}

/// Windows tools (PowerShell's `>`, Notepad's "Unicode") write UTF-16: with a BOM, little
/// or big endian, and without one. Each imports as the UTF-8 file would, MTL included.
/// Before: "triangles 0, warnings 0".
#[test]
fn utf16_obj_and_mtl_import_like_utf8() {
    for (be, bom) in [(false, true), (true, true), (false, false), (true, false)] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        write(d, "quad.obj", utf16(QUAD_OBJ, be, bom));
        write(d, "quad.mtl", utf16(QUAD_MTL, be, bom));
        let what = format!("UTF-16 {} {}", if be { "BE" } else { "LE" }, bom);
        let i = import(&d.join("quad.obj"), &strict()).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_quad(&i, &what);
    }
}

/// A UTF-8 byte-order mark (Notepad's "UTF-8 with BOM") on the OBJ and on the MTL. Before:
/// the first statement was not recognised (`\u{feff}v`), so the first vertex was lost and
/// the faces' indices ran past the end.
#[test]
fn utf8_bom_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bom = |s: &str| [&b"\xEF\xBB\xBF"[..], s.as_bytes()].concat();
    write(
        d,
        "quad.obj",
        bom("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nmtllib quad.mtl\nusemtl leaf\nf 1 2 3 4\n"),
    );
    write(d, "quad.mtl", bom(QUAD_MTL));
    let i = import(&d.join("quad.obj"), &strict()).unwrap();
    assert_quad(&i, "UTF-8 BOM");
    assert_eq!(i.scene.bounds.min.to_array(), [0.0, 0.0, 0.0]);
}

/// A file with content but nothing billow understands as OBJ (a binary file, or a text in
/// an encoding it cannot guess) is not a silent empty import: a warning says why there is
/// nothing, naming the first line it could not read; `--strict` refuses it.
#[test]
fn content_that_is_not_obj_is_a_warning_not_silence() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "x.obj",
        b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01garbage\nmore garbage\n",
    );
    let i = import(&d.join("x.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(i.scene.triangles.len(), 0);
    assert_eq!(i.report.warnings.len(), 1, "{:?}", i.report);
    let w = &i.report.warnings[0].message;
    assert!(w.contains("no triangles") && w.contains("line 1"), "{w}");
    assert!(import(&d.join("x.obj"), &strict()).is_err());

    // Vertices but no face: said too.
    write(d, "v.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let i = import(&d.join("v.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(i.report.warnings.len(), 1, "{:?}", i.report);
    assert!(
        i.report.warnings[0].message.contains("no triangles"),
        "{:?}",
        i.report
    );
}

/// An MTL that holds no material (nothing billow reads as MTL) and an OBJ whose `usemtl`
/// names a material no library defines: each a warning, not a silent default material.
#[test]
fn an_mtl_without_materials_and_an_undefined_usemtl_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "quad.obj", QUAD_OBJ);
    write(d, "quad.mtl", "this is not\nan MTL file\n");
    let i = import(&d.join("quad.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(i.scene.triangles.len(), 2);
    let msgs = i.report.messages();
    assert!(
        msgs.iter()
            .any(|m| m.contains("quad.mtl") && m.contains("no material") && m.contains("line 1")),
        "{msgs:?}"
    );
    assert!(
        msgs.iter()
            .any(|m| m.contains("'leaf'") && m.contains("default material")),
        "{msgs:?}"
    );
}

/// `Ks 0` (Blender), `Ka 1`, `Ke 0`, `Tf 1`, `Kd 0.5`: one value means g = b = r (the MTL
/// specification). Before: "a colour needs three values", and the whole library (every
/// material) was dropped.
#[test]
fn mtl_colours_with_one_value_are_grey() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "quad.obj", QUAD_OBJ);
    write(
        d,
        "quad.mtl",
        "# Blender MTL File\nnewmtl leaf\nNs 250\nKa 1\nKs 0\nKe 0\nTf 1\nKd 0.5\nd 1\nillum 2\n",
    );
    let i = import(&d.join("quad.obj"), &strict()).unwrap();
    let m = i.scene.material(&i.scene.triangles[0]);
    assert_eq!(m.name, "leaf");
    assert_eq!(m.base_color_factor.to_array(), [0.5, 0.5, 0.5, 1.0]);
    assert!(i.report.warnings.is_empty(), "{:?}", i.report);
}

/// `p` and `l` statements are not imported, and the import says so once per file with
/// their counts (as a glTF point or line primitive gets a warning). A three-vertex `l` is a
/// polyline, not a triangle. Before: silently dropped, and `l 1 2 3` became a triangle.
#[test]
fn points_and_lines_are_counted_in_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "pl.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\np 1\np 2 3\nl 1 2\nl 1 2 3\nl 2 4 3\n",
    );
    let i = import(&d.join("pl.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(i.scene.triangles.len(), 1, "{:?}", i.report);
    assert_eq!(i.report.warnings.len(), 1, "{:?}", i.report);
    let w = &i.report.warnings[0].message;
    assert!(w.contains("2 point") && w.contains("3 line"), "{w}");
    let e = import(&d.join("pl.obj"), &strict()).unwrap_err();
    assert!(e.to_string().contains("3 line"), "{e}");
}

/// An MTL library with a line that does not parse was read: it is among the report's
/// files (so a depfile lists it and fixing it rebakes). Before: a library that failed to
/// parse was not listed.
#[test]
fn an_mtl_with_a_bad_line_is_among_the_files_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "quad.obj", QUAD_OBJ);
    write(d, "quad.mtl", "newmtl leaf\nKd 0.25 0.5 0.75\nKd x y z\n");
    let i = import(&d.join("quad.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(i.report.files, [d.join("quad.mtl")], "{:?}", i.report);
    assert!(
        i.report
            .messages()
            .iter()
            .any(|m| m.contains("quad.mtl") && m.contains("line 3") && m.contains("Kd x y z")),
        "{:?}",
        i.report
    );
}

/// A TGA texture (3ds Max and game assets use them): TGA has no signature to sniff, so the
/// file name's extension says what it is. Before: "unrecognised image format", and the
/// material fell back to its factor colour.
#[test]
fn a_tga_texture_loads_by_its_extension() {
    use image::ImageEncoder;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rgba: Vec<u8> = (0..8 * 4)
        .flat_map(|i: u32| [i as u8 * 8, 100, 200, 255])
        .collect();
    let mut tga = Vec::new();
    image::codecs::tga::TgaEncoder::new(&mut tga)
        .write_image(&rgba, 8, 4, image::ExtendedColorType::Rgba8)
        .unwrap();
    write(d, "bark.TGA", &tga);
    write(d, "quad.obj", QUAD_OBJ);
    write(d, "quad.mtl", "newmtl leaf\nKd 1 1 1\nmap_Kd bark.TGA\n");
    let i = import(&d.join("quad.obj"), &strict()).unwrap();
    let t = &i.scene.textures[i.scene.materials[0].base_color_texture.unwrap() as usize];
    assert_eq!((t.width, t.height), (8, 4));
    assert!(t.texels.iter().flatten().eq(rgba.iter()));
}

/// The report's account of the files: `files` every file read (in first-read order), and
/// `missing` every file looked for and not read (a missing MTL library, a missing texture),
/// in first-looked-for order, each once; neither holds the other's.
#[test]
fn the_report_lists_files_read_and_files_missing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        d,
        "m.obj",
        "mtllib gone.mtl\nmtllib here.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n\
         usemtl b\nf 1 2 3\nusemtl c\nf 3 2 1\n",
    );
    write(
        d,
        "here.mtl",
        "newmtl a\nmap_Kd no such.png\nnewmtl b\nmap_Kd bad.png\nnewmtl c\nmap_Kd no such.png\n",
    );
    write(d, "bad.png", "not a PNG");
    let i = import(&d.join("m.obj"), &ImportOptions::default()).unwrap();
    assert_eq!(
        i.report.files,
        [d.join("here.mtl"), d.join("bad.png")],
        "{:?}",
        i.report
    );
    assert_eq!(
        i.report.missing,
        [d.join("gone.mtl"), d.join("no such.png")],
        "{:?}",
        i.report
    );
    assert!(!i.report.is_empty());
    let shown = billow::inspect::inspect(&i, &d.join("m.obj"));
    assert_eq!(
        shown.missing_files,
        [d.join("gone.mtl"), d.join("no such.png")].map(|p| p.display().to_string())
    );
    assert_eq!(shown.files.len(), 2);
    let msgs = i.report.messages();
    assert!(msgs.iter().any(|m| m.contains("gone.mtl")), "{msgs:?}");
    assert!(msgs.iter().any(|m| m.contains("no such.png")), "{msgs:?}");
    assert!(msgs.iter().any(|m| m.contains("bad.png")), "{msgs:?}");
}

/// A glTF whose image file is missing: in `missing`, not in `files` (its buffer is).
#[test]
fn a_missing_gltf_image_is_in_missing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let positions: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    write(d, "t.bin", &positions);
    write(
        d,
        "t.gltf",
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"t.bin","byteLength":36}],
        "bufferViews":[{"buffer":0,"byteLength":36}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
          "min":[0,0,0],"max":[1,1,0]}],
        "images":[{"uri":"gone.jpg"}],"textures":[{"source":0}],
        "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]}],
        "nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#,
    );
    let i = import(&d.join("t.gltf"), &ImportOptions::default()).unwrap();
    assert_eq!(i.scene.triangles.len(), 1);
    assert_eq!(i.report.files, [d.join("t.bin")]);
    assert_eq!(i.report.missing, [d.join("gone.jpg")]);
}
