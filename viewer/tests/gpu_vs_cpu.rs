//! The GPU slicer (billow-view) against the CPU slicer (`billow::eval::slicer`), the
//! reference, on the same asset and camera.
//!
//! Tolerance (premultiplied linear RGBA, all four channels): RMSE ≤ 0.005 and
//! max |Δ| ≤ 0.05 (lavapipe measures ~6e-4 and ~4e-3) over the image; the slice count must be identical. What differs
//! legitimately: the Rgba16Float accumulation (10-bit mantissa per blend, the CPU composites
//! in f32), the GPU's fixed-point texture filtering weights and LOD fraction, and pixels
//! whose centre lies within rounding of a polygon edge (rasterizer rules vs the CPU
//! spans). A diff image (CPU | GPU | heatmap × 4) is written on failure.

mod common;

use billow::eval::image::write_comparison_png;
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow_core::camera::Camera;
use billow_core::slicing::Spacing;
use billow_core::Aabb;
use billow_format::VolumeAsset;
use billow_view::{Renderer, SliceParams, ViewCamera};
use glam::{Mat4, Vec3};

const RMSE_TOL: f64 = 0.005;
const MAX_ABS_TOL: f32 = 0.05;

fn check(
    name: &str,
    asset: &VolumeAsset,
    cam: &Camera,
    spacing: Spacing,
    min_coverage: f64,
) -> Option<()> {
    let gpu = common::gpu_or_skip(name)?;
    let cpu = render_volume(
        asset,
        cam,
        &SlicerParams {
            spacing,
            ..Default::default()
        },
    )
    .expect("CPU render");
    let mut r = Renderer::new(gpu);
    r.params = SliceParams {
        spacing,
        ..Default::default()
    };
    r.add_volume(asset, vec![Mat4::IDENTITY]).expect("upload");
    let (img, stats) = r
        .render_image(&ViewCamera::from_camera(cam))
        .expect("GPU render");
    let gpu_img = common::image_f32(&img);
    let err = compare(&cpu.image, &gpu_img).expect("compare");
    let max_abs = cpu
        .image
        .data
        .iter()
        .zip(&gpu_img.data)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    let ok = err.rmse <= RMSE_TOL && max_abs <= MAX_ABS_TOL && stats.slices == cpu.stats.slices;
    println!(
        "{name}: slices gpu {} cpu {}, rmse {:.5}, max |Δ| {:.4}, coverage cpu {:.4} gpu {:.4}",
        stats.slices,
        cpu.stats.slices,
        err.rmse,
        max_abs,
        cpu.image.coverage(),
        gpu_img.coverage()
    );
    if !ok {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&cpu.image, &gpu_img, 4.0, &p).expect("write diff");
        panic!(
            "{name}: GPU vs CPU rmse {:.5} (tol {RMSE_TOL}), max |Δ| {max_abs:.4} (tol {MAX_ABS_TOL}), \
             slices {} vs {}; diff image: {}",
            err.rmse,
            stats.slices,
            cpu.stats.slices,
            p.display()
        );
    }
    assert!(
        cpu.image.coverage() > min_coverage,
        "{name}: the view must show the volume"
    );
    Some(())
}

fn unit_bounds() -> Aabb {
    Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    }
}

#[test]
fn adaptive_close_view_matches_cpu() {
    let cam = Camera::framed(
        &unit_bounds(),
        Vec3::new(1.0, -0.7, -0.4),
        std::f32::consts::FRAC_PI_4,
        128,
        128,
        1.0,
    );
    check(
        "adaptive_close",
        &common::ball_asset(false),
        &cam,
        Spacing::Adaptive { bias: 1.0 },
        0.05,
    );
}

#[test]
fn adaptive_far_view_uses_coarse_mips_and_matches_cpu() {
    // At 4× the framed distance a pixel covers about 2 voxels: MIP level ~1, opacity corrected.
    let cam = Camera::framed(
        &unit_bounds(),
        Vec3::new(-0.3, -0.5, -1.0),
        std::f32::consts::FRAC_PI_4,
        96,
        64,
        4.0,
    );
    check(
        "adaptive_far",
        &common::ball_asset(false),
        &cam,
        Spacing::Adaptive { bias: 1.0 },
        0.003,
    );
}

#[test]
fn uniform_spacing_and_shell_repeat_match_cpu() {
    let cam = Camera::framed(
        &unit_bounds(),
        Vec3::new(0.2, -1.0, 0.6),
        std::f32::consts::FRAC_PI_4,
        112,
        112,
        1.3,
    );
    check(
        "uniform_shell",
        &common::ball_asset(true),
        &cam,
        Spacing::Uniform { spacing: 0.05 },
        0.05,
    );
}

#[test]
fn the_same_frame_twice_is_bit_identical() {
    let Some(gpu) = common::gpu_or_skip("the_same_frame_twice_is_bit_identical") else {
        return;
    };
    let c = Camera::framed(
        &unit_bounds(),
        Vec3::new(1.0, -0.7, -0.4),
        std::f32::consts::FRAC_PI_4,
        64,
        64,
        1.0,
    );
    let mut r = Renderer::new(gpu);
    // Both assets in one texture batch (a software adapter starts with one texture per
    // batch: volume_pass::preferred_batch).
    r.texture_batch = 2;
    // Two overlapping instances of one asset (one texture), plus a second asset: one
    // draw per (slice, asset) in a fixed order.
    r.add_volume(
        &common::ball_asset(false),
        vec![
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(0.3, 0.0, 0.2)),
        ],
    )
    .expect("upload");
    r.add_volume(
        &common::ball_asset(true),
        vec![Mat4::from_translation(Vec3::new(-0.2, 0.3, 0.0))],
    )
    .expect("upload");
    let (a, sa) = r
        .render_image(&ViewCamera::from_camera(&c))
        .expect("render");
    let (b, sb) = r
        .render_image(&ViewCamera::from_camera(&c))
        .expect("render");
    assert_eq!(sa, sb);
    assert_eq!(
        sa.draw_calls, sa.slabs,
        "two assets share one texture batch: one draw per slab: {sa:?}"
    );
    assert!(a.data == b.data, "two renders of the same frame differ");
    assert!(
        a.data.iter().any(|p| p[3] > 0.1),
        "the frame shows the volume"
    );
}
