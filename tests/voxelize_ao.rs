//! Baked ambient occlusion (`Bake::Ao`): enclosed, isolated and corner voxels, alpha-mask
//! occluders, determinism across thread counts, recorded parameters.

use std::collections::BTreeMap;

use billow::scene::{AlphaMode, Material, Scene, SceneBuilder, Texture, Wrap};
use billow::voxelize::{
    bake_params, slice_stack, voxelize, Bake, Dir, Resolution, VoxelizeOptions,
};
use billow_core::Aabb;
use glam::{Vec3, Vec4};

/// An axis-aligned square quad perpendicular to `axis` at `depth`, spanning `[lo, hi]` on
/// the two other axes (double-sided materials are used, so the winding does not matter).
fn quad(sb: &mut SceneBuilder, axis: usize, depth: f32, lo: [f32; 2], hi: [f32; 2], m: u32) {
    let (u, v) = [(1, 2), (0, 2), (0, 1)][axis];
    let p = |a: f32, b: f32| {
        let mut q = [0.0; 3];
        q[axis] = depth;
        q[u] = a;
        q[v] = b;
        Vec3::from_array(q)
    };
    let mesh = sb.mesh("q");
    sb.quad(
        [
            p(lo[0], lo[1]),
            p(hi[0], lo[1]),
            p(hi[0], hi[1]),
            p(lo[0], hi[1]),
        ],
        Vec4::ONE,
        m,
        mesh,
    );
}

fn opaque(sb: &mut SceneBuilder) -> u32 {
    sb.material(Material {
        base_color_factor: Vec4::new(0.8, 0.6, 0.4, 1.0),
        double_sided: true,
        ..Material::default()
    })
}

/// A small probe quad through the centre of voxel `(c, c, c)` of an 8³ grid over [0, 8]³.
fn probe(sb: &mut SceneBuilder, c: f32) {
    let m = opaque(sb);
    quad(sb, 2, c + 0.5, [c + 0.2, c + 0.2], [c + 0.8, c + 0.8], m);
}

fn opts(bake: Bake) -> VoxelizeOptions {
    VoxelizeOptions {
        resolution: Resolution::Exact([8; 3]),
        bounds: Some(Aabb {
            min: Vec3::ZERO,
            max: Vec3::splat(8.0),
        }),
        bake,
        ..VoxelizeOptions::default()
    }
}

fn ao_bake() -> Bake {
    Bake::Ao {
        rays: 256,
        distance: Some(20.0),
    }
}

/// AO of voxel `(c, c, c)`: its baked colour over its unbaked colour (seen from +Z).
fn ao_at(scene: &Scene, c: usize, bake: Bake) -> f32 {
    let i = c + 8 * (c + 8 * c);
    let lit = slice_stack(scene, &opts(bake), Dir::PosZ).unwrap().rgba[i];
    let plain = slice_stack(scene, &opts(Bake::None), Dir::PosZ)
        .unwrap()
        .rgba[i];
    assert!(
        plain.w > 0.0 && plain.x > 0.0,
        "probe voxel is empty: {plain}"
    );
    assert_eq!(lit.w, plain.w, "AO must not change alpha");
    lit.x / plain.x
}

fn closed_box(sb: &mut SceneBuilder, lo: f32, hi: f32) {
    let m = opaque(sb);
    for axis in 0..3 {
        for d in [lo, hi] {
            quad(sb, axis, d, [lo, lo], [hi, hi], m);
        }
    }
}

#[test]
fn voxel_inside_a_closed_box_is_fully_occluded() {
    let mut sb = SceneBuilder::new();
    closed_box(&mut sb, 1.0, 7.0);
    probe(&mut sb, 4.0);
    let ao = ao_at(&sb.finish(), 4, ao_bake());
    assert!(ao < 1e-3, "AO inside a closed box: {ao}");
}

#[test]
fn single_sided_box_occludes_from_inside_too() {
    // Every triangle occludes from both sides.
    let mut sb = SceneBuilder::new();
    let m = sb.material(Material::default());
    for axis in 0..3 {
        for d in [1.0, 7.0] {
            quad(&mut sb, axis, d, [1.0, 1.0], [7.0, 7.0], m);
        }
    }
    probe(&mut sb, 4.0);
    assert!(ao_at(&sb.finish(), 4, ao_bake()) < 1e-3);
}

