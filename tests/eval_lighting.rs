//! The lit reference: ambient occlusion at the hit point, computed by the bake's own
//! estimator (src/voxelize/ao.rs), selected from an AO-baked asset's header.

use std::collections::BTreeMap;

use billow::eval::lighting::Lighting;
use billow::eval::reference::ReferenceRenderer;
use billow::eval::suite::{reference_lighting, spec, EvalOptions, Evaluator, PreparedAsset};
use billow::scene::{Material, Scene, SceneBuilder};
use billow::voxelize::{
    bake_params, voxelize, AoRays, Bake, CombineFn, GridSpec, Preset, Resolution, VoxelizeOptions,
};
use glam::{Vec3, Vec4};

fn white(sb: &mut SceneBuilder) -> u32 {
    sb.material(Material {
        base_color_factor: Vec4::ONE,
        double_sided: true,
        ..Material::default()
    })
}

/// A floor `y = 0` and a wall `x = 0`, both `[-s, s]` wide.
fn floor_and_wall(s: f32) -> Scene {
    let mut sb = SceneBuilder::new();
    let m = white(&mut sb);
    let mesh = sb.mesh("l");
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    sb.quad(
        [v(-s, 0., -s), v(-s, 0., s), v(s, 0., s), v(s, 0., -s)],
        Vec4::ONE,
        m,
        mesh,
    );
    sb.quad(
        [v(0., -s, -s), v(0., s, -s), v(0., s, s), v(0., -s, s)],
        Vec4::ONE,
        m,
        mesh,
    );
    sb.finish()
}

#[test]
fn ao_next_to_a_wall_matches_the_analytic_fraction() {
    // A point at distance h from an infinite wall, rays uniform over the full sphere and
    // counted up to distance D: a direction hits the wall within D iff its component
    // towards the wall is ≥ h/D, a fraction (1 − h/D)/2 of the sphere (Archimedes), so
    // AO = (1 + h/D)/2 for h < D and 1 beyond. The floor under the point lies within
    // t_min and never occludes (the bake's rule: a surface does not occlude itself).
    let scene = floor_and_wall(20.0);
    let d = 2.0;
    let grid = GridSpec {
        dims: [400, 400, 400],
        min: Vec3::splat(-20.0),
        voxel: Vec3::splat(0.1),
    };
    let rays = AoRays {
        rays: 1024,
        ..AoRays::for_grid(&grid, 1024, d)
    };
    let rr = ReferenceRenderer::new(&scene)
        .with_lighting(Lighting::Ao {
            rays,
            grid,
            shaded: None,
            two_sided: false,
        })
        .unwrap();
    for h in [0.25f32, 0.5, 1.0, 1.5, 1.9, 2.5] {
        // 20 points in different voxels (independent direction sets), averaged.
        let n = 20;
        let mut sum = 0.0f64;
        for k in 0..n {
            let z = 0.05 + 0.1 * k as f32 - 1.0;
            let c = rr.trace(Vec3::new(h, 5.0, z), -Vec3::Y, 0.0, 100.0);
            assert_eq!(c.w, 1.0);
            assert!(c.x == c.y && c.y == c.z, "{c}");
            sum += f64::from(c.x);
        }
        let got = sum / f64::from(n);
        let want = f64::from((1.0 + h / d).min(2.0) / 2.0).min(1.0);
        // Standard error of 20 × 1024 rays ≈ 0.0035; 0.015 is over 4 σ.
        assert!((got - want).abs() < 0.015, "h = {h}: AO {got} vs {want}");
        if h > d {
            assert!(
                (got - 1.0).abs() < 1e-6,
                "beyond the AO distance nothing occludes: {got}"
            );
        }
    }
    // Unlit: the same rays see plain white.
    let unlit = ReferenceRenderer::new(&scene);
    assert_eq!(
        unlit.trace(Vec3::new(0.25, 5.0, 0.0), -Vec3::Y, 0.0, 100.0),
        Vec4::ONE
    );
}

