//! Edge cases of `billow::emptyspace::prune`: empty, full, single-voxel, odd and non-cubic
//! volumes, normals travelling with their bricks, the threshold, shells and already pruned
//! assets refused — and, for every pruned asset, **exact sampling at every MIP level**:
//! each band samples, at every level it serves, what the source samples there, inside its
//! cells, and the source samples zero outside them.

use billow::emptyspace::occupancy::apply_threshold;
use billow::emptyspace::synthetic::{set_normal_field, volume_from_fn};
use billow::emptyspace::{prune, EmptySpaceError, EmptySpaceOptions};
use billow::eval::volume_sampler::DecodedVolume;
use billow_format::{mip_dims, ColourSpace, Prism, VolumeAsset};
use glam::{Mat3, Vec3};

fn roundtrip(a: &VolumeAsset) {
    let bytes = a.to_bytes().expect("valid asset");
    assert_eq!(VolumeAsset::from_bytes(&bytes).unwrap(), *a);
}

/// The affine map world → uvw of a prism (from vertices 0..=3).
fn uvw_map(c: &Prism) -> impl Fn(Vec3) -> Vec3 {
    let p = |i: usize| Vec3::from(c.pos[i]) - Vec3::from(c.pos[0]);
    let t = |i: usize| Vec3::from(c.uvw[i]) - Vec3::from(c.uvw[0]);
    let m = Mat3::from_cols(t(1), t(2), t(3)) * Mat3::from_cols(p(1), p(2), p(3)).inverse();
    let (p0, t0) = (Vec3::from(c.pos[0]), Vec3::from(c.uvw[0]));
    move |x| t0 + m * (x - p0)
}

/// A cell box: world corners and its world → uvw map.
type CellBox = (Vec3, Vec3, Box<dyn Fn(Vec3) -> Vec3>);

/// World boxes of a band's cells (two prisms per box) with their uvw maps.
fn boxes(cells: &[Prism]) -> Vec<CellBox> {
    cells
        .chunks(2)
        .map(|pair| {
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for c in pair {
                for p in &c.pos {
                    lo = lo.min(Vec3::from(*p));
                    hi = hi.max(Vec3::from(*p));
                }
            }
            let f: Box<dyn Fn(Vec3) -> Vec3> = Box::new(uvw_map(&pair[0]));
            (lo, hi, f)
        })
        .collect()
}

