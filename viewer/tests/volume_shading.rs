//! Runtime shading of volumes from their Toksvig normals on the GPU (VB §3.2
//! "Reflectance"), against the analytic Lambert ratio and against the CPU slicer.
//!
//! - The ball of `billow::noise_volume::sphere` (64³, radius 0.8, radial normals) seen
//!   along −z and lit from +x with ambient 0.3 is brighter on its +x side than on its −x
//!   side by the Lambert ratio `(a + (1 − a)·sin 45°) / a` at the points 45° off the view
//!   axis, within 5 % (as tests/volume_shading.rs checks for the CPU slicer).
//! - GPU and CPU renders of lit volumes agree: RMSE ≤ 0.005 over premultiplied linear
//!   RGBA (the tolerance of gpu_vs_cpu.rs, whose notes on what differs apply), a diff image
//!   on failure.
//! - The same for a volume of normal moments (format 1.4, lit two-sided).
//! - Baking normals changes the picture: a torus voxelized with and without normals
//!   renders differently (it was pixel-identical when the viewer ignored normals).
//! - The viewer's default light is the one the CPU side uses without a scene
//!   (`billow_core::shading::{DEFAULT_LIGHT, DEFAULT_AMBIENT}`).

mod common;

use billow::eval::image::write_comparison_png;
use billow::eval::lighting::VolumeLight;
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow::eval::ImageF32;
use billow::noise_volume::{asteroid, sphere};
use billow::test_support::mean_around as around;
use billow_core::camera::Camera;
use billow_core::shading::{DEFAULT_AMBIENT, DEFAULT_LIGHT};
use billow_core::Aabb;
use billow_format::VolumeAsset;
use billow_view::{Renderer, ViewCamera};
use glam::{Mat4, Vec3};

const AMBIENT: f32 = 0.3;
const TOL: f32 = 0.05;
const RMSE_TOL: f64 = 0.005;

fn box_camera(dir: Vec3, size: u32) -> Camera {
    let b = Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::ONE,
    };
    Camera::framed(&b, dir, std::f32::consts::FRAC_PI_4, size, size, 1.0)
}

fn gpu_render(
    gpu: billow_view::Gpu,
    asset: &VolumeAsset,
    cam: &Camera,
    light: VolumeLight,
) -> ImageF32 {
    let mut r = Renderer::new(gpu);
    r.light_dir = light.dir;
    r.ambient = light.ambient;
    r.add_volume(asset, vec![Mat4::IDENTITY]).expect("upload");
    let (img, _) = r
        .render_image(&ViewCamera::from_camera(cam))
        .expect("GPU render");
    common::image_f32(&img)
}

#[test]
fn a_ball_lit_from_plus_x_is_brighter_there_by_the_lambert_ratio_on_the_gpu() {
    let Some(gpu) = common::gpu_or_skip("volume_shading::lambert_ratio") else {
        return;
    };
    let asset = sphere(64, Vec3::splat(0.5));
    let cam = box_camera(Vec3::NEG_Z, 128);
    let light = VolumeLight {
        dir: Vec3::X,
        ambient: AMBIENT,
    };
    let img = gpu_render(gpu, &asset, &cam, light);
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let plus = around(&img, &cam, Vec3::new(0.8 * s, 0.0, 0.8 * s));
    let minus = around(&img, &cam, Vec3::new(-0.8 * s, 0.0, 0.8 * s));
    let want = (AMBIENT + (1.0 - AMBIENT) * s) / AMBIENT;
    let got = plus.x / minus.x;
    println!(
        "GPU: +x {:.4}, −x {:.4}, ratio {got:.3} (Lambert {want:.3})",
        plus.x, minus.x
    );
    assert!(plus.w > 0.99 && minus.w > 0.99, "{plus} {minus}");
    assert!(
        (got / want - 1.0).abs() < TOL,
        "ratio +x/−x {got:.3}, Lambert {want:.3} (tolerance {TOL})"
    );
}

fn gpu_matches_cpu(name: &str, asset: &VolumeAsset, cam: &Camera, light: VolumeLight) {
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let cpu = render_volume(
        asset,
        cam,
        &SlicerParams {
            light: Some(light),
            ..Default::default()
        },
    )
    .expect("CPU render")
    .image;
    let unlit = render_volume(
        asset,
        cam,
        &SlicerParams {
            light: None,
            ..Default::default()
        },
    )
    .expect("CPU render")
    .image;
    let img = gpu_render(gpu, asset, cam, light);
    let err = compare(&cpu, &img).expect("compare");
    let shading = compare(&cpu, &unlit).expect("compare");
    println!(
        "{name}: GPU vs CPU rmse {:.5}; the shading itself changes the CPU image by rmse {:.4}",
        err.rmse, shading.rmse
    );
    assert!(
        shading.rmse > 0.005,
        "{name}: the view must show shading (lit vs unlit rmse {:.4})",
        shading.rmse
    );
    if err.rmse > RMSE_TOL {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&cpu, &img, 4.0, &p).expect("write diff");
        panic!(
            "{name}: GPU vs CPU rmse {:.5} (tol {RMSE_TOL}); diff image: {}",
            err.rmse,
            p.display()
        );
    }
}

