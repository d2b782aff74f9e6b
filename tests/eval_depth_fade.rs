//! Volumes meeting opaque surfaces (issue 22, "terraces"): the wall-through-oak scene
//! (`fixtures/scenes/oak_wall.ron`: the bundled oak, an 80 × 80 wall in the plane x = 0)
//! rendered by the CPU slicer over the wall at the default spacing, against the same
//! slicer at an eighth of the spacing (uniform `v₀/8`, MIP level 0 like the default
//! here: the converged reference), at 32³ (`fixtures/scenes/oak32.billow`, 128² pixels)
//! and 128³ (voxelized here from `fixtures/oak`, `--combine opaque` as the fixture,
//! 256² pixels, so that a pixel is no larger than a voxel in both).
//!
//! Measured over the pixels where the wall is behind the volume (the cut): a slice drawn
//! whole or not at all there (a hard depth test) is off by up to one slice's opacity in
//! bands, the terraces; fading each slice over its slab (`render_decoded_over`) leaves
//! only the sampling error the rest of the image has. Tolerance: RMSE over the cut ≤
//! [`CUT_RMSE`] (a hard depth test measures 0.0144 at 32³ and 0.0094 at 128³, see
//! docs/eval.md "Depth fade").

use billow::eval::image::write_comparison_png;
use billow::eval::slicer::{render_decoded_over, OpaqueBackdrop, SlicerParams};
use billow::eval::volume_sampler::DecodedVolume;
use billow::eval::ImageF32;
use billow::test_support::oak_wall::{camera, oak, WALL};
use billow_core::camera::Camera;
use billow_core::slicing::Spacing;
use glam::Vec4;

const CUT_RMSE: f64 = 0.008;

/// The wall (x = 0, y ∈ [−1, 79], z ∈ [−40, 40]) as view distances and a flat colour.
fn wall(cam: &Camera) -> OpaqueBackdrop {
    let mut colour = ImageF32::new(cam.width, cam.height);
    let mut depth = vec![f32::INFINITY; (cam.width * cam.height) as usize];
    for y in 0..cam.height {
        for x in 0..cam.width {
            let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            if r.dir.x.abs() < 1e-9 {
                continue;
            }
            let t = -r.origin.x / r.dir.x;
            let p = r.origin + r.dir * t;
            if t > cam.near && (-1.0..=79.0).contains(&p.y) && (-40.0..=40.0).contains(&p.z) {
                depth[(y * cam.width + x) as usize] = t;
                colour.set(x, y, Vec4::from_array(WALL));
            }
        }
    }
    OpaqueBackdrop { depth, colour }
}

/// RMSE (all four channels) over the pixels where the wall is and the volume in front of
/// it is visible (`a` differs from the bare wall), and that pixel count.
fn cut_rmse(a: &ImageF32, b: &ImageF32, backdrop: &OpaqueBackdrop) -> (f64, usize) {
    let (mut se, mut n) = (0.0f64, 0usize);
    for (i, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        let bare = backdrop.colour.data[i];
        if backdrop.depth[i].is_finite() && (*q - bare).abs().max_element() > 0.02 {
            let d = *p - *q;
            se += f64::from(d.dot(d)) / 4.0;
            n += 1;
        }
    }
    ((se / n.max(1) as f64).sqrt(), n)
}

fn check(res: u32) {
    let asset = oak(res, "eval_depth_fade");
    let vol = DecodedVolume::decode(&asset).expect("decode");
    // Pixels no larger than a voxel: slices at v₀, MIP level 0 (as the reference).
    let cam = camera(if res <= 32 { 128 } else { 256 });
    let backdrop = wall(&cam);
    let dims = asset.level_dims(0);
    let render = |params: &SlicerParams| {
        render_decoded_over(&vol, dims, &asset.cells, &cam, params, &backdrop).expect("render")
    };
    let got = render(&SlicerParams::default());
    let v0 = got.stats.voxel_size;
    let fine = render(&SlicerParams {
        spacing: Spacing::Uniform { spacing: v0 / 8.0 },
        ..Default::default()
    });
    assert!(
        got.stats.max_spacing <= v0 * 1.2,
        "the default spacing must be about v₀ here (MIP level ~0, as the reference): {:?}",
        got.stats
    );
    let (rmse, n) = cut_rmse(&got.image, &fine.image, &backdrop);
    println!(
        "oak {res}³: {} slices vs {} (v₀ = {v0}), cut RMSE vs v₀/8 {rmse:.4} over {n} pixels",
        got.stats.slices, fine.stats.slices
    );
    assert!(
        n > 500,
        "the wall must cut a visible part of the oak ({n} pixels)"
    );
    if rmse.is_nan() || rmse > CUT_RMSE {
        let p = std::env::temp_dir().join(format!("eval_depth_fade_{res}.diff.png"));
        write_comparison_png(&fine.image, &got.image, 4.0, &p).expect("diff image");
        panic!(
            "oak {res}³ over the wall: RMSE over the cut {rmse:.4} (tol {CUT_RMSE}); diff (v₀/8 | default | heatmap × 4): {}",
            p.display()
        );
    }
}

#[test]
fn oak_wall_32_has_no_terraces() {
    check(32);
}

#[test]
fn oak_wall_128_has_no_terraces() {
    check(128);
}
