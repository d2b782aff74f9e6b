//! The `.glb` export of a billboard cloud: strict glTF load, billow's own importer, and a
//! render in the eval's reference ray tracer close to the source oak's render — close
//! enough that a broken export (UVs flipped inside each billboard, back faces missing)
//! fails the same bound.

use std::path::{Path, PathBuf};

use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::eval::image::write_comparisons_png;
use billow::eval::metrics::compare;
use billow::eval::ImageF32;
use billow::export::{
    cloud_glb_bytes, cloud_gltf_bytes, write_cloud_glb, write_cloud_gltf, GltfContainer,
    GltfOptions,
};
use billow::import::{import, ImportOptions};
use billow::scene::Scene;
use billow::test_support::reference_renders;
use billow_core::camera::Camera;
use glam::{Vec3, Vec4};

fn oak_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/oak/eztree_oak_medium.gltf")
}

fn bake_oak(scene: &Scene, lods: u32) -> billow_format::CloudAsset {
    let opts = BbcloudOptions {
        samples: 200,
        seed: 3,
        lods,
        atlas_size: 2048,
        shading: Shading {
            light: None, // unlit: the reference renderer shows albedo
            ambient: 1.0,
        },
        ..BbcloudOptions::default()
    };
    bake(scene, &opts, "billow test", None, &|_, _| {})
        .expect("bake")
        .0
}

/// Box-downsample by `f` (premultiplied): compares the low frequencies a billboard
/// cloud is meant to keep, not leaf-level parallax.
fn downsample(img: &ImageF32, f: u32) -> ImageF32 {
    let mut out = ImageF32::new(img.width / f, img.height / f);
    for y in 0..out.height {
        for x in 0..out.width {
            let mut s = Vec4::ZERO;
            for j in 0..f {
                for i in 0..f {
                    s += img.get(x * f + i, y * f + j);
                }
            }
            out.set(x, y, s / (f * f) as f32);
        }
    }
    out
}

fn views(scene: &Scene) -> Vec<Camera> {
    [
        Vec3::NEG_Z,
        Vec3::X,
        Vec3::new(1.0, -0.5, 1.0).normalize(),
        Vec3::new(-1.0, -0.3, -0.4).normalize(),
    ]
    .iter()
    .map(|&d| Camera::framed(&scene.bounds, d, 0.6, 128, 128, 1.0))
    .collect()
}

/// Mean over views of the RMSE (premultiplied RGBA) of 4×-downsampled renders.
fn error(reference: &[ImageF32], test: &[ImageF32]) -> f64 {
    let e: f64 = reference
        .iter()
        .zip(test)
        .map(|(r, t)| {
            compare(&downsample(r, 4), &downsample(t, 4))
                .expect("same size")
                .rmse
        })
        .sum();
    e / reference.len() as f64
}

fn is_cloud(scene: &Scene, t: &billow::scene::Triangle) -> bool {
    scene.material(t).name.starts_with("lod")
}

