//! Bake options: Lacewell §5's view preference, the up axis of the final cross, foliage by
//! material name, and BLEND foliage.

mod bbcloud_common;

use bbcloud_common::{leafy_scene, oak, oak_leaves, scene_of, vtx};
use billow::bbcloud::foliage::classify;
use billow::bbcloud::lod::cross_normals;
use billow::bbcloud::plane_search::{search, Found, SearchParams};
use billow::bbcloud::{bake, BbcloudOptions, Shading, ViewDirs, ViewPreference};
use billow::scene::{AlphaMode, Material, Triangle};
use glam::{Vec2, Vec3, Vec4};

/// Area-weighted mean of `|n · axis|` over the billboards: 1 if all face along `axis`.
fn mean_facing(found: &[Found], axis: Vec3) -> f64 {
    let (num, den) = found.iter().fold((0.0, 0.0), |(n, d), f| {
        let a = f64::from(f.area);
        (n + a * f64::from(f.plane.normal.dot(axis).abs()), d + a)
    });
    num / den
}

/// With the paper's parameters on the oak, preferring horizontal views (a walker's) makes
/// the billboards more vertical; preferring a view along +Z turns them towards ±Z.
#[test]
fn view_preference_turns_billboards_towards_the_views() {
    let (leaves, r) = oak_leaves();
    let base = SearchParams {
        epsilon: 0.04 * r,
        samples: 200,
        seed: 4,
        ..SearchParams::default()
    };
    let with = |dirs: ViewDirs| SearchParams {
        view: Some(ViewPreference {
            dirs,
            strength: 1.0,
        }),
        ..base.clone()
    };
    let (free, _) = search(&leaves, &base, &|_, _| {});
    let (horiz, _) = search(
        &leaves,
        &with(ViewDirs::Horizontal { up: Vec3::Y }),
        &|_, _| {},
    );
    let (front, _) = search(
        &leaves,
        &with(ViewDirs::Directions(vec![Vec3::Z])),
        &|_, _| {},
    );
    let (fy, hy) = (mean_facing(&free, Vec3::Y), mean_facing(&horiz, Vec3::Y));
    // Area on near-horizontal billboards (|n·y| > 0.8: seen edge-on from the side).
    let flat = |f: &[Found]| {
        let a: f64 = f.iter().map(|x| f64::from(x.area)).sum();
        f.iter()
            .filter(|x| x.plane.normal.y.abs() > 0.8)
            .map(|x| f64::from(x.area))
            .sum::<f64>()
            / a
    };
    println!(
        "area on near-horizontal billboards: free {:.3}, horizontal views {:.3}",
        flat(&free),
        flat(&horiz)
    );
    let (fz, zz) = (mean_facing(&free, Vec3::Z), mean_facing(&front, Vec3::Z));
    println!(
        "mean |n·y|: free {fy:.3}, horizontal views {hy:.3}; mean |n·z|: free {fz:.3}, +z view {zz:.3}; billboards {} / {} / {}",
        free.len(),
        horiz.len(),
        front.len()
    );
    // Measured: 0.486 → 0.403 mean |n·y|, and the area on near-horizontal billboards (edge-on
    // to every expected view) 16.6 % → 2.1 %.
    assert!(
        hy < 0.9 * fy,
        "horizontal views: |n·y| {hy:.3} vs {fy:.3} without"
    );
    assert!(
        flat(&horiz) < 0.3 * flat(&free),
        "near-horizontal area {:.3} vs {:.3}",
        flat(&horiz),
        flat(&free)
    );
    assert!(zz > 1.3 * fz, "+z view: |n·z| {zz:.3} vs {fz:.3} without");
    // Still Algorithm 1's partition: every leaf on exactly one billboard.
    for cloud in [&horiz, &front] {
        let n: usize = cloud.iter().map(|f| f.members.len()).sum();
        assert_eq!(n, leaves.len());
    }
}

/// The whole bake passes the preference to every searched level and records it.
#[test]
fn bake_records_the_view_preference() {
    let scene = leafy_scene(120);
    let opts = |view| BbcloudOptions {
        samples: 60,
        lods: 2,
        atlas_size: 256,
        supersample: 1,
        epsilon: 0.1,
        view,
        ..BbcloudOptions::default()
    };
    let pref = ViewPreference {
        dirs: ViewDirs::Horizontal { up: Vec3::Y },
        strength: 1.0,
    };
    let (a, _) = bake(&scene, &opts(Some(pref)), "t", None, &|_, _| {}).unwrap();
    let (b, _) = bake(&scene, &opts(None), "t", None, &|_, _| {}).unwrap();
    let p = &a.header.params;
    assert_eq!(p["view_dirs"], "horizontal(up 0,1,0)");
    assert_eq!(p["view_strength"], "1");
    assert!(!b.header.params.contains_key("view_dirs"));
    assert_ne!(
        a.billboards[0].plane, b.billboards[0].plane,
        "the preference reaches the search"
    );
    // An invalid preference is a parameter error.
    let bad = ViewPreference {
        dirs: ViewDirs::Directions(vec![]),
        strength: 1.0,
    };
    assert!(bake(&scene, &opts(Some(bad)), "t", None, &|_, _| {}).is_err());
}

