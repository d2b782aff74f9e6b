//! The BVH over a scene's triangles (obvhs BVH2), shared by everything that casts rays at
//! the source mesh (the reference renderer's build is the same; voxelize's baked AO).
//!
//! Primitive `i` of the BVH is triangle `bvh.primitive_indices[i]` of the scene. The build
//! is single-threaded (obvhs without its `parallel` feature), so the tree — and therefore
//! any traversal order — is the same on every run and for every thread count.

use std::time::Duration;

use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::Bvh2;
use obvhs::BvhBuildParams;

use crate::scene::Scene;

/// A BVH2 over every triangle of `scene` (`None` when it has none). A triangle with a
/// non-finite vertex enters as a degenerate triangle at the origin (never hit), so
/// primitive indices still match the scene's.
pub fn scene_bvh(scene: &Scene) -> Option<Bvh2> {
    let tris: Vec<obvhs::triangle::Triangle> = scene
        .triangles
        .iter()
        .map(|t| {
            let p = if t.v.iter().all(|v| v.position.is_finite()) {
                t.v.map(|v| v.position)
            } else {
                [glam::Vec3::ZERO; 3]
            };
            obvhs::triangle::Triangle {
                v0: p[0].into(),
                v1: p[1].into(),
                v2: p[2].into(),
            }
        })
        .collect();
    (!tris.is_empty()).then(|| {
        build_bvh2_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        )
    })
}