#[test]
fn glb_is_valid_gltf_and_renders_like_the_source() {
    let source = import(&oak_path(), &ImportOptions::default())
        .expect("oak")
        .scene;
    let asset = bake_oak(&source, 2);
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("oak.glb");
    write_cloud_glb(&asset, &glb, &GltfOptions::default()).expect("export");
    assert_eq!(
        std::fs::read(&glb).unwrap(),
        cloud_glb_bytes(&asset, &GltfOptions::default()).unwrap(),
        "the written file is the bytes"
    );

    // 1. The gltf crate's strict import (validation, buffers, images decoded).
    let (doc, buffers, images) = gltf::import(&glb).expect("strict glTF import");
    assert_eq!(buffers.len(), 1);
    assert_eq!(doc.scenes().count(), 2, "one scene per LOD");
    assert_eq!(doc.default_scene().unwrap().name(), Some("lod0"));
    let names: Vec<&str> = doc.nodes().filter_map(|n| n.name()).collect();
    assert_eq!(names, ["lod0", "lod1", "trunk"]);
    assert_eq!(
        images.len(),
        asset.atlases.len() + 1,
        "one PNG per atlas and the bark texture"
    );
    for (img, at) in images.iter().zip(&asset.atlases) {
        assert_eq!((img.width, img.height), (at.width, at.height));
        assert_eq!(img.format, gltf::image::Format::R8G8B8A8);
    }
    for (l, lv) in asset.levels.iter().enumerate() {
        let mesh = doc
            .meshes()
            .find(|m| m.name() == Some(&format!("lod{l}")))
            .unwrap();
        let quads: usize = mesh
            .primitives()
            .map(|p| {
                let m = p.material();
                assert_eq!(m.alpha_mode(), gltf::material::AlphaMode::Mask);
                assert!(!m.double_sided());
                assert!(m.unlit());
                assert_eq!(p.morph_targets().count(), 1);
                p.indices().unwrap().count() / 6
            })
            .sum();
        assert_eq!(quads, 2 * lv.billboard_count as usize, "front + back quads");
    }

    // 2. billow's own importer: the default scene is LOD 0 + trunk.
    let cloud = import(&glb, &ImportOptions { strict: true })
        .expect("billow import")
        .scene;
    let n_cloud = cloud
        .triangles
        .iter()
        .filter(|t| is_cloud(&cloud, t))
        .count();
    assert_eq!(n_cloud, 4 * asset.levels[0].billboard_count as usize);
    assert_eq!(
        cloud.triangles.len() - n_cloud,
        asset.trunk.triangles.len(),
        "trunk kept"
    );

    // 3. Renders close to the source; broken exports do not.
    let cams = views(&source);
    let reference = reference_renders(&source, &cams);
    let good = reference_renders(&cloud, &cams);
    let mut flipped = cloud.clone();
    for t in flipped.triangles.iter_mut() {
        if flipped.materials[t.material as usize]
            .name
            .starts_with("lod")
        {
            // Each quad triangle spans its UV rectangle: mirror v inside it.
            let lo = t.v.iter().map(|v| v.uv.y).fold(f32::INFINITY, f32::min);
            let hi = t.v.iter().map(|v| v.uv.y).fold(f32::NEG_INFINITY, f32::max);
            t.v.iter_mut().for_each(|v| v.uv.y = lo + hi - v.uv.y);
        }
    }
    let mut no_back = cloud.clone();
    let mats = no_back.materials.clone();
    no_back
        .triangles
        .retain(|t| !mats[t.material as usize].name.ends_with("/back"));
    let flipped_img = reference_renders(&flipped, &cams);
    let no_back_img = reference_renders(&no_back, &cams);
    let (e_good, e_flip, e_back) = (
        error(&reference, &good),
        error(&reference, &flipped_img),
        error(&reference, &no_back_img),
    );
    let full: Vec<f64> = reference
        .iter()
        .zip(&good)
        .map(|(r, g)| compare(r, g).unwrap().rmse)
        .collect();
    let cov: Vec<f64> = reference
        .iter()
        .zip(&good)
        .map(|(r, g)| compare(r, g).unwrap().coverage_rel_diff)
        .collect();
    println!(
        "4x-downsampled RMSE: good {e_good:.4}, flipped UV {e_flip:.4}, no back faces {e_back:.4}; full-res RMSE {full:.4?}; coverage rel diff {cov:.4?}"
    );
    let bound = 0.025;
    let ok = e_good < bound && e_flip > bound && e_back > bound;
    if !ok {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bbcloud_gltf_diff.png");
        let _ = write_comparisons_png(
            &reference[0],
            &[&good[0], &flipped_img[0], &no_back_img[0]],
            4.0,
            &out,
        );
        panic!(
            "good {e_good}, flipped {e_flip}, no back {e_back} vs bound {bound}; diff image {}",
            out.display()
        );
    }
    assert!(cov.iter().all(|c| c.abs() < 0.08), "coverage {cov:?}");
}

