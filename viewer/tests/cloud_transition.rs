//! A billboard cloud mid-transition (Lacewell §3): the oak baked into a foliage mesh +
//! two billboard levels (level 2 = the two crossed billboards), drawn with the LOD
//! distance forced (`lod_distance_override`) so every level and morph factor can be
//! shown at the same camera.
//!
//! What must hold (coverage = the alpha channel averaged over 8×8-pixel blocks, the
//! silhouette's shape rather than texture detail):
//! - the stats report the level and morph factor the distances imply;
//! - morphing removes the silhouette pop: level 1 at the end of its transition (a ≈ 1,
//!   every vertex in its parent's plane) differs from level 2 by less than half as much
//!   as level 1 unmorphed does, and the frame mid-transition (a = 0.5) lies in between;
//! - the foliage mesh (level 0) at the end of its transition covers what level 1 covers
//!   (mean block difference < 0.035);
//! - the trunk is drawn by the mesh pass;
//! - with the dithered dissolve on (`cloud_pass` module docs), an instance at a switch
//!   distance draws both levels with complementary masks: every pixel shows one of the two
//!   levels (no holes where both cover, no z-fighting), in the proportion `t`, and the band's
//!   ends show the levels alone.
//!
//! Diff images (A | B | heat map) are written on failure.

mod common;

use billow::bbcloud::{bake, BbcloudOptions};
use billow::eval::image::write_comparison_png;
use billow::import::{import, ImportOptions};
use billow_core::camera::Camera;
use billow_core::Aabb;
use billow_view::{Renderer, RgbaImage};
use common::image_f32;
use glam::{Mat4, Vec3};

/// Side of the blocks over which coverage is averaged before comparing: the shape of
/// the silhouette, not the texture detail (the parent level's atlas has half the
/// texel density, so its leaves are blurrier by design).
const BLOCK: usize = 8;

/// Mean |Δ coverage| between two frames, per `BLOCK`² block.
fn coverage_diff(a: &RgbaImage, b: &RgbaImage) -> f64 {
    let (w, h) = (a.width as usize, a.height as usize);
    let mean = |img: &RgbaImage, bx: usize, by: usize| {
        let mut s = 0.0f64;
        for y in by * BLOCK..(by + 1) * BLOCK {
            for x in bx * BLOCK..(bx + 1) * BLOCK {
                s += f64::from(img.data[y * w + x][3].clamp(0.0, 1.0));
            }
        }
        s / (BLOCK * BLOCK) as f64
    };
    let (nx, ny) = (w / BLOCK, h / BLOCK);
    let mut d = 0.0;
    for by in 0..ny {
        for bx in 0..nx {
            d += (mean(a, bx, by) - mean(b, bx, by)).abs();
        }
    }
    d / (nx * ny) as f64
}

