//! The shadow map is fitted to the receivers in view, in cascades (issue 22, item 5):
//! pure math on `shadow::cascades`, no GPU.
//!
//! - At the `oak_clouds` gallery camera (a 2000-unit ground, six oaks from 60 to 750
//!   units away) the shadow texels at the nearest oak's canopy are at most 1/4 unit
//!   (leaf scale: the oak is 65 units tall) and at least 10× denser than those of the
//!   map fitted to the whole scene's bounding sphere (the fit before, 1024² over
//!   2830 units); no oak's canopy gets fewer texels than before. The base map (one map
//!   over the whole view) is denser than the sphere fit too (≥ 1.3×), at `oak_trees`
//!   (the whole scene in view) no worse.
//! - Every point of the scene's bounds inside the view lies inside the base map, the whole
//!   scene within its depth range (casters outside the view still cast); every cascade
//!   shares the base's depth, and the uniform's scale and offset take a point's base NDC
//!   to its NDC in each cascade.
//! - Culling a caster from a cascade: left out only when no point of its sphere lands in
//!   the cascade's window.
//! - Texel snapping: moving the camera a little moves every window by whole texels and
//!   keeps its size, so shadow edges do not shimmer.
//!
//! Scene bounds as `Renderer::content_bounds` makes them (the ground's quad; a cloud
//! instance's bounding sphere of radius 49.6 around the oak's centre, 32.4 up: the
//! tallest point y = 82; the oak volume's bounds, 64.7 tall, scaled ≤ 1.1).

use billow_view::shadow::{
    cascades, frustum_scene_points, light_camera, light_camera_for_view, sphere_in_window,
    texel_density, texel_density_at,
};
use billow_view::ViewCamera;
use glam::Vec3;

const SIZE: u32 = 1024;

/// The camera `billow view` makes for a scene camera: near/far from the content's
/// bounding sphere (bin/billow/view.rs).
fn scene_camera(eye: Vec3, target: Vec3, fov_deg: f32, bounds: (Vec3, Vec3)) -> ViewCamera {
    let centre = 0.5 * (bounds.0 + bounds.1);
    let radius = 0.5 * (bounds.1 - bounds.0).length();
    let dist = (eye - centre).length();
    let near = ((dist - radius) * 0.5).max(radius * 1e-3);
    let far = (dist + radius) * 2.0;
    ViewCamera::look_at(
        eye,
        target,
        Vec3::Y,
        fov_deg.to_radians(),
        640,
        480,
        near,
        far,
    )
}

/// The fit before: the whole scene's bounding sphere.
fn sphere_fit(light: Vec3, bounds: (Vec3, Vec3)) -> ViewCamera {
    light_camera(
        light,
        0.5 * (bounds.0 + bounds.1),
        0.5 * (bounds.1 - bounds.0).length(),
        SIZE,
    )
}

fn oak_clouds() -> (Vec3, ViewCamera, (Vec3, Vec3)) {
    let bounds = (
        Vec3::new(-1000.0, 0.0, -1400.0),
        Vec3::new(1000.0, 82.0, 600.0),
    );
    let cam = scene_camera(
        Vec3::new(-60.0, 45.0, 170.0),
        Vec3::new(60.0, 30.0, -300.0),
        40.0,
        bounds,
    );
    (Vec3::new(0.3, 1.0, 0.2), cam, bounds)
}

fn oak_trees() -> (Vec3, ViewCamera, (Vec3, Vec3)) {
    let bounds = (
        Vec3::new(-130.0, 0.0, -130.0),
        Vec3::new(130.0, 71.2, 130.0),
    );
    let cam = scene_camera(
        Vec3::new(150.0, 62.0, 170.0),
        Vec3::new(0.0, 26.0, 0.0),
        40.0,
        bounds,
    );
    (Vec3::new(0.5, 1.0, 0.35), cam, bounds)
}

/// `p` in the light camera's clip space.
fn light_clip(light: &ViewCamera, p: Vec3) -> Vec3 {
    (light.projection() * light.view).project_point3(p)
}

/// The oak instances of `oak_clouds.ron`, a point 40 up in each canopy.
const OAKS: [(f32, f32); 6] = [
    (-75.0, 70.0),
    (-20.0, -60.0),
    (35.0, -190.0),
    (95.0, -330.0),
    (165.0, -500.0),
    (250.0, -720.0),
];

#[test]
fn leaf_scale_shadow_texels_at_the_oak_clouds_camera() {
    let (l, cam, bounds) = oak_clouds();
    let before = texel_density(&sphere_fit(l, bounds));
    let cs = cascades(l, &cam, bounds, SIZE);
    assert!(cs.cameras.len() > 1, "{} cascades", cs.cameras.len());
    for (i, (x, z)) in OAKS.into_iter().enumerate() {
        let p = Vec3::new(x, 40.0, z);
        let after = texel_density_at(&cs, p);
        eprintln!(
            "oak {i} at {:.0} units: {before:.3} → {after:.3} texels per unit ({:.1}×)",
            (p - cam.eye()).length(),
            after / before
        );
        assert!(
            after >= before,
            "oak {i}: {after:.3} texels/unit, fewer than the sphere fit's {before:.3}"
        );
        if i == 0 {
            assert!(
                after >= 4.0 && after >= 10.0 * before,
                "the nearest oak's canopy gets {after:.3} texels/unit (before {before:.3}): \
                 not leaf scale"
            );
        }
    }
}

