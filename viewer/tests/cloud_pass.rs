//! The cloud pass on small synthetic cloud assets (one billboard level: a 2×2 quad in
//! the plane z = 0, facing +z), rendered headless at a forced LOD distance so every
//! instance shows the billboard level:
//! - no buffers or bind groups are made per frame once the first frame has sized the
//!   instance buffer, with 1 and with 300 instances, shadows on (two passes per frame);
//! - billboards are alpha-tested: every pixel of a cloud-only frame has alpha 0 or 1,
//!   covered pixels show the texel's straight colour, and an opaque mesh behind the
//!   cloud is hidden wherever the cloud is drawn;
//! - the frame does not depend on the order of the instances (overlapping billboards
//!   with partial-alpha texels) and is identical when rendered twice;
//! - an asset baked unlit with normal maps is lit at runtime like meshes: light along
//!   the billboard normal, against it and at 60° gives `ambient + (1 − ambient)·|N·L|`
//!   (1, 1, 0.65 for ambient 0.3); a tilted normal map turns the lit direction the way
//!   SPEC §9.4's tangent frame says (front and back); a baked-lighting asset is not
//!   relit;
//! - the oak baked with `--normal-map --unlit` (billboards only): lit from L and −L the
//!   frame is the same (two-sided Lambert, as meshes), a side light relights it; baked
//!   lit, it does not change with the light.
//!
//! The synthetic clouds are `common::cloud`'s; the shadow tests are in `cloud_shadows.rs`.

mod common;

use billow_format::{CloudAsset, Mesh};
use billow_view::mesh_pass::MeshData;
use billow_view::{Renderer, RgbaImage, ViewCamera};
use common::cloud::*;
use glam::{Mat4, Quat, Vec3};

#[test]
fn the_cloud_pass_makes_no_gpu_resources_per_frame() {
    let name = "the_cloud_pass_makes_no_gpu_resources_per_frame";
    for count in [1usize, 300] {
        let Some(gpu) = common::gpu_or_skip(name) else {
            return;
        };
        let instances: Vec<Mat4> = (0..count)
            .map(|i| {
                let (x, y) = ((i % 20) as f32 - 10.0, (i / 20) as f32 - 7.0);
                Mat4::from_translation(Vec3::new(2.5 * x, 2.5 * y, -((i % 7) as f32)))
            })
            .collect();
        let mut r = renderer(gpu, &asset(banded, None, false), instances);
        r.set_shadows(true);
        let cam = camera(64, 60.0, false);
        let target = billow_view::target::Target::new(&r.gpu, 64, 64);
        let mut after_first = None;
        for frame in 0..6 {
            let stats = r.render(&target, &cam).expect("render");
            r.gpu.wait().expect("wait");
            assert_eq!(stats.cloud_quads, 2 * count, "two sides per instance");
            // One instanced draw for the whole level.
            assert_eq!(stats.draw_calls, 1, "{count} instances: one draw");
            let made = r.cloud_resources_created();
            match after_first {
                None => after_first = Some(made),
                Some(m) => assert_eq!(
                    made,
                    m,
                    "{count} instances, frame {frame}: the cloud pass made {} buffers or \
                     bind groups after the first frame",
                    made - m
                ),
            }
        }
    }
}