#[test]
fn a_cloud_mid_transition_morphs_instead_of_popping() {
    let name = "a_cloud_mid_transition_morphs_instead_of_popping";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).expect("oak").scene;
    let opts = BbcloudOptions {
        samples: 60,
        lods: 2,
        atlas_size: 1024,
        supersample: 2,
        ..Default::default()
    };
    let (asset, _) = bake(&scene, &opts, "test", None, &|_, _| {}).expect("bake");
    assert_eq!(asset.levels.len(), 2);

    let (d0, d1) = (100.0f32, 200.0f32);
    let mut r = Renderer::new(gpu);
    r.add_cloud(&asset, vec![Mat4::IDENTITY], Some(vec![d0, d1]), 0.5, 0.8)
        .expect("upload");
    // The morph alone first (switch in one frame); the dissolve is checked at the end.
    r.set_cloud_dissolve(0, 0.0).expect("dissolve");
    assert_eq!(r.passes(), ["mesh", "cloud", "resolve"], "trunk + cloud");
    let b = &asset.header.bounds;
    let bounds = Aabb {
        min: Vec3::from(b.min),
        max: Vec3::from(b.max),
    };
    // Side view, as Lacewell's plots (view parallel to the ground).
    let c = Camera::framed(&bounds, Vec3::new(-0.9, -0.5, -0.6), 0.8, 96, 96, 1.0);
    let cam = common::view_camera(&c);
    let mut at = |z: f32| {
        r.lod_distance_override = Some(z);
        let (img, stats) = r.render_image(&cam).expect("render");
        (img, stats.cloud_lods[0])
    };
    let dissolving = |r: &mut Renderer, z: f32| {
        r.lod_distance_override = Some(z);
        let (img, stats) = r.render_image(&cam).expect("render");
        (img, stats.cloud_dissolves[0], stats.cloud_quads)
    };
    let (mesh0, l) = at(10.0);
    assert_eq!(l, (0, 0.0));
    let (mesh_end, l) = at(d0 - 1e-3);
    assert!(l.0 == 0 && l.1 > 0.99, "{l:?}");
    let (lv1, l) = at(d0);
    assert_eq!(l, (1, 0.0));
    let (lv1_mid, l) = at(0.75 * d1);
    assert!(l.0 == 1 && (l.1 - 0.5).abs() < 1e-4, "{l:?}");
    let (lv1_end, l) = at(d1 - 1e-3);
    assert!(l.0 == 1 && l.1 > 0.99, "{l:?}");
    let (lv2, l) = at(d1);
    assert_eq!(l, (2, 0.0));

    let out = common::out_dir();
    let fail = |what: &str, a: &RgbaImage, b: &RgbaImage| -> String {
        let p = out.join(format!("{name}.{what}.diff.png"));
        write_comparison_png(&image_f32(a), &image_f32(b), 4.0, &p).expect("diff image");
        format!("{what}: diff image {}", p.display())
    };
    // Billboard level 1 -> 2 (the crossed pair): the geometry changes a lot.
    let pop = coverage_diff(&lv1, &lv2);
    let morphed = coverage_diff(&lv1_end, &lv2);
    let mid = coverage_diff(&lv1_mid, &lv2);
    println!("level 1 -> 2: unmorphed {pop:.4}, mid {mid:.4}, morphed {morphed:.4}");
    assert!(pop > 0.02, "level 1 and 2 must differ ({pop})");
    assert!(
        morphed < 0.5 * pop,
        "morphing must remove most of the pop ({morphed:.4} vs {pop:.4}); {}",
        fail("level1-end_vs_level2", &lv1_end, &lv2)
    );
    assert!(
        morphed <= mid && mid <= pop,
        "mid-transition {mid:.4} must lie between {morphed:.4} and {pop:.4}; {}",
        fail("level1-mid_vs_level2", &lv1_mid, &lv2)
    );
    // Foliage mesh -> level 1: the leaves slide onto their billboards, whose textures
    // are those leaves projected; at a = 1 the coverage must match level 1's. (This
    // also fails when alpha-tested leaf textures lose coverage in their MIPs: measured
    // 0.076 before coverage-preserving MIPs, 0.021 with them.)
    let pop = coverage_diff(&mesh0, &lv1);
    let morphed = coverage_diff(&mesh_end, &lv1);
    println!("mesh -> level 1: unmorphed {pop:.4}, morphed {morphed:.4}");
    assert!(
        morphed < 0.035,
        "the flattened leaves must cover what level 1 covers ({morphed:.4}); {}",
        fail("mesh-end_vs_level1", &mesh_end, &lv1)
    );
    assert!(lv2.data.iter().any(|p| p[3] > 0.5), "the cloud is visible");

    // The dissolve around d1: the morph now ends where the band begins, so level 1 there
    // is `lv1_end` (every vertex on its parent's plane), and level 2 past it is `lv2`.
    let h = 0.375f32;
    r.set_cloud_dissolve(0, h).expect("dissolve");
    let (start, t0, _) = dissolving(&mut r, d1 * (-h + 1e-3).exp2());
    let (end, t1, _) = dissolving(&mut r, d1 * (h - 1e-3).exp2());
    let (half, t, quads) = dissolving(&mut r, d1);
    let (_, _, quads2) = dissolving(&mut r, 2.0 * d1);
    assert!(
        t0 < 0.01 && t1 > 0.99 && (t - 0.5).abs() < 1e-4,
        "{t0} {t} {t1}"
    );
    assert!(
        quads > quads2,
        "both levels drawn: {quads} quads, level 2 alone {quads2}"
    );
    let same = |a: [f32; 4], b: [f32; 4]| (0..4).all(|i| (a[i] - b[i]).abs() <= 2e-3);
    let (mut holes, mut neither, mut from2, mut differ) = (0, 0, 0, 0);
    for i in 0..half.data.len() {
        // The band's ends as the two levels: the same geometry as mid-band (level 1 fully
        // morphed; `lv1_end` is a hair short of it), each with under 0.1 % of the other.
        let (p, a, b) = (half.data[i], start.data[i], end.data[i]);
        if a[3] > 0.99 && b[3] > 0.99 && p[3] < 0.5 {
            holes += 1;
        }
        if !same(p, a) && !same(p, b) {
            neither += 1;
        }
        if !same(a, b) {
            differ += 1;
            if same(p, b) {
                from2 += 1;
            }
        }
    }
    let n = half.data.len();
    let share = from2 as f64 / differ.max(1) as f64;
    println!(
        "dissolve at t = 0.5: {holes} holes, {neither} pixels from neither level, \
         {share:.3} of the {differ} differing pixels from level 2"
    );
    let band_ends = coverage_diff(&start, &lv1_end).max(coverage_diff(&end, &lv2));
    assert!(
        band_ends < 0.01,
        "the band's ends must show one level each ({band_ends:.4}); {}",
        fail("band-start_vs_level1-end", &start, &lv1_end)
    );
    assert!(
        holes == 0 && (neither as f64) < 0.005 * n as f64,
        "complementary masks: {holes} holes, {neither} of {n} pixels from neither level; {}",
        fail("dissolve-half_vs_level2", &half, &lv2)
    );
    assert!(
        differ > 100 && (share - 0.5).abs() < 0.15,
        "half the differing pixels must come from level 2 at t = 0.5: {share:.3} of {differ}"
    );
}
