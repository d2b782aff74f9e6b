//! "No visible change": CPU slicer renders (the eval renderer, VB paper §3.3) of a real
//! baked volume before and after `emptyspace` at its **default** settings agree within a
//! tiny tolerance from the eval's whole view set (6 axes + 8 diagonals) at 1×, 4× and 16×
//! the framed distance — slices at every LOD from level 0 to the coarsest, through every
//! band of the pruned asset — and a deliberately apron-less packing fails the very same
//! comparison, so the test can see seams.
//!
//! The volume is the bundled oak baked inside the test (`voxelize --res 80 --align 8`,
//! 72×80×72, 7 MIP levels). Images are 48×48: at 1× the slices sample LOD ≈ 0.6–1.5, at
//! 16× the coarsest levels. Both assets are drawn by the plain renderer
//! ([`render_decoded`]): each places its slices over its own cells' depth range — the
//! pruned asset's tail band keeps the source's box, so the slices are the same (asserted).

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow::emptyspace::{prune, EmptySpaceOptions, Pruned};
use billow::eval::image::write_comparisons_png;
use billow::eval::slicer::{render_decoded, SliceStats, SlicerParams};
use billow::eval::volume_sampler::DecodedVolume;
use billow::eval::ImageF32;
use billow::import::{import, ImportOptions};
use billow::test_support::max_abs_diff as max_abs;
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};
use billow_core::camera::{view_set, Camera, ViewDirections};
use billow_core::Aabb;
use billow_format::VolumeAsset;
use glam::Vec3;

/// Largest allowed per-pixel, per-channel difference (premultiplied linear, 0–1): a
/// quarter of one 8-bit step.
const MAX_ABS: f32 = 1.0 / 1024.0;
const PX: u32 = 48;

fn oak() -> VolumeAsset {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).unwrap().scene;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(80),
        align: 8,
        ..VoxelizeOptions::default()
    };
    let v = voxelize(&scene, &opts, &|_, _| {}).unwrap();
    v.into_asset("emptyspace_render", None, BTreeMap::new())
}

fn render(vol: &DecodedVolume, a: &VolumeAsset, cam: &Camera) -> (ImageF32, SliceStats) {
    let r = render_decoded(
        vol,
        a.level_dims(0),
        &a.cells,
        cam,
        &SlicerParams::default(),
    )
    .unwrap();
    (r.image, r.stats)
}

fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("emptyspace_render");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The first level of each band of `a` (the base is 0).
fn band_starts(a: &VolumeAsset) -> Vec<u32> {
    std::iter::once(0)
        .chain(a.bands.iter().map(|b| b.first_level))
        .collect()
}

/// Worst difference over the view set; writes a diff image for every view above the
/// tolerance when `diff_on_fail`. Also returns, per band of the pruned asset, whether some
/// slice's LOD fell in it, and the largest LOD sampled.
fn compare(
    src: &VolumeAsset,
    pruned: &Pruned,
    tag: &str,
    diff_on_fail: bool,
) -> (f32, Vec<bool>, f32) {
    // Through the file format: what a reader gets.
    let p = VolumeAsset::from_bytes(&pruned.asset.to_bytes().unwrap()).unwrap();
    assert_eq!(p, pruned.asset);
    let (vs, vp) = (
        DecodedVolume::decode(src).unwrap(),
        DecodedVolume::decode(&p).unwrap(),
    );
    let b = &src.header.bounds;
    let bounds = Aabb {
        min: Vec3::from(b.min),
        max: Vec3::from(b.max),
    };
    let starts = band_starts(&p);
    let max_lod = p.max_lod() as f32;
    let mut used = vec![false; starts.len()];
    let (mut worst, mut top) = (0.0f32, 0.0f32);
    let views = view_set(ViewDirections::All);
    assert_eq!(views.len(), 14 * 3);
    for v in &views {
        let cam = v.camera(&bounds, std::f32::consts::FRAC_PI_4, PX, PX);
        let (a, sa) = render(&vs, src, &cam);
        let (b, sb) = render(&vp, &p, &cam);
        assert!(a.coverage() > 0.0, "{}: the source renders nothing", v.name);
        assert_eq!(sa.slices, sb.slices, "{}: different slices", v.name);
        assert!((sa.voxel_size - sb.voxel_size).abs() <= 1e-6 * sa.voxel_size);
        let lod = |d: f32| (d / sa.voxel_size).log2().clamp(0.0, max_lod);
        let (lo, hi) = (lod(sa.min_spacing), lod(sa.max_spacing));
        top = top.max(hi);
        for (i, u) in used.iter_mut().enumerate() {
            let end = starts.get(i + 1).map_or(f32::INFINITY, |&f| f as f32);
            *u |= lo < end && hi >= starts[i] as f32;
        }
        let d = max_abs(&a, &b);
        if d > MAX_ABS && diff_on_fail {
            let path = out_dir().join(format!("{tag}_{}.png", v.name.replace(['@', '.'], "_")));
            write_comparisons_png(&a, &[&b], 16.0, &path).unwrap();
            eprintln!("{}: max |Δ| = {d}; diff image {}", v.name, path.display());
        }
        worst = worst.max(d);
    }
    (worst, used, top)
}

#[test]
fn pruning_at_default_settings_changes_no_pixel_at_any_distance() {
    let src = oak();
    assert_eq!(src.level_dims(0), [72, 80, 72]);
    let p = prune(&src, &EmptySpaceOptions::default()).unwrap();
    let s = &p.stats;
    assert!(!s.kept_whole && s.boxes >= 2, "{s:?}");
    assert!(s.saving > 0.1, "the test needs a real saving: {s:?}");
    assert!(!p.asset.bands.is_empty(), "{s:?}");
    let (d, used, top) = compare(&src, &p, "apron", true);
    println!(
        "saving {:.3}, bands from {:?}, max |Δ| {d:.2e}, largest LOD {top:.2}",
        s.saving,
        band_starts(&p.asset)
    );
    assert!(
        used.iter().all(|&u| u),
        "every band must be exercised: {used:?} (bands from {:?})",
        band_starts(&p.asset)
    );
    assert!(
        top >= p.asset.max_lod() as f32 - 0.5,
        "the 16× views must reach the coarsest levels: {top}"
    );
    assert!(
        d <= MAX_ABS,
        "max |Δ| {d} > {MAX_ABS} (diff images in {})",
        out_dir().display()
    );
}

#[test]
fn an_apron_less_packing_shows_seams_in_the_same_comparison() {
    let src = oak();
    let o = EmptySpaceOptions {
        apron: false,
        ..Default::default()
    };
    let p = prune(&src, &o).unwrap();
    assert!(p.stats.boxes >= 2 && !p.stats.kept_whole, "{:?}", p.stats);
    let (d, _, _) = compare(&src, &p, "no_apron", false);
    println!("without aprons: max |Δ| {d:.3}");
    assert!(
        d > 10.0 * MAX_ABS,
        "without aprons the renders should differ visibly at brick borders, max |Δ| = {d}"
    );
}