#[test]
fn cross_normals_are_perpendicular_to_up_and_each_other() {
    for up in [
        Vec3::X,
        -Vec3::X,
        Vec3::Y,
        -Vec3::Y,
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(0.3, 0.9, -0.2).normalize(),
    ] {
        let [a, b] = cross_normals(up);
        for n in [a, b] {
            assert!(
                (n.length() - 1.0).abs() < 1e-6 && n.dot(up).abs() < 1e-6,
                "{up}"
            );
        }
        assert!(a.dot(b).abs() < 1e-6, "{up}");
    }
    // +Y (glTF) keeps the historical +X and +Z.
    assert_eq!(cross_normals(Vec3::Y), [Vec3::X, Vec3::Z]);
}

/// The last level's two billboards contain the up axis through the foliage centre: for
/// +Z up their normals are horizontal in the XY plane, not in XZ as for +Y.
#[test]
fn up_axis_orients_the_final_cross() {
    let scene = leafy_scene(100);
    for up in [Vec3::Y, Vec3::Z, -Vec3::X] {
        let opts = BbcloudOptions {
            samples: 30,
            lods: 2,
            atlas_size: 256,
            supersample: 1,
            epsilon: 0.1,
            up,
            ..BbcloudOptions::default()
        };
        let (a, _) = bake(&scene, &opts, "t", None, &|_, _| {}).unwrap();
        let last = a.levels[1];
        assert_eq!(last.billboard_count, 2);
        let cross = &a.billboards[last.first_billboard as usize..];
        let n: Vec<Vec3> = cross.iter().map(|b| Vec3::from_slice(&b.plane)).collect();
        assert!(n[0].dot(n[1]).abs() < 1e-6);
        // The foliage's bounding-sphere centre (centre of its vertices' box) is on both.
        let leaf_pts = scene
            .triangles
            .iter()
            .filter(|t| t.material == 1)
            .flat_map(|t| t.v.iter().map(|v| v.position));
        let (lo, hi) = leaf_pts.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
            (a.min(p), b.max(p))
        });
        let centre = 0.5 * (lo + hi);
        for b in cross {
            let nb = Vec3::from_slice(&b.plane);
            assert!(nb.dot(up).abs() < 1e-6, "{up}: normal {nb} not horizontal");
            assert!(
                (nb.dot(centre) - b.plane[3]).abs() < 1e-5,
                "{up}: off centre"
            );
        }
        let u = &a.header.params["up"];
        assert_eq!(u, &format!("{},{},{}", up.x, up.y, up.z));
    }
}

fn quad(c: Vec3, a: Vec3, b: Vec3, material: u32) -> [Triangle; 2] {
    let n = a.cross(b).normalize();
    let q = [c, c + a, c + a + b, c + b];
    let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
    [[0, 1, 2], [0, 2, 3]].map(|t| Triangle {
        v: t.map(|k| vtx(q[k], n, uv[k])),
        material,
        mesh: 0,
    })
}

/// Opaque "bark", MASK "leaves", BLEND "veil" (base colour alpha 0.5).
fn three_materials() -> billow::scene::Scene {
    let mut tris = Vec::new();
    for k in 0..4 {
        let c = Vec3::new(k as f32, 0.0, 0.0);
        tris.extend(quad(c, Vec3::X * 0.8, Vec3::Y * 0.8, 0));
        tris.extend(quad(c + Vec3::Z, Vec3::X * 0.8, Vec3::Y * 0.8, 1));
        tris.extend(quad(c + Vec3::Z * 2.0, Vec3::X * 0.8, Vec3::Y * 0.8, 2));
    }
    let m = |name: &str, alpha_mode, a: f32| Material {
        name: name.into(),
        base_color_factor: Vec4::new(0.2, 0.6, 0.1, a),
        alpha_mode,
        double_sided: true,
        ..Material::default()
    };
    scene_of(
        tris,
        vec![
            m("bark", AlphaMode::Opaque, 1.0),
            m("leaves", AlphaMode::Mask { cutoff: 0.5 }, 1.0),
            m("veil", AlphaMode::Blend, 0.5),
        ],
    )
}

