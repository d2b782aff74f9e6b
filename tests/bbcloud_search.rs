//! Algorithm 1 (plane search) properties and whole-bake determinism.

use billow::bbcloud::plane_search::{search, Element, SearchParams};
use billow::bbcloud::{bake, BbcloudOptions};
use billow::rng::Pcg32;
use billow::scene::{Aabb, AlphaMode, Material, Scene, Triangle, Vertex};
use billow_format::CloudAsset;
use glam::{Vec2, Vec3, Vec4};

fn params(eps: f32, samples: u32, seed: u64) -> SearchParams {
    SearchParams {
        epsilon: eps,
        samples,
        seed,
        stream: 0,
        max_extent: None,
    }
}

/// `n` triangles of size ~`size` scattered in a disc of radius 1 of the plane through
/// `origin` spanned by `a`, `b`, each vertex moved by up to `jitter` along the normal.
fn group(
    rng: &mut Pcg32,
    n: usize,
    origin: Vec3,
    a: Vec3,
    b: Vec3,
    size: f32,
    jitter: f32,
) -> Vec<Element> {
    let nrm = a.cross(b).normalize();
    (0..n)
        .map(|_| {
            let c = Vec2::new(rng.range_f32(-0.7, 0.7), rng.range_f32(-0.7, 0.7));
            let v = [(0.0, 0.0), (1.0, 0.1), (0.3, 0.9)].map(|(x, y)| {
                let p = c + size * Vec2::new(x, y);
                origin + a * p.x + b * p.y + nrm * rng.range_f32(-jitter, jitter)
            });
            Element::triangle(v[0], v[1], v[2])
        })
        .collect()
}

fn check_partition(n: usize, found: &[billow::bbcloud::Found]) {
    let mut seen = vec![0u32; n];
    for f in found {
        for &m in &f.members {
            seen[m as usize] += 1;
        }
        assert!(f.plane.normal.is_finite() && f.plane.offset.is_finite());
        assert!((f.plane.normal.length() - 1.0).abs() < 1e-5);
    }
    assert!(
        seen.iter().all(|&c| c == 1),
        "every element on exactly one billboard: {seen:?}"
    );
}

fn check_slab(elems: &[Element], found: &[billow::bbcloud::Found], eps: f32) {
    for f in found {
        for &m in &f.members {
            let e = &elems[m as usize];
            for v in &e.verts[..e.count] {
                let d = f.plane.distance(*v).abs();
                assert!(
                    d <= eps * (1.0 + 1e-4) + 1e-6,
                    "vertex {d} from its billboard, eps {eps}"
                );
            }
        }
    }
}

#[test]
fn coplanar_groups_land_on_one_billboard_and_far_ones_never() {
    let eps = 0.02;
    for seed in 0..5u64 {
        let mut rng = Pcg32::seeded(100 + seed, 0);
        let mut elems = group(&mut rng, 40, Vec3::ZERO, Vec3::X, Vec3::Z, 0.6, 0.2 * eps);
        // Parallel, 2.5 ε away: no plane is within ε of both.
        elems.extend(group(
            &mut rng,
            40,
            Vec3::Y * 2.5 * eps,
            Vec3::X,
            Vec3::Z,
            0.6,
            0.2 * eps,
        ));
        // A vertical group elsewhere.
        elems.extend(group(
            &mut rng,
            40,
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::Y,
            Vec3::Z,
            0.6,
            0.2 * eps,
        ));
        let (found, stats) = search(&elems, &params(eps, 500, seed), &|_, _| {});
        check_partition(elems.len(), &found);
        check_slab(&elems, &found, eps);
        for g in 0..3 {
            let holders: Vec<usize> = (0..found.len())
                .filter(|&i| found[i].members.iter().any(|&m| m as usize / 40 == g))
                .collect();
            assert_eq!(
                holders.len(),
                1,
                "seed {seed}: group {g} split over {holders:?}"
            );
        }
        for f in &found {
            let a = f.members.iter().any(|&m| m < 40);
            let b = f.members.iter().any(|&m| (40..80).contains(&m));
            assert!(!(a && b), "groups 2.5 ε apart share a billboard");
        }
        assert_eq!(stats.degenerate_redraws + stats.fallback_planes, 0);
    }
}

