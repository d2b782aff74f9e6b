//! The procedural hard cases survive a trip through OBJ and the importer unchanged:
//! positions, normals, UVs (with OBJ's flipped v) and vertex colours.

use billow::import::{import, ImportOptions};
use billow::procgen::{furry_torus, truss, write_obj};
use billow::scene::Scene;

fn roundtrip(scene: &Scene, name: &str) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    write_obj(scene, &path).unwrap();
    import(&path, &ImportOptions { strict: true }).unwrap()
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