#[test]
fn billboards_are_alpha_tested_and_hide_what_lies_behind() {
    let name = "billboards_are_alpha_tested_and_hide_what_lies_behind";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let cloud = asset(banded, None, false);
    let mut r = renderer(gpu, &cloud, vec![Mat4::IDENTITY]);
    r.ambient = 0.3;
    let cam = camera(96, 4.0, false);
    let (alone, _) = r.render_image(&cam).expect("render");
    let covered: Vec<usize> = (0..alone.data.len())
        .filter(|&i| alone.data[i][3] > 0.0)
        .collect();
    let partial = alone
        .data
        .iter()
        .filter(|p| p[3] > 0.0 && p[3] < 1.0)
        .count();
    assert!(covered.len() > 500, "the billboard is visible");
    assert_eq!(
        partial,
        0,
        "{partial} of {} covered pixels have a partial alpha",
        covered.len()
    );
    // Covered pixels show the straight colour (baked lighting, no shadow: k = 1) — the
    // 0.75 band too, not 0.75 × the colour.
    let worst = covered
        .iter()
        .map(|&i| {
            (0..3)
                .map(|c| (alone.data[i][c] - stored(c)).abs())
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    assert!(worst < 0.02, "covered pixels are off the albedo by {worst}");
    // The quad spans x ∈ [-1, 1] at distance 4 (fov 0.8): pixels 48 ± 28.4; the
    // bands change at x = -0.5, 0, 0.5. Drawn: the 0.75 and 1 bands, from the centre
    // column (where the filtered alpha crosses 0.5) to the right edge.
    let row = 48;
    let xs: Vec<u32> = (0..96)
        .filter(|&x| pixel(&alone, x, row)[3] > 0.0)
        .collect();
    let (x0, x1) = (*xs.first().expect("covered"), *xs.last().expect("covered"));
    assert!(
        (46..=50).contains(&x0) && (74..=78).contains(&x1) && xs.len() as u32 == x1 - x0 + 1,
        "covered columns {xs:?}"
    );

    // An opaque green wall behind the cloud: hidden exactly where the cloud is drawn.
    let green = [0.1, 0.9, 0.2, 1.0];
    r.add_mesh(&MeshData::quad(
        Vec3::new(-3.0, -3.0, -0.5),
        Vec3::new(6.0, 0.0, 0.0),
        Vec3::new(0.0, 6.0, 0.0),
        green,
    ))
    .expect("wall");
    let (both, _) = r.render_image(&cam).expect("render");
    for &i in &covered {
        assert_eq!(
            both.data[i], alone.data[i],
            "pixel {i}: the wall shows through the cloud"
        );
    }
    assert!(
        both.data.iter().all(|p| p[3] == 1.0),
        "wall + cloud cover the frame opaquely"
    );
}

#[test]
fn cloud_frames_do_not_depend_on_instance_order() {
    let name = "cloud_frames_do_not_depend_on_instance_order";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    // Twelve billboards in a staggered stack: overlapping on screen, at distinct depths,
    // some turned about y (their partial-alpha bands overlap the others).
    let m: Vec<Mat4> = (0..12)
        .map(|i| {
            let f = i as f32;
            Mat4::from_rotation_translation(
                Quat::from_rotation_y(0.3 * (f - 6.0) / 6.0),
                Vec3::new(0.35 * (f - 6.0), 0.2 * ((i % 3) as f32 - 1.0), -0.4 * f),
            )
        })
        .collect();
    let cloud = asset(banded, None, false);
    let cam = camera(96, 9.0, false);
    let a = renderer(gpu, &cloud, m.clone());
    let (img_a, _) = a.render_image(&cam).expect("render");
    let (img_a2, _) = a.render_image(&cam).expect("render");
    assert!(img_a.data == img_a2.data, "the same frame twice differs");
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let mut rev = m.clone();
    rev.reverse();
    let b = renderer(gpu, &cloud, rev);
    let (img_b, _) = b.render_image(&cam).expect("render");
    let differ = img_a
        .data
        .iter()
        .zip(&img_b.data)
        .filter(|(p, q)| p != q)
        .count();
    assert_eq!(differ, 0, "{differ} pixels change with the instance order");
    assert!(img_a.data.iter().filter(|p| p[3] > 0.0).count() > 1000);
}

/// Centre colour of the synthetic billboard lit from `light` (towards the light), seen
/// from the front (or the back).
fn lit(gpu: billow_view::Gpu, cloud: &CloudAsset, light: Vec3, back: bool) -> [f32; 4] {
    let mut r = renderer(gpu, cloud, vec![Mat4::IDENTITY]);
    r.ambient = 0.3;
    r.light_dir = light.normalize();
    let (img, _) = r.render_image(&camera(64, 4.0, back)).expect("render");
    centre_mean(&img, 8)
}

#[test]
fn unlit_normal_mapped_billboards_are_lit_like_meshes() {
    let name = "unlit_normal_mapped_billboards_are_lit_like_meshes";
    let ambient = 0.3f32;
    let k = |cos: f32| ambient + (1.0 - ambient) * cos.abs();
    let opaque = |_: u32, _: u32| 1.0;
    let check = |what: &str, cloud: &CloudAsset, light: Vec3, back: bool, want: f32| {
        let Some(gpu) = common::gpu_or_skip(name) else {
            return false;
        };
        let c = lit(gpu, cloud, light, back);
        assert_eq!(c[3], 1.0, "{what}: covered");
        for (ch, v) in c.iter().take(3).enumerate() {
            let got = v / stored(ch);
            assert!(
                (got - want).abs() < 0.01,
                "{what}: channel {ch} is {got:.4} × the albedo, want {want:.4}"
            );
        }
        true
    };
    // Flat normal map: the billboard's normal, +z on the front.
    let flat = asset(opaque, Some([0.0, 0.0, 1.0]), true);
    if !check("flat, light along +z", &flat, Vec3::Z, false, k(1.0)) {
        return;
    }
    check("flat, light along -z", &flat, -Vec3::Z, false, k(1.0));
    let sixty = Vec3::new(60f32.to_radians().sin(), 0.0, 0.5);
    check("flat, light at 60°", &flat, sixty, false, k(0.5));
    check("flat, back side, 60°", &flat, -sixty, true, k(0.5));
    // Tilted toward T = U = +x: N = (0.6, 0, 0.8).
    let t = asset(opaque, Some([0.6, 0.0, 0.8]), true);
    let l = Vec3::new(1.0, 0.0, 1.0).normalize();
    check("T tilt, front", &t, l, false, k(0.6 * l.x + 0.8 * l.z));
    check(
        "T tilt, other side of the normal",
        &t,
        Vec3::new(-1.0, 0.0, 1.0),
        false,
        k(-0.6 * l.x + 0.8 * l.z),
    );
    // Back side: N = 0.6·T − 0.8·z (the same T, N = −normal).
    check(
        "T tilt, back",
        &t,
        Vec3::new(1.0, 0.0, -1.0),
        true,
        k(0.6 * l.x + 0.8 * l.z),
    );
    // Tilted toward B = −V = −y (image up: v grows along +y here).
    let b = asset(opaque, Some([0.0, 0.6, 0.8]), true);
    check(
        "B tilt",
        &b,
        Vec3::new(0.0, -1.0, 1.0),
        false,
        k(0.6 * l.x + 0.8 * l.z),
    );
    check(
        "B tilt, other side",
        &b,
        Vec3::new(0.0, 1.0, 1.0),
        false,
        k(-0.6 * l.x + 0.8 * l.z),
    );
    // Baked lighting (the default): not relit, whatever the normal map says.
    let baked = asset(opaque, Some([0.0, 0.0, 1.0]), false);
    check("baked, light at 60°", &baked, sixty, false, 1.0);
    let plain = asset(opaque, None, true);
    check("unlit without normals, 60°", &plain, sixty, false, 1.0);
}

/// Mean linear RGB over the covered pixels, and their count.
fn covered_mean(img: &RgbaImage) -> ([f32; 3], usize) {
    let mut s = [0.0f32; 3];
    let mut n = 0;
    for p in img.data.iter().filter(|p| p[3] > 0.0) {
        for c in 0..3 {
            s[c] += p[c];
        }
        n += 1;
    }
    (s.map(|v| v / n.max(1) as f32), n)
}

#[test]
fn the_oak_baked_unlit_with_normal_maps_is_lit_by_the_viewer() {
    use billow::bbcloud::bake::Shading;
    use billow::bbcloud::{bake, BbcloudOptions};
    use billow::import::{import, ImportOptions};
    let name = "the_oak_baked_unlit_with_normal_maps_is_lit_by_the_viewer";
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).expect("oak").scene;
    let opts = |unlit: bool| BbcloudOptions {
        samples: 30,
        lods: 1,
        atlas_size: 512,
        supersample: 1,
        normal_map: true,
        shading: Shading {
            light: if unlit {
                None
            } else {
                Some(Vec3::new(0.3, 1.0, 0.2).normalize())
            },
            ambient: 0.3,
        },
        ..Default::default()
    };
    // Level 1 (the billboards) seen from the side, lit from `light`.
    let frame = |asset: &CloudAsset, light: Vec3| -> Option<RgbaImage> {
        let gpu = common::gpu_or_skip(name)?;
        let mut r = Renderer::new(gpu);
        r.add_cloud(asset, vec![Mat4::IDENTITY], Some(vec![1.0]), 0.0, 0.8)
            .expect("upload");
        r.lod_distance_override = Some(10.0);
        r.ambient = 0.3;
        r.light_dir = light.normalize();
        let b = &asset.header.bounds;
        let c = 0.5 * (Vec3::from(b.min) + Vec3::from(b.max));
        let rad = 0.5 * (Vec3::from(b.max) - Vec3::from(b.min)).length();
        let eye = c + Vec3::new(1.0, 0.2, 0.6).normalize() * 2.5 * rad;
        let cam = ViewCamera::look_at(eye, c, Vec3::Y, 0.8, 96, 96, 0.1 * rad, 10.0 * rad);
        Some(r.render_image(&cam).expect("render").0)
    };
    // Billboards only: the kept mesh (trunk) is the mesh pass's, lit at runtime anyway.
    let (mut unlit, _) = bake(&scene, &opts(true), "test", None, &|_, _| {}).expect("bake");
    unlit.trunk = Mesh::default();
    assert!(unlit.atlases.iter().all(|a| a.normals.is_some()));
    let l = Vec3::new(0.4, 0.8, 0.45);
    let Some(a) = frame(&unlit, l) else {
        return;
    };
    let b = frame(&unlit, -l).expect("adapter");
    let side = frame(&unlit, Vec3::new(0.45, 0.0, -0.4)).expect("adapter");
    let (ma, n) = covered_mean(&a);
    let (mb, _) = covered_mean(&b);
    let (ms, _) = covered_mean(&side);
    assert!(n > 150, "the oak is visible ({n} pixels)");
    // Two-sided Lambert, as the mesh pass: opposite lights give the same frame.
    let differ = a.data.iter().zip(&b.data).filter(|(p, q)| p != q).count();
    assert_eq!(
        differ, 0,
        "L and -L differ on {differ} pixels ({ma:?} vs {mb:?})"
    );
    // Another direction relights it: some pixels change, by a Lambert factor in
    // [ambient, 1] of the albedo (so the ratio of the two frames stays within it).
    let changed = a
        .data
        .iter()
        .zip(&side.data)
        .filter(|(p, q)| p != q)
        .count();
    assert!(
        changed > n / 4,
        "a side light changes only {changed} of {n} pixels"
    );
    for c in 0..3 {
        let ratio = ms[c] / ma[c];
        assert!(
            (0.3 / 1.0..=1.0 / 0.3).contains(&ratio),
            "channel {c}: side / top mean {ratio}"
        );
    }
    // The same oak baked lit (the default) is not relit.
    let (mut lit_asset, _) = bake(&scene, &opts(false), "test", None, &|_, _| {}).expect("bake");
    lit_asset.trunk = Mesh::default();
    let la = frame(&lit_asset, l).expect("adapter");
    let ls = frame(&lit_asset, Vec3::new(0.45, 0.0, -0.4)).expect("adapter");
    assert!(
        la.data == ls.data,
        "baked lighting must not change with the light"
    );
}
