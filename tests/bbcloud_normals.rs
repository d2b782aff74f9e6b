//! Normal maps per billboard (`normal_map`, SPEC §9.4): tangent-space normals of the leaves
//! in each side's frame (T, B, N) = (U, −V, ±n), stored as a layer of every atlas (format
//! 1.1, `ANRM`) and exported as the glTF `normalTexture` with matching `TANGENT`s.

mod bbcloud_common;

use bbcloud_common::{scene_of, vtx};
use billow::bbcloud::{bake, BbcloudOptions, Shading};
use billow::export::{write_cloud_glb, GltfOptions};
use billow::rng::Pcg32;
use billow::scene::{AlphaMode, Material, Scene, Triangle};
use billow_format::{Billboard, CloudAsset};
use glam::{Vec2, Vec3, Vec4};

/// The one normal all leaves share.
fn leaf_normal() -> Vec3 {
    Vec3::new(1.0, 2.0, 3.0).normalize()
}

/// 150 parallel leaf cards (normal `leaf_normal()`) scattered in a ball.
fn parallel_leaves() -> Scene {
    let mut rng = Pcg32::seeded(8, 1);
    let n = leaf_normal();
    let a = n.any_orthonormal_vector();
    let b = n.cross(a);
    let mut tris = Vec::new();
    for _ in 0..150 {
        let c = loop {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if c.length() < 1.0 {
                break c;
            }
        };
        let q = [c, c + a * 0.12, c + (a + b) * 0.12, c + b * 0.12];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        for t in [[0, 1, 2], [0, 2, 3]] {
            tris.push(Triangle {
                v: t.map(|k| vtx(q[k], n, uv[k])),
                material: 0,
                mesh: 0,
            });
        }
    }
    scene_of(
        tris,
        vec![Material {
            name: "leaves".into(),
            base_color_factor: Vec4::new(0.2, 0.6, 0.1, 1.0),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            double_sided: true,
            ..Material::default()
        }],
    )
}

fn bake_with_normals(scene: &Scene) -> CloudAsset {
    let opts = BbcloudOptions {
        samples: 80,
        lods: 2,
        atlas_size: 512,
        supersample: 2,
        epsilon: 0.05,
        normal_map: true,
        shading: Shading {
            light: None,
            ambient: 1.0,
        },
        ..BbcloudOptions::default()
    };
    bake(scene, &opts, "billow test", None, &|_, _| {})
        .unwrap()
        .0
}

/// Side frame of a billboard: (T, B, N) = (U, −V, ±n).
fn frame(b: &Billboard, front: bool) -> [Vec3; 3] {
    let c = b.corners.map(Vec3::from);
    let n = Vec3::from_slice(&b.plane);
    let u = (c[1] - c[0]).normalize();
    let v = (c[3] - c[0]).normalize();
    [u, -v, if front { n } else { -n }]
}

/// Every texel of one side's UV rectangle (level 0): (colour alpha, decoded world normal,
/// raw normal texel).
fn side_texels(a: &CloudAsset, b: &Billboard, front: bool) -> Vec<(u8, Vec3, [u8; 4])> {
    let r = if front { b.front } else { b.back };
    let at = &a.atlases[r.atlas as usize];
    let nm = &at.normals.as_ref().expect("normal map")[0];
    let [t, bt, n] = frame(b, front);
    let px = |u: f32, s: u32| (u * s as f32).round() as u32;
    let mut out = Vec::new();
    for y in px(r.uv[1], at.height)..px(r.uv[3], at.height) {
        for x in px(r.uv[0], at.width)..px(r.uv[2], at.width) {
            let i = 4 * (y * at.width + x) as usize;
            let raw: [u8; 4] = nm[i..i + 4].try_into().unwrap();
            let d = |c: u8| f32::from(c) / 255.0 * 2.0 - 1.0;
            let ts = Vec3::new(d(raw[0]), d(raw[1]), d(raw[2]));
            out.push((at.mips[0][i + 3], t * ts.x + bt * ts.y + n * ts.z, raw));
        }
    }
    out
}

