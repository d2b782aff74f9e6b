//! Shadows of the cloud pass, on the synthetic clouds of `common::cloud`:
//! - shadow cascades leave out the casters outside their windows and the frame stays the
//!   same as with every caster drawn into every cascade;
//! - a still frame reuses the shadow atlas, and any change draws it again; while the
//!   camera moves the far cascades are kept a few frames;
//! - a billboard casts the same shadow lit from either side (the shadow pass draws the
//!   quad facing the light);
//! - a shadowed baked billboard keeps a leaf's ambient share of its baked colour.

mod common;

use billow_view::mesh_pass::MeshData;
use billow_view::{Renderer, RgbaImage, ViewCamera};
use common::cloud::*;
use glam::{Mat4, Quat, Vec3};

/// A grey ground quad at y = −1 from corner `(x, z)`, `size` = (along +x, along −z),
/// with shadows on under the light towards `light`.
fn shadowed_on_ground(r: &mut Renderer, (x, z): (f32, f32), size: (f32, f32), light: Vec3) {
    r.add_mesh(&MeshData::quad(
        Vec3::new(x, -1.0, z),
        Vec3::new(0.0, 0.0, -size.1),
        Vec3::new(size.0, 0.0, 0.0),
        [0.6, 0.6, 0.6, 1.0],
    ))
    .expect("ground");
    r.set_shadows(true);
    r.light_dir = light.normalize();
}

/// 128×96 from 1.5 units up at z = 6, looking down −z at the point (0, 0, `z`).
fn down_the_row(z: f32) -> ViewCamera {
    ViewCamera::look_at(
        Vec3::new(0.0, 1.5, 6.0),
        Vec3::new(0.0, 0.0, z),
        Vec3::Y,
        0.8,
        128,
        96,
        0.5,
        1000.0,
    )
}

/// A row of upright billboards (4 units wide) every 5 units from 4 to 300 units down
/// −z, alternately left and right of the axis, over a ground quad, seen along the row
/// (a deep view: several cascades, instances across their windows' edges), and one
/// wide billboard off to the side; shadows on.
fn shadow_row(gpu: billow_view::Gpu, light: Vec3) -> (Renderer, ViewCamera) {
    let instances = (0..60)
        .map(|i| {
            let x = if i % 2 == 0 { -3.0 } else { 3.0 };
            Mat4::from_scale_rotation_translation(
                Vec3::splat(2.0),
                Quat::IDENTITY,
                Vec3::new(x, 1.0, -4.0 - 5.0 * i as f32),
            )
        })
        // A wide one whose centre lies outside the view and the near cascades' windows
        // while its edge casts into view.
        .chain([Mat4::from_scale_rotation_translation(
            Vec3::splat(12.0),
            Quat::IDENTITY,
            Vec3::new(26.0, 11.0, -20.0),
        )])
        .collect();
    let mut r = renderer(gpu, &asset(banded, None, false), instances);
    shadowed_on_ground(&mut r, (-200.0, 50.0), (400.0, 450.0), light);
    let cam = down_the_row(-300.0);
    (r, cam)
}

/// Casters outside a cascade's window, and the flat ground under the light, are left out
/// of it; the picture keeps every shadow.
#[test]
fn shadow_cascades_leave_out_casters_that_cast_on_nothing_in_them() {
    let name = "shadow_cascades_leave_out_casters_that_cast_on_nothing_in_them";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    // From the right and behind the row: the shadows fall left, towards the camera.
    let (mut r, cam) = shadow_row(gpu, Vec3::new(1.0, 1.0, -0.5));
    let (culled, s) = r.render_image(&cam).expect("render");
    r.shadow_culling = false;
    let (all, s_all) = r.render_image(&cam).expect("render");
    assert!(
        s.shadow_casters_culled > 0 && s.shadow_casters < s_all.shadow_casters,
        "casters drawn {} (culled {}) against {} without culling: nothing was left out",
        s.shadow_casters,
        s.shadow_casters_culled,
        s_all.shadow_casters
    );
    assert_eq!(s_all.shadow_casters_culled, 0);
    // Casters outside a window change nothing. The ground, left out as well (flat, with
    // nothing behind it from the light), can only have shadowed itself: its PCF
    // footprint met its own texels a little nearer the light than the bias allowed
    // (up to 2 % darker at this light). So a pixel is the same or, on the ground, a
    // little brighter.
    let w = cam.width as usize;
    let (mut brighter, mut worst) = (0, 0.0f32);
    for (i, (a, b)) in culled.data.iter().zip(&all.data).enumerate() {
        if a == b {
            continue;
        }
        let d = a[0] - b[0];
        assert!(
            d > 0.0 && d < 0.03 && i / w >= cam.height as usize / 2 && a[3] == b[3],
            "pixel {i} changed when casters were culled: {a:?} against {b:?}"
        );
        brighter += 1;
        worst = worst.max(d);
    }
    println!("{brighter} ground pixels brighter without the ground's own shadow (at most {worst})");
    // The shadows are there: darker ground pixels than the lit ground.
    let ground = |img: &RgbaImage| {
        img.data
            .iter()
            .filter(|p| p[3] > 0.0 && (p[0] - p[1]).abs() < 1e-3 && p[0] < 0.35)
            .count()
    };
    assert!(
        ground(&culled) > 20,
        "shadowed ground pixels {}",
        ground(&culled)
    );
}