#[test]
fn isolated_voxel_is_unoccluded() {
    let mut sb = SceneBuilder::new();
    probe(&mut sb, 4.0);
    let ao = ao_at(&sb.finish(), 4, ao_bake());
    assert!(ao > 0.999, "AO of an isolated voxel: {ao}");
}

#[test]
fn voxel_in_a_corner_is_partly_occluded() {
    // Three walls meeting at (1, 1, 1); the probe at voxel (2, 2, 2), 1.5 from each wall.
    let mut sb = SceneBuilder::new();
    let m = opaque(&mut sb);
    for axis in 0..3 {
        quad(&mut sb, axis, 1.0, [1.0, 1.0], [8.0, 8.0], m);
    }
    probe(&mut sb, 2.0);
    let scene = sb.finish();
    let ao = ao_at(&scene, 2, ao_bake());
    // Unbounded walls would leave exactly one octant open (1/8); these are finite.
    assert!(ao > 0.1 && ao < 0.6, "AO in a corner: {ao}");
    // A shorter distance sees less of the walls: more light.
    let near = ao_at(
        &scene,
        2,
        Bake::Ao {
            rays: 256,
            distance: Some(2.0),
        },
    );
    assert!(near > ao, "AO with distance 2: {near}, with 20: {ao}");
}

#[test]
fn alpha_mask_occludes_only_where_alpha_passes() {
    let wall = |alpha: u8| {
        let mut sb = SceneBuilder::new();
        let m = sb.material(Material {
            base_color_texture: Some(0),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            double_sided: true,
            ..Material::default()
        });
        quad(&mut sb, 0, 2.0, [0.0, 0.0], [8.0, 8.0], m);
        probe(&mut sb, 4.0);
        let mut scene = sb.finish();
        scene.textures.push(Texture {
            name: "a".into(),
            width: 1,
            height: 1,
            texels: vec![[255, 255, 255, alpha]],
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            encoded: None,
        });
        scene
    };
    let cut = ao_at(&wall(0), 4, ao_bake());
    let solid = ao_at(&wall(255), 4, ao_bake());
    assert!(cut > 0.999, "a fully cut-out wall must not occlude: {cut}");
    assert!(solid < 0.8, "a solid wall occludes: {solid}");
}

#[test]
fn ao_is_deterministic_across_thread_counts() {
    let mut sb = SceneBuilder::new();
    let m = opaque(&mut sb);
    for axis in 0..3 {
        quad(&mut sb, axis, 1.0, [1.0, 1.0], [8.0, 8.0], m);
    }
    for c in [2.0, 3.0, 5.0] {
        probe(&mut sb, c);
    }
    let scene = sb.finish();
    let o = VoxelizeOptions {
        normals: true,
        ..opts(Bake::Ao {
            rays: 16,
            distance: None,
        })
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| voxelize(&scene, &o, &|_, _| {}).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.levels, b.levels);
    assert_eq!(a.normals, b.normals);
    let plain = voxelize(&scene, &opts(Bake::None), &|_, _| {}).unwrap();
    assert_ne!(a.levels, plain.levels, "AO changed nothing");
    // Alpha is untouched at every level.
    for (l, p) in a.levels.iter().zip(&plain.levels) {
        assert!(l
            .chunks_exact(4)
            .zip(p.chunks_exact(4))
            .all(|(x, y)| x[3] == y[3]));
    }
    let params = bake_params(&a, &o, &BTreeMap::new());
    assert_eq!(params["bake"], "ao");
    assert_eq!(params["ao_rays"], "16");
    let d: f32 = params["ao_distance"].parse().unwrap();
    assert!(
        (d - 0.2 * 8.0 * 3f32.sqrt()).abs() < 1e-4,
        "default distance {d}"
    );
    assert!(!bake_params(&plain, &opts(Bake::None), &BTreeMap::new()).contains_key("bake"));
}

#[test]
fn bad_ao_options_are_refused() {
    let mut sb = SceneBuilder::new();
    probe(&mut sb, 4.0);
    let scene = sb.finish();
    for bake in [
        Bake::Ao {
            rays: 0,
            distance: None,
        },
        Bake::Ao {
            rays: 8,
            distance: Some(-1.0),
        },
        Bake::Ao {
            rays: 8,
            distance: Some(f32::NAN),
        },
    ] {
        assert!(
            voxelize(&scene, &opts(bake), &|_, _| {}).is_err(),
            "{bake:?}"
        );
    }
}
