//! Slice rasterization, binning, alpha modes, faces, resolution parsing and grid fitting.

use billow::scene::{AlphaMode, Material, Scene, SceneBuilder};
use billow::voxelize::{
    fit_grid, grid_for, slice_stack, voxelize, Dir, Resolution, ResolutionError, SliceStack,
    VoxelizeError, VoxelizeOptions,
};
use billow_core::Aabb;
use glam::{Vec3, Vec4};

fn material(alpha_mode: AlphaMode, double_sided: bool) -> Material {
    Material {
        alpha_mode,
        double_sided,
        ..Material::default()
    }
}

/// An axis-aligned square quad perpendicular to `axis` at coordinate `depth`, spanning
/// `[lo, hi]` on the two other axes, front face towards +axis (or −axis when `flip`).
#[allow(clippy::too_many_arguments)]
fn quad(
    sb: &mut SceneBuilder,
    axis: usize,
    depth: f32,
    lo: f32,
    hi: f32,
    color: Vec4,
    m: u32,
    flip: bool,
) {
    let (u, v) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let p = |a: f32, b: f32| {
        let mut q = [0.0; 3];
        q[axis] = depth;
        q[u] = a;
        q[v] = b;
        Vec3::from_array(q)
    };
    let mut c = [p(lo, lo), p(hi, lo), p(hi, hi), p(lo, hi)];
    if flip {
        c.reverse();
    }
    let mesh = sb.mesh("q");
    sb.quad(c, color, m, mesh);
}

fn cube_opts(n: u32) -> VoxelizeOptions {
    VoxelizeOptions {
        resolution: Resolution::Exact([n; 3]),
        bounds: Some(Aabb {
            min: Vec3::ZERO,
            max: Vec3::splat(n as f32),
        }),
        ..VoxelizeOptions::default()
    }
}

fn at(s: &SliceStack, p: [usize; 3]) -> Vec4 {
    let d = s.grid.dims.map(|d| d as usize);
    s.rgba[p[0] + d[0] * (p[1] + d[1] * p[2])]
}

fn non_empty(s: &SliceStack) -> Vec<[usize; 3]> {
    let d = s.grid.dims.map(|d| d as usize);
    let mut out = Vec::new();
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                if at(s, [x, y, z]).w > 0.0 {
                    out.push([x, y, z]);
                }
            }
        }
    }
    out
}

#[test]
fn quad_at_known_depth_lands_in_its_slice_from_each_direction() {
    // Grid [0,8]³, voxel size 1. A double-sided quad perpendicular to each axis at depth
    // 3.5 (mid-slice) and at exactly 5.0 (a slice boundary: belongs to slice 5).
    for axis in 0..3 {
        for (depth, slice) in [(3.5f32, 3usize), (5.0, 5)] {
            let mut sb = SceneBuilder::new();
            let m = sb.material(material(AlphaMode::Opaque, true));
            quad(
                &mut sb,
                axis,
                depth,
                2.0,
                6.0,
                Vec4::new(0.2, 0.4, 0.6, 1.0),
                m,
                false,
            );
            let scene = sb.finish();
            for dir in Dir::ALL {
                let s = slice_stack(&scene, &cube_opts(8), dir).unwrap();
                let got = non_empty(&s);
                if dir.axis() != axis {
                    assert!(
                        got.is_empty(),
                        "axis {axis} quad is edge-on from {dir:?} but saw {got:?}"
                    );
                    continue;
                }
                assert_eq!(got.len(), 16, "axis {axis} depth {depth} from {dir:?}");
                for p in got {
                    assert_eq!(p[axis], slice, "axis {axis} depth {depth} from {dir:?}");
                    for (a, &c) in p.iter().enumerate() {
                        if a != axis {
                            assert!((2..6).contains(&c));
                        }
                    }
                    let v = at(&s, p);
                    assert!(
                        (v - Vec4::new(0.2, 0.4, 0.6, 1.0)).abs().max_element() < 1e-6,
                        "{v}"
                    );
                }
            }
        }
    }
}