#[test]
fn normal_maps_hold_the_leaf_normals_in_each_side_frame() {
    let a = bake_with_normals(&parallel_leaves());
    assert_eq!(a.header.params["normal_map"], "tangent");
    let nl = leaf_normal();
    let mut covered = 0;
    for (l, lv) in a.levels.iter().enumerate() {
        let range = lv.first_billboard as usize..(lv.first_billboard + lv.billboard_count) as usize;
        for b in &a.billboards[range] {
            let n = Vec3::from_slice(&b.plane);
            for front in [true, false] {
                // The nearest leaf seen from this side, its normal turned towards the viewer.
                let side = if front { n } else { -n };
                let want = if nl.dot(side) >= 0.0 { nl } else { -nl };
                for (alpha, world, raw) in side_texels(&a, b, front) {
                    if alpha == 0 {
                        assert_eq!(raw, [128, 128, 255, 255], "empty texel not flat");
                        continue;
                    }
                    covered += 1;
                    assert!(
                        world.distance(want) < 0.03,
                        "level {l}, front {front}: decoded {world} vs leaf normal {want}"
                    );
                    assert!(
                        raw[3] > 245,
                        "parallel normals: mean length 1, got {}",
                        raw[3]
                    );
                }
            }
        }
    }
    assert!(covered > 2000, "only {covered} covered texels");
    // The final cross stands across the leaves: its maps are far from flat, so the frame
    // matters (a map written in the wrong frame fails the check above).
    let cross = &a.billboards[a.levels[1].first_billboard as usize];
    let tilted = side_texels(&a, cross, true)
        .iter()
        .filter(|t| t.0 > 0)
        .all(|t| t.2[2] < 240);
    assert!(tilted, "cross normals should be tilted in tangent space");
}

#[test]
fn normal_maps_round_trip_as_format_1_1_and_without_are_1_0() {
    let s = parallel_leaves();
    let a = bake_with_normals(&s);
    let bytes = a.to_bytes().unwrap();
    assert_eq!(&bytes[8..12], &[1, 0, 1, 0], "format 1.1");
    let back = CloudAsset::from_bytes(&bytes).unwrap();
    assert_eq!(back, a);
    for at in &a.atlases {
        let n = at.normals.as_ref().unwrap();
        assert_eq!(n.len(), at.mips.len(), "one normal level per colour level");
    }
    let mut plain = a.clone();
    plain.atlases.iter_mut().for_each(|x| x.normals = None);
    assert_eq!(
        &plain.to_bytes().unwrap()[8..12],
        &[1, 0, 0, 0],
        "format 1.0"
    );
}

#[test]
fn gltf_export_carries_normal_textures_and_tangents() {
    let a = bake_with_normals(&parallel_leaves());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("n.glb");
    write_cloud_glb(&a, &path, &GltfOptions::default()).unwrap();
    let (doc, buffers, images) = gltf::import(&path).expect("strict glTF import");
    assert!(doc.extensions_used().all(|e| e != "KHR_materials_unlit"));
    let mut prims = 0;
    for mesh in doc
        .meshes()
        .filter(|m| m.name().unwrap_or("").starts_with("lod"))
    {
        for p in mesh.primitives() {
            let m = p.material();
            assert!(!m.unlit(), "a normal-mapped billboard is lit");
            let nt = m.normal_texture().expect("normalTexture");
            let img = &images[nt.texture().source().index()];
            assert_eq!(img.format, gltf::image::Format::R8G8B8);
            let r = p.reader(|b| Some(&buffers[b.index()]));
            let nrm: Vec<[f32; 3]> = r.read_normals().unwrap().collect();
            let tan: Vec<[f32; 4]> = r.read_tangents().expect("TANGENT").collect();
            let back = m.name().unwrap().ends_with("/back");
            for (n, t) in nrm.iter().zip(&tan) {
                let (n, tv) = (Vec3::from(*n), Vec3::new(t[0], t[1], t[2]));
                assert!(n.dot(tv).abs() < 1e-5 && (tv.length() - 1.0).abs() < 1e-5);
                assert_eq!(t[3], if back { 1.0 } else { -1.0 });
            }
            prims += 1;
        }
    }
    assert!(prims >= 4);
    // The exported normal image is the asset's level 0 (RGB).
    let at = &a.atlases[0];
    let n0 = &at.normals.as_ref().unwrap()[0];
    let found = images.iter().any(|img| {
        img.format == gltf::image::Format::R8G8B8
            && img.width == at.width
            && img
                .pixels
                .chunks_exact(3)
                .zip(n0.chunks_exact(4))
                .all(|(p, q)| p == &q[..3])
    });
    assert!(found, "no exported image equals atlas 0's normal map");
    // Bitangent cross(N, T)·w is −V on both sides of a billboard.
    let b = &a.billboards[0];
    let n = Vec3::from_slice(&b.plane);
    let c = b.corners.map(Vec3::from);
    let (u, v) = ((c[1] - c[0]).normalize(), (c[3] - c[0]).normalize());
    assert!((n.cross(u) * -1.0 + v).length() < 1e-5);
    assert!(((-n).cross(u) * 1.0 + v).length() < 1e-5);
}