/// The check of the module docs, on colour. Returns the number of points compared.
fn samples_match(src: &VolumeAsset, pruned: &VolumeAsset) -> usize {
    let (s, p) = (
        DecodedVolume::decode(src).unwrap(),
        DecodedVolume::decode(pruned).unwrap(),
    );
    let d0 = src.level_dims(0).map(|v| v as f32);
    let levels = src.levels.len() as u32;
    // Bands: (first level, last level served, decoded texture, cells).
    let mut bands = vec![(0u32, &p, pruned.cells.as_slice())];
    bands.extend(
        p.bands
            .iter()
            .map(|b| (b.first_level, &b.volume, b.cells.as_slice())),
    );
    let mut checked = 0;
    for (i, &(first, vol, cells)) in bands.iter().enumerate() {
        let last = bands.get(i + 1).map_or(levels - 1, |b| b.0);
        let bx = boxes(cells);
        for l in first..=last {
            let lb = (l - first) as usize;
            assert!(lb < vol.level_count(), "band {i} lacks level {l}");
            // Inside: a jittered grid over each box, ~1.7 points per level-0 voxel.
            for (lo, hi, map) in &bx {
                let n = ((*hi - *lo) * Vec3::from(d0) * 1.7).ceil().max(Vec3::ONE);
                for z in 0..n.z as u32 {
                    for y in 0..n.y as u32 {
                        for x in 0..n.x as u32 {
                            let f = (Vec3::new(x as f32, y as f32, z as f32) + 0.37) / n;
                            let w = *lo + (*hi - *lo) * f;
                            let a = s.sample_level(l as usize, w);
                            let b = vol.sample_level(lb, map(w));
                            assert!(
                                (a - b).abs().max_element() < 1e-5,
                                "band {i} level {l} at {w}: source {a} vs pruned {b}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
            // Outside every box of the band the source samples exactly zero here.
            let n = (Vec3::from(d0) * 1.3).ceil();
            for z in 0..n.z as u32 {
                for y in 0..n.y as u32 {
                    for x in 0..n.x as u32 {
                        let w = (Vec3::new(x as f32, y as f32, z as f32) + 0.41) / n;
                        let inside = bx.iter().any(|(lo, hi, _)| {
                            (w - *lo).min_element() >= -1e-4 && (*hi - w).min_element() >= -1e-4
                        });
                        if !inside {
                            let a = s.sample_level(l as usize, w);
                            assert!(
                                a.max_element() == 0.0,
                                "band {i} level {l}: source {a} at {w} dropped"
                            );
                        }
                    }
                }
            }
        }
    }
    checked
}

/// The same volume with its normals in place of its colour (raw bytes read as unorm): the
/// colour check then checks that every normal texel lands where its colour texel does.
fn normals_as_colour(a: &VolumeAsset) -> VolumeAsset {
    let mut n = a.clone();
    n.header.colour_space = ColourSpace::LinearPremultiplied;
    n.levels = a.normals.clone().expect("normals");
    n.normals = None;
    n.header.volume.as_mut().unwrap().normals = None;
    for b in &mut n.bands {
        b.levels = b.normals.take().expect("band normals");
    }
    n
}

fn exact(src: &VolumeAsset, pruned: &VolumeAsset) {
    assert!(samples_match(src, pruned) > 0 || pruned.cells.is_empty());
    if src.normals.is_some() {
        samples_match(&normals_as_colour(src), &normals_as_colour(pruned));
    }
}

/// Two blobs, a bar and a diagonal line, with a normal field that differs in every texel.
fn sparse(dims: [u32; 3]) -> VolumeAsset {
    let [w, h, d] = dims;
    let mut a = volume_from_fn(dims, true, |x, y, z| {
        let near = |c: [u32; 3], r: u32| {
            x.abs_diff(c[0]) <= r && y.abs_diff(c[1]) <= r && z.abs_diff(c[2]) <= r
        };
        let bar = y == h / 2 && z == d / 2 && (w / 3..2 * w / 3).contains(&x);
        // A diagonal line across the volume: boxes must cut through it, so aprons carry
        // content there.
        let diag = y == x * h / w && z == x * d / w && (w / 6..5 * w / 6).contains(&x);
        if near([w / 5, h / 5, d / 5], 1) || near([w - 2, h - 2, d - 2], 0) || bar || diag {
            [
                (x * 5) as u8,
                (y * 3) as u8,
                (z * 7) as u8,
                120 + (x + y + z) as u8 % 100,
            ]
        } else {
            [0; 4]
        }
    });
    set_normal_field(&mut a, |x, y, z| {
        [
            (x * 7 % 200) as i8,
            ((y * 11 % 200) as i32 - 100) as i8,
            (z * 13 % 127) as i8,
        ]
    });
    a
}

#[test]
fn an_all_empty_volume_gives_a_valid_asset_with_zero_cells() {
    let src = volume_from_fn([16, 8, 12], true, |_, _, _| [0; 4]);
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    assert_eq!((p.stats.boxes, p.stats.cells), (0, 0));
    assert!(p.asset.cells.is_empty() && p.asset.bands.is_empty());
    assert_eq!(p.asset.level_dims(0), [1, 1, 1]);
    assert!(p.asset.header.pruned().is_some());
    assert!(p.stats.saving > 0.99);
    roundtrip(&p.asset);
}

#[test]
fn an_all_opaque_volume_is_one_box_kept_whole() {
    let src = volume_from_fn([16, 16, 16], false, |x, y, z| {
        [x as u8, y as u8, z as u8, 255]
    });
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    assert!(p.stats.kept_whole, "{:?}", p.stats);
    assert_eq!(p.stats.bands.len(), 1);
    assert_eq!(
        (p.asset.levels.clone(), p.asset.cells.clone()),
        (src.levels.clone(), src.cells.clone())
    );
    assert!(p.asset.bands.is_empty());
    assert_eq!(p.stats.saving, 0.0);
    roundtrip(&p.asset);
}

#[test]
fn a_single_voxel_becomes_small_bricks_exact_at_every_level() {
    let mut src = volume_from_fn([32, 32, 32], true, |x, y, z| {
        if (x, y, z) == (20, 9, 13) {
            [10, 20, 30, 200]
        } else {
            [0; 4]
        }
    });
    set_normal_field(&mut src, |_, _, _| [-90, 20, 90]);
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    let s = &p.stats;
    assert!(!s.kept_whole && s.saving > 0.9, "{s:?}");
    // Level 0 keeps the voxel's trilinear support, a few blocks, not the 32³ volume.
    assert!(s.voxels_kept <= 6 * 6 * 6 && s.voxels_kept >= 8, "{s:?}");
    assert!(
        p.asset.bands.len() >= 2,
        "coarse levels are bricked too: {s:?}"
    );
    exact(&src, &p.asset);
    roundtrip(&p.asset);
}

#[test]
fn odd_sizes_are_kept_whole_with_a_clear_note() {
    let src = sparse([37, 19, 23]);
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    assert!(p.stats.kept_whole && p.asset.bands.is_empty());
    let note = p.stats.note.as_deref().unwrap();
    assert!(
        note.contains("37x19x23") && note.contains("--align"),
        "{note}"
    );
    assert_eq!(p.asset.levels, src.levels);
}

#[test]
fn even_non_cubic_sizes_prune_for_real_and_sample_exactly_at_every_level() {
    for dims in [[64u32, 8, 36], [48, 32, 40], [12, 96, 8]] {
        let src = sparse(dims);
        let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
        let s = &p.stats;
        assert!(!s.kept_whole, "{dims:?}: {s:?}");
        println!(
            "{dims:?}: saving {:.3}, kept {} of {} voxels, {} boxes, {} bands",
            s.saving,
            s.voxels_kept,
            s.voxels_before,
            s.boxes,
            s.bands.len()
        );
        assert!(s.saving > 0.2, "{dims:?}: saving {:.3}", s.saving);
        assert!(
            s.voxels_kept * 3 < s.voxels_before,
            "{dims:?}: level 0 keeps {} of {} voxels",
            s.voxels_kept,
            s.voxels_before
        );
        assert!(s.atlas_dims.iter().all(|d| d % 2 == 0), "{s:?}");
        p.asset.validate().unwrap();
        exact(&src, &p.asset);
        roundtrip(&p.asset);
    }
}

/// The 4×4 block layout of a compressed prune (`bc_blocks`, `emptyspace --compress bc`):
/// just as exact at every level, every band's level-0 atlas in whole 4×4 blocks, and each
/// atlas block a copy of one source block — checked through the cells: every box's uvw
/// corner on the atlas's x/y sits on the same 4-texel phase as its world corner on the
/// source's (the box's inset in its slot is what carries the alignment).
#[test]
fn the_bc_block_layout_is_exact_and_keeps_4x4_blocks_whole() {
    for dims in [[48u32, 32, 40], [96, 48, 24], [64, 64, 32]] {
        let src = sparse(dims);
        let o = EmptySpaceOptions {
            bc_blocks: true,
            ..EmptySpaceOptions::default()
        };
        let p = prune(&src, &o).unwrap();
        let s = &p.stats;
        assert!(!s.kept_whole, "{dims:?}: {s:?}");
        assert!(
            p.asset.header.params["emptyspace"].contains("blocks=4x4"),
            "{:?}",
            p.asset.header.params
        );
        exact(&src, &p.asset);
        roundtrip(&p.asset);
        let bands = std::iter::once((p.asset.level_dims(0), &p.asset.cells, 0u32)).chain(
            p.asset
                .bands
                .iter()
                .filter(|b| b.levels.len() == 2)
                .map(|b| (b.dims, &b.cells, b.first_level)),
        );
        for (d, cells, k) in bands {
            assert!(
                d[0].is_multiple_of(4) && d[1].is_multiple_of(4),
                "{dims:?}: band {k} atlas {d:?}"
            );
            let n = mip_dims(dims, k);
            for c in cells {
                // Texel coordinates of the corners in the atlas and in the source level (the
                // source's cells map the unit cube onto the texture).
                let atlas: Vec<[i64; 3]> = (0..6)
                    .map(|v| [0, 1, 2].map(|a| (c.uvw[v][a] * d[a] as f32).round() as i64))
                    .collect();
                let source: Vec<[i64; 3]> = (0..6)
                    .map(|v| [0, 1, 2].map(|a| (c.pos[v][a] * n[a] as f32).round() as i64))
                    .collect();
                for a in 0..2 {
                    // The source axis atlas axis `a` holds (x and y may swap; z stays z):
                    // the one whose corner offsets it repeats.
                    let b = (0..2)
                        .find(|&b| {
                            (0..6).all(|v| atlas[v][a] - atlas[0][a] == source[v][b] - source[0][b])
                        })
                        .unwrap_or_else(|| panic!("{dims:?}: band {k}: no axis for {a}"));
                    for v in 0..6 {
                        assert_eq!(
                            atlas[v][a].rem_euclid(4),
                            source[v][b].rem_euclid(4),
                            "{dims:?}: band {k}, atlas axis {a} (source {b}): {atlas:?} {source:?}"
                        );
                    }
                }
                assert!((0..6).all(|v| atlas[v][2] - atlas[0][2] == source[v][2] - source[0][2]));
            }
        }
    }
}

#[test]
fn the_threshold_drops_faint_texels_and_nothing_else() {
    let src = volume_from_fn([32, 16, 24], true, |x, y, z| {
        let a = if x < 12 {
            200
        } else if (x + y + z) % 3 == 0 {
            20
        } else {
            0
        };
        [a / 2, a / 3, a / 4, a]
    });
    let o = EmptySpaceOptions {
        threshold: 40,
        ..Default::default()
    };
    let p = prune(&src, &o).unwrap();
    let plain = prune(&src, &EmptySpaceOptions::default()).unwrap();
    assert!(
        p.stats.saving > plain.stats.saving,
        "{:?} vs {:?}",
        p.stats,
        plain.stats
    );
    // Exactly the source with every texel of alpha ≤ 40 zeroed.
    let mut kept = src.clone();
    for l in 0..kept.levels.len() {
        apply_threshold(
            &mut kept.levels[l],
            kept.normals.as_mut().map(|n| n[l].as_mut_slice()),
            40,
        );
    }
    exact(&kept, &p.asset);
}

#[test]
fn max_tiers_limits_the_bricked_levels() {
    let src = sparse([48, 32, 40]);
    let whole = prune(
        &src,
        &EmptySpaceOptions {
            max_tiers: Some(0),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(whole.stats.kept_whole);
    let one = prune(
        &src,
        &EmptySpaceOptions {
            max_tiers: Some(1),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(one.stats.tail_level, 1);
    assert_eq!(one.asset.bands.len(), 1);
    exact(&src, &one.asset);
}

#[test]
fn shells_pruned_and_banded_assets_and_bad_parameters_are_refused() {
    let src = sparse([16, 16, 16]);
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    match prune(&p.asset, &EmptySpaceOptions::default()) {
        Err(EmptySpaceError::AlreadyPruned(s)) => assert!(s.contains("boxes=")),
        other => panic!("{other:?}"),
    }
    let mut unmarked = p.asset.clone();
    unmarked
        .header
        .params
        .remove(billow_format::param::EMPTYSPACE);
    if !unmarked.bands.is_empty() {
        assert_eq!(
            prune(&unmarked, &EmptySpaceOptions::default()),
            Err(EmptySpaceError::HasBands)
        );
    }
    let mut shell = src.clone();
    shell
        .header
        .params
        .insert("shell".into(), "height=0.1".into());
    assert_eq!(
        prune(&shell, &EmptySpaceOptions::default()),
        Err(EmptySpaceError::Shell)
    );
    let mut skew = src.clone();
    skew.cells[0].pos[1][0] += 0.25;
    assert!(matches!(
        prune(&skew, &EmptySpaceOptions::default()),
        Err(EmptySpaceError::NotABox(0))
    ));
    // The limits `billow emptyspace --help` prints: refused just past them, accepted at them.
    use billow::emptyspace::{MAX_DEPTH, MIN_CELL_COST, MIN_GAIN_RANGE};
    for bad in [
        EmptySpaceOptions {
            min_gain: MIN_GAIN_RANGE.end,
            ..Default::default()
        },
        EmptySpaceOptions {
            min_gain: -f64::EPSILON,
            ..Default::default()
        },
        EmptySpaceOptions {
            cell_cost: f64::NAN,
            ..Default::default()
        },
        EmptySpaceOptions {
            cell_cost: MIN_CELL_COST - 1e-9,
            ..Default::default()
        },
        EmptySpaceOptions {
            max_depth: MAX_DEPTH + 1,
            ..Default::default()
        },
    ] {
        assert!(
            matches!(prune(&src, &bad), Err(EmptySpaceError::InvalidParam(_))),
            "{bad:?}"
        );
    }
    let edge = EmptySpaceOptions {
        min_gain: MIN_GAIN_RANGE.start,
        cell_cost: MIN_CELL_COST,
        max_depth: MAX_DEPTH,
        ..Default::default()
    };
    assert!(prune(&src, &edge).is_ok(), "{edge:?}");
}

#[test]
fn pruning_is_deterministic() {
    let src = sparse([40, 24, 32]);
    let a = prune(&src, &EmptySpaceOptions::default())
        .unwrap()
        .asset
        .to_bytes()
        .unwrap();
    let b = prune(&src, &EmptySpaceOptions::default())
        .unwrap()
        .asset
        .to_bytes()
        .unwrap();
    assert_eq!(a, b);
}

#[test]
fn a_tier_atlas_over_the_memory_limit_is_refused_before_it_is_allocated() {
    let src = sparse([32, 32, 32]);
    let plain = prune(&src, &EmptySpaceOptions::default()).unwrap();
    assert!(!plain.stats.kept_whole, "{:?}", plain.stats);
    // Held: the source (colour and normals), a thresholded copy of it when there is a
    // threshold, then each tier's atlas as it is made.
    let bytes = |l: &[Vec<u8>]| l.iter().map(|l| l.len() as u64).sum::<u64>();
    let source = bytes(&src.levels) + bytes(src.normals.as_deref().unwrap());
    let atlases: u64 = plain.stats.bands[..plain.stats.bands.len() - 1]
        .iter()
        .map(|b| b.texel_bytes)
        .sum();
    let o = |threshold, memory_limit| EmptySpaceOptions {
        threshold,
        memory_limit,
        ..Default::default()
    };
    // The smallest limit that passes (bisection) holds at least the source and the
    // atlases kept and gives the same asset; one byte less is refused with a clear error.
    let (mut lo, mut hi) = (0u64, 1u64 << 40);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        match prune(&src, &o(0, mid)) {
            Ok(_) => hi = mid,
            Err(EmptySpaceError::TooMuchMemory { .. }) => lo = mid,
            Err(e) => panic!("{e}"),
        }
    }
    assert!(hi >= source + atlases, "{hi} < {source} + {atlases}");
    assert_eq!(prune(&src, &o(0, hi)).unwrap().asset, plain.asset);
    let e = prune(&src, &o(0, hi - 1)).unwrap_err();
    assert!(e.to_string().contains("GiB of memory"), "{e}");
    // Only the source fits: the first atlas is refused. With a threshold the copy counts.
    let first = |t, limit| {
        matches!(
            prune(&src, &o(t, limit)),
            Err(EmptySpaceError::TooMuchMemory { tier: 0, .. })
        )
    };
    assert!(first(0, source));
    assert!(!first(0, source + atlases));
    assert!(first(40, source + atlases));
    assert!(prune(&src, &o(40, 2 * source + hi)).is_ok());
}
