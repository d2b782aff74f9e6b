//! Import of the shared real-world assets: exact counts, materials, warnings, errors.

use std::path::{Path, PathBuf};

mod common;

use billow::import::{import, ImportErrorKind, ImportOptions, Imported};
use billow::inspect::inspect;
use billow::scene::{AlphaMode, Scene};

fn asset(rel: &str) -> Option<PathBuf> {
    common::shared_assets(&format!("import_assets ({rel})")).map(|root| root.join(rel))
}

/// The bundled oak (fixtures/oak, the same files as the shared corpus's
/// eztree_oak_medium): always there, so the oak tests never skip.
fn oak(file: &str) -> PathBuf {
    common::repo().join("fixtures/oak").join(file)
}

fn ok(p: &Path) -> Imported {
    import(p, &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn err(p: &Path) -> billow::import::ImportError {
    let e = import(p, &ImportOptions::default()).expect_err("expected an error");
    let name = p.file_name().unwrap().to_string_lossy();
    assert!(
        e.to_string().contains(name.as_ref()),
        "error does not name the file: {e}"
    );
    e
}

fn check_oak(s: &Imported) {
    assert_eq!(s.scene.triangles.len(), 13_806);
    assert_eq!(s.report.dropped_triangles, 0);
    assert_eq!(s.scene.materials.len(), 2);
    let leaf = s
        .scene
        .materials
        .iter()
        .find(|m| m.name == "leaves")
        .expect("leaf material");
    assert_eq!(leaf.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    assert!(leaf.double_sided);
    let t = &s.scene.textures[leaf.base_color_texture.expect("leaf texture") as usize];
    assert_eq!((t.width, t.height), (1024, 1024));
    let bark = s
        .scene
        .materials
        .iter()
        .find(|m| m.name == "bark")
        .expect("bark material");
    assert_eq!(bark.alpha_mode, AlphaMode::Opaque);
    assert!(bark.base_color_texture.is_some());
    // A ~65 m tall oak standing on y = 0.
    let (min, size) = (s.scene.bounds.min, s.scene.bounds.size());
    assert!(min.y.abs() < 1e-3, "{min}");
    assert!(
        (60.0..70.0).contains(&size.y) && (45.0..60.0).contains(&size.x),
        "{size}"
    );
    let leaves: usize = s
        .scene
        .meshes
        .iter()
        .filter(|m| m.name == "leaves")
        .map(|m| m.triangles)
        .sum();
    assert_eq!(leaves, 10_640);
    assert!(s.report.warnings.is_empty(), "{:?}", s.report.warnings);
    // Every UV lands in the image (glTF convention; OBJ v flipped on import) and normals are unit.
    for t in &s.scene.triangles {
        for v in &t.v {
            assert!((v.normal.length() - 1.0).abs() < 1e-3);
        }
    }
}

#[test]
fn oak_gltf() {
    let p = oak("eztree_oak_medium.gltf");
    let s = ok(&p);
    check_oak(&s);
    let r = inspect(&s, &p);
    assert_eq!(r.triangles, 13_806);
    assert!(r.textures.iter().all(|t| t.found && t.width == Some(1024)));
    let text = r.to_string();
    assert!(
        text.contains("13806") && text.contains("mask 0.5"),
        "{text}"
    );
    serde_json::to_string(&r).unwrap();
}

#[test]
fn oak_obj_matches_gltf() {
    let p = oak("eztree_oak_medium.obj");
    let s = ok(&p);
    check_oak(&s);
    // Same leaf UVs as the glTF (OBJ v flipped back into glTF convention).
    let g = ok(&oak("eztree_oak_medium.gltf"));
    let leaf_uv = |s: &Scene| {
        let mut uv: Vec<(i64, i64)> = s
            .triangles
            .iter()
            .flat_map(|t| {
                t.v.iter()
                    .map(|v| ((v.uv.x * 1e3) as i64, (v.uv.y * 1e3) as i64))
            })
            .collect();
        uv.sort();
        uv.dedup();
        uv
    };
    assert_eq!(leaf_uv(&s.scene), leaf_uv(&g.scene));
}

#[test]
fn bunny_nan_inf_is_an_error() {
    let Some(p) = asset("bad_inputs/derived_mutations/bunny_nan_inf.obj") else {
        return;
    };
    let e = err(&p);
    assert_eq!(e.kind(), ImportErrorKind::Invalid);
    assert!(e.to_string().contains("non-finite"), "{e}");
}

#[test]
fn bunny_degenerate_faces_are_dropped() {
    let Some(p) = asset("bad_inputs/derived_mutations/bunny_degenerate_faces.obj") else {
        return;
    };
    let s = ok(&p);
    // 40 appended faces: 20 with a repeated index and 10 collinear are zero-area
    // (dropped); 10 duplicates of existing faces have area and are kept.
    assert_eq!(s.report.dropped_triangles, 30);
    assert_eq!(s.scene.triangles.len(), 6_598 + 10);
}

#[test]
fn oak_missing_leaf_texture_warns_or_fails_strict() {
    let Some(p) =
        asset("bad_inputs/derived_mutations/oak_missing_leaf_texture/eztree_oak_medium.gltf")
    else {
        return;
    };
    let s = ok(&p);
    assert_eq!(s.scene.triangles.len(), 13_806);
    assert_eq!(s.report.warnings.len(), 1, "{:?}", s.report.warnings);
    let leaf = s
        .scene
        .materials
        .iter()
        .find(|m| m.name == "leaves")
        .unwrap();
    assert_eq!(leaf.base_color_texture, None);
    let r = inspect(&s, &p);
    let missing: Vec<_> = r.textures.iter().filter(|t| !t.found).collect();
    assert_eq!(missing.len(), 1);
    assert!(missing[0].name.contains("oak_color"), "{:?}", missing[0]);
    assert!(r.to_string().contains("MISSING"));
    let e = import(&p, &ImportOptions { strict: true }).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Strict);
}

#[test]
fn oak_zero_area_leaves_are_counted() {
    let Some(p) = asset("bad_inputs/derived_mutations/oak_zero_area_leaves.gltf") else {
        return;
    };
    let s = ok(&p);
    assert_eq!(s.report.dropped_triangles, 1_520);
    assert_eq!(s.scene.triangles.len(), 13_806 - 1_520);
    // Parent-relative image URIs ("../../eztree_oak_medium/...") resolve.
    assert!(s.report.warnings.is_empty(), "{:?}", s.report.warnings);
    assert!(s.report.textures.iter().all(|t| t.found));
}

#[test]
fn unsupported_required_extensions_are_named() {
    for (f, ext) in [
        ("grass.glb", "EXT_texture_webp"),
        ("rock1.glb", "KHR_draco_mesh_compression"),
    ] {
        let Some(p) = asset(&format!("bad_inputs/unsupported_required_extensions/{f}")) else {
            return;
        };
        let e = err(&p);
        assert_eq!(e.kind(), ImportErrorKind::Unsupported);
        assert!(e.to_string().contains(ext), "{e}");
    }
}

#[test]
fn lantern_missing_base_color_warns() {
    let Some(p) = asset("lantern_missing_basecolor/Lantern.gltf") else {
        return;
    };
    let s = ok(&p);
    assert_eq!(s.scene.triangles.len(), 5_394);
    assert_eq!(s.scene.meshes.len(), 3);
    assert_eq!(s.report.warnings.len(), 1, "{:?}", s.report.warnings);
    assert!(s.report.warnings[0]
        .message
        .contains("Lantern_baseColor.png"));
    assert!(s
        .scene
        .materials
        .iter()
        .all(|m| m.base_color_texture.is_none()));
}

#[test]
fn tobj_invalid_index_and_lines() {
    let Some(p) = asset("tobj_obj_testfiles/obj/invalid_index.obj") else {
        return;
    };
    let e = err(&p);
    assert_eq!(e.kind(), ImportErrorKind::Invalid);
    assert!(e.to_string().contains("out of range"), "{e}");
    let s = ok(&asset("tobj_obj_testfiles/obj/lines.obj").unwrap());
    assert_eq!(s.scene.triangles.len(), 0);
    assert!(s.scene.bounds.is_empty());
}

#[test]
fn cornell_box_warns_for_missing_textures() {
    let Some(p) = asset("tobj_obj_testfiles/obj/cornell_box.obj") else {
        return;
    };
    let s = ok(&p);
    assert_eq!(s.scene.triangles.len(), 36);
    assert_eq!(s.scene.meshes.len(), 8);
    assert!(
        s.report
            .warnings
            .iter()
            .any(|w| w.message.contains("this diffuse texture has spaces.jpg")),
        "{:?}",
        s.report.warnings
    );
    assert!(s.report.textures.iter().all(|t| !t.found));
    assert!(s
        .report
        .textures
        .iter()
        .any(|t| t.name == "this diffuse texture has spaces.jpg"));
    assert!(import(&p, &ImportOptions { strict: true }).is_err());
}

#[test]
fn validator_samples() {
    let base = "gltf_validator_testsuite/test/base/data/";
    let Some(p) = asset(&format!("{base}mesh_data/index_buffer_oob.gltf")) else {
        return;
    };
    let e = err(&p);
    assert_eq!(e.kind(), ImportErrorKind::Invalid);
    // invalid_elements_float.gltf holds NaN/Inf in an accessor that no mesh uses: nothing
    // to import, so it imports as an empty scene.
    let s = ok(&asset(&format!("{base}accessor_data/invalid_elements_float.gltf")).unwrap());
    assert_eq!(s.scene.triangles.len(), 0);
    for f in ["node/node_loop.gltf", "node/node_loop_scene.gltf"] {
        assert_eq!(
            err(&asset(&format!("{base}{f}")).unwrap()).kind(),
            ImportErrorKind::Invalid
        );
    }
    let s = ok(&asset("eztree_flowers/flower_blue.glb").unwrap());
    assert_eq!(s.scene.triangles.len() + s.report.dropped_triangles, 788);
}
