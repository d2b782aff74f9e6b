//! Thin layers in the GPU slicer (issue 22, "see-through stripes"): a one-voxel-thick
//! opaque plane seen at 30°, 45° and 60° above it stays opaque, as in the CPU slicer
//! (tests/eval_thin_layer.rs, same asset, cameras and measure:
//! `billow::test_support::thin_layer`).
//!
//! The 64³ volume in `[0,1]³` holds only the layer `y = 32`, α = 1 at every MIP level.
//! Cameras at azimuth 30°, a near distance (MIP level 0) and a far one (MIP level ≈ 1).
//! Over the pixels whose centre ray meets the layer two voxels or more inside its edges:
//! mean alpha ≥ 0.98 and every row's mean alpha (rows with ≥ 8 such pixels) ≥ 0.95.
//! The GPU image must also match the CPU slicer's (RMSE ≤ 0.005, as tests/gpu_vs_cpu.rs).
//! A diff image (CPU | GPU | heatmap × 4) is written on failure.

mod common;

use billow::eval::image::write_comparison_png;
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow::test_support::thin_layer::{
    camera, coverage, plane_asset, Chain, AREA_TOL, FAR, NEAR, ROW_TOL,
};
use billow_view::Renderer;
use glam::Mat4;

const RMSE_TOL: f64 = 0.005;

#[test]
fn one_voxel_opaque_plane_is_covered_on_the_gpu() {
    let name = "one_voxel_opaque_plane_is_covered_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let asset = plane_asset(Chain::Opaque);
    let mut r = Renderer::new(gpu);
    r.add_volume(&asset, vec![Mat4::IDENTITY]).expect("upload");
    let mut failures = Vec::new();
    for distance in [NEAR, FAR] {
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let vc = common::view_camera(&cam);
            let (img, _) = r.render_image(&vc).expect("render");
            let gpu_img = common::image_f32(&img);
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