#[test]
fn foliage_by_alpha_mode_or_by_name() {
    let s = three_materials();
    let by = |names: &[&str]| -> Vec<u32> {
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        let f = classify(&s, &names).unwrap();
        let mut per = vec![0u32; 3];
        for (t, _) in s.triangles.iter().zip(&f).filter(|(_, &f)| f) {
            per[t.material as usize] += 1;
        }
        per
    };
    assert_eq!(by(&[]), [0, 8, 8], "MASK and BLEND are foliage by default");
    assert_eq!(
        by(&["bark"]),
        [8, 0, 0],
        "a name selects exactly that material"
    );
    assert_eq!(by(&["veil", "bark"]), [8, 0, 8]);
    assert!(classify(&s, &["nope".to_string()]).is_err());
    // The bake follows: bark as foliage, leaves and veil kept as the mesh.
    let opts = BbcloudOptions {
        samples: 30,
        lods: 1,
        atlas_size: 256,
        supersample: 1,
        foliage: vec!["bark".into()],
        ..BbcloudOptions::default()
    };
    let (a, stats) = bake(&s, &opts, "t", None, &|_, _| {}).unwrap();
    assert_eq!((stats.foliage_triangles, stats.kept_triangles), (8, 16));
    assert!(a.foliage.materials.iter().all(|&m| m == 0));
    assert!(a.trunk.materials.iter().all(|&m| m != 0));
    assert_eq!(a.header.params["foliage"], "bark");
}

/// BLEND foliage keeps its alpha: the veil's billboard is half covered where the veil is,
/// its colour premultiplied by that alpha (sRGB-encoded premultiplied bytes).
#[test]
fn blend_foliage_bakes_its_alpha() {
    let s = three_materials();
    let opts = BbcloudOptions {
        samples: 50,
        lods: 1,
        atlas_size: 256,
        supersample: 2,
        texel_density: Some(16.0),
        foliage: vec!["veil".into()],
        shading: Shading {
            light: None,
            ambient: 1.0,
        },
        ..BbcloudOptions::default()
    };
    let (a, _) = bake(&s, &opts, "t", None, &|_, _| {}).unwrap();
    assert_eq!(
        a.levels[0].billboard_count, 1,
        "the veil quads are coplanar"
    );
    let b = &a.billboards[0];
    let at = &a.atlases[b.front.atlas as usize];
    let [u0, v0, u1, v1] = b.front.uv;
    let (x0, y0) = (
        (u0 * at.width as f32) as u32,
        (v0 * at.height as f32) as u32,
    );
    let (x1, y1) = (
        (u1 * at.width as f32) as u32,
        (v1 * at.height as f32) as u32,
    );
    let lut = billow::texture::srgb_to_linear_lut();
    let mut alphas = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let p = &at.mips[0][4 * (y * at.width + x) as usize..][..4];
            alphas.push(p[3]);
            if p[3] == 128 {
                // Premultiplied: green = 0.6 · 0.5 in linear.
                assert!((lut[p[1] as usize] - 0.3).abs() < 0.01, "{p:?}");
            }
        }
    }
    let half = alphas.iter().filter(|&&a| a == 128).count();
    let full = alphas.iter().filter(|&&a| a > 200).count();
    assert!(
        half > alphas.len() / 2,
        "{half} of {} texels at alpha 0.5",
        alphas.len()
    );
    assert_eq!(full, 0, "BLEND alpha is not turned into coverage 1");
    // The same material as MASK would be cut away entirely (alpha 0.5 < cutoff 0.5 is
    // false, so MASK keeps it at alpha 1): a different result, so the check can fail.
    let mut masked = s.clone();
    masked.materials[2].alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let (m, _) = bake(&masked, &opts, "t", None, &|_, _| {}).unwrap();
    assert_ne!(m.atlases[0].mips[0], a.atlases[0].mips[0]);
}

/// The oak's bark selected by name goes into the cloud; its leaves stay a mesh.
#[test]
fn oak_bark_by_name() {
    let scene = oak();
    let opts = BbcloudOptions {
        samples: 20,
        lods: 1,
        atlas_size: 256,
        supersample: 1,
        foliage: vec!["bark".into()],
        ..BbcloudOptions::default()
    };
    let (a, stats) = bake(&scene, &opts, "t", None, &|_, _| {}).unwrap();
    assert_eq!(
        (stats.foliage_triangles, stats.kept_triangles),
        (3166, 10_640)
    );
    assert_eq!(a.foliage.triangles.len(), 3166);
    assert_eq!(a.trunk.triangles.len(), 10_640);
}

