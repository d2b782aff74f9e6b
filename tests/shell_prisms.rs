//! Shells (volumetric textures): prisms extruded from a surface along its normals.

use std::collections::{BTreeMap, HashMap};

use billow::procgen::torus;
use billow::scene::{Material, Scene, SceneBuilder, Triangle, Vertex};
use billow::shell::{shell, shell_asset, shell_prisms, ShellError};
use billow_format::{Bounds, ColourSpace, Header, Prism, VolumeAsset};
use glam::{Mat3, Vec2, Vec3, Vec4};

/// The unit square in the xz plane at y = 0, facing +Y (counter-clockwise from above).
fn flat_quad() -> Scene {
    let mut sb = SceneBuilder::new();
    let m = sb.material(Material::default());
    let mesh = sb.mesh("quad");
    // Explicit UVs (glTF convention, v down): u along +z, v along −x. (`SceneBuilder::quad`
    // gives its third corner the UV (1, 1) like the second, so its first triangle has a
    // zero-area UV layout.)
    let v = |p: Vec3, uv: Vec2| Vertex {
        position: p,
        normal: Vec3::Y,
        uv,
        color: Vec4::ONE,
    };
    let c = [
        v(Vec3::ZERO, Vec2::new(0.0, 1.0)),
        v(Vec3::Z, Vec2::new(1.0, 1.0)),
        v(Vec3::new(1.0, 0.0, 1.0), Vec2::new(1.0, 0.0)),
        v(Vec3::X, Vec2::ZERO),
    ];
    sb.triangle([c[0], c[1], c[2]], m, mesh);
    sb.triangle([c[0], c[2], c[3]], m, mesh);
    sb.finish()
}

/// World-space Jacobian ∂pos/∂uvw of a prism (affine: vertices 0, 1, 2, 3).
fn jacobian(p: &Prism) -> Mat3 {
    let d = |a: &[[f32; 3]; 6], i: usize| Vec3::from(a[i]) - Vec3::from(a[0]);
    let pm = Mat3::from_cols(d(&p.pos, 1), d(&p.pos, 2), d(&p.pos, 3));
    let tm = Mat3::from_cols(d(&p.uvw, 1), d(&p.uvw, 2), d(&p.uvw, 3));
    pm * tm.inverse()
}

fn check_winding(p: &Prism) {
    let v = |i: usize| Vec3::from(p.pos[i]);
    let n = (v(1) - v(0)).cross(v(2) - v(0));
    for k in 0..3 {
        assert!(
            n.dot(v(k + 3) - v(k)) > 0.0,
            "bottom winding points towards the top"
        );
    }
}

#[test]
fn flat_quad_gives_two_prisms_exactly_height_above() {
    let h = 0.25;
    let s = shell(&flat_quad(), h, Vec2::new(3.0, 2.0)).unwrap();
    assert_eq!(s.prisms.len(), 2);
    assert_eq!(
        (
            s.skipped,
            s.mirrored,
            s.folded,
            s.uv_degenerate,
            s.replaced_normals
        ),
        (0, 0, 0, 0, 0)
    );
    for p in &s.prisms {
        check_winding(p);
        for k in 0..3 {
            let (b, t) = (p.pos[k], p.pos[k + 3]);
            assert_eq!(b[1], 0.0);
            assert_eq!(
                [t[0], t[1], t[2]],
                [b[0], h, b[2]],
                "top straight above the bottom"
            );
            // uvw: (u·su, 0|1, v·sv).
            assert_eq!(p.uvw[k][1], 0.0);
            assert_eq!(p.uvw[k + 3][1], 1.0);
            assert_eq!(
                [p.uvw[k][0], p.uvw[k][2]],
                [p.uvw[k + 3][0], p.uvw[k + 3][2]]
            );
            assert!(
                [0.0, 3.0].contains(&p.uvw[k][0]) && [0.0, 2.0].contains(&p.uvw[k][2]),
                "{:?}",
                p.uvw
            );
        }
        // Texture y (height) runs along the normal, `height` per unit; x along ∂p/∂u, z along ∂p/∂v.
        let j = jacobian(p);
        assert!((j.col(1) - Vec3::new(0.0, h, 0.0)).length() < 1e-6, "{j}");
        assert!((j.col(0) - Vec3::Z / 3.0).length() < 1e-6, "{j}");
        assert!((j.col(2) - Vec3::NEG_X / 2.0).length() < 1e-6, "{j}");
        assert!(j.determinant() > 0.0, "not mirrored");
    }
    assert_eq!(
        s.bounds,
        Bounds {
            min: [0.0; 3],
            max: [1.0, h, 1.0]
        }
    );
    assert_eq!(
        shell_prisms(&flat_quad(), h, Vec2::new(3.0, 2.0)).unwrap(),
        s.prisms
    );
}