#[test]
fn random_soup_is_partitioned_within_the_slab() {
    let mut rng = Pcg32::seeded(7, 1);
    let elems: Vec<Element> = (0..600)
        .map(|_| {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0;
            let r = || {
                Vec3::new(
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                    rng.next_f32() - 0.5,
                ) * 0.2
            };
            let mut r = r;
            Element::triangle(c, c + r(), c + r())
        })
        .collect();
    for eps in [0.01, 0.05, 0.2] {
        let (found, _) = search(&elems, &params(eps, 50, 3), &|_, _| {});
        check_partition(elems.len(), &found);
        check_slab(&elems, &found, eps);
    }
}

#[test]
fn degenerate_seeds_never_give_nan_planes() {
    let mut rng = Pcg32::seeded(9, 0);
    let p = Vec3::new(0.3, 0.2, 0.1);
    let mut elems = vec![
        Element::triangle(p, p, p),                            // a point
        Element::triangle(Vec3::ZERO, Vec3::X, Vec3::X * 2.0), // collinear
        Element::triangle(Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1e-9, 0.0)), // near-collinear
        Element::triangle(Vec3::ZERO, Vec3::new(1e-30, 0.0, 0.0), Vec3::Y * 1e-30), // tiny
    ];
    for _ in 0..20 {
        let a = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        elems.push(Element::triangle(a, a + Vec3::X * 1e-3, a + Vec3::X * 2e-3));
        // collinear
    }
    elems.extend(group(&mut rng, 10, Vec3::ZERO, Vec3::X, Vec3::Y, 0.3, 0.0));
    let (found, stats) = search(&elems, &params(0.01, 64, 1), &|_, _| {});
    check_partition(elems.len(), &found);
    assert!(stats.degenerate_redraws > 0, "{stats:?}");
    // Only degenerate elements: every plane is a fallback, none is NaN.
    let only: Vec<Element> = elems[..24].to_vec();
    let (found, stats) = search(&only, &params(0.01, 16, 2), &|_, _| {});
    check_partition(only.len(), &found);
    assert!(
        stats.fallback_planes > 0 && stats.skipped_candidates > 0,
        "{stats:?}"
    );
}

/// Leaf cards (MASK) scattered in a sphere plus a few opaque trunk triangles.
pub fn leafy_scene(leaves: usize) -> Scene {
    let mut rng = Pcg32::seeded(42, 7);
    let vtx = |p: Vec3, n: Vec3, uv: Vec2| Vertex {
        position: p,
        normal: n,
        uv,
        color: Vec4::ONE,
    };
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
        texture_report: vec![],
        warnings: vec![],
        dropped_triangles: 0,
        bounds,
    }
}

fn small_opts(seed: u64) -> BbcloudOptions {
    BbcloudOptions {
        samples: 60,
        seed,
        lods: 3,
        atlas_size: 256,
        supersample: 2,
        epsilon: 0.08,
        ..BbcloudOptions::default()
    }
}

fn bake_bytes(scene: &Scene, opts: &BbcloudOptions, threads: usize) -> Vec<u8> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let (asset, _) = bake(scene, opts, "billow test", None, &|_, _| {}).unwrap();
        asset.to_bytes().unwrap()
    })
}

#[test]
fn same_seed_same_bytes_for_1_and_2_threads_and_other_seed_differs() {
    let scene = leafy_scene(150);
    let a = bake_bytes(&scene, &small_opts(5), 1);
    let b = bake_bytes(&scene, &small_opts(5), 2);
    assert!(a == b, "1 and 2 threads gave different assets");
    let c = bake_bytes(&scene, &small_opts(6), 2);
    assert_ne!(a, c, "a different seed gave the same cloud");
    for bytes in [&a, &c] {
        let asset = CloudAsset::from_bytes(bytes).expect("valid cloud");
        assert_eq!(asset.levels.len(), 3);
        assert_eq!(asset.levels[2].billboard_count, 2, "last LOD is the cross");
        assert_eq!(asset.foliage.triangles.len(), 300);
        assert_eq!(asset.trunk.triangles.len(), 6);
        // Every foliage triangle is on exactly one level-0 billboard, and the counts agree.
        let mut per = vec![0u32; asset.levels[0].billboard_count as usize];
        asset
            .foliage
            .billboard
            .iter()
            .for_each(|&b| per[b as usize] += 1);
        for (i, &n) in per.iter().enumerate() {
            assert_eq!(n, asset.billboards[i].elements);
        }
    }
}

