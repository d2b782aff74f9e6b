//! glTF `KHR_materials_unlit`: the importer records it on the material, and `billow view`
//! draws such a material unlit — its pixels are its base colour whatever the light
//! direction and whether or not it lies in a shadow — while a lit material of the same
//! colour beside it is darkened (so the light really changed). Billboard-cloud exports
//! are unlit with their lighting baked in; lighting them again made them darker.

mod common;

use std::path::{Path, PathBuf};

use billow::import::{import, ImportOptions};
use common::{repo, run};

/// Linear base colour of both quads.
const COLOUR: [f32; 3] = [0.8, 0.3, 0.1];
const W: u32 = 96;
const H: u32 = 64;
const EYE: [f32; 3] = [0.0, 0.5, 4.0];
const TARGET: [f32; 3] = [0.0, 0.5, 0.0];
const FOV_DEG: f32 = 45.0;

/// Three double-sided quads, non-indexed, with +Z / +Y normals: an unlit one
/// (x ∈ [−1.1, −0.1], y ∈ [0, 1], z = 0), a lit one of the same colour (x ∈ [0.1, 1.1]),
/// and a white lit roof at y = 1.6 that shadows both when the light is overhead.
fn write_scene_gltf(dir: &Path) -> PathBuf {
    let quad = |a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]| [a, b, c, a, c, d];
    let quads = [
        (
            quad(
                [-1.1, 0., 0.],
                [-0.1, 0., 0.],
                [-0.1, 1., 0.],
                [-1.1, 1., 0.],
            ),
            [0f32, 0., 1.],
        ),
        (
            quad([0.1, 0., 0.], [1.1, 0., 0.], [1.1, 1., 0.], [0.1, 1., 0.]),
            [0., 0., 1.],
        ),
        (
            quad(
                [-2., 1.6, 1.],
                [2., 1.6, 1.],
                [2., 1.6, -1.],
                [-2., 1.6, -1.],
            ),
            [0., 1., 0.],
        ),
    ];
    let mut bin = Vec::new();
    for (pos, n) in &quads {
        for p in pos {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for _ in 0..6 {
            for c in n {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    std::fs::write(dir.join("quads.bin"), &bin).unwrap();
    let [r, g, b] = COLOUR;
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_materials_unlit"],
  "buffers": [{{"uri": "quads.bin", "byteLength": {len}}}],
  "bufferViews": [{{"buffer": 0, "byteLength": {len}}}],
  "accessors": [
    {{"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 6, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 6, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 144, "componentType": 5126, "count": 6, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 216, "componentType": 5126, "count": 6, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 288, "componentType": 5126, "count": 6, "type": "VEC3"}},
    {{"bufferView": 0, "byteOffset": 360, "componentType": 5126, "count": 6, "type": "VEC3"}}
  ],
  "materials": [
    {{"name": "baked", "doubleSided": true,
      "pbrMetallicRoughness": {{"baseColorFactor": [{r}, {g}, {b}, 1], "metallicFactor": 0}},
      "extensions": {{"KHR_materials_unlit": {{}}}}}},
    {{"name": "lit", "doubleSided": true,
      "pbrMetallicRoughness": {{"baseColorFactor": [{r}, {g}, {b}, 1], "metallicFactor": 0}}}},
    {{"name": "roof", "doubleSided": true}}
  ],
  "meshes": [
    {{"name": "unlit", "primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "material": 0}}]}},
    {{"name": "lit", "primitives": [{{"attributes": {{"POSITION": 2, "NORMAL": 3}}, "material": 1}}]}},
    {{"name": "roof", "primitives": [{{"attributes": {{"POSITION": 4, "NORMAL": 5}}, "material": 2}}]}}
  ],
  "nodes": [{{"mesh": 0}}, {{"mesh": 1}}, {{"mesh": 2}}],
  "scenes": [{{"nodes": [0, 1, 2]}}],
  "scene": 0
}}"#,
        len = bin.len()
    );
    let p = dir.join("quads.gltf");
    std::fs::write(&p, json).unwrap();
    p
}

#[test]
fn import_reads_khr_materials_unlit() {
    let dir = tempfile::tempdir().unwrap();
    let s = import(&write_scene_gltf(dir.path()), &ImportOptions::default())
        .unwrap()
        .scene;
    let flags: Vec<(&str, bool)> = s
        .materials
        .iter()
        .map(|m| (m.name.as_str(), m.unlit))
        .collect();
    assert_eq!(flags, [("baked", true), ("lit", false), ("roof", false)]);
    // Other importers never set it.
    let obj = import(
        &repo().join("fixtures/scenes/wall.obj"),
        &ImportOptions::default(),
    )
    .unwrap()
    .scene;
    assert!(!obj.materials.is_empty());
    assert!(obj.materials.iter().all(|m| !m.unlit));
    let oak = import(
        &repo().join("fixtures/oak/eztree_oak_medium.gltf"),
        &ImportOptions::default(),
    )
    .unwrap()
    .scene;
    assert!(oak.materials.iter().all(|m| !m.unlit));
}

/// Linear [0, 1] → 8-bit sRGB.
fn srgb8(c: f32) -> f32 {
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    s * 255.0
}

/// Pixel (column, row) of world point `p` for the scene's camera (right-handed, y up,
/// vertical field of view, aspect W/H).
fn project(p: [f32; 3]) -> (u32, u32) {
    let t = (FOV_DEG.to_radians() / 2.0).tan();
    let d = EYE[2] - p[2]; // the camera looks down −Z from EYE
    let x = (p[0] - EYE[0]) / d / (t * W as f32 / H as f32);
    let y = (p[1] - EYE[1]) / d / t;
    (
        ((x + 1.0) / 2.0 * W as f32) as u32,
        ((1.0 - y) / 2.0 * H as f32) as u32,
    )
}

/// Mean 8-bit RGB over a 5×5 block around world point `p`; every pixel must be opaque.
fn block_mean(img: &image::RgbaImage, p: [f32; 3]) -> [f32; 3] {
    let (cx, cy) = project(p);
    let mut sum = [0f32; 3];
    for y in cy - 2..=cy + 2 {
        for x in cx - 2..=cx + 2 {
            let px = img.get_pixel(x, y);
            assert_eq!(px[3], 255, "pixel ({x}, {y}) not covered: {px:?}");
            for c in 0..3 {
                sum[c] += px[c] as f32 / 25.0;
            }
        }
    }
    sum
}

/// RON tuple `(x, y, z)`.
fn tuple(v: [f32; 3]) -> String {
    format!("({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

#[test]
fn view_draws_unlit_materials_at_their_base_colour() {
    let dir = tempfile::tempdir().unwrap();
    write_scene_gltf(dir.path());
    let expected = COLOUR.map(srgb8);
    // Facing, grazing and overhead (the roof then shadows both quads).
    let lights = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.05], [0.0, 1.0, 0.0]];
    for (i, l) in lights.iter().enumerate() {
        let ron = format!(
            "(camera: Some((eye: {}, target: {}, fov_deg: {FOV_DEG:?})),
              light: (direction: {}, ambient: 0.3),
              shadows: true,
              meshes: [(path: \"quads.gltf\")])",
            tuple(EYE),
            tuple(TARGET),
            tuple(*l)
        );
        let scene = format!("scene{i}.ron");
        std::fs::write(dir.path().join(&scene), &ron).unwrap();
        let shot = format!("shot{i}.png");
        let size = format!("{W}x{H}");
        let r = run(
            &[
                "view",
                &scene,
                "--headless",
                "--size",
                &size,
                "--screenshot",
                &shot,
            ],
            dir.path(),
        );
        if r.code != Some(0) && r.stderr.contains("no GPU adapter") {
            common::skip(
                "view_draws_unlit_materials_at_their_base_colour",
                r.stderr.trim(),
            );
            return;
        }
        assert_eq!(r.code, Some(0), "{ron}\n{}", r.stderr);
        let img = image::open(dir.path().join(&shot)).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (W, H));
        let unlit = block_mean(&img, [-0.6, 0.5, 0.0]);
        let lit = block_mean(&img, [0.6, 0.5, 0.0]);
        for c in 0..3 {
            assert!(
                (unlit[c] - expected[c]).abs() <= 1.5,
                "light {l:?}: unlit quad {unlit:?}, base colour {expected:?} (8-bit sRGB)"
            );
        }
        // The lit twin is darkened by this light (grazing, or shadowed by the roof):
        // the light and the shadow were really there.
        if i > 0 {
            assert!(
                lit[0] < expected[0] - 40.0,
                "light {l:?}: lit quad {lit:?} not darker than {expected:?}"
            );
        }
    }
}