/// The inside of a box corner: floor `y = 0`, walls `x = 0` and `z = 0`, all `[0, 4]`.
fn corner() -> Scene {
    let mut sb = SceneBuilder::new();
    let m = white(&mut sb);
    let mesh = sb.mesh("corner");
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let s = 4.0;
    sb.quad(
        [v(0., 0., 0.), v(0., 0., s), v(s, 0., s), v(s, 0., 0.)],
        Vec4::ONE,
        m,
        mesh,
    );
    sb.quad(
        [v(0., 0., 0.), v(0., s, 0.), v(0., s, s), v(0., 0., s)],
        Vec4::ONE,
        m,
        mesh,
    );
    sb.quad(
        [v(0., 0., 0.), v(s, 0., 0.), v(s, s, 0.), v(0., s, 0.)],
        Vec4::ONE,
        m,
        mesh,
    );
    sb.finish()
}

#[test]
fn ao_baked_volume_matches_the_lit_reference_better() {
    let scene = corner();
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(32),
        bake: Bake::ao(),
        combine: CombineFn::Preset(Preset::Opaque),
        ..VoxelizeOptions::default()
    };
    let volume = voxelize(&scene, &opts, &|_, _| {}).unwrap();
    let params = bake_params(&volume, &opts, &BTreeMap::new());
    let asset = volume.into_asset("test", None, params);
    let (lighting, note) = reference_lighting(&asset).unwrap();
    assert!(note.is_none());
    let Lighting::Ao { rays, grid, .. } = lighting else {
        panic!("an AO asset selects the AO reference, got {lighting:?}");
    };
    assert_eq!(rays.rays, billow::voxelize::DEFAULT_AO_RAYS);
    assert_eq!(grid.dims, asset.level_dims(0));
    let prepared = PreparedAsset::new(&asset).unwrap();
    let options = EvalOptions {
        width: 64,
        height: 64,
        reference_per_axis: 2,
        raster_1spp: false,
        ..EvalOptions::default()
    };
    let lit = Evaluator::new(
        &scene,
        EvalOptions {
            lighting,
            ..options
        },
    )
    .unwrap();
    let unlit = Evaluator::new(&scene, options).unwrap();
    // Each plane seen face-on (a one-voxel-thick layer seen at a slant is not opaque in the
    // volume, which would swamp the lighting difference, see docs/eval.md).
    for (name, dir) in [("-y", -Vec3::Y), ("-x", -Vec3::X), ("-z", -Vec3::Z)] {
        let v = spec(name, dir, 1.0);
        let (rl, lit_ref) = (lit.reference(&v).unwrap(), unlit.reference(&v).unwrap());
        // The lit reference darkens towards the corner and is nowhere brighter than unlit.
        let darker = rl
            .image
            .data
            .iter()
            .zip(&lit_ref.image.data)
            .filter(|(a, b)| a.x < b.x - 0.05)
            .count();
        assert!(darker > 200, "{name}: only {darker} pixels darkened by AO");
        assert!(rl
            .image
            .data
            .iter()
            .zip(&lit_ref.image.data)
            .all(|(a, b)| a.x <= b.x + 1e-6 && a.w == b.w));
        let (el, _) = lit.asset(&prepared, &rl).unwrap();
        let (eu, img) = unlit.asset(&prepared, &lit_ref).unwrap();
        if let Ok(dir) = std::env::var("BILLOW_EVAL_PNG") {
            let p = std::path::Path::new(&dir).join(format!("ao_{name}.png"));
            billow::eval::image::write_comparisons_png(&rl.image, &[&img, &lit_ref.image], 4.0, &p)
                .unwrap();
        }
        // Straight colour error where the reference is opaque and the volume covers: the
        // opacity of a one-voxel-thick plane in the volume depends on where the slices fall,
        // and the walls seen edge-on are one-voxel strips: geometric errors that are the
        // same lit or unlit.
        let interior = |r: &billow::eval::ImageF32| -> (f64, usize) {
            let mut sum = 0.0;
            let mut n = 0;
            for (a, b) in r.data.iter().zip(&img.data) {
                if a.w == 1.0 && b.w > 0.2 {
                    let straight = b.truncate() / b.w;
                    sum += f64::from((a.truncate() - straight).abs().max_element());
                    n += 1;
                }
            }
            (sum / n.max(1) as f64, n)
        };
        let ((dl, n), (du, _)) = (interior(&rl.image), interior(&lit_ref.image));
        eprintln!(
            "{name}: RMSE lit {:.4} unlit {:.4}; interior |Δrgb| lit {dl:.4} unlit {du:.4} ({n} px)",
            el.asset.rmse, eu.asset.rmse
        );
        assert!(n > 500, "{name}: {n} interior pixels");
        assert!(
            dl < 0.4 * du,
            "{name}: interior colour error against the lit reference {dl} vs unlit {du}"
        );
        assert!(
            el.asset.rmse < eu.asset.rmse,
            "{name}: RMSE {} vs {}",
            el.asset.rmse,
            eu.asset.rmse
        );
    }
}