/// The limits `billow bbcloud --help` prints are the ones the library refuses by: each
/// option is accepted at its limit and refused just past it, naming itself.
#[test]
fn options_are_refused_exactly_past_their_published_limits() {
    use billow::bbcloud::{
        check_ambient, check_view_strength, estimate, BbcloudError, LARGEST_MAX_EXTENT,
        MAX_ATLAS_SIZE, MAX_EPSILON, MAX_GUTTER, MAX_LODS, MAX_MIP_LEVELS, MAX_SAMPLES,
        MAX_SUPERSAMPLE, MAX_VIEW_DIRS, MIN_ATLAS_SIZE, UNIT_RANGE,
    };
    let scene = leafy_scene(20);
    let refused = |o: &BbcloudOptions| match estimate(&scene, o) {
        Err(BbcloudError::BadParameter { option, .. }) => Some(option),
        Ok(_) => None,
        Err(e) => panic!("{e}"),
    };
    let d = BbcloudOptions::default;
    let next_up = |x: f32| f32::from_bits(x.to_bits() + 1);
    let view = |n: usize, strength: f32| {
        Some(ViewPreference {
            dirs: ViewDirs::Directions(vec![Vec3::Z; n]),
            strength,
        })
    };
    let shading = |ambient: f32| Shading {
        light: None,
        ambient,
    };
    #[rustfmt::skip]
    let cases: Vec<(&str, BbcloudOptions, BbcloudOptions)> = vec![
        ("epsilon", BbcloudOptions { epsilon: MAX_EPSILON, ..d() },
            BbcloudOptions { epsilon: next_up(MAX_EPSILON), ..d() }),
        ("samples", BbcloudOptions { samples: MAX_SAMPLES, ..d() },
            BbcloudOptions { samples: MAX_SAMPLES + 1, ..d() }),
        ("lods", BbcloudOptions { lods: MAX_LODS, ..d() },
            BbcloudOptions { lods: MAX_LODS + 1, ..d() }),
        ("atlas_size", BbcloudOptions { atlas_size: MIN_ATLAS_SIZE, ..d() },
            BbcloudOptions { atlas_size: MIN_ATLAS_SIZE / 2, ..d() }),
        ("atlas_size", BbcloudOptions { atlas_size: MAX_ATLAS_SIZE, ..d() },
            BbcloudOptions { atlas_size: MAX_ATLAS_SIZE * 2, ..d() }),
        ("max_extent", BbcloudOptions { max_extent: Some(LARGEST_MAX_EXTENT), ..d() },
            BbcloudOptions { max_extent: Some(next_up(LARGEST_MAX_EXTENT)), ..d() }),
        ("supersample", BbcloudOptions { supersample: MAX_SUPERSAMPLE, ..d() },
            BbcloudOptions { supersample: MAX_SUPERSAMPLE + 1, ..d() }),
        ("gutter", BbcloudOptions { gutter: MAX_GUTTER, ..d() },
            BbcloudOptions { gutter: MAX_GUTTER + 1, ..d() }),
        ("mip_levels", BbcloudOptions { mip_levels: MAX_MIP_LEVELS, ..d() },
            BbcloudOptions { mip_levels: MAX_MIP_LEVELS + 1, ..d() }),
        ("ambient", BbcloudOptions { shading: shading(*UNIT_RANGE.end()), ..d() },
            BbcloudOptions { shading: shading(next_up(*UNIT_RANGE.end())), ..d() }),
        ("view_strength", BbcloudOptions { view: view(1, *UNIT_RANGE.end()), ..d() },
            BbcloudOptions { view: view(1, next_up(*UNIT_RANGE.end())), ..d() }),
        ("view", BbcloudOptions { view: view(MAX_VIEW_DIRS, 1.0), ..d() },
            BbcloudOptions { view: view(MAX_VIEW_DIRS + 1, 1.0), ..d() }),
    ];
    for (option, at, past) in &cases {
        assert_eq!(refused(at), None, "{option} at its limit");
        assert_eq!(refused(past), Some(*option), "{option} past its limit");
    }
    assert!(check_ambient(*UNIT_RANGE.start()).is_ok());
    assert!(check_ambient(-f32::MIN_POSITIVE).is_err());
    assert!(check_view_strength(*UNIT_RANGE.start()).is_ok());
    assert!(check_view_strength(f32::NAN).is_err());
}
