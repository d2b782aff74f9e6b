//! Morphing between levels (Lacewell §3, Figure 3), on a real bake of the oak with three
//! levels: every stored parent projection lies on the parent billboard's plane and is the
//! orthogonal projection of its vertex, the parent is the billboard whose slab holds the
//! child, and morphing the exported glTF at weight 1 puts every vertex on its parent.

mod bbcloud_common;

use std::collections::HashMap;

use bbcloud_common::oak;
use billow::bbcloud::{bake, BbcloudOptions};
use billow::export::{write_cloud_glb, GltfOptions};
use billow_format::CloudAsset;
use glam::Vec3;

fn bake_oak() -> CloudAsset {
    let opts = BbcloudOptions {
        samples: 60,
        seed: 5,
        lods: 3,
        atlas_size: 512,
        supersample: 1,
        ..BbcloudOptions::default()
    };
    bake(&oak(), &opts, "billow test", None, &|_, _| {})
        .unwrap()
        .0
}

fn plane(p: &[f32; 4]) -> (Vec3, f32) {
    (Vec3::new(p[0], p[1], p[2]), p[3])
}

#[test]
fn parent_projections_lie_on_the_parent_plane() {
    let a = bake_oak();
    assert_eq!(a.levels.len(), 3);
    let scale = Vec3::from(a.header.bounds.max).distance(Vec3::from(a.header.bounds.min));
    let tol = 1e-5 * scale;
    let mut checked = 0;
    for (l, lv) in a.levels.iter().enumerate() {
        let range = lv.first_billboard as usize..(lv.first_billboard + lv.billboard_count) as usize;
        for b in &a.billboards[range] {
            let Some(p) = b.parent else {
                assert_eq!(l, a.levels.len() - 1, "only the last level has no parent");
                assert_eq!(b.parent_corners, b.corners, "last level: its own corners");
                continue;
            };
            let parent = &a.billboards[p as usize];
            let (n, r) = plane(&parent.plane);
            // The parent is the billboard of the next level whose slab holds this one (the
            // search's ε for searched levels; the cross takes everything). The stored quad
            // is the searched one grown to whole texels: up to one texel more per side.
            if l + 2 < a.levels.len() {
                let eps = a.levels[l + 1].epsilon;
                let grow = std::f32::consts::SQRT_2 / lv.texel_density;
                for c in b.corners {
                    let d = (n.dot(Vec3::from(c)) - r).abs();
                    assert!(
                        d < eps + grow,
                        "corner {d} from its parent, ε {eps} + {grow}"
                    );
                }
            }
            for (c, pc) in b.corners.iter().zip(&b.parent_corners) {
                let (c, pc) = (Vec3::from(*c), Vec3::from(*pc));
                assert!((n.dot(pc) - r).abs() < tol, "not on the parent plane");
                // Orthogonal: the displacement is along the parent's normal, and equals the
                // projection computed here.
                assert!(
                    (pc - c).cross(n).length() < tol,
                    "not an orthogonal projection"
                );
                assert!((pc - (c - (n.dot(c) - r) * n)).length() < tol);
                checked += 1;
            }
        }
    }
    assert!(checked >= 4 * 100, "only {checked} corners checked");
    // The foliage mesh morphs onto its level-0 billboards the same way.
    let f = &a.foliage;
    for (t, tri) in f.triangles.iter().enumerate() {
        let (n, r) = plane(&a.billboards[f.billboard[t] as usize].plane);
        for &v in tri {
            let (p, m) = (
                Vec3::from(f.vertices[v as usize].position),
                Vec3::from(f.morph[v as usize]),
            );
            assert!((n.dot(m) - r).abs() < tol);
            assert!((m - (p - (n.dot(p) - r) * n)).length() < tol);
        }
    }
}

/// In the `.glb`, each LOD mesh's morph target at weight 1 moves every quad corner onto
/// its parent billboard: `POSITION + target` is the stored parent projection.
#[test]
fn gltf_morph_at_weight_one_reaches_the_parents() {
    let a = bake_oak();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("oak.glb");
    write_cloud_glb(&a, &path, &GltfOptions::default()).unwrap();
    let (doc, buffers, _) = gltf::import(&path).expect("strict import");
    let key = |p: [f32; 3]| p.map(f32::to_bits);
    for (l, lv) in a.levels.iter().enumerate() {
        let range = lv.first_billboard as usize..(lv.first_billboard + lv.billboard_count) as usize;
        let mut parent_of: HashMap<[u32; 3], [f32; 3]> = HashMap::new();
        for b in &a.billboards[range] {
            for (c, pc) in b.corners.iter().zip(&b.parent_corners) {
                parent_of.insert(key(*c), *pc);
            }
        }
        let mesh = doc
            .meshes()
            .find(|m| m.name() == Some(&format!("lod{l}")))
            .expect("LOD mesh");
        assert_eq!(mesh.weights(), Some(&[0.0][..]));
        let mut moved = 0;
        for prim in mesh.primitives() {
            let r = prim.reader(|b| Some(&buffers[b.index()]));
            let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
            let (dp, _, _) = r.read_morph_targets().next().expect("one morph target");
            let dp: Vec<[f32; 3]> = dp.expect("position displacements").collect();
            assert_eq!(pos.len(), dp.len());
            for (p, d) in pos.iter().zip(&dp) {
                let target = parent_of[&key(*p)];
                let at_one = Vec3::from(*p) + Vec3::from(*d);
                assert!(
                    at_one.distance(Vec3::from(target)) < 1e-5,
                    "lod{l}: {at_one} vs parent projection {target:?}"
                );
                if l + 1 == a.levels.len() {
                    assert_eq!(*d, [0.0; 3], "the last level does not move");
                }
                moved += 1;
            }
        }
        assert_eq!(
            moved,
            8 * lv.billboard_count as usize,
            "4 corners × 2 sides"
        );
    }
}