#[test]
fn lit_ball_gpu_matches_cpu() {
    gpu_matches_cpu(
        "lit_ball",
        &sphere(64, Vec3::new(0.6, 0.5, 0.4)),
        &box_camera(Vec3::new(0.4, -0.5, -1.0), 128),
        VolumeLight::default(),
    );
}

/// Normal moments are lit two-sided by the viewer as by the CPU slicer
/// (`billow_core::shading::moments_diffuse_factor`, `volume.wgsl`'s `moments_cosine`).
#[test]
fn lit_ball_of_moments_gpu_matches_cpu() {
    gpu_matches_cpu(
        "lit_ball_moments",
        &common::as_moments(sphere(64, Vec3::new(0.6, 0.5, 0.4))),
        &box_camera(Vec3::new(0.4, -0.5, -1.0), 128),
        VolumeLight {
            dir: Vec3::new(-0.8, 0.5, 0.2).normalize(),
            ambient: 0.3,
        },
    );
}

#[test]
fn lit_asteroid_gpu_matches_cpu() {
    // Far enough that coarser MIP levels (Toksvig-shortened normals) are sampled.
    let b = Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::ONE,
    };
    let cam = Camera::framed(
        &b,
        Vec3::new(-0.7, -0.3, -1.0),
        std::f32::consts::FRAC_PI_4,
        96,
        96,
        2.5,
    );
    gpu_matches_cpu(
        "lit_asteroid",
        &asteroid(64, 105),
        &cam,
        VolumeLight {
            dir: Vec3::new(0.5, 0.6, 0.3).normalize(),
            ambient: 0.35,
        },
    );
}

#[test]
fn baking_normals_changes_the_viewers_picture() {
    let Some(gpu) = common::gpu_or_skip("volume_shading::normals_change_the_picture") else {
        return;
    };
    use billow::voxelize::{voxelize, VoxelizeOptions};
    let scene = billow::procgen::torus(1.0, 0.4, 48, 24);
    let bake = |normals: bool| {
        let opts = VoxelizeOptions {
            resolution: billow::voxelize::Resolution::Longest(48),
            normals,
            ..Default::default()
        };
        let v = voxelize(&scene, &opts, &|_, _| {}).expect("voxelize");
        let params = billow::voxelize::asset::bake_params(&v, &opts, &Default::default());
        v.into_asset("test", None, params)
    };
    let (with, without) = (bake(true), bake(false));
    assert!(with.normals.is_some() && without.normals.is_none());
    let b = &with.header.bounds;
    let bounds = Aabb {
        min: Vec3::from(b.min),
        max: Vec3::from(b.max),
    };
    let cam = Camera::framed(
        &bounds,
        Vec3::new(0.3, -1.0, -0.6),
        std::f32::consts::FRAC_PI_4,
        96,
        96,
        1.0,
    );
    let shot = |gpu: billow_view::Gpu, asset: &VolumeAsset| {
        let mut r = Renderer::new(gpu);
        r.add_volume(asset, vec![Mat4::IDENTITY]).expect("upload");
        r.render_image(&ViewCamera::from_camera(&cam))
            .expect("render")
            .0
    };
    let a = shot(gpu, &with);
    let Some(gpu) = common::gpu_or_skip("volume_shading::normals_change_the_picture") else {
        return;
    };
    let b = shot(gpu, &without);
    let diff: f32 = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).sum::<f32>())
        .sum::<f32>()
        / (3 * a.data.len()) as f32;
    let changed = a
        .data
        .iter()
        .zip(&b.data)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 0.02))
        .count();
    println!("normals vs none: mean |Δrgb| {diff:.4}, {changed} pixels differ by > 0.02");
    assert!(
        changed > a.data.len() / 20,
        "baking normals must change the picture: {changed} pixels differ"
    );
}

#[test]
fn the_viewers_default_light_is_billows() {
    let Some(gpu) = common::gpu_or_skip("volume_shading::default_light") else {
        return;
    };
    let r = Renderer::new(gpu);
    assert!((r.light_dir - DEFAULT_LIGHT.normalize()).length() < 1e-6);
    assert_eq!(r.ambient, DEFAULT_AMBIENT);
    let scene = billow_view::scene::SceneFile::default();
    assert!(
        (Vec3::from(scene.light.direction).normalize() - DEFAULT_LIGHT.normalize()).length() < 1e-6
    );
    assert_eq!(scene.light.ambient, DEFAULT_AMBIENT);
}
