//! The `.glb` export of a billboard cloud: strict glTF load, billow's own importer, and a
//! render in the eval's reference ray tracer close to the source oak's render — close
//! enough that a broken export (UVs flipped inside each billboard, back faces missing)
//! fails the same bound.

use std::path::{Path, PathBuf};

use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::camera::Camera;
use billow::eval::image::write_comparisons_png;
use billow::eval::metrics::compare;
use billow::eval::reference::{ReferenceRenderer, Sampling};
use billow::eval::ImageF32;
use billow::export::{cloud_glb_bytes, write_cloud_glb, GltfOptions};
use billow::import::{import, ImportOptions};
use billow::scene::Scene;
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

fn render_all(scene: &Scene, cams: &[Camera]) -> Vec<ImageF32> {
    let r = ReferenceRenderer::new(scene);
    cams.iter()
        .map(|c| {
            r.render(c, Sampling::Stratified { per_axis: 3 })
                .expect("render")
        })
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
    let reference = render_all(&source, &cams);
    let good = render_all(&cloud, &cams);
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
    let flipped_img = render_all(&flipped, &cams);
    let no_back_img = render_all(&no_back, &cams);
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

/// Pictures for docs/bbcloud.md (not a check): `BBCLOUD_PICTURES=docs/bbcloud cargo test
/// --release --test bbcloud_gltf -- --ignored`. Writes the source | cloud | difference
/// panels of two views, each LOD's render, and LOD 0's atlas (straight alpha, reduced).
#[test]
#[ignore]
fn pictures_for_the_docs() {
    let Some(out) = std::env::var_os("BBCLOUD_PICTURES") else {
        println!("set BBCLOUD_PICTURES=DIR to write the pictures");
        return;
    };
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out).unwrap();
    let source = import(&oak_path(), &ImportOptions::default())
        .expect("oak")
        .scene;
    let opts = BbcloudOptions {
        lods: 3,
        shading: Shading {
            light: None,
            ambient: 1.0,
        },
        ..BbcloudOptions::default()
    };
    let asset = bake(&source, &opts, "billow docs", None, &|_, _| {})
        .unwrap()
        .0;
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("oak.glb");
    write_cloud_glb(&asset, &glb, &GltfOptions::default()).unwrap();
    let (doc, _, _) = gltf::import(&glb).unwrap();
    let cams: Vec<Camera> = [Vec3::NEG_Z, Vec3::new(1.0, -0.4, 1.0).normalize()]
        .iter()
        .map(|&d| Camera::framed(&source.bounds, d, 0.6, 320, 320, 1.0))
        .collect();
    let reference = render_all(&source, &cams);
    let cloud = import(&glb, &ImportOptions::default()).unwrap().scene;
    let lod0 = render_all(&cloud, &cams);
    for (i, name) in ["front", "diagonal"].iter().enumerate() {
        write_comparisons_png(
            &reference[i],
            &[&lod0[i]],
            4.0,
            &out.join(format!("oak_vs_lod0_{name}.png")),
        )
        .unwrap();
    }
    // Each LOD alone (with the trunk): keep only its material prefix.
    let mut lods = Vec::new();
    for l in 0..doc.scenes().count() {
        // The default scene is LOD 0; other LODs: swap the cloud triangles of LOD 0 for LOD l
        // by re-exporting an asset whose only level is l.
        let mut one = asset.clone();
        let lv = asset.levels[l];
        let range = lv.first_billboard as usize..(lv.first_billboard + lv.billboard_count) as usize;
        let arange = lv.first_atlas as usize..(lv.first_atlas + lv.atlas_count) as usize;
        one.billboards = asset.billboards[range].to_vec();
        one.atlases = asset.atlases[arange].to_vec();
        for b in one.billboards.iter_mut() {
            b.parent = None;
            b.front.atlas -= lv.first_atlas;
            b.back.atlas -= lv.first_atlas;
        }
        one.levels = vec![billow_format::CloudLevel {
            first_billboard: 0,
            first_atlas: 0,
            ..lv
        }];
        one.foliage.billboard.iter_mut().for_each(|b| *b = 0);
        if one.billboards.len() < asset.levels[0].billboard_count as usize {
            one.foliage = Default::default();
        }
        let p = dir.path().join(format!("lod{l}.glb"));
        write_cloud_glb(&one, &p, &GltfOptions::default()).unwrap();
        let s = import(&p, &ImportOptions::default()).unwrap().scene;
        lods.push(render_all(&s, &cams[..1]).remove(0));
    }
    let refs: Vec<&ImageF32> = lods.iter().collect();
    write_comparisons_png(&reference[0], &refs, 4.0, &out.join("oak_lods_front.png")).unwrap();
    // LOD 0's atlas, straight alpha over white-free transparency, reduced to 512.
    let png = billow::bbcloud::straight::atlas_png(&asset.atlases[0]).unwrap();
    let img = image::load_from_memory(&png).unwrap();
    img.resize(512, 512, image::imageops::FilterType::Triangle)
        .save(out.join("oak_lod0_atlas.png"))
        .unwrap();
}