/// A frame whose camera, light and casters are those of the frame before reuses its
/// shadow atlas (the same picture, the same counts); a moved camera, a new light or a
/// new dissolve draws it again, and the picture is a fresh renderer's.
#[test]
fn a_still_frame_reuses_the_shadow_atlas_and_any_change_draws_it_again() {
    let name = "a_still_frame_reuses_the_shadow_atlas_and_any_change_draws_it_again";
    let (Some(gpu), Some(gpu_fresh)) = (common::gpu_or_skip(name), common::gpu_or_skip(name))
    else {
        return;
    };
    let light = Vec3::new(1.0, 1.0, -0.5);
    let (mut r, cam) = shadow_row(gpu, light);
    let (mut fresh, _) = shadow_row(gpu_fresh, light);
    // Every tile drawn again once the camera moves (the far ones are otherwise kept a
    // few frames: the next test).
    r.shadow_keep_far = false;
    let (first, s1) = r.render_image(&cam).expect("render");
    let (again, s2) = r.render_image(&cam).expect("render");
    assert!(!s1.shadow_reused && s2.shadow_reused, "{s1:?} then {s2:?}");
    assert_eq!(
        (s2.shadow_casters, s2.shadow_casters_culled),
        (s1.shadow_casters, s1.shadow_casters_culled)
    );
    assert!(
        first.data == again.data,
        "the reused atlas changed the picture"
    );
    let same_as_fresh = |r: &Renderer, fresh: &Renderer, cam: &ViewCamera, what: &str| {
        let (img, s) = r.render_image(cam).expect("render");
        assert!(!s.shadow_reused, "{what}: the atlas was reused");
        let (want, _) = fresh.render_image(cam).expect("render");
        let differ = (0..img.data.len())
            .filter(|&i| img.data[i] != want.data[i])
            .count();
        assert_eq!(
            differ, 0,
            "{what}: {differ} pixels differ from a fresh renderer's"
        );
    };
    let moved = cam.with_view(cam.view * Mat4::from_translation(Vec3::new(-1.3, 0.0, 0.8)));
    same_as_fresh(&r, &fresh, &moved, "camera moved");
    let other = Vec3::new(-1.0, 1.0, -0.4).normalize();
    r.light_dir = other;
    fresh.light_dir = other;
    same_as_fresh(&r, &fresh, &moved, "light moved");
    r.set_cloud_dissolve(0, 0.0).expect("dissolve");
    fresh.set_cloud_dissolve(0, 0.0).expect("dissolve");
    same_as_fresh(&r, &fresh, &moved, "dissolve set");
}

/// Pixels of `a` and `b` whose colour differs by more than 8/255 in a channel, and the
/// largest difference.
fn differing(a: &RgbaImage, b: &RgbaImage) -> (usize, f32) {
    let mut n = 0;
    let mut max = 0.0f32;
    for (p, q) in a.data.iter().zip(&b.data) {
        let d = (0..4).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max);
        n += usize::from(d > 8.0 / 255.0);
        max = max.max(d);
    }
    (n, max)
}