/// A floor `y = 0` over `[-2, 2]²` (white, or unlit) and, 1 above its centre, a small
/// opaque square that shades it from an overhead light.
fn floor_and_roof(unlit: bool) -> Scene {
    let mut sb = SceneBuilder::new();
    let floor = sb.material(Material {
        base_color_factor: Vec4::ONE,
        double_sided: true,
        unlit,
        ..Material::default()
    });
    let roof = white(&mut sb);
    let mesh = sb.mesh("l");
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    sb.quad(
        [
            v(-2., 0., -2.),
            v(-2., 0., 2.),
            v(2., 0., 2.),
            v(2., 0., -2.),
        ],
        Vec4::ONE,
        floor,
        mesh,
    );
    sb.quad(
        [
            v(-0.5, 1., -0.5),
            v(-0.5, 1., 0.5),
            v(0.5, 1., 0.5),
            v(0.5, 1., -0.5),
        ],
        Vec4::ONE,
        roof,
        mesh,
    );
    sb.finish()
}

/// `billow eval --light`'s reference is the mesh as the viewer's mesh pass lights it:
/// two-sided Lambert with ambient (a light from below lights the floor as one from above
/// does), unlit materials unshaded, and with `--shadows` the light's transmittance (a
/// roof leaves the ambient term alone under it).
#[test]
fn scene_lighting_is_the_viewers_mesh_model() {
    let grey = |c: Vec4| (c.x, c.w);
    // A ray grazing under the roof to the floor's centre.
    let (o, d) = (
        Vec3::new(3.0, 0.5, 0.0),
        Vec3::new(-3.0, -0.5, 0.0).normalize(),
    );
    let at = |scene: &Scene, light: Vec3, shadows: bool| {
        let r = ReferenceRenderer::new(scene)
            .with_lighting(Lighting::Scene {
                light: light.normalize(),
                ambient: 0.3,
                shadows,
            })
            .unwrap();
        grey(r.trace(o, d, 0.0, 100.0))
    };
    let s = floor_and_roof(false);
    let close = |a: (f32, f32), b: f32| (a.0 - b).abs() < 1e-4 && a.1 == 1.0;
    assert!(
        close(at(&s, Vec3::Y, false), 1.0),
        "{:?}",
        at(&s, Vec3::Y, false)
    );
    assert!(close(at(&s, -Vec3::Y, false), 1.0), "two-sided");
    assert!(close(at(&s, Vec3::X, false), 0.3), "grazing: ambient");
    let k = 0.3 + 0.7 * std::f32::consts::FRAC_1_SQRT_2;
    assert!(close(at(&s, Vec3::new(1.0, 1.0, 0.0), false), k));
    assert!(
        close(at(&s, Vec3::Y, true), 0.3),
        "under the roof: {:?}",
        at(&s, Vec3::Y, true)
    );
    assert!(close(
        at(&s, Vec3::new(1.0, 0.2, 0.0), true),
        0.3 + 0.7 * 0.2 / 1.04f32.sqrt()
    ));
    let unlit = floor_and_roof(true);
    assert!(close(at(&unlit, Vec3::X, true), 1.0), "unlit: unshaded");
}

/// The reference states the lighting models itself (src/eval/reference.rs), so that a
/// mistake in the asset path's statement (`billow_core::shading`, used by the bakes and
/// the slicer) is an error against it rather than shared: the two agree.
#[test]
fn the_references_lighting_models_agree_with_the_asset_paths() {
    use billow::eval::reference::{one_sided, two_sided};
    use billow_core::shading::{diffuse_factor, volume_diffuse_factor};
    let mut rng = billow::rng::Pcg32::new(7, 11);
    for _ in 0..2000 {
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let (n, l) = (v() * 0.9, v().normalize_or(Vec3::Y));
        let ambient = (n.x + 1.0) * 0.5;
        assert!((two_sided(n, l, ambient, 1.0) - diffuse_factor(n, l, ambient)).abs() < 1e-6);
        assert!(
            (one_sided(n, l, ambient) - volume_diffuse_factor(n, l, ambient, 1.0)).abs() < 1e-6
        );
    }
}