#[test]
fn single_sided_quad_is_seen_only_from_the_side_it_faces() {
    for flip in [false, true] {
        let mut sb = SceneBuilder::new();
        let m = sb.material(material(AlphaMode::Opaque, false));
        quad(&mut sb, 2, 3.5, 2.0, 6.0, Vec4::ONE, m, flip);
        let scene = sb.finish();
        let pos = non_empty(&slice_stack(&scene, &cube_opts(8), Dir::PosZ).unwrap()).len();
        let neg = non_empty(&slice_stack(&scene, &cube_opts(8), Dir::NegZ).unwrap()).len();
        assert_eq!((pos, neg), if flip { (0, 16) } else { (16, 0) });
    }
}

#[test]
fn partial_coverage_gives_fractional_alpha() {
    // x from 2 to 6.5: column x = 6 is half covered; with 4×4 samples exactly 0.5.
    let mut sb = SceneBuilder::new();
    let m = sb.material(material(AlphaMode::Opaque, true));
    let mesh = sb.mesh("q");
    let (lo, hi) = (Vec3::new(2.0, 2.0, 3.5), Vec3::new(6.5, 6.0, 3.5));
    sb.quad(
        [
            lo,
            Vec3::new(hi.x, lo.y, 3.5),
            hi,
            Vec3::new(lo.x, hi.y, 3.5),
        ],
        Vec4::ONE,
        m,
        mesh,
    );
    let s = slice_stack(&sb.finish(), &cube_opts(8), Dir::PosZ).unwrap();
    assert_eq!(at(&s, [6, 3, 3]).w, 0.5);
    assert_eq!(at(&s, [5, 3, 3]).w, 1.0);
    assert_eq!(at(&s, [7, 3, 3]).w, 0.0);
}

#[test]
fn blend_quad_half_alpha_and_mask_cutoff() {
    let colour = Vec4::new(0.8, 0.4, 0.2, 0.5);
    for (mode, want) in [
        (AlphaMode::Blend, Vec4::new(0.4, 0.2, 0.1, 0.5)),
        (
            AlphaMode::Mask { cutoff: 0.4 },
            Vec4::new(0.8, 0.4, 0.2, 1.0),
        ),
        (AlphaMode::Mask { cutoff: 0.6 }, Vec4::ZERO),
        (AlphaMode::Opaque, Vec4::new(0.8, 0.4, 0.2, 1.0)),
    ] {
        let mut sb = SceneBuilder::new();
        let m = sb.material(material(mode, true));
        quad(&mut sb, 1, 4.5, 1.0, 7.0, colour, m, false);
        let s = slice_stack(&sb.finish(), &cube_opts(8), Dir::NegY).unwrap();
        let v = at(&s, [3, 4, 3]);
        assert!(
            (v - want).abs().max_element() < 1e-6,
            "{mode:?}: {v} != {want}"
        );
    }
}

#[test]
fn two_blend_quads_in_one_voxel_composite_front_to_back() {
    // Two 50% quads in the same slice (z = 3.2 red, z = 3.8 green): from +Z green is in
    // front, from −Z red is.
    let mut sb = SceneBuilder::new();
    let m = sb.material(material(AlphaMode::Blend, true));
    quad(
        &mut sb,
        2,
        3.2,
        2.0,
        6.0,
        Vec4::new(1.0, 0.0, 0.0, 0.5),
        m,
        false,
    );
    quad(
        &mut sb,
        2,
        3.8,
        2.0,
        6.0,
        Vec4::new(0.0, 1.0, 0.0, 0.5),
        m,
        false,
    );
    let scene = sb.finish();
    let pz = at(
        &slice_stack(&scene, &cube_opts(8), Dir::PosZ).unwrap(),
        [3, 3, 3],
    );
    let nz = at(
        &slice_stack(&scene, &cube_opts(8), Dir::NegZ).unwrap(),
        [3, 3, 3],
    );
    assert!(
        (pz - Vec4::new(0.25, 0.5, 0.0, 0.75)).abs().max_element() < 1e-6,
        "{pz}"
    );
    assert!(
        (nz - Vec4::new(0.5, 0.25, 0.0, 0.75)).abs().max_element() < 1e-6,
        "{nz}"
    );
}

