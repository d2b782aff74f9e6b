//! Shared by the bbcloud tests: a synthetic leafy scene and the oak.
#![allow(dead_code)]

use billow::bbcloud::Element;
use billow::rng::Pcg32;
use billow::scene::{AlphaMode, Material, Scene, Triangle, Vertex};
use billow_core::Aabb;
use glam::{Vec2, Vec3, Vec4};

/// The bundled oak, from the library's package or the CLI's (bin/billow).
pub fn oak_path() -> std::path::PathBuf {
    billow::test_support::repo().join("fixtures/oak/eztree_oak_medium.gltf")
}

pub fn oak() -> Scene {
    billow::import::import(&oak_path(), &Default::default())
        .expect("oak")
        .scene
}

/// The oak's leaf triangles as search elements, and the foliage's bounding-sphere radius.
pub fn oak_leaves() -> (Vec<Element>, f32) {
    let scene = oak();
    let leaves: Vec<Element> = scene
        .triangles
        .iter()
        .filter(|t| scene.material(t).alpha_mode != AlphaMode::Opaque)
        .map(|t| Element::triangle(t.v[0].position, t.v[1].position, t.v[2].position))
        .collect();
    let pts = || leaves.iter().flat_map(|e| e.verts[..3].to_vec());
    let (lo, hi) = pts().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
        (a.min(p), b.max(p))
    });
    let c = 0.5 * (lo + hi);
    let r = pts().map(|p| p.distance(c)).fold(0.0, f32::max);
    (leaves, r)
}

pub fn vtx(p: Vec3, n: Vec3, uv: Vec2) -> Vertex {
    Vertex {
        position: p,
        normal: n,
        uv,
        color: Vec4::ONE,
    }
}

/// A scene from triangles and materials, bounds computed.
pub fn scene_of(triangles: Vec<Triangle>, materials: Vec<Material>) -> Scene {
    let mut bounds = Aabb::EMPTY;
    triangles
        .iter()
        .flat_map(|t| t.v.iter())
        .for_each(|v| bounds.grow(v.position));
    Scene {
        triangles,
        materials,
        textures: vec![],
        meshes: vec![],
        bounds,
    }
}

/// Leaf cards (MASK) scattered in a sphere plus a few opaque trunk triangles.
pub fn leafy_scene(leaves: usize) -> Scene {
    let mut rng = Pcg32::seeded(42, 7);
    let mut triangles = Vec::new();
    for i in 0..leaves {
        let c = loop {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if c.length() < 1.0 {
                break c + Vec3::Y * 2.0;
            }
        };
        let a = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        )
        .normalize_or(Vec3::X);
        let b = a.any_orthonormal_vector();
        let n = a.cross(b);
        let s = 0.15;
        let q = [c, c + a * s, c + (a + b) * s, c + b * s];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        for t in [[0, 1, 2], [0, 2, 3]] {
            triangles.push(Triangle {
                v: t.map(|k| vtx(q[k], n, uv[k])),
                material: 1,
                mesh: (i % 2) as u32,
            });
        }
    }
    for k in 0..6 {
        let a = k as f32 * 1.047;
        let (p, q) = (
            Vec3::new(a.cos(), 0.0, a.sin()) * 0.1,
            Vec3::new((a + 1.047).cos(), 0.0, (a + 1.047).sin()) * 0.1,
        );
        let n = (p + q).normalize();
        triangles.push(Triangle {
            v: [
                vtx(p, n, Vec2::ZERO),
                vtx(q, n, Vec2::X),
                vtx(q + Vec3::Y * 2.0, n, Vec2::ONE),
            ],
            material: 0,
            mesh: 0,
        });
    }
    let mut bounds = Aabb::EMPTY;
    triangles
        .iter()
        .flat_map(|t| t.v.iter())
        .for_each(|v| bounds.grow(v.position));
    let leaf = Material {
        name: "leaves".into(),
        base_color_factor: Vec4::new(0.2, 0.6, 0.1, 1.0),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        ..Material::default()
    };
    Scene {
        triangles,
        materials: vec![
            Material {
                name: "bark".into(),
                ..Material::default()
            },
            leaf,
        ],
        textures: vec![],
        meshes: vec![],
        bounds,
    }
}