/// `--lighting unlit` compares the unlit mesh with the asset unlit: a volume that stores
/// normal moments (the default) is drawn with its albedo, not shaded by the default light
/// (which read −39 % luminance on the spot against its unlit mesh).
#[test]
fn unlit_evaluation_draws_a_lit_volume_unlit_too() {
    use billow::eval::evaluate::ReferenceLighting;
    use billow::eval::evaluate::{evaluate, Asset, EvaluateHooks, EvaluateOptions};
    use billow::voxelize::{bake, BakeHooks, BakeOptions};
    let scene = billow::procgen::torus(1.0, 0.35, 32, 16);
    let baked = bake(
        &scene,
        &BakeOptions::at(Resolution::Longest(32)),
        &BakeHooks::default(),
    )
    .expect("bake");
    assert!(baked.asset.has_moments(), "the default bake stores moments");
    let options = EvaluateOptions {
        width: 64,
        height: 64,
        views: vec![spec("+x+y+z", Vec3::ONE, 1.0), spec("+y", Vec3::Y, 1.0)],
        lighting: ReferenceLighting::Unlit,
        ..EvaluateOptions::default()
    };
    let e = evaluate(
        &scene,
        &Asset::Volume(baked.asset),
        &options,
        &mut EvaluateHooks::default(),
    )
    .expect("evaluate");
    let lum = e.levels[0].mean.luminance_rel_diff;
    assert!(
        lum.abs() < 0.03,
        "unlit: the asset's mean covered luminance is {:+.1} % of the unlit mesh's",
        100.0 * lum
    );
}

/// `billow eval --shadows` shadows a volume too (by its own transmittance towards the
/// light, `billow::eval::volume_shadow`): a 2×2 floor under a 1×1 roof, lit from above
/// and seen from below (the floor is lit two-sided, and the roof's shadow falls through
/// it: a quarter of what is seen). The roof's shadow darkens the ray-traced
/// mesh's covered luminance, and the volume's by the same ratio within 5 %. Until
/// 2026-12-06 the slicer drew volumes unshadowed (ratio 1).
#[test]
fn with_shadows_a_volume_is_shadowed_as_the_mesh_is() {
    use billow::eval::evaluate::ReferenceLighting;
    use billow::eval::evaluate::{evaluate, Asset, EvaluateHooks, EvaluateOptions};
    use billow::eval::lighting::EvalLight;
    use billow::voxelize::{bake, BakeHooks, BakeOptions};
    let mut sb = SceneBuilder::new();
    let m = white(&mut sb);
    let mesh = sb.mesh("l");
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let square = |h: f32, y: f32| [v(-h, y, -h), v(-h, y, h), v(h, y, h), v(h, y, -h)];
    sb.quad(square(1.0, 0.0), Vec4::ONE, m, mesh);
    sb.quad(square(0.5, 0.6), Vec4::ONE, m, mesh);
    let scene = sb.finish();
    let baked = bake(
        &scene,
        &BakeOptions::at(Resolution::Longest(48)),
        &BakeHooks::default(),
    )
    .expect("bake");
    let luminance = |shadows: bool| {
        let options = EvaluateOptions {
            width: 64,
            height: 64,
            views: vec![spec("+y", Vec3::new(0.1, 1.0, 0.1), 1.0)],
            lighting: ReferenceLighting::Lights {
                lights: vec![EvalLight::new("overhead", Vec3::Y, 0.3).unwrap()],
                shadows,
            },
            ..EvaluateOptions::default()
        };
        let e = evaluate(
            &scene,
            &Asset::Volume(baked.asset.clone()),
            &options,
            &mut EvaluateHooks::default(),
        )
        .expect("evaluate");
        let a = &e.levels[0].views[0].asset;
        (a.luminance_reference, a.luminance_test)
    };
    let (lit_ref, lit_vol) = luminance(false);
    let (dark_ref, dark_vol) = luminance(true);
    let (r_ref, r_vol) = (dark_ref / lit_ref, dark_vol / lit_vol);
    eprintln!("shadowed / unshadowed: mesh {r_ref:.3}, volume {r_vol:.3}");
    assert!(
        r_ref < 0.85,
        "the roof must shadow the floor in view: {r_ref:.3}"
    );
    assert!(
        (r_vol / r_ref - 1.0).abs() < 0.05,
        "the volume's shadowed / unshadowed luminance {r_vol:.3} against the mesh's {r_ref:.3}"
    );
}