/// While the camera moves, the tile of cascade `k ≥ 1` is kept for at most `2^k − 1`
/// frames, and only while its window holds the receivers its cascade is fitted to:
/// two renderers fed the same frames agree bit for bit, a frame with kept tiles looks
/// like a fresh renderer's (at most 1 % of its pixels differ by more than 8/255), and
/// once the camera stands still every kept tile is drawn again within `2^k` frames,
/// then reused, the picture a fresh renderer's.
#[test]
fn a_moving_camera_keeps_the_far_cascades_a_few_frames() {
    let name = "a_moving_camera_keeps_the_far_cascades_a_few_frames";
    let (Some(ga), Some(gb), Some(gf)) = (
        common::gpu_or_skip(name),
        common::gpu_or_skip(name),
        common::gpu_or_skip(name),
    ) else {
        return;
    };
    let light = Vec3::new(1.0, 1.0, -0.5);
    let (a, cam) = shadow_row(ga, light);
    let (b, _) = shadow_row(gb, light);
    let (mut fresh, _) = shadow_row(gf, light);
    fresh.shadow_keep_far = false;
    let mut kept = 0;
    let mut last = cam;
    for f in 0..8 {
        // A dolly forward and a little sideways.
        let step = Vec3::new(0.02, 0.0, -0.1) * f as f32;
        last = cam.with_view(cam.view * Mat4::from_translation(-step));
        let (ia, sa) = a.render_image(&last).expect("render");
        let (ib, sb) = b.render_image(&last).expect("render");
        assert!(ia.data == ib.data, "frame {f}: two renderers differ");
        assert_eq!(sa, sb, "frame {f}");
        for (k, c) in sa.shadow_cascades.iter().enumerate() {
            assert!(
                c.age < 1 << k,
                "frame {f}, cascade {k}: kept {} frames",
                c.age
            );
            kept += usize::from(!c.drawn && c.age > 0);
        }
        let (want, _) = fresh.render_image(&last).expect("render");
        let (n, max) = differing(&ia, &want);
        assert!(
            n * 100 <= ia.data.len(),
            "frame {f}: {n} pixels (max {max}) differ from a fresh renderer's"
        );
    }
    assert!(kept > 0, "no far tile was kept while the camera moved");
    let mut reused = false;
    for _ in 0..1 << billow_view::shadow::CASCADES {
        let (img, s) = a.render_image(&last).expect("render");
        if s.shadow_cascades.iter().all(|c| !c.drawn && c.age == 0) {
            let (want, _) = fresh.render_image(&last).expect("render");
            assert!(img.data == want.data, "still again: not a fresh renderer's");
            reused = true;
            break;
        }
    }
    assert!(
        reused,
        "a still camera did not come back to reusing the atlas"
    );
}

