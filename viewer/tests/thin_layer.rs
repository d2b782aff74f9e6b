//! Thin layers in the GPU slicer (issue 22, "see-through stripes"): a one-voxel-thick
//! opaque plane seen at 30°, 45° and 60° above it stays opaque, as in the CPU slicer
//! (tests/eval_thin_layer.rs, same asset, cameras and measure).
//!
//! The 64³ volume in `[0,1]³` holds only the layer `y = 32`, α = 1 at every MIP level.
//! Cameras at azimuth 30°, a near distance (MIP level 0) and a far one (MIP level ≈ 1).
//! Over the pixels whose centre ray meets the layer two voxels or more inside its edges:
//! mean alpha ≥ 0.98 and every row's mean alpha (rows with ≥ 8 such pixels) ≥ 0.95.
//! The GPU image must also match the CPU slicer's (RMSE ≤ 0.005, as tests/gpu_vs_cpu.rs).
//! A diff image (CPU | GPU | heatmap × 4) is written on failure.

mod common;

use billow::eval::image::{linear_to_srgb, write_comparison_png};
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow::eval::ImageF32;
use billow_core::camera::Camera;
use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, VolumeAsset};
use billow_view::{Renderer, ViewCamera};
use glam::{Mat4, Vec3, Vec4};

const N: u32 = 64;
const LAYER: u32 = 32;
const SIZE: u32 = 128;
const COLOR: [f32; 3] = [0.3, 0.6, 0.2];
const AREA_TOL: f64 = 0.98;
const ROW_TOL: f64 = 0.95;
const RMSE_TOL: f64 = 0.005;

fn plane_asset() -> VolumeAsset {
    let dims = [N; 3];
    let mips = full_mip_count(dims);
    let q = |v: f32| (v * 255.0).round() as u8;
    let texel = [
        q(linear_to_srgb(COLOR[0])),
        q(linear_to_srgb(COLOR[1])),
        q(linear_to_srgb(COLOR[2])),
        255,
    ];
    let levels = (0..mips)
        .map(|l| {
            let d = mip_dims(dims, l);
            let layer = LAYER >> l;
            let mut v = vec![0u8; (d[0] * d[1] * d[2] * 4) as usize];
            for z in 0..d[2] {
                for x in 0..d[0] {
                    let i = 4 * (x + d[0] * (layer + d[1] * z)) as usize;
                    v[i..i + 4].copy_from_slice(&texel);
                }
            }
            v
        })
        .collect();
    VolumeAsset {
        header: Header::volume(
            "thin layer",
            ColourSpace::SrgbPremultiplied,
            dims,
            mips,
            false,
        ),
        levels,
        normals: None,
        bands: Vec::new(),
        cells: common::box_prisms([0.0; 3], [1.0; 3], |p| p),
    }
}

fn layer_y() -> f32 {
    (LAYER as f32 + 0.5) / N as f32
}

fn camera(elevation_deg: f32, distance: f32) -> Camera {
    let (e, az) = (elevation_deg.to_radians(), 30f32.to_radians());
    let target = Vec3::new(0.5, layer_y(), 0.5);
    let dir = Vec3::new(e.cos() * az.sin(), e.sin(), e.cos() * az.cos());
    Camera {
        eye: target + dir * distance,
        target,
        up: Vec3::Y,
        fov_y: std::f32::consts::FRAC_PI_4,
        width: SIZE,
        height: SIZE,
        near: 0.05,
        far: distance + 3.0,
    }
}

/// (mean alpha over the layer's pixels, worst row mean, rows measured).
fn coverage(img: &ImageF32, cam: &Camera) -> (f64, f64, usize) {
    let m = 2.0 / N as f32;
    let (mut sum, mut n) = (0.0f64, 0usize);
    let mut worst = f64::INFINITY;
    let mut rows = 0;
    for y in 0..cam.height {
        let (mut rs, mut rn) = (0.0f64, 0usize);
        for x in 0..cam.width {
            let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            if r.dir.y.abs() < 1e-9 {
                continue;
            }
            let t = (layer_y() - r.origin.y) / r.dir.y;
            let p = r.origin + r.dir * t;
            if t > 0.0 && p.x > m && p.x < 1.0 - m && p.z > m && p.z < 1.0 - m {
                rs += f64::from(img.get(x, y).w);
                rn += 1;
            }
        }
        sum += rs;
        n += rn;
        if rn >= 8 {
            rows += 1;
            worst = worst.min(rs / rn as f64);
        }
    }
    (sum / n.max(1) as f64, worst, rows)
}

#[test]
fn one_voxel_opaque_plane_is_covered_on_the_gpu() {
    let name = "one_voxel_opaque_plane_is_covered_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let asset = plane_asset();
    let mut r = Renderer::new(gpu);
    r.add_volume(&asset, vec![Mat4::IDENTITY]).expect("upload");
    let mut failures = Vec::new();
    for distance in [1.8f32, 4.5] {
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let vc = ViewCamera::from_parts(
                cam.view(),
                cam.fov_y,
                cam.width,
                cam.height,
                cam.near,
                cam.far,
            );
            let (img, _) = r.render_image(&vc).expect("render");
            let gpu_img = ImageF32 {
                width: img.width,
                height: img.height,
                data: img.data.iter().map(|p| Vec4::from_array(*p)).collect(),
            };
            let cpu = render_volume(&asset, &cam, &SlicerParams::default())
                .expect("CPU render")
                .image;
            let (area, row, rows) = coverage(&gpu_img, &cam);
            let rmse = compare(&cpu, &gpu_img).expect("compare").rmse;
            println!(
                "distance {distance} elevation {elevation}°: GPU area {area:.4}, worst row {row:.4} ({rows} rows), rmse vs CPU {rmse:.5}"
            );
            assert!(rows >= 12, "the layer must cover rows ({rows})");
            if !(area >= AREA_TOL && row >= ROW_TOL && rmse <= RMSE_TOL) {
                let p = common::out_dir().join(format!("{name}_{distance}_{elevation}.diff.png"));
                write_comparison_png(&cpu, &gpu_img, 4.0, &p).expect("diff image");
                failures.push(format!(
                    "distance {distance}, {elevation}°: area {area:.4} (≥ {AREA_TOL}), worst row {row:.4} (≥ {ROW_TOL}), rmse vs CPU {rmse:.5} (≤ {RMSE_TOL}); diff {}",
                    p.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
