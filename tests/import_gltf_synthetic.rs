//! Hand-written glTF files: node transforms, mirrored nodes, warnings, hostile headers.

use std::path::{Path, PathBuf};

use billow::import::{import, ImportErrorKind, ImportOptions, Imported};
use glam::Vec3;

/// One triangle (0,0,0) (1,0,0) (0,1,0), normals +Z, in a file whose name has a space.
fn write_bin(dir: &Path) {
    let mut bin = Vec::new();
    for v in [
        [0f32, 0., 0.],
        [1., 0., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [0., 0., 1.],
        [0., 0., 1.],
    ] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    std::fs::write(dir.join("tri data.bin"), bin).unwrap();
}

fn write_gltf(
    dir: &Path,
    name: &str,
    nodes: &str,
    scenes: &str,
    extra_accessor_count: u64,
) -> PathBuf {
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "buffers": [{{"uri": "tri%20data.bin", "byteLength": 72}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 36}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": {extra_accessor_count}, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}}
  ],
  "meshes": [{{"name": "tri", "primitives": [
    {{"attributes": {{"POSITION": 0, "NORMAL": 1}}}},
    {{"attributes": {{"POSITION": 0}}, "mode": 0}}
  ]}}],
  "nodes": {nodes}
  {scenes}
}}"#
    );
    let p = dir.join(name);
    std::fs::write(&p, json).unwrap();
    p
}

const S: f32 = std::f32::consts::FRAC_1_SQRT_2;

fn hierarchy_nodes() -> String {
    format!(
        r#"[
    {{"name": "parent", "translation": [10, 0, 0], "rotation": [0, 0, {S}, {S}], "scale": [2, 2, 2], "children": [1]}},
    {{"name": "child", "translation": [1, 0, 0], "scale": [1, 2, 1], "mesh": 0}},
    {{"name": "mirror", "scale": [-1, 1, 1], "mesh": 0}}
  ]"#
    )
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn node_hierarchy_transforms_and_mirroring() {
    let dir = tempfile::tempdir().unwrap();
    write_bin(dir.path());
    let p = write_gltf(
        dir.path(),
        "h.gltf",
        &hierarchy_nodes(),
        r#", "scene": 0, "scenes": [{"nodes": [0, 2]}]"#,
        3,
    );
    let Imported { scene, report } = import(&p, &ImportOptions::default()).unwrap();
    assert_eq!(scene.triangles.len(), 2);
    // Points primitive skipped with a warning.
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    assert!(report.warnings[0].message.contains("skipped"));

    // World = T(10,0,0) · Rz(90°) · S(2) · T(1,0,0) · S(1,2,1):
    // p ↦ (10 − 4·p.y, 2·(p.x + 1), 2·p.z).
    let t = &scene.triangles[0];
    let got: Vec<Vec3> = t.v.iter().map(|v| v.position).collect();
    assert!(close(got[0], Vec3::new(10.0, 2.0, 0.0)), "{got:?}");
    assert!(close(got[1], Vec3::new(10.0, 4.0, 0.0)), "{got:?}");
    assert!(close(got[2], Vec3::new(6.0, 2.0, 0.0)), "{got:?}");
    for v in &t.v {
        assert!(close(v.normal, Vec3::Z), "{:?}", v.normal);
    }
    assert!(t.cross().normalize().dot(Vec3::Z) > 0.999);

    // Mirrored node: positions mirrored, winding flipped so the geometric front
    // (counter-clockwise) side still agrees with the shading normal.
    let m = &scene.triangles[1];
    let mut pos: Vec<[i32; 3]> =
        m.v.iter()
            .map(|v| v.position.round().as_ivec3().to_array())
            .collect();
    pos.sort();
    assert_eq!(pos, vec![[-1, 0, 0], [0, 0, 0], [0, 1, 0]]);
    for v in &m.v {
        assert!(close(v.normal, Vec3::Z), "{:?}", v.normal);
        assert!(
            m.cross().dot(v.normal) > 0.0,
            "mirrored triangle faces away from its normal"
        );
    }
    assert!(close(scene.bounds.min, Vec3::new(-1.0, 0.0, 0.0)));
    assert!(close(scene.bounds.max, Vec3::new(10.0, 4.0, 0.0)));

    // Strict: the skipped points primitive becomes an error.
    let e = import(&p, &ImportOptions { strict: true }).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Strict);
    assert!(e.to_string().contains("h.gltf"), "{e}");
}

#[test]
fn no_scene_uses_all_root_nodes() {
    let dir = tempfile::tempdir().unwrap();
    write_bin(dir.path());
    let p = write_gltf(dir.path(), "roots.gltf", &hierarchy_nodes(), "", 3);
    let scene = import(&p, &ImportOptions::default()).unwrap().scene;
    assert_eq!(scene.triangles.len(), 2);
}

#[test]
fn node_cycle_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    write_bin(dir.path());
    let nodes = r#"[{"children": [1], "mesh": 0}, {"children": [2]}, {"children": [0]}]"#;
    let p = write_gltf(
        dir.path(),
        "cycle.gltf",
        nodes,
        r#", "scene": 0, "scenes": [{"nodes": [0]}]"#,
        3,
    );
    let e = import(&p, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Invalid);
    assert!(e.to_string().contains("loop"), "{e}");
    // A node shared by two parents would expand exponentially: refused too.
    let nodes = r#"[{"children": [2], "mesh": 0}, {"children": [2]}, {"mesh": 0}]"#;
    let p = write_gltf(dir.path(), "dag.gltf", nodes, "", 3);
    assert_eq!(
        import(&p, &ImportOptions::default()).unwrap_err().kind(),
        ImportErrorKind::Invalid
    );
}

#[test]
fn hostile_accessor_count_is_refused_without_allocating() {
    let dir = tempfile::tempdir().unwrap();
    write_bin(dir.path());
    let p = write_gltf(
        dir.path(),
        "huge.gltf",
        &hierarchy_nodes(),
        "",
        4_000_000_000_000,
    );
    let e = import(&p, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Invalid);
    assert!(
        e.to_string().contains("huge.gltf") && e.to_string().contains("exceeds"),
        "{e}"
    );
}

#[test]
fn missing_buffer_file_is_an_io_error_and_unknown_extension_unsupported() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_gltf(dir.path(), "nobin.gltf", &hierarchy_nodes(), "", 3);
    let e = import(&p, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Io);
    assert!(e.to_string().contains("nobin.gltf"), "{e}");
    // A missing file is an I/O error whatever its name; an existing file with an
    // unknown extension is unsupported.
    let fbx = dir.path().join("x.fbx");
    let e = import(&fbx, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Io);
    std::fs::write(&fbx, b"Kaydara FBX Binary  \0").unwrap();
    let e = import(&fbx, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.kind(), ImportErrorKind::Unsupported);
    assert!(e.to_string().contains("unknown mesh file extension"), "{e}");
}