#[test]
fn a_billboard_casts_the_same_shadow_lit_from_either_side() {
    let name = "a_billboard_casts_the_same_shadow_lit_from_either_side";
    let shadowed = |light: Vec3| {
        let gpu = common::gpu_or_skip(name)?;
        let mut r = renderer(gpu, &asset(banded, None, false), vec![Mat4::IDENTITY]);
        shadowed_on_ground(&mut r, (-6.0, 6.0), (12.0, 12.0), light);
        // From straight above: the ground fills the frame, the billboard is a line.
        let cam = ViewCamera::look_at(
            Vec3::new(0.0, 8.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::NEG_Z,
            0.8,
            96,
            96,
            1.0,
            100.0,
        );
        let (img, _) = r.render_image(&cam).expect("render");
        let grey = |p: &&[f32; 4]| (p[0] - p[1]).abs() < 1e-3;
        let lit = img
            .data
            .iter()
            .filter(grey)
            .map(|p| p[0])
            .fold(0.0, f32::max);
        Some(
            img.data
                .iter()
                .filter(grey)
                .filter(|p| p[0] < 0.8 * lit)
                .count(),
        )
    };
    let Some(front) = shadowed(Vec3::new(0.0, 1.0, 0.6)) else {
        return;
    };
    let Some(back) = shadowed(Vec3::new(0.0, 1.0, -0.6)) else {
        return;
    };
    assert!(front > 100, "lit from the front: {front} shadowed pixels");
    assert!(
        front.abs_diff(back) * 20 <= front,
        "shadowed pixels lit from the front {front}, from behind {back}"
    );
}

/// A baked billboard in a mesh's shadow keeps the ambient share of its baked colour that a
/// leaf lit at the mean two-sided cosine ½ has: `k = a / (a + (1 − a)/2)` (`cloud.wgsl`,
/// `baked_shadow_factor`), 0.4615 at ambient 0.3. Scaling it by the ambient alone (0.3, as
/// before 2026-12-06) took the ambient share of the baked colour, which already holds
/// the ambient: the oak's shadowed cloud read 18 % darker than the mesh under its own
/// bake light. Lit (no occluder) it keeps its baked colour.
#[test]
fn a_shadowed_baked_billboard_keeps_the_ambient_share_of_a_leaf() {
    let name = "a_shadowed_baked_billboard_keeps_the_ambient_share_of_a_leaf";
    let ambient = 0.3f32;
    let opaque = |_: u32, _: u32| 1.0;
    let light = Vec3::new(1.0, 0.0, 1.0).normalize();
    let shaded = |occluded: bool| {
        let gpu = common::gpu_or_skip(name)?;
        let mut r = renderer(gpu, &asset(opaque, None, false), vec![Mat4::IDENTITY]);
        r.ambient = ambient;
        r.light_dir = light;
        r.set_shadows(true);
        if occluded {
            // A 6×6 quad across the light, 6 units towards it: behind the camera.
            let c = 6.0 * light;
            let (u, v) = (Vec3::new(1.0, 0.0, -1.0).normalize() * 6.0, Vec3::Y * 6.0);
            r.add_mesh(&MeshData::quad(
                c - 0.5 * u - 0.5 * v,
                u,
                v,
                [0.5, 0.5, 0.5, 1.0],
            ))
            .expect("occluder");
        }
        let (img, _) = r.render_image(&camera(64, 4.0, false)).expect("render");
        Some(centre_mean(&img, 8))
    };
    let Some(lit) = shaded(false) else {
        return;
    };
    let Some(dark) = shaded(true) else {
        return;
    };
    let k = ambient / (ambient + 0.5 * (1.0 - ambient));
    for ch in 0..3 {
        let (l, d) = (lit[ch] / stored(ch), dark[ch] / stored(ch));
        assert!(
            (l - 1.0).abs() < 0.01,
            "lit: channel {ch} is {l:.4} × the baked colour"
        );
        assert!(
            (d - k).abs() < 0.02,
            "shadowed: channel {ch} is {d:.4} × the baked colour, want {k:.4} (not {ambient})"
        );
    }
}

/// A flat ground casts on nothing that stands on it: with the light above, no cascade
/// draws it (that the picture is the same either way is the first test's check, whose
/// ground is left out too); with the light below the ground's plane, the wall above it
/// lies behind the ground from the light, and every drawn cascade holding it draws it.
#[test]
fn a_flat_ground_is_drawn_into_the_cascades_only_when_something_lies_behind_it() {
    let name = "a_flat_ground_is_drawn_into_the_cascades_only_when_something_lies_behind_it";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let cam = down_the_row(-30.0);
    let mut r = Renderer::new(gpu);
    // A wall standing on the ground, 10 units down the view.
    r.add_mesh(&MeshData::quad(
        Vec3::new(-2.0, -1.0, -10.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
        [0.8, 0.2, 0.2, 1.0],
    ))
    .expect("wall");
    let above = Vec3::new(1.0, 1.0, -0.5);
    shadowed_on_ground(&mut r, (-50.0, 20.0), (100.0, 100.0), above);
    let mut counts = Vec::new();
    for light in [above, Vec3::new(1.0, -1.0, -0.5)] {
        r.light_dir = light.normalize();
        let (_, s) = r.render_image(&cam).expect("render");
        assert!(!s.shadow_cascades.is_empty(), "no cascade under {light}");
        counts.push(
            s.shadow_cascades
                .iter()
                .map(|c| (c.casters, c.culled))
                .collect::<Vec<_>>(),
        );
    }
    // Light above: at most the wall is drawn, the ground is left out of every cascade.
    assert!(
        counts[0]
            .iter()
            .all(|&(drawn, culled)| drawn <= 1 && culled >= 1),
        "light above: (drawn, culled) per cascade {:?}",
        counts[0]
    );
    // Light below: the ground is drawn into every cascade (its window holds the ground).
    assert!(
        counts[1].iter().all(|&(drawn, _)| drawn >= 1)
            && counts[1].iter().map(|c| c.0).sum::<usize>()
                > counts[0].iter().map(|c| c.0).sum::<usize>(),
        "light below: (drawn, culled) per cascade {:?}, above {:?}",
        counts[1],
        counts[0]
    );
}
