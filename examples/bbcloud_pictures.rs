//! The pictures of docs/bbcloud.md (not a check): the source | cloud | difference panels
//! of two views of the bundled oak, each LOD's render, and LOD 0's atlas (straight alpha,
//! reduced), written into DIR.
//!
//! `cargo run --release --example bbcloud_pictures -- docs/bbcloud`

use std::path::PathBuf;

use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::eval::image::write_comparisons_png;
use billow::eval::ImageF32;
use billow::export::{write_cloud_glb, GltfOptions};
use billow::import::{import, ImportOptions};
use billow::test_support::reference_renders;
use billow_core::camera::Camera;
use glam::Vec3;

fn oak_path() -> PathBuf {
    billow::test_support::repo().join("fixtures/oak/eztree_oak_medium.gltf")
}

fn main() {
    let Some(out) = std::env::args_os().nth(1) else {
        eprintln!("usage: bbcloud_pictures DIR (docs/bbcloud for the docs' pictures)");
        std::process::exit(2);
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
    let reference = reference_renders(&source, &cams);
    let cloud = import(&glb, &ImportOptions::default()).unwrap().scene;
    let lod0 = reference_renders(&cloud, &cams);
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
        lods.push(reference_renders(&s, &cams[..1]).remove(0));
    }
    let refs: Vec<&ImageF32> = lods.iter().collect();
    write_comparisons_png(&reference[0], &refs, 4.0, &out.join("oak_lods_front.png")).unwrap();
    // LOD 0's atlas, straight alpha over white-free transparency, reduced to 512.
    let png = billow::export::straight::atlas_png(&asset.atlases[0]).unwrap();
    let img = image::load_from_memory(&png).unwrap();
    img.resize(512, 512, image::imageops::FilterType::Triangle)
        .save(out.join("oak_lod0_atlas.png"))
        .unwrap();
}
