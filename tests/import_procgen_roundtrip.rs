//! The procedural hard cases survive a trip through OBJ and the importer unchanged:
//! positions, normals, UVs (with OBJ's flipped v) and vertex colours; and the import
//! report of such a trip says exactly what the import saw.

use billow::import::{import, ImportErrorKind, ImportOptions, ImportReport, TextureReport};
use billow::procgen::{furry_torus, leafy_tree, truss, write_obj};
use billow::scene::Scene;

fn roundtrip(scene: &Scene, name: &str) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_obj(scene, &path).unwrap();
    import(&path, &ImportOptions { strict: true })
        .unwrap()
        .scene
}

fn assert_same(a: &Scene, b: &Scene) {
    assert_eq!(a.triangles.len(), b.triangles.len());
    for (ta, tb) in a.triangles.iter().zip(&b.triangles) {
        for (va, vb) in ta.v.iter().zip(&tb.v) {
            assert!(
                va.position.abs_diff_eq(vb.position, 1e-5),
                "{va:?} vs {vb:?}"
            );
            assert!(va.normal.abs_diff_eq(vb.normal, 1e-5), "{va:?} vs {vb:?}");
            assert!(va.uv.abs_diff_eq(vb.uv, 1e-5), "{va:?} vs {vb:?}");
            assert!(va.color.abs_diff_eq(vb.color, 1e-5), "{va:?} vs {vb:?}");
        }
    }
}

#[test]
fn truss_roundtrips_through_obj() {
    let s = truss(10.0, 3.0, 4, 0.005);
    assert_same(&s, &roundtrip(&s, "truss.obj"));
}

#[test]
fn furry_torus_roundtrips_through_obj() {
    let s = furry_torus(50, 9);
    assert_same(&s, &roundtrip(&s, "fur.obj"));
}

/// A generated scene has nothing to report: written as OBJ and imported, its report holds
/// only the MTL library read — no warning, no texture, no dropped triangle.
#[test]
fn generated_scene_imports_with_an_empty_report() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("truss.obj");
    write_obj(&truss(10.0, 3.0, 4, 0.005), &path).unwrap();
    let report = import(&path, &ImportOptions { strict: true })
        .unwrap()
        .report;
    assert_eq!(
        report,
        ImportReport {
            files: vec![dir.path().join("truss.mtl")],
            ..ImportReport::default()
        }
    );
    assert!(ImportReport::default().is_empty());
    assert!(!report.is_empty());
}

/// The generated tree's leaf texture deleted after writing: the import reports it as
/// missing (texture list and one warning naming it), keeps the geometry, and `--strict`
/// refuses the file instead.
#[test]
fn missing_texture_is_reported_and_strict_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tree.obj");
    let tree = leafy_tree(40, 3, 1);
    write_obj(&tree, &path).unwrap();
    let present = import(&path, &ImportOptions { strict: true }).unwrap();
    assert_eq!(
        present.report.textures,
        [TextureReport {
            name: "leaf.png".into(),
            found: true
        }]
    );
    assert!(present.report.warnings.is_empty());
    std::fs::remove_file(dir.path().join("leaf.png")).unwrap();
    let missing = import(&path, &ImportOptions::default()).unwrap();
    assert_eq!(missing.scene.triangles.len(), tree.triangles.len());
    assert_eq!(
        missing.report.textures,
        [TextureReport {
            name: "leaf.png".into(),
            found: false
        }]
    );
    assert_eq!(missing.report.warnings.len(), 1, "{:?}", missing.report);
    assert!(
        missing.report.warnings[0].message.contains("leaf.png"),
        "{:?}",
        missing.report.warnings
    );
    assert_eq!(missing.report.files, [dir.path().join("tree.mtl")]);
    assert_eq!(missing.report.missing, [dir.path().join("leaf.png")]);
    assert!(present.report.missing.is_empty());
    assert_eq!(missing.report.dropped_triangles, 0);
    let e = import(&path, &ImportOptions { strict: true }).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Strict);
    assert!(e.to_string().contains("leaf.png"), "{e}");
}