#[test]
fn the_cascades_share_the_base_map_s_depth_and_its_ndc() {
    for (name, (l, cam, bounds)) in [("oak_clouds", oak_clouds()), ("oak_trees", oak_trees())] {
        let cs = cascades(l, &cam, bounds, SIZE);
        let pts = frustum_scene_points(&cam, bounds);
        for (k, c) in cs.cameras.iter().enumerate() {
            let m = cs.uniform.map[k];
            for p in &pts {
                let b = light_clip(&cs.base, *p);
                let q = light_clip(c, *p);
                let mapped = (b.x * m[0] + m[2], b.y * m[1] + m[3]);
                let tol = 1e-3 * m[0].max(1.0);
                assert!(
                    (mapped.0 - q.x).abs() < tol
                        && (mapped.1 - q.y).abs() < tol
                        && (b.z - q.z).abs() < 1e-5,
                    "{name}, cascade {k} ({m:?}): {p} maps to {mapped:?}/{} but is at {q}",
                    b.z
                );
            }
        }
    }
}

#[test]
fn the_base_map_is_fitted_to_the_receivers_in_view() {
    for (name, (l, cam, bounds), min_gain) in [
        ("oak_clouds", oak_clouds(), 1.3),
        ("oak_trees", oak_trees(), 1.0),
    ] {
        let before = texel_density(&sphere_fit(l, bounds));
        let fitted = light_camera_for_view(l, &cam, bounds, SIZE);
        let after = texel_density(&fitted);
        eprintln!(
            "{name}: {before:.3} → {after:.3} texels per unit ({:.2}×)",
            after / before
        );
        assert!(
            after >= min_gain * before,
            "{name}: fitted density {after:.3} texels/unit is not {min_gain}× the \
             whole-scene fit's {before:.3}"
        );
        // Every visible receiver is inside the map, every caster inside its depth range.
        let pts = frustum_scene_points(&cam, bounds);
        assert!(pts.len() >= 8, "{name}: {} points", pts.len());
        for p in &pts {
            let c = light_clip(&fitted, *p);
            assert!(
                c.x.abs() <= 1.0 && c.y.abs() <= 1.0 && (0.0..=1.0).contains(&c.z),
                "{name}: receiver {p} at {c} is outside the map"
            );
        }
        for i in 0..8 {
            let p = Vec3::select(
                glam::BVec3::new(i & 1 == 1, i & 2 == 2, i & 4 == 4),
                bounds.1,
                bounds.0,
            );
            let z = light_clip(&fitted, p).z;
            assert!((0.0..=1.0).contains(&z), "{name}: caster {p} at depth {z}");
        }
    }
}

#[test]
fn the_fitted_windows_move_by_whole_texels() {
    let (l, cam, bounds) = oak_clouds();
    let ca = cascades(l, &cam, bounds, SIZE);
    for step in [0.37f32, 1.3, 4.1] {
        let moved = cam
            .with_view(cam.view * glam::Mat4::from_translation(Vec3::new(-step, 0.0, 0.6 * step)));
        let cb = cascades(l, &moved, bounds, SIZE);
        let pairs = std::iter::once((&ca.base, &cb.base)).chain(ca.cameras.iter().zip(&cb.cameras));
        for (k, (a, b)) in pairs.enumerate() {
            if b.ortho_half_height != a.ortho_half_height {
                // A window may step to the next quarter octave; never more.
                let r = b.ortho_half_height.unwrap() / a.ortho_half_height.unwrap();
                assert!(
                    (r - 2f32.powf(0.25)).abs() < 1e-3 || (r - 2f32.powf(-0.25)).abs() < 1e-3,
                    "moved {step}: window {k} changed size by {r}"
                );
                continue;
            }
            // The world origin's position in both maps differs by whole texels.
            let texel = a.pixel_size_at(1.0);
            let (pa, pb) = (a.to_view(Vec3::ZERO), b.to_view(Vec3::ZERO));
            for d in [(pa.x - pb.x) / texel, (pa.y - pb.y) / texel] {
                assert!(
                    (d - d.round()).abs() < 2e-2,
                    "moved {step}: window {k} moved {d} texels"
                );
            }
        }
    }
}

/// `sphere_in_window` never leaves out a sphere of which some point lands in the
/// cascade's window (random spheres around the oak_clouds cascades), and does leave
/// out spheres that lie away from it.
#[test]
fn a_caster_is_culled_only_when_no_point_of_its_sphere_reaches_the_window() {
    let (light, camera, bounds) = oak_clouds();
    let cs = cascades(light, &camera, bounds, SIZE);
    let mut rng = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f32 / (1u64 << 53) as f32
    };
    let (lo, hi) = bounds;
    let (mut kept, mut left_out) = (0, 0);
    for c in &cs.cameras {
        for _ in 0..2000 {
            let centre = lo + (hi - lo) * Vec3::new(next(), next(), next());
            let radius = 1.0 + 60.0 * next();
            let seen = sphere_in_window(c, centre, radius);
            if seen {
                kept += 1;
                continue;
            }
            left_out += 1;
            for _ in 0..64 {
                let d = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
                let p = centre + d.normalize_or_zero() * radius * next().cbrt();
                let q = light_clip(c, p);
                assert!(
                    q.x.abs() > 1.0 || q.y.abs() > 1.0,
                    "sphere {centre} r {radius} left out, but its point {p} lands at {q}"
                );
            }
        }
    }
    assert!(
        kept > 100 && left_out > 100,
        "kept {kept}, left out {left_out}"
    );
}
