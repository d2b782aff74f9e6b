//! The measurements of docs/eval.md "Thin layers" (issue 22, "see-through stripes"):
//! which of slice spacing, adaptive vs uniform spacing, opacity correction and MIP choice
//! makes the stripes. Prints the table's rows: the layer's covered area and worst row at
//! 30°, 45° and 60° above it, near and far (`billow::test_support::thin_layer`, the scene
//! and measure of tests/eval_thin_layer.rs and viewer/tests/thin_layer.rs).
//!
//! `cargo run --release --example thin_layer_measurements`

use billow::eval::slicer::{render_volume, SlicerParams};
use billow::eval::volume_sampler::MipFilter;
use billow::test_support::thin_layer::{camera, coverage, plane_asset, Chain, FAR, N, NEAR};
use billow_core::slicing::Spacing;
use billow_format::VolumeAsset;

fn main() {
    let v0 = 1.0 / N as f32;
    let opaque = plane_asset(Chain::Opaque);
    let mean = plane_asset(Chain::Mean);
    let cases: Vec<(&str, &VolumeAsset, SlicerParams, f32)> = vec![
        (
            "adaptive ×1 (default), near",
            &opaque,
            SlicerParams::default(),
            NEAR,
        ),
        (
            "adaptive ×½, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.5 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "adaptive ×¼, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.25 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "uniform v₀, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Uniform { spacing: v0 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "uniform v₀/4, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Uniform { spacing: v0 / 4.0 },
                ..Default::default()
            },
            NEAR,
        ),
        ("adaptive ×1, far", &opaque, SlicerParams::default(), FAR),
        (
            "adaptive ×1, far, nearest MIP",
            &opaque,
            SlicerParams {
                mip_filter: MipFilter::Nearest,
                ..Default::default()
            },
            FAR,
        ),
        (
            "adaptive ×¼, far",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.25 },
                ..Default::default()
            },
            FAR,
        ),
        (
            "mean-combine MIPs, near",
            &mean,
            SlicerParams::default(),
            NEAR,
        ),
        (
            "mean-combine MIPs, far",
            &mean,
            SlicerParams::default(),
            FAR,
        ),
    ];
    println!("| case | 30° area / worst row | 45° | 60° |\n|---|---|---|---|");
    for (name, asset, params, distance) in cases {
        let mut line = format!("| {name} |");
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let (area, row, _) = coverage(
                &render_volume(asset, &cam, &params).expect("render").image,
                &cam,
            );
            line += &format!(" {area:.3} / {row:.3} |");
        }
        println!("{line}");
    }
}
