//! Edge cases of `billow::emptyspace::prune`: empty, full, single-voxel, odd and non-cubic
//! volumes, normals travelling with their bricks, shells and already pruned assets refused,
//! and level-0 sampling of the pruned volume equal to the source wherever a box is.

use billow::emptyspace::synthetic::volume_from_fn;
use billow::emptyspace::{prune, EmptySpaceError, EmptySpaceOptions, PARAM_KEY};
use billow::eval::volume_sampler::DecodedVolume;
use billow_format::VolumeAsset;
use glam::Vec3;

fn opts(e: u32) -> EmptySpaceOptions {
    EmptySpaceOptions {
        exact_levels: e,
        cell_cost: 0.0,
        ..Default::default()
    }
}

fn roundtrip(a: &VolumeAsset) {
    let bytes = a.to_bytes().expect("valid asset");
    let back = VolumeAsset::from_container(billow_format::from_bytes(&bytes).unwrap()).unwrap();
    assert_eq!(&back, a);
}

/// Level-0 texel value of the source at every voxel centre inside the pruned cells equals
/// the pruned asset's sample there (maps each cell's world point → its uvw).
fn level0_matches(src: &VolumeAsset, pruned: &VolumeAsset) {
    let (s, p) = (
        DecodedVolume::decode(src).unwrap(),
        DecodedVolume::decode(pruned).unwrap(),
    );
    let d = Vec3::from(src.level_dims(0).map(|v| v as f32));
    let mut checked = 0;
    for c in &pruned.cells {
        let lo = Vec3::from(c.pos[0]).min(Vec3::from(c.pos[4]));
        let hi = Vec3::from(c.pos[0]).max(Vec3::from(c.pos[4]));
        let (tlo, thi) = (
            Vec3::from(c.uvw[0]).min(Vec3::from(c.uvw[4])),
            Vec3::from(c.uvw[0]).max(Vec3::from(c.uvw[4])),
        );
        // Every voxel centre inside the cell's box (the two prisms share it).
        let v0 = (lo * d).round();
        let v1 = (hi * d).round();
        for z in v0.z as u32..v1.z as u32 {
            for y in v0.y as u32..v1.y as u32 {
                for x in v0.x as u32..v1.x as u32 {
                    let w = (Vec3::new(x as f32, y as f32, z as f32) + 0.5) / d;
                    let t = tlo + (thi - tlo) * (w - lo) / (hi - lo);
                    let a = s.sample_level(0, w);
                    let b = p.sample_level(0, t);
                    assert!((a - b).abs().max_element() < 1e-5, "at {w}: {a} vs {b}");
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 0 || pruned.cells.is_empty());
}

#[test]
fn an_all_empty_volume_gives_a_valid_asset_with_zero_cells() {
    let src = volume_from_fn([16, 8, 12], true, |_, _, _| [0; 4]);
    let p = prune(&src, &opts(1)).unwrap();
    assert_eq!(p.stats.boxes, 0);
    assert!(p.asset.cells.is_empty());
    assert_eq!(p.asset.level_dims(0), [1, 1, 1]);
    assert!(p.asset.header.params.contains_key(PARAM_KEY));
    roundtrip(&p.asset);
}

#[test]
fn an_all_opaque_volume_is_one_box_kept_whole() {
    let src = volume_from_fn([16, 16, 16], false, |x, y, z| {
        [x as u8, y as u8, z as u8, 255]
    });
    for e in [1, 3] {
        let p = prune(&src, &opts(e)).unwrap();
        assert_eq!(p.stats.boxes, 1);
        assert!(p.stats.kept_whole);
        assert_eq!(p.asset.levels, src.levels);
        assert_eq!(p.asset.cells, src.cells);
        roundtrip(&p.asset);
    }
}

#[test]
fn a_single_voxel_becomes_one_small_brick() {
    let src = volume_from_fn([32, 32, 32], true, |x, y, z| {
        if (x, y, z) == (20, 9, 13) {
            [10, 20, 30, 200]
        } else {
            [0; 4]
        }
    });
    let p = prune(&src, &opts(1)).unwrap();
    assert_eq!(p.stats.boxes, 1);
    assert!(!p.stats.kept_whole);
    // The voxel's filter support reaches its 26 neighbours: 3³ voxels, + 1-voxel apron.
    assert_eq!(p.stats.voxels_kept, 27);
    assert_eq!(p.stats.atlas_dims, [5, 5, 5]);
    assert!(p.stats.saving > 0.99);
    level0_matches(&src, &p.asset);
    // Normals travel with the brick: the voxel's normal is in the atlas.
    let n = &p.asset.normals.as_ref().unwrap()[0];
    assert!(n.chunks(4).any(|t| t == [0, 127, 0, 0]));
    roundtrip(&p.asset);
}

#[test]
fn odd_and_non_cubic_sizes_prune_and_sample_exactly_at_level_0() {
    for dims in [[37u32, 19, 23], [64, 9, 33], [5, 70, 3]] {
        let src = volume_from_fn(dims, true, |x, y, z| {
            let blob = |c: [u32; 3], r: u32| {
                let d = |a: u32, b: u32| a.abs_diff(b);
                d(x, c[0]) <= r && d(y, c[1]) <= r && d(z, c[2]) <= r
            };
            let c1 = [dims[0] / 5, dims[1] / 5, dims[2] / 5];
            let c2 = [dims[0] - 2, dims[1] - 2, dims[2] - 2];
            if blob(c1, 1) || blob(c2, 0) {
                [(x * 5) as u8, (y * 3) as u8, (z * 7) as u8, 180]
            } else {
                [0; 4]
            }
        });
        for e in [1, 2] {
            let p = prune(&src, &opts(e)).unwrap();
            assert!(p.stats.boxes >= 1, "{dims:?}");
            p.asset.validate().unwrap();
            level0_matches(&src, &p.asset);
            roundtrip(&p.asset);
            let b = p.stats.block as u32;
            if !p.stats.kept_whole {
                assert!(
                    p.stats.atlas_dims.iter().all(|d| d.is_multiple_of(b)),
                    "{:?}",
                    p.stats
                );
            }
        }
    }
}

#[test]
fn shells_and_pruned_assets_are_refused_with_clear_errors() {
    let src = volume_from_fn([16, 16, 16], false, |x, _, _| {
        if x < 2 {
            [9, 9, 9, 99]
        } else {
            [0; 4]
        }
    });
    let p = prune(&src, &opts(1)).unwrap();
    match prune(&p.asset, &opts(1)) {
        Err(EmptySpaceError::AlreadyPruned(s)) => assert!(s.contains("boxes=")),
        other => panic!("{other:?}"),
    }
    let mut shell = src.clone();
    shell
        .header
        .params
        .insert("shell".into(), "height=0.1".into());
    assert_eq!(prune(&shell, &opts(1)), Err(EmptySpaceError::Shell));
    let mut skew = src.clone();
    skew.cells[0].pos[1][0] += 0.25;
    assert!(matches!(
        prune(&skew, &opts(1)),
        Err(EmptySpaceError::NotABox(0))
    ));
    assert!(matches!(
        prune(&src, &opts(0)),
        Err(EmptySpaceError::InvalidParam(_))
    ));
}

#[test]
fn pruning_is_deterministic() {
    let src = volume_from_fn([40, 24, 32], true, |x, y, z| {
        if (x + 2 * y + 3 * z) % 37 < 2 && x > 5 {
            [40, 50, 60, 128]
        } else {
            [0; 4]
        }
    });
    let a = prune(&src, &opts(2)).unwrap().asset.to_bytes().unwrap();
    let b = prune(&src, &opts(2)).unwrap().asset.to_bytes().unwrap();
    assert_eq!(a, b);
}