/// Three groups as in the first test: `n` coplanar triangles each, two parallel 2.5 ε apart
/// and one perpendicular, far away.
fn three_groups(seed: u64, n: usize, eps: f32) -> Vec<Element> {
    let mut rng = Pcg32::seeded(100 + seed, 0);
    let mut elems = group(&mut rng, n, Vec3::ZERO, Vec3::X, Vec3::Z, 0.6, 0.2 * eps);
    elems.extend(group(
        &mut rng,
        n,
        Vec3::Y * 2.5 * eps,
        Vec3::X,
        Vec3::Z,
        0.6,
        0.2 * eps,
    ));
    elems.extend(group(
        &mut rng,
        n,
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::Y,
        Vec3::Z,
        0.6,
        0.2 * eps,
    ));
    elems
}

/// Which elements share a billboard, as sorted sets of `ids[member]`.
fn partition(found: &[billow::bbcloud::Found], ids: &[usize]) -> Vec<Vec<usize>> {
    let mut p: Vec<Vec<usize>> = found
        .iter()
        .map(|f| {
            let mut s: Vec<usize> = f.members.iter().map(|&m| ids[m as usize]).collect();
            s.sort_unstable();
            s
        })
        .collect();
    p.sort();
    p
}

/// "Removing one triangle's leaves changes nothing else for the same seed." The search is
/// global and random (one PCG32 stream drawing among the remaining elements), so removing
/// a leaf triangle shifts every later draw and the planes are not bit-identical; what
/// must not change is the cloud's structure elsewhere: which triangles share a billboard.
/// Removing any one triangle of a group leaves every billboard of the other groups with
/// exactly the same members, and its own group on one billboard minus that triangle.
#[test]
fn removing_one_leaf_changes_nothing_else() {
    let eps = 0.02;
    for seed in 0..3u64 {
        let elems = three_groups(seed, 30, eps);
        let all: Vec<usize> = (0..elems.len()).collect();
        let (found, _) = search(&elems, &params(eps, 300, seed), &|_, _| {});
        let before = partition(&found, &all);
        for removed in [0usize, 31, 89] {
            let ids: Vec<usize> = all.iter().copied().filter(|&i| i != removed).collect();
            let fewer: Vec<Element> = ids.iter().map(|&i| elems[i]).collect();
            let (f2, _) = search(&fewer, &params(eps, 300, seed), &|_, _| {});
            check_partition(fewer.len(), &f2);
            check_slab(&fewer, &f2, eps);
            let expect: Vec<Vec<usize>> = {
                let mut e: Vec<Vec<usize>> = before
                    .iter()
                    .map(|s| s.iter().copied().filter(|&i| i != removed).collect())
                    .filter(|s: &Vec<usize>| !s.is_empty())
                    .collect();
                e.sort();
                e
            };
            assert_eq!(
                partition(&f2, &ids),
                expect,
                "seed {seed}, removed {removed}"
            );
        }
    }
}

/// §5's extent limit: every billboard's members lie within `r` of one seed centroid, so
/// any two of their vertices are at most 2r apart; the cloud is still a partition within
/// the slab, and a limit smaller than a group splits it.
#[test]
fn extent_limit_bounds_billboards() {
    let eps = 0.02;
    let elems = three_groups(1, 40, eps);
    let (free, _) = search(&elems, &params(eps, 300, 1), &|_, _| {});
    let r = 0.8;
    let p = SearchParams {
        max_extent: Some(r),
        ..params(eps, 300, 1)
    };
    let (lim, stats) = search(&elems, &p, &|_, _| {});
    check_partition(elems.len(), &lim);
    check_slab(&elems, &lim, eps);
    for f in &lim {
        let pts: Vec<Vec3> = f
            .members
            .iter()
            .flat_map(|&m| elems[m as usize].verts[..3].to_vec())
            .collect();
        for a in &pts {
            for b in &pts {
                assert!(a.distance(*b) <= 2.0 * r + 1e-5, "billboard wider than 2r");
            }
        }
    }
    assert!(
        lim.len() > free.len(),
        "groups of extent ~1.3 must split under r = {r}: {} vs {} ({stats:?})",
        lim.len(),
        free.len()
    );
}
