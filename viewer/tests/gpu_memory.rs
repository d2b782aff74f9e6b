//! What the reports print as GPU texture bytes (`billow_core::gpu_memory`, in `voxelize`,
//! `bbcloud`, `emptyspace`, `info` and `eval`) is what the viewer allocates: the bytes of
//! the textures made while an asset is added, counted from their descriptors
//! (`Gpu::asset_texture_bytes`), equal the prediction for a device without BC7 sampling
//! (lavapipe: software adapters upload decoded), for a volume with normals, the same
//! volume pruned into LOD bands, and a cloud baked unlit with normal maps and a kept mesh,
//! drawn three times: its mesh textures are uploaded once for the foliage mesh and every
//! instance's kept mesh (before 2026-12-05 the mesh pass uploaded them again for each
//! instance: 24.1 MB for one instance of this cloud against 12.9 MB predicted).
//!
//! Needs a GPU adapter (lavapipe is enough): without one it prints `SKIP: …` on stderr,
//! except under CI (env `CI` set) where it fails.

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::emptyspace::{prune, EmptySpaceOptions};
use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};
use billow_core::gpu_memory::{cloud_gpu_bytes, volume_gpu_bytes};
use billow_view::Renderer;
use glam::Mat4;

#[test]
fn reported_gpu_bytes_are_what_the_viewer_allocates() {
    let name = "reported_gpu_bytes_are_what_the_viewer_allocates";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).unwrap().scene;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(80),
        align: 8,
        normals: true,
        ..VoxelizeOptions::default()
    };
    let volume =
        voxelize(&scene, &opts, &|_, _| {})
            .unwrap()
            .into_asset("test", None, BTreeMap::new());
    assert!(volume.normals.is_some());
    let pruned = prune(&volume, &EmptySpaceOptions::default()).unwrap().asset;
    assert!(!pruned.bands.is_empty(), "the test needs a banded asset");
    let cloud_opts = BbcloudOptions {
        samples: 40,
        seed: 1,
        atlas_size: 256,
        normal_map: true,
        shading: Shading {
            light: None,
            ambient: 0.3,
        },
        ..BbcloudOptions::default()
    };
    let (cloud, _) = bake(&scene, &cloud_opts, "test", None, &|_, _| {}).unwrap();
    assert!(cloud.atlases.iter().all(|a| a.normals.is_some()));
    assert!(!cloud.textures.is_empty(), "the kept trunk has a texture");

    let mut r = Renderer::new(gpu);
    assert!(
        !r.gpu.sample_blocks,
        "a software adapter draws decoded textures"
    );
    let added = |r: &mut Renderer, add: &dyn Fn(&mut Renderer)| {
        let before = r.gpu.asset_texture_bytes();
        add(r);
        r.gpu.asset_texture_bytes() - before
    };
    let v = added(&mut r, &|r| {
        r.add_volume(&volume, vec![Mat4::IDENTITY]).unwrap()
    });
    assert_eq!(v, volume_gpu_bytes(&volume, false).without_bc, "volume");
    let p = added(&mut r, &|r| {
        r.add_volume(&pruned, vec![Mat4::IDENTITY]).unwrap()
    });
    assert_eq!(p, volume_gpu_bytes(&pruned, false).without_bc, "pruned");
    // The second of two: the passes' own 1×1 dummies are made with the first.
    let add_cloud = |r: &mut Renderer| {
        let at = |x: f32| Mat4::from_translation(glam::Vec3::new(x, 0.0, 0.0));
        r.add_cloud(&cloud, vec![at(0.0), at(100.0), at(200.0)], None, 0.25, 0.8)
            .unwrap()
    };
    added(&mut r, &add_cloud);
    let c = added(&mut r, &add_cloud);
    let want = cloud_gpu_bytes(&cloud, false).without_bc;
    println!("volume {v} B, pruned {p} B, cloud {c} B (predicted {want} B)");
    assert_eq!(c, want, "cloud");
    // With BC7 sampled the colour is a byte a texel; normals stay 8.
    let bc = volume_gpu_bytes(&volume, true);
    assert!(bc.with_bc < bc.without_bc && bc.without_bc == v);
}