#[test]
fn shared_diagonal_is_covered_once() {
    // A 50% quad whose diagonal passes through sample positions: no sample may be
    // composited twice (0.75) or missed (0).
    let mut sb = SceneBuilder::new();
    let m = sb.material(material(AlphaMode::Blend, true));
    quad(
        &mut sb,
        2,
        0.5,
        0.0,
        8.0,
        Vec4::new(1.0, 1.0, 1.0, 0.5),
        m,
        false,
    );
    let s = slice_stack(&sb.finish(), &cube_opts(8), Dir::PosZ).unwrap();
    for y in 0..8 {
        for x in 0..8 {
            assert_eq!(at(&s, [x, y, 0]).w, 0.5, "({x},{y})");
        }
    }
}

#[test]
fn normals_face_the_camera_and_cancel_for_double_sided_leaves() {
    let mut sb = SceneBuilder::new();
    let m = sb.material(material(AlphaMode::Opaque, true));
    quad(&mut sb, 2, 3.5, 2.0, 6.0, Vec4::ONE, m, false);
    let scene = sb.finish();
    let opts = VoxelizeOptions {
        normals: true,
        ..cube_opts(8)
    };
    let p = slice_stack(&scene, &opts, Dir::PosZ).unwrap();
    let n = slice_stack(&scene, &opts, Dir::NegZ).unwrap();
    let idx = 3 + 8 * (3 + 8 * 3);
    assert!((p.normals.as_ref().unwrap()[idx] - Vec3::Z).length() < 1e-3);
    assert!((n.normals.as_ref().unwrap()[idx] + Vec3::Z).length() < 1e-3);
    // Combined: +Z and −Z cancel to a zero normal, encoded as zeros, no NaN.
    let vol = voxelize(&scene, &opts, &|_, _| {}).unwrap();
    let nb = &vol.normals.as_ref().unwrap()[0][4 * idx..4 * idx + 4];
    assert_eq!(nb, &[0, 0, 0, 0]);
    // A single-sided quad keeps a unit normal.
    let mut sb = SceneBuilder::new();
    let m = sb.material(material(AlphaMode::Opaque, false));
    quad(&mut sb, 2, 3.5, 2.0, 6.0, Vec4::ONE, m, false);
    let vol = voxelize(&sb.finish(), &opts, &|_, _| {}).unwrap();
    assert_eq!(
        &vol.normals.as_ref().unwrap()[0][4 * idx..4 * idx + 4],
        &[0, 0, 127, 0]
    );
}

#[test]
fn resolution_parsing() {
    assert_eq!("128".parse::<Resolution>(), Ok(Resolution::Longest(128)));
    assert_eq!(
        "256x128X64".parse::<Resolution>(),
        Ok(Resolution::Exact([256, 128, 64]))
    );
    assert_eq!(Resolution::Exact([5, 3, 7]).to_string(), "5x3x7");
    let err = |s: &str| s.parse::<Resolution>().unwrap_err();
    assert!(matches!(err("0"), ResolutionError::Zero { .. }));
    assert!(matches!(
        err("100000"),
        ResolutionError::TooLarge {
            value: 100000,
            max: 2048,
            ..
        }
    ));
    assert!(matches!(
        err("99999999999999999999999"),
        ResolutionError::TooLarge { .. }
    ));
    assert_eq!(err("12x0x4"), ResolutionError::Zero { axis: 'y' });
    assert!(matches!(err("abc"), ResolutionError::NotANumber { .. }));
    assert!(matches!(
        err("12x4"),
        ResolutionError::WrongArity { parts: 2, .. }
    ));
    assert!(matches!(
        err("-5"),
        ResolutionError::Negative { axis: 'n', .. }
    ));
    assert!(matches!(
        err("4x-2x4"),
        ResolutionError::Negative { axis: 'y', .. }
    ));
    assert!(matches!(err(""), ResolutionError::Empty));
    for s in ["0", "100000", "12x0x4", "abc", "12x4", ""] {
        let msg = err(s).to_string();
        assert!(msg.contains("resolution"), "{msg}");
    }
    assert!(err("12x0x4").to_string().contains("y size is 0"));
    assert!(err("100000").to_string().contains("2048"));
    // The single-number form names what N is.
    assert!(err("0").to_string().contains("N (the longest axis) is 0"));
    assert!(err("100000")
        .to_string()
        .contains("N (the longest axis) 100000 is larger"));
}

