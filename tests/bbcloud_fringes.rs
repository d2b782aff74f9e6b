//! MIPs without dark fringes, on the oak's leaves.
//!
//! A straight-alpha consumer (a glTF viewer) builds MIPs from the exported PNG by averaging
//! straight colour regardless of alpha. Where transparent texels carry black (a naive
//! un-premultiply), leaf edges darken with distance. The export dilates colour into the
//! transparent texels (pull-push over the asset's premultiplied MIPs), so the straight
//! colour of partly covered texels stays that of the leaves at every MIP level. The
//! asset's own premultiplied MIPs are checked the same way.

use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::export::straight::{straight_rgba8, straight_rgba8_undilated};
use billow::import::{import, ImportOptions};
use billow::texture::srgb_to_linear_lut;
use glam::{Vec3, Vec4};

/// Linear straight RGBA of an 8-bit straight sRGB image.
fn decode(rgba: &[u8]) -> Vec<Vec4> {
    let l = srgb_to_linear_lut();
    rgba.chunks_exact(4)
        .map(|p| {
            Vec4::new(
                l[p[0] as usize],
                l[p[1] as usize],
                l[p[2] as usize],
                f32::from(p[3]) / 255.0,
            )
        })
        .collect()
}

/// A viewer's MIP: unweighted 2×2 box filter of straight linear colour and alpha.
fn viewer_mip(img: &[Vec4], w: usize, h: usize) -> (Vec<Vec4>, usize, usize) {
    let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
    let mut out = Vec::with_capacity(w2 * h2);
    for y in 0..h2 {
        for x in 0..w2 {
            let g = |i: usize, j: usize| img[(2 * y + j).min(h - 1) * w + (2 * x + i).min(w - 1)];
            out.push(0.25 * (g(0, 0) + g(1, 0) + g(0, 1) + g(1, 1)));
        }
    }
    (out, w2, h2)
}

fn luma(c: Vec3) -> f64 {
    f64::from(0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
}

/// Mean luma of straight colour over edge texels (0.1 < α < 0.9).
fn edge_luma(img: &[Vec4]) -> (f64, usize) {
    let e: Vec<f64> = img
        .iter()
        .filter(|p| p.w > 0.1 && p.w < 0.9)
        .map(|p| luma(p.truncate()))
        .collect();
    (e.iter().sum::<f64>() / e.len().max(1) as f64, e.len())
}

#[test]
fn oak_leaf_edges_do_not_darken_in_mips() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).unwrap().scene;
    let opts = BbcloudOptions {
        samples: 100,
        seed: 2,
        atlas_size: 1024,
        shading: Shading {
            light: None,
            ambient: 1.0,
        },
        ..BbcloudOptions::default()
    };
    let (asset, _) = bake(&scene, &opts, "billow test", None, &|_, _| {}).unwrap();
    let atlas = &asset.atlases[0];
    let (w, h) = (atlas.width as usize, atlas.height as usize);
    let good = decode(&straight_rgba8(atlas, 0));
    let naive = decode(&straight_rgba8_undilated(atlas, 0));
    // The mean leaf colour: alpha-weighted mean straight colour of level 0.
    let (num, den) = good.iter().fold((0.0, 0.0), |(n, d), p| {
        (n + luma(p.truncate()) * f64::from(p.w), d + f64::from(p.w))
    });
    assert!(den > 10_000.0, "too little coverage: {den}");
    let mean = num / den;

    let tol = 0.08;
    let (mut g, mut n, mut dims) = (good, naive, (w, h));
    let mut report = Vec::new();
    for level in 1..=4usize {
        let (g2, w2, h2) = viewer_mip(&g, dims.0, dims.1);
        let (n2, _, _) = viewer_mip(&n, dims.0, dims.1);
        (g, n, dims) = (g2, n2, (w2, h2));
        let (lg, count) = edge_luma(&g);
        let (ln, _) = edge_luma(&n);
        // The asset's own (premultiplied) MIP at this level, un-premultiplied (the stored
        // chain is capped, SPEC §9.4: only the levels it has).
        let lo = if level < atlas.mips.len() {
            edge_luma(&decode(&straight_rgba8_undilated(atlas, level))).0
        } else {
            mean
        };
        report.push((level, count, lg / mean, ln / mean, lo / mean));
        assert!(count > 200, "level {level}: only {count} edge texels");
        // No dark fringe (at most `tol` darker), no light halo (at most 2·tol lighter): the
        // dilated colour is an alpha-weighted mean of nearby leaves, a little lighter than
        // the all-leaf mean where edge texels are (measured 1.06–1.09 at levels 1–3).
        assert!(
            lg / mean > 1.0 - tol && lg / mean < 1.0 + 2.0 * tol,
            "level {level}: dilated edges at {:.3} of the leaf colour; {report:.3?}",
            lg / mean
        );
        assert!(
            (lo / mean - 1.0).abs() < tol,
            "level {level}: the asset's premultiplied MIP edges at {:.3}; {report:.3?}",
            lo / mean
        );
        // The check can fail: black transparent texels darken the edges well beyond it.
        assert!(
            ln / mean < 1.0 - 2.0 * tol,
            "level {level}: undilated edges only at {:.3}?",
            ln / mean
        );
    }
    println!(
        "(level, edge texels, dilated, undilated, asset MIP) / leaf luma {mean:.4}: {report:.3?}"
    );
}