/// A small tree as OBJ + MTL in `dir`: a trunk of three opaque quads textured with a JPEG
/// (`bark`), a PNG (`moss`) and a BMP (`stone`), and a crown of alpha-masked leaf quads.
/// Returns the OBJ's path.
fn textured_tree(dir: &Path) -> PathBuf {
    use image::{ExtendedColorType, ImageEncoder};
    let (w, h) = (64u32, 32u32);
    let rgb: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i % w * 4) as u8, (i / w * 8) as u8, 90])
        .collect();
    let rgba: Vec<u8> = rgb
        .chunks(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 85)
        .encode(&rgb, w, h, ExtendedColorType::Rgb8)
        .unwrap();
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgba, w, h, ExtendedColorType::Rgba8)
        .unwrap();
    let mut bmp = Vec::new();
    image::codecs::bmp::BmpEncoder::new(&mut bmp)
        .write_image(&rgba, w, h, ExtendedColorType::Rgba8)
        .unwrap();
    let leaf: Vec<u8> = (0..16 * 16)
        .flat_map(|i: u32| {
            let (x, y) = (i % 16, i / 16);
            let inside = (x as i32 - 8).pow(2) + (y as i32 - 8).pow(2) < 40;
            [40, 140, 30, if inside { 255 } else { 0 }]
        })
        .collect();
    let mut leaf_png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut leaf_png)
        .write_image(&leaf, 16, 16, ExtendedColorType::Rgba8)
        .unwrap();
    std::fs::write(dir.join("bark.jpg"), &jpeg).unwrap();
    std::fs::write(dir.join("moss.png"), &png).unwrap();
    std::fs::write(dir.join("stone.bmp"), &bmp).unwrap();
    std::fs::write(dir.join("leaf.png"), &leaf_png).unwrap();
    std::fs::write(
        dir.join("tree.mtl"),
        "newmtl bark\nKd 1 1 1\nmap_Kd bark.jpg\n\nnewmtl moss\nKd 1 1 1\nmap_Kd moss.png\n\n\
         newmtl stone\nKd 1 1 1\nmap_Kd stone.bmp\n\nnewmtl leaf\nKd 1 1 1\nmap_Kd leaf.png\n\
         map_d leaf.png\n",
    )
    .unwrap();
    let mut obj = String::from("mtllib tree.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    let mut n = 0;
    let mut quad = |obj: &mut String, c: [[f32; 3]; 4], mat: &str| {
        obj.push_str(&format!("usemtl {mat}\n"));
        for p in c {
            obj.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
        }
        obj.push_str(&format!(
            "f {}/1 {}/2 {}/3 {}/4\n",
            n + 1,
            n + 2,
            n + 3,
            n + 4
        ));
        n += 4;
    };
    for (k, mat) in ["bark", "moss", "stone"].iter().enumerate() {
        let x = k as f32 * 0.2 - 0.2;
        quad(
            &mut obj,
            [
                [x, 0.0, 0.0],
                [x + 0.1, 0.0, 0.0],
                [x + 0.1, 2.0, 0.0],
                [x, 2.0, 0.0],
            ],
            mat,
        );
    }
    for k in 0..12 {
        let a = k as f32 * 0.52;
        let (s, c) = a.sin_cos();
        let (x, y, z) = (c * 0.6, 2.0 + (k % 3) as f32 * 0.3, s * 0.6);
        quad(
            &mut obj,
            [
                [x - 0.2 * s, y, z + 0.2 * c],
                [x + 0.2 * s, y, z - 0.2 * c],
                [x + 0.2 * s, y + 0.4, z - 0.2 * c],
                [x - 0.2 * s, y + 0.4, z + 0.2 * c],
            ],
            "leaf",
        );
    }
    let path = dir.join("tree.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// The trunk keeps what glTF can carry as it was: the source's JPEG and PNG bytes
/// (identical, with their mimeType), the source's material names and image/texture names;
/// only an image glTF cannot hold (BMP) is encoded as PNG. Before: every trunk texture was
/// re-encoded as PNG (the oak's 298 KB bark JPEG as a PNG several times larger) and named
/// `trunk/material0`, `texture0`.
#[test]
fn trunk_keeps_source_image_bytes_and_names() {
    let dir = tempfile::tempdir().unwrap();
    let obj = textured_tree(dir.path());
    let scene = import(&obj, &ImportOptions { strict: true }).unwrap().scene;
    let opts = BbcloudOptions {
        samples: 20,
        lods: 1,
        atlas_size: 256,
        ..BbcloudOptions::default()
    };
    let asset = bake(&scene, &opts, "billow test", None, &|_, _| {})
        .unwrap()
        .0;
    let opts = GltfOptions {
        source: Some(&scene),
        ..GltfOptions::default()
    };
    let glb = cloud_glb_bytes(&asset, &opts).unwrap();
    assert_eq!(
        glb,
        cloud_glb_bytes(&asset, &opts).unwrap(),
        "deterministic"
    );
    let doc = gltf::Gltf::from_slice(&glb).unwrap();
    let blob = doc.blob.as_deref().unwrap();
    let trunk = doc.meshes().find(|m| m.name() == Some("trunk")).unwrap();
    let mut seen = Vec::new();
    for p in trunk.primitives() {
        let m = p.material();
        let name = m.name().unwrap().to_string();
        let tex = m
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap()
            .texture();
        let img = tex.source();
        let gltf::image::Source::View { view, mime_type } = img.source() else {
            panic!("{name}: image not in the buffer")
        };
        let bytes = &blob[view.offset()..view.offset() + view.length()];
        let (file, mime) = match name.as_str() {
            "bark" => ("bark.jpg", "image/jpeg"),
            "moss" => ("moss.png", "image/png"),
            "stone" => ("stone.bmp", "image/png"),
            other => panic!("trunk material named {other:?}"),
        };
        assert_eq!(mime_type, mime, "{name}");
        assert_eq!(tex.name(), Some(file), "{name}");
        assert_eq!(img.name(), Some(file), "{name}");
        let source = std::fs::read(dir.path().join(file)).unwrap();
        if file.ends_with(".bmp") {
            // Re-encoded: the same texels as the BMP, as PNG.
            let a = image::load_from_memory(bytes).unwrap().into_rgba8();
            let b = image::load_from_memory(&source).unwrap().into_rgba8();
            assert_eq!(a, b, "{name}");
        } else {
            assert!(bytes == source, "{name}: the source's bytes, unchanged");
        }
        seen.push(name);
    }
    seen.sort();
    assert_eq!(seen, ["bark", "moss", "stone"]);

    // Without the source scene (a caller with only the asset): generic names, PNG images
    // that decode to the same texels.
    let plain = cloud_glb_bytes(&asset, &GltfOptions::default()).unwrap();
    let (doc, _, images) = gltf::import_slice(&plain).unwrap();
    let trunk = doc.meshes().find(|m| m.name() == Some("trunk")).unwrap();
    for p in trunk.primitives() {
        let m = p.material();
        assert!(
            m.name().unwrap().starts_with("trunk/material"),
            "{:?}",
            m.name()
        );
        let img = m
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap()
            .texture()
            .source();
        let gltf::image::Source::View { mime_type, .. } = img.source() else {
            panic!("image not in the buffer")
        };
        assert_eq!(mime_type, "image/png");
        assert_eq!(images[img.index()].format, gltf::image::Format::R8G8B8A8);
    }
    // The source of another scene is refused, not half used.
    let mut other = scene.clone();
    other.textures.pop();
    let wrong = GltfOptions {
        source: Some(&other),
        ..GltfOptions::default()
    };
    let e = cloud_glb_bytes(&asset, &wrong).unwrap_err().to_string();
    assert!(e.contains("source scene"), "{e}");
}

/// `GltfContainer::Embedded` writes the `.glb`'s document as one JSON `.gltf`: the buffer
/// a base64 `data:` URI of the same bytes, everything else equal; the `gltf` crate loads
/// both to the same buffers and images.
#[test]
fn embedded_gltf_holds_the_glb_document() {
    let dir = tempfile::tempdir().unwrap();
    let obj = textured_tree(dir.path());
    let scene = import(&obj, &ImportOptions { strict: true }).unwrap().scene;
    let opts = BbcloudOptions {
        samples: 20,
        lods: 2,
        atlas_size: 256,
        ..BbcloudOptions::default()
    };
    let asset = bake(&scene, &opts, "billow test", None, &|_, _| {})
        .unwrap()
        .0;
    let glb_opts = GltfOptions {
        source: Some(&scene),
        ..GltfOptions::default()
    };
    let gltf_opts = GltfOptions {
        container: GltfContainer::Embedded,
        ..glb_opts
    };
    let glb = cloud_gltf_bytes(&asset, &glb_opts).unwrap();
    assert_eq!(
        glb,
        cloud_glb_bytes(&asset, &gltf_opts).unwrap(),
        "glb whatever the container"
    );
    let text = cloud_gltf_bytes(&asset, &gltf_opts).unwrap();
    assert_eq!(
        text,
        cloud_gltf_bytes(&asset, &gltf_opts).unwrap(),
        "deterministic"
    );
    let written = dir.path().join("cloud.gltf");
    write_cloud_gltf(&asset, &written, &gltf_opts).unwrap();
    assert_eq!(std::fs::read(&written).unwrap(), text);

    // The JSON documents are equal but for the buffer's URI.
    let binary = gltf::Gltf::from_slice(&glb).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&text).unwrap();
    let uri = json["buffers"][0]
        .as_object_mut()
        .unwrap()
        .remove("uri")
        .unwrap();
    let uri = uri.as_str().unwrap();
    let payload = uri
        .strip_prefix("data:application/octet-stream;base64,")
        .expect("a base64 data: URI");
    assert_eq!(
        json,
        serde_json::to_value(binary.document.as_json()).unwrap()
    );
    // The same bytes: the gltf crate's loads of both agree.
    let (_, glb_buffers, glb_images) = gltf::import_slice(&glb).unwrap();
    let (_, buffers, images) = gltf::import(&written).unwrap();
    assert_eq!(buffers.len(), 1);
    assert_eq!(*buffers[0], *glb_buffers[0]);
    assert_eq!(*buffers[0], binary.blob.unwrap()[..]);
    assert_eq!(payload.len(), buffers[0].len().div_ceil(3) * 4);
    assert_eq!(images.len(), glb_images.len());
    for (a, b) in images.iter().zip(&glb_images) {
        assert_eq!((a.width, a.height, a.format), (b.width, b.height, b.format));
        assert!(a.pixels == b.pixels);
    }
    assert_eq!(
        GltfContainer::from_path(Path::new("a/B.GLTF")),
        Some(GltfContainer::Embedded)
    );
    assert_eq!(
        GltfContainer::from_path(Path::new("b.glb")),
        Some(GltfContainer::Glb)
    );
    assert_eq!(GltfContainer::from_path(Path::new("c.gltf.tmp")), None);
    assert_eq!(GltfContainer::from_path(Path::new("glb")), None);
}