#[test]
fn huge_resolution_is_refused_before_allocating() {
    let mut sb = SceneBuilder::new();
    let m = sb.material(Material::default());
    quad(&mut sb, 2, 0.5, 0.0, 1.0, Vec4::ONE, m, false);
    let scene = sb.finish();
    let opts = VoxelizeOptions {
        resolution: Resolution::Exact([2048; 3]),
        ..VoxelizeOptions::default()
    };
    let t = std::time::Instant::now();
    let e = voxelize(&scene, &opts, &|_, _| {}).unwrap_err();
    assert!(t.elapsed().as_secs_f64() < 1.0);
    assert!(matches!(e, VoxelizeError::TooMuchMemory { .. }), "{e}");
    assert!(e.to_string().contains("GiB"), "{e}");
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(0),
        ..VoxelizeOptions::default()
    };
    assert!(matches!(
        voxelize(&scene, &opts, &|_, _| {}),
        Err(VoxelizeError::Resolution(_))
    ));
    let opts = VoxelizeOptions {
        supersample: 0,
        ..VoxelizeOptions::default()
    };
    assert!(matches!(
        voxelize(&scene, &opts, &|_, _| {}),
        Err(VoxelizeError::InvalidOption { .. })
    ));
    let empty = SceneBuilder::new().finish();
    assert!(matches!(
        voxelize(&empty, &VoxelizeOptions::default(), &|_, _| {}),
        Err(VoxelizeError::EmptyScene)
    ));
}

#[test]
fn grid_fitting_margin_and_proportions() {
    let b = Aabb {
        min: Vec3::new(0.0, 0.0, 0.0),
        max: Vec3::new(4.0, 2.0, 0.0),
    };
    // Longest(9) with half a voxel of margin: 4 = 8 voxels of 0.5, plus 2 × ½ voxel.
    let g = fit_grid(&b, Resolution::Longest(9), 0.5).unwrap();
    assert_eq!(g.dims, [9, 5, 1]);
    assert!((g.voxel - Vec3::splat(0.5)).abs().max_element() < 1e-6);
    assert!(
        (g.min - Vec3::new(-0.25, -0.25, -0.25)).abs().max_element() < 1e-6,
        "{:?}",
        g.min
    );
    // Exact: non-cubic voxels; a flat axis gets the largest voxel size.
    let g = fit_grid(&b, Resolution::Exact([4, 4, 2]), 0.0).unwrap();
    assert_eq!(g.dims, [4, 4, 2]);
    assert!((g.voxel - Vec3::new(1.0, 0.5, 1.0)).abs().max_element() < 1e-6);
    assert_eq!(
        fit_grid(&b, Resolution::Longest(1), 0.5).unwrap().dims,
        [1, 1, 1]
    );
    assert!(fit_grid(&Aabb::EMPTY, Resolution::Longest(8), 0.5).is_err());
    // The scene's own bounds get the margin.
    let mut sb = SceneBuilder::new();
    let m = sb.material(Material::default());
    quad(&mut sb, 2, 1.0, 0.0, 3.0, Vec4::ONE, m, false);
    let g = grid_for(
        &sb.finish(),
        &VoxelizeOptions {
            resolution: Resolution::Longest(4),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(g.dims, [4, 4, 1]);
    assert!((g.voxel.x - 1.0).abs() < 1e-6);
}

#[allow(dead_code)]
fn unused(_: Scene) {}
