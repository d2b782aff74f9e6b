//! Thin layers in the CPU slicer (issue 22, "see-through stripes"): a one-voxel-thick
//! opaque plane seen at 30°, 45° and 60° above it must stay opaque.
//!
//! Setup: a 64³ volume in `[0,1]³` whose only non-empty voxels are the layer `y = 32`
//! (α = 1 at every MIP level, the chain the `opaque`/`max` combine bakes for a plane:
//! composited along y, one voxel thick at every level). The camera looks at the layer's
//! centre from azimuth 30° at a near distance (pixels smaller than a voxel: slices at
//! `v₀`, MIP level 0) and a far one (MIP level ≈ 1). "Covered" is measured over the
//! pixels whose centre ray meets the layer at least two voxels inside its edges: the mean
//! alpha there (the area) must be ≥ 0.98 and the mean alpha of every pixel row with at
//! least 8 such pixels ≥ 0.95 (stripes run along rows: a slice plane meets the layer in a
//! line of constant depth).
//!
//! The layer, cameras and measure are `billow::test_support::thin_layer`, shared with the
//! GPU slicer's test (viewer/tests/thin_layer.rs); `cargo run --release --example
//! thin_layer_measurements` prints the table of docs/eval.md "Thin layers".

use billow::eval::slicer::{render_volume, SlicerParams};
use billow::eval::ImageF32;
use billow::test_support::thin_layer::{
    camera, coverage, plane_asset, Chain, AREA_TOL, FAR, NEAR, ROW_TOL,
};
use billow_core::camera::Camera;
use billow_format::VolumeAsset;

fn render(asset: &VolumeAsset, cam: &Camera, params: &SlicerParams) -> ImageF32 {
    render_volume(asset, cam, params).expect("render").image
}

#[test]
fn one_voxel_opaque_plane_is_covered_at_30_45_60_degrees() {
    let asset = plane_asset(Chain::Opaque);
    let mut failures = Vec::new();
    for distance in [NEAR, FAR] {
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let img = render(&asset, &cam, &SlicerParams::default());
            let (area, row, rows) = coverage(&img, &cam);
            println!(
                "distance {distance} elevation {elevation}°: area {area:.4}, worst row {row:.4} ({rows} rows)"
            );
            assert!(rows >= 12, "the layer must cover rows ({rows})");
            if !(area >= AREA_TOL && row >= ROW_TOL) {
                let p = std::env::temp_dir()
                    .join(format!("eval_thin_layer_{distance}_{elevation}.png"));
                img.write_png(&p).expect("png");
                failures.push(format!(
                    "distance {distance}, {elevation}°: area {area:.4} (≥ {AREA_TOL}), worst row {row:.4} (≥ {ROW_TOL}); image {}",
                    p.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