#[test]
fn torus_shell_has_one_prism_per_triangle_all_tops_outside() {
    let (r_major, r_minor, h) = (1.0, 0.35, 0.08);
    let (segments, sides) = (24, 12);
    let surface = torus(r_major, r_minor, segments, sides);
    assert_eq!(surface.triangles.len(), 2 * 24 * 12);
    let scale = Vec2::new(6.0, 2.0);
    let s = shell(&surface, h, scale).unwrap();
    assert_eq!(s.prisms.len(), 2 * (segments * sides) as usize);
    assert_eq!(
        (
            s.skipped,
            s.mirrored,
            s.folded,
            s.uv_degenerate,
            s.replaced_normals
        ),
        (0, 0, 0, 0, 0)
    );
    // Distance of a point from the tube's centre circle.
    let tube = |p: [f32; 3]| {
        let radial = Vec2::new(p[0], p[2]).length() - r_major;
        Vec2::new(radial, p[1]).length()
    };
    let (mut umax, mut vmax) = (0f32, 0f32);
    for p in &s.prisms {
        check_winding(p);
        for k in 0..3 {
            assert!(
                (tube(p.pos[k]) - r_minor).abs() < 1e-5,
                "bottom on the surface"
            );
            let d = tube(p.pos[k + 3]);
            assert!(
                (d - (r_minor + h)).abs() < 1e-4,
                "top outside, at height {h}: {d}"
            );
            let (b, t) = (p.uvw[k], p.uvw[k + 3]);
            assert_eq!((b[1], t[1]), (0.0, 1.0));
            assert_eq!((b[0], b[2]), (t[0], t[2]));
            assert!((0.0..=scale.x).contains(&b[0]) && (0.0..=scale.y).contains(&b[2]));
            umax = umax.max(b[0]);
            vmax = vmax.max(b[2]);
        }
        assert!(
            jacobian(p).determinant() > 0.0,
            "torus UVs map the tile unmirrored"
        );
    }
    assert!(
        (umax - scale.x).abs() < 1e-5 && (vmax - scale.y).abs() < 1e-5,
        "UV range fully used"
    );
}

/// Flat-shaded box: corners shared by faces with different normals still get one top vertex.
#[test]
fn flat_shaded_box_shell_has_no_cracks() {
    let mut sb = SceneBuilder::new();
    let m = sb.material(Material::default());
    let mesh = sb.mesh("box");
    billow::procgen::beam(&mut sb, Vec3::ZERO, Vec3::Y, 1.0, m, mesh);
    let surface = sb.finish();
    let s = shell(&surface, 0.1, Vec2::ONE).unwrap();
    assert_eq!(s.prisms.len(), 12);
    let mut tops: HashMap<[u32; 3], [u32; 3]> = HashMap::new();
    for p in &s.prisms {
        check_winding(p);
        for k in 0..3 {
            let key = p.pos[k].map(f32::to_bits);
            let top = p.pos[k + 3].map(f32::to_bits);
            assert_eq!(
                *tops.entry(key).or_insert(top),
                top,
                "one top per bottom vertex"
            );
            let off = Vec3::from(p.pos[k + 3]) - Vec3::from(p.pos[k]);
            assert!((off.length() - 0.1).abs() < 1e-5);
            // Corner of the box: the offset points diagonally outward.
            let c = Vec3::from(p.pos[k]) - Vec3::new(0.0, 0.5, 0.0);
            assert!(off.dot(c) > 0.0);
        }
    }
    assert_eq!(tops.len(), 8);
}

