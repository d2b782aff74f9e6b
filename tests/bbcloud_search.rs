//! Algorithm 1 (plane search) properties, the accelerated scan against the plain one, and
//! whole-bake determinism.

mod bbcloud_common;

use bbcloud_common::{leafy_scene, oak_leaves};
use billow::bbcloud::plane_search::{search, SearchParams};
use billow::bbcloud::Element;
use billow::bbcloud::{bake, BbcloudOptions};
use billow::rng::Pcg32;
use billow::scene::Scene;
use billow_format::CloudAsset;
use glam::{Vec2, Vec3};

fn params(eps: f32, samples: u32, seed: u64) -> SearchParams {
    SearchParams {
        epsilon: eps,
        samples,
        seed,
        ..SearchParams::default()
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
        assert_eq!(stats.degenerate_seeds + stats.fallback_planes, 0);
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
    // All 24 degenerate elements are skipped as seeds (counted), never drawn.
    assert_eq!(stats.degenerate_seeds, 24, "{stats:?}");
    for f in &found {
        assert!(
            f.seed >= 24 || stats.fallback_planes > 0,
            "degenerate seed {f:?}"
        );
    }
    // Only degenerate elements: every plane is a fallback, none is NaN.
    let only: Vec<Element> = elems[..24].to_vec();
    let (found, stats) = search(&only, &params(0.01, 16, 2), &|_, _| {});
    check_partition(only.len(), &found);
    assert_eq!(stats.candidates, 0, "{stats:?}");
    assert_eq!(stats.fallback_planes as usize, found.len(), "{stats:?}");
    assert!(
        found.len() < only.len(),
        "fallback planes absorb coplanar degenerates"
    );
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

/// The acceleration structure (runs of elements culled by their boxes) must give the same
/// cloud as the plain scan for the same seed: on the oak's leaves (level 0), on the quads of
/// that cloud (a LOD level), with the extent limit and with a view preference.
#[test]
fn accelerated_scan_gives_the_plain_scan_cloud() {
    let (leaves, r) = oak_leaves();
    assert_eq!(leaves.len(), 10_640);
    let run = |elems: &[Element], p: &SearchParams| {
        let fast = search(elems, p, &|_, _| {});
        let plain = search(
            elems,
            &SearchParams {
                accelerate: false,
                ..p.clone()
            },
            &|_, _| {},
        );
        assert!(fast == plain, "accelerated and plain scans differ");
        fast.0
    };
    let p0 = params(0.04 * r, 60, 11);
    let level0 = run(&leaves, &p0);
    check_partition(leaves.len(), &level0);
    check_slab(&leaves, &level0, 0.04 * r);
    // Quads: each billboard's members' bounding rectangle in its plane, as the LOD chain
    // feeds them (the rectangle itself does not matter here, only that they are quads).
    let quads: Vec<Element> = level0
        .iter()
        .map(|f| {
            let pts: Vec<Vec3> = f
                .members
                .iter()
                .flat_map(|&m| leaves[m as usize].verts[..3].to_vec())
                .collect();
            Element::quad(billow::bbcloud::rect::trim(&f.plane, &pts).corners())
        })
        .collect();
    let p1 = SearchParams {
        stream: 1,
        ..params(0.08 * r, 60, 11)
    };
    run(&quads, &p1);
    let limited = SearchParams {
        max_extent: Some(0.3 * r),
        ..params(0.04 * r, 40, 12)
    };
    let lim = run(&leaves, &limited);
    assert!(
        lim.len() > level0.len(),
        "the extent limit splits billboards"
    );
    let view = SearchParams {
        view: Some(billow::bbcloud::ViewPreference {
            dirs: billow::bbcloud::ViewDirs::Horizontal { up: Vec3::Y },
            strength: 0.7,
        }),
        ..params(0.04 * r, 40, 13)
    };
    run(&leaves, &view);
}
