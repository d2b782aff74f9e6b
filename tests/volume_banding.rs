//! Issue 38, item 5: no contour bands on a solid surface. A closed torus baked at the
//! defaults (BC7) and drawn by the CPU slicer must not add more high-frequency energy
//! inside its surface (`billow::eval::banding`) than the same bake uncompressed: the bands
//! came from BC7 blocks fitted in sRGB-encoded premultiplied colour, where a partly covered
//! voxel of one albedo does not lie on the block's line from zero (the volume's colour is
//! now linear when compressed, `billow::compress::linear_colour`). On the build before, the
//! compressed torus added 0.015 (the uncompressed one 0.000).

use billow::compress::Compression;
use billow::eval::banding::{banding, Banding};
use billow::eval::lighting::{EvalLight, Lighting};
use billow::eval::suite::{spec, EvalOptions, Evaluator, PreparedAsset};
use billow::procgen::torus;
use billow::voxelize::{bake, BakeHooks, BakeOptions, Resolution};
use glam::Vec3;

/// The torus baked at 64 voxels (`compression`), drawn from three directions at 128² lit by
/// an ambient of 1 (its colour as stored: the bands are in colour and opacity, not in the
/// lighting), against the ray-traced mesh: the banding of each view.
fn banding_of(compression: Compression) -> Vec<Banding> {
    let scene = torus(1.0, 0.35, 48, 24);
    let opts = BakeOptions {
        compression,
        decode_blocks: true,
        ..BakeOptions::at(Resolution::Longest(64))
    };
    let baked = bake(&scene, &opts, &BakeHooks::default()).expect("bake");
    assert_eq!(
        baked.asset.header.compress().is_some(),
        compression == Compression::Bc
    );
    let prepared = PreparedAsset::new(&baked.asset).expect("prepare");
    let mut eval = Evaluator::new(
        &scene,
        EvalOptions {
            width: 128,
            height: 128,
            raster_1spp: false,
            lighting: Lighting::Scene {
                light: Vec3::Y,
                ambient: 1.0,
                shadows: false,
            },
            ..EvalOptions::default()
        },
    )
    .expect("evaluator");
    let light = EvalLight::new("ambient", billow_core::shading::DEFAULT_LIGHT, 1.0).expect("light");
    eval.set_light(&light, false).expect("light");
    [
        ("+y", Vec3::Y),
        ("+x+y+z", Vec3::ONE),
        ("-x+y", Vec3::new(-1.0, 0.6, 0.2)),
    ]
    .into_iter()
    .map(|(name, dir)| {
        let reference = eval.reference(&spec(name, dir, 1.0)).expect("reference");
        let (_, image) = eval.asset(&prepared, &reference).expect("asset");
        banding(&reference.image, &image)
    })
    .collect()
}

#[test]
fn a_compressed_solid_surface_shows_no_more_banding_than_an_uncompressed_one() {
    let bc = banding_of(Compression::Bc);
    let raw = banding_of(Compression::None);
    for (i, (b, r)) in bc.iter().zip(&raw).enumerate() {
        eprintln!(
            "view {i}: excess high-frequency luma RMS, BC7 {:+.4}, uncompressed {:+.4} \
             ({} interior pixels)",
            b.excess, r.excess, b.pixels
        );
        assert!(b.pixels > 500, "view {i}: {} interior pixels", b.pixels);
        assert!(
            b.excess <= r.excess + 0.003 && b.excess < 0.005,
            "view {i}: the BC7 torus adds {:.4} of high-frequency luma (uncompressed {:.4}): \
             contour bands",
            b.excess,
            r.excess
        );
    }
}