#[test]
fn bad_parameters_and_surfaces_are_errors() {
    let q = flat_quad();
    for h in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(
            matches!(shell(&q, h, Vec2::ONE), Err(ShellError::InvalidHeight(_))),
            "{h}"
        );
    }
    for sc in [Vec2::ZERO, Vec2::new(1.0, -1.0), Vec2::new(f32::NAN, 1.0)] {
        assert!(matches!(
            shell(&q, 0.1, sc),
            Err(ShellError::InvalidUvScale(_))
        ));
    }
    let empty = SceneBuilder::new().finish();
    assert_eq!(
        shell(&empty, 0.1, Vec2::ONE).unwrap_err(),
        ShellError::EmptySurface
    );

    // Degenerate triangles are skipped and counted; all degenerate is an error.
    let v = |p: Vec3, uv: Vec2| Vertex {
        position: p,
        normal: Vec3::Y,
        uv,
        color: Vec4::ONE,
    };
    let line = Triangle {
        v: [
            v(Vec3::ZERO, Vec2::ZERO),
            v(Vec3::X, Vec2::X),
            v(Vec3::X * 2.0, Vec2::Y),
        ],
        material: 0,
        mesh: 0,
    };
    let nan_uv = Triangle {
        v: [
            v(Vec3::ZERO, Vec2::NAN),
            v(Vec3::Z, Vec2::X),
            v(Vec3::X, Vec2::Y),
        ],
        material: 0,
        mesh: 0,
    };
    let mut bad = flat_quad();
    bad.triangles = vec![line, nan_uv];
    assert_eq!(
        shell(&bad, 0.1, Vec2::ONE).unwrap_err(),
        ShellError::NoPrisms { skipped: 2 }
    );
    let mut mixed = flat_quad();
    mixed.triangles.push(line);
    let s = shell(&mixed, 0.1, Vec2::ONE).unwrap();
    assert_eq!((s.prisms.len(), s.skipped), (2, 1));
    assert!(s.describe().contains("skipped=1"));
}

#[test]
fn shell_asset_replaces_cells_bounds_and_params() {
    let volume = VolumeAsset {
        header: Header {
            seed: Some(7),
            params: BTreeMap::from([("res".to_string(), "2x2x2".to_string())]),
            ..Header::volume(
                "billow test",
                ColourSpace::SrgbPremultiplied,
                [2, 2, 2],
                2,
                false,
            )
        },
        levels: vec![vec![200; 32], vec![100; 4]],
        normals: None,
        bands: Vec::new(),
        cells: billow_core::cells::box_prisms(Vec3::ZERO, Vec3::ONE).to_vec(),
    };
    let s = shell(&torus(1.0, 0.35, 16, 8), 0.1, Vec2::new(4.0, 2.0)).unwrap();
    let (bounds, prisms) = (s.bounds, s.prisms.clone());
    let a = shell_asset(&volume, s);
    a.validate().unwrap();
    assert_eq!(a.cells, prisms);
    assert_eq!(a.header.bounds, bounds);
    assert!(
        (bounds.max[0] - 1.45).abs() < 1e-3 && (bounds.max[1] - 0.45).abs() < 1e-3,
        "{bounds:?}"
    );
    assert_eq!(a.header.params["res"], "2x2x2");
    assert_eq!(
        a.header.params["shell"],
        "height=0.1 uv_scale=4x2 prisms=256 skipped=0"
    );
    assert_eq!(
        (a.levels.clone(), a.header.seed),
        (volume.levels.clone(), Some(7))
    );
    assert_eq!(VolumeAsset::from_bytes(&a.to_bytes().unwrap()).unwrap(), a);
}
