//! Slab partitioning and texture batches change what is drawn, never the picture:
//! - partitioned vs plain slicing of instances spread in depth: bit-identical images,
//!   fewer cell × slice instances, empty slabs skipped;
//! - nine assets in batches of 8 textures (two batches, drawn slice by slice) vs one
//!   asset with nine instances (one batch, one draw per slab): bit-identical images.

mod common;

use billow_core::camera::Camera;
use billow_core::Aabb;
use billow_view::{FrameStats, Renderer, RgbaImage, SliceParams, ViewCamera};
use glam::{Mat4, Vec3};

fn camera() -> ViewCamera {
    // A row of instances along the view axis, seen from the front.
    let bounds = Aabb {
        min: Vec3::new(0.0, 0.0, -12.0),
        max: Vec3::new(1.5, 1.0, 1.0),
    };
    let c = Camera::framed(&bounds, Vec3::new(0.15, -0.1, -1.0), 0.7, 96, 80, 1.0);
    common::view_camera(&c)
}

/// Nine positions: three clusters far apart in depth.
fn positions() -> Vec<Mat4> {
    let mut v = Vec::new();
    for (k, z) in [0.0f32, -5.5, -11.0].iter().enumerate() {
        for i in 0..3 {
            let t = Vec3::new(0.25 * i as f32, 0.1 * k as f32, z - 0.3 * i as f32);
            v.push(Mat4::from_translation(t));
        }
    }
    v
}

fn render(r: &mut Renderer, partition: bool) -> (RgbaImage, FrameStats) {
    r.params = SliceParams {
        partition,
        slab_min_slices: 4,
        ..Default::default()
    };
    r.render_image(&camera()).expect("render")
}

#[test]
fn partitioning_draws_less_and_changes_no_pixel() {
    let Some(gpu) = common::gpu_or_skip("partitioning_draws_less_and_changes_no_pixel") else {
        return;
    };
    let mut r = Renderer::new(gpu);
    r.add_volume(&common::ball_asset(false), positions())
        .expect("upload");
    let (plain, sp) = render(&mut r, false);
    let (slabs, ss) = render(&mut r, true);
    println!("plain: {sp:?}\npartitioned: {ss:?}");
    assert_eq!(sp.slices, ss.slices);
    assert_eq!(sp.slabs, 1);
    assert!(ss.slabs > 1 && ss.empty_slabs > 0, "{ss:?}");
    assert!(
        ss.instances * 2 < sp.instances,
        "partitioning should skip most cell × slice pairs: {} vs {}",
        ss.instances,
        sp.instances
    );
    assert!(
        plain.data.iter().any(|p| p[3] > 0.2),
        "the frame shows the volumes"
    );
    assert!(plain.data == slabs.data, "partitioning changed the image");
}

#[test]
fn two_texture_batches_draw_the_same_picture_as_one() {
    let Some(gpu) = common::gpu_or_skip("two_texture_batches_draw_the_same_picture_as_one") else {
        return;
    };
    let ball = common::ball_asset(false);
    let mut one = Renderer::new(gpu);
    one.add_volume(&ball, positions()).expect("upload");
    let (a, sa) = render(&mut one, true);
    let mut many = Renderer::new(one.gpu);
    many.texture_batch = 8;
    for m in positions() {
        many.add_volume(&ball, vec![m]).expect("upload");
    }
    let (b, sb) = render(&mut many, true);
    println!("one asset: {sa:?}\nnine assets: {sb:?}");
    assert_eq!(sa.draw_calls, sa.slabs, "one batch: one draw per slab");
    assert!(sb.draw_calls > sb.slabs, "two batches: per-slice draws");
    assert_eq!(sa.instances, sb.instances);
    assert!(a.data == b.data, "texture batches changed the image");
}
