//! Volumes meeting opaque surfaces on the GPU (issue 22, "terraces"): the
//! wall-through-oak scene (`fixtures/scenes/oak_wall.ron`) at 32³ and 128³, the GPU
//! render against the CPU slicer composited over the same wall
//! (`billow::eval::slicer::render_decoded_over`, which fades each slice over its slab at
//! the opaque depth; tests/eval_depth_fade.rs checks that reference against a slicing
//! four times finer).
//!
//! The wall is an unlit mesh (ambient 1), its colour read back from a GPU render of the
//! wall alone, its depth the exact ray/plane distance. Tolerance (premultiplied linear
//! RGBA): RMSE ≤ 0.005 over the image (as tests/gpu_vs_cpu.rs) and ≤ 0.01 over the cut
//! (pixels where the wall is behind the visible volume; the viewer's hard depth test and
//! alpha filtering before issue 22 measured 0.027 at 32³ and 0.023 at 128³ there). A diff
//! image (CPU | GPU | heatmap × 4) is written on failure.

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow::eval::image::write_comparison_png;
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_decoded_over, OpaqueBackdrop, SlicerParams};
use billow::eval::volume_sampler::DecodedVolume;
use billow::eval::ImageF32;
use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, CombineFn, Preset, Resolution, VoxelizeOptions};
use billow_core::camera::Camera;
use billow_format::VolumeAsset;
use billow_view::mesh_pass::MeshData;
use billow_view::{Renderer, RgbaImage, ViewCamera};
use glam::{Mat4, Vec3, Vec4};

const RMSE_TOL: f64 = 0.005;
const CUT_RMSE_TOL: f64 = 0.01;
const WALL: [f32; 4] = [0.5, 0.45, 0.4, 1.0];

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn oak(res: u32) -> VolumeAsset {
    if res == 32 {
        return VolumeAsset::read(&repo().join("fixtures/scenes/oak32.billow")).expect("oak32");
    }
    let scene = import(
        &repo().join("fixtures/oak/eztree_oak_medium.gltf"),
        &ImportOptions::default(),
    )
    .expect("import the oak")
    .scene;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        combine: CombineFn::Preset(Preset::Opaque),
        ..VoxelizeOptions::default()
    };
    voxelize(&scene, &opts, &|_, _| {})
        .expect("voxelize")
        .into_asset("oak_wall_fade", None, BTreeMap::new())
}

fn camera(size: u32) -> Camera {
    Camera {
        eye: Vec3::new(110.0, 60.0, 70.0),
        target: Vec3::new(0.0, 30.0, 0.0),
        up: Vec3::Y,
        fov_y: 45f32.to_radians(),
        width: size,
        height: size,
        near: 1.0,
        far: 400.0,
    }
}

fn image(i: &RgbaImage) -> ImageF32 {
    ImageF32 {
        width: i.width,
        height: i.height,
        data: i.data.iter().map(|p| Vec4::from_array(*p)).collect(),
    }
}

fn check(name: &str, res: u32, size: u32) {
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let asset = oak(res);
    let cam = camera(size);
    let vc = ViewCamera::from_parts(
        cam.view(),
        cam.fov_y,
        cam.width,
        cam.height,
        cam.near,
        cam.far,
    );
    // wall.obj (2 × 2 in x = 0) scaled by 40, moved down by 1.
    let wall = MeshData::quad(
        Vec3::new(0.0, -1.0, -40.0),
        Vec3::new(0.0, 0.0, 80.0),
        Vec3::new(0.0, 80.0, 0.0),
        WALL,
    );
    let mut r = Renderer::new(gpu);
    r.ambient = 1.0; // unlit wall
    r.add_mesh(&wall).expect("wall");
    let (bare, _) = r.render_image(&vc).expect("wall alone");
    let bare = image(&bare);
    r.add_volume(&asset, vec![Mat4::IDENTITY]).expect("oak");
    let (got, stats) = r.render_image(&vc).expect("wall and oak");
    let got = image(&got);

    let mut depth = vec![f32::INFINITY; (size * size) as usize];
    for y in 0..size {
        for x in 0..size {
            if bare.get(x, y).w < 0.5 {
                continue;
            }
            let ray = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            // `dir` has a unit component along the view axis: t is the view distance.
            depth[(y * size + x) as usize] = -ray.origin.x / ray.dir.x;
        }
    }
    let backdrop = OpaqueBackdrop {
        depth,
        colour: bare.clone(),
    };
    let vol = DecodedVolume::decode(&asset).expect("decode");
    let cpu = render_decoded_over(
        &vol,
        asset.level_dims(0),
        &asset.cells,
        &cam,
        &SlicerParams::default(),
        &backdrop,
    )
    .expect("CPU render");
    let rmse = compare(&cpu.image, &got).expect("compare").rmse;
    let (mut se, mut n) = (0.0f64, 0usize);
    for i in 0..got.data.len() {
        let (c, b) = (cpu.image.data[i], bare.data[i]);
        if backdrop.depth[i].is_finite() && (c - b).abs().max_element() > 0.02 {
            let d = got.data[i] - c;
            se += f64::from(d.dot(d)) / 4.0;
            n += 1;
        }
    }
    let cut = (se / n.max(1) as f64).sqrt();
    println!(
        "{name}: slices gpu {} cpu {}, rmse {rmse:.5}, cut rmse {cut:.5} over {n} pixels",
        stats.slices, cpu.stats.slices
    );
    assert!(n > 500, "the wall must cut a visible part of the oak ({n})");
    if !(rmse <= RMSE_TOL && cut <= CUT_RMSE_TOL) {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&cpu.image, &got, 4.0, &p).expect("diff image");
        panic!(
            "{name}: GPU vs CPU rmse {rmse:.5} (tol {RMSE_TOL}), over the cut {cut:.5} (tol {CUT_RMSE_TOL}); diff: {}",
            p.display()
        );
    }
}

#[test]
fn oak_wall_32_fades_like_the_cpu_slicer() {
    check("oak_wall_32_fades_like_the_cpu_slicer", 32, 128);
}

#[test]
fn oak_wall_128_fades_like_the_cpu_slicer() {
    check("oak_wall_128_fades_like_the_cpu_slicer", 128, 192);
}
