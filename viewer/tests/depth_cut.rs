//! A mesh plane through a volume cuts it (the paper's z-buffer compliance): the opaque
//! wall is drawn first, the slices behind it fail the depth test.
//!
//! Setup: the 16³ ball in [0,1]³ seen along −z; an opaque red wall in the plane
//! z = 0.5 covering the left half of the image (x < 0.5). Expected:
//! - left half: the **front half** of the ball (cells with z ≥ 0.5 only, rendered
//!   separately) over the red wall; alpha 1. Tolerance max |Δ| ≤ 0.03 (slices start at
//!   the nearest depth in both renders, so they coincide; only the slice that lands
//!   within depth precision of the wall may differ);
//! - right half (no wall): identical to the ball without the wall (max |Δ| ≤ 1e-3).
//!
//! A diff image is written on failure.

mod common;

use billow::eval::image::write_comparison_png;
use billow_core::camera::Camera;
use billow_core::Aabb;
use billow_view::mesh_pass::MeshData;
use billow_view::Renderer;
use common::image_f32;
use glam::{Mat4, Vec3, Vec4};

#[test]
fn a_mesh_plane_through_a_volume_cuts_it() {
    let name = "a_mesh_plane_through_a_volume_cuts_it";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let bounds = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let c = Camera::framed(
        &bounds,
        Vec3::NEG_Z,
        std::f32::consts::FRAC_PI_4,
        96,
        96,
        1.0,
    );
    let cam = common::view_camera(&c);
    // The ball with its cells split at z = 0.5 (so the front half can be drawn alone).
    let mut full = common::ball_asset(false);
    full.cells = Vec::new();
    for (z0, z1) in [(0.0, 0.5), (0.5, 1.0)] {
        full.cells
            .extend(common::box_prisms([0.0, 0.0, z0], [1.0, 1.0, z1], |p| p));
    }
    let mut front = full.clone();
    front.cells.drain(..2);
    let red = [1.0, 0.0, 0.0, 1.0];
    let wall = MeshData::quad(
        Vec3::new(-0.5, -0.5, 0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        red,
    );

    let render = |asset: &billow_format::VolumeAsset, with_wall: bool, gpu| {
        let mut r = Renderer::new(gpu);
        r.ambient = 1.0; // unlit: the wall is exactly `red`
        r.add_volume(asset, vec![Mat4::IDENTITY]).expect("volume");
        if with_wall {
            r.add_mesh(&wall).expect("wall");
        }
        let passes = r.passes();
        let (img, _) = r.render_image(&cam).expect("render");
        (image_f32(&img), passes)
    };
    let (cut, passes) = render(&full, true, gpu);
    assert_eq!(passes, ["mesh", "volume", "resolve"]);
    let gpu = common::gpu_or_skip(name).expect("adapter");
    let (whole, _) = render(&full, false, gpu);
    let gpu = common::gpu_or_skip(name).expect("adapter");
    let (front_only, _) = render(&front, false, gpu);

    let (w, h) = (cut.width, cut.height);
    let mut expected = whole.clone();
    let (mut worst_left, mut worst_right, mut hidden) = (0.0f32, 0.0f32, 0.0f32);
    for y in 0..h {
        for x in 0..w {
            let got = cut.get(x, y);
            if x + 2 < w / 2 {
                let f = front_only.get(x, y);
                let want = f + Vec4::from_array(red) * (1.0 - f.w);
                expected.set(x, y, want);
                worst_left = worst_left.max((got - want).abs().max_element());
                // How much of the back half the wall hides here.
                hidden = hidden.max((whole.get(x, y) - f).w);
            } else if x > w / 2 + 2 {
                worst_right = worst_right.max((got - whole.get(x, y)).abs().max_element());
            }
        }
    }
    println!("left max |Δ| {worst_left:.4}, right max |Δ| {worst_right:.5}, back half alpha up to {hidden:.3}");
    let ok = worst_left <= 0.03 && worst_right <= 1e-3;
    if !ok {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&expected, &cut, 4.0, &p).expect("diff image");
        panic!(
            "wall cut: left max |Δ| {worst_left} (tol 0.03), right {worst_right} (tol 1e-3); diff: {}",
            p.display()
        );
    }
    // The test means something only if the wall hides a visible part of the ball.
    assert!(hidden > 0.1, "the back half must matter ({hidden})");
}
