//! "No visible change": CPU slicer renders (the eval renderer, VB paper §3.3) of a volume
//! before and after `emptyspace` agree within a tiny tolerance from the eval's view
//! directions at 1×, 4× and 16× the framed distance — and a deliberately apron-less
//! packing fails the very same comparison (so the test can see seams).
//!
//! The volume is 64³ with a staircase of three touching 18 × 8 × 8 steps, so the kd-tree
//! cuts through content and brick borders carry content on both sides. With
//! `exact_levels = 3` (levels 0–2 exact, bricks aligned to 4 voxels) the image sizes are
//! chosen per distance so that every slice samples levels ≤ 2 (checked below from the
//! slicer's spacing): 128 px at 1×, 160 px at 4×, 512 px at 16×; the 16× view thus
//! exercises MIP levels 1–2 over the whole object.
//!
//! Both renders place their slices over the *source's* depth range
//! ([`render_decoded_in_depth_range`]), so they sample the same depths; what remains is
//! the volume data each pixel reads.

use std::path::PathBuf;

use billow::camera::{to_view, Camera};
use billow::emptyspace::synthetic::volume_from_fn;
use billow::emptyspace::{prune, EmptySpaceOptions};
use billow::eval::image::write_comparisons_png;
use billow::eval::slicer::{render_decoded_in_depth_range, SlicerParams};
use billow::eval::volume_sampler::DecodedVolume;
use billow::eval::ImageF32;
use billow::scene::Aabb;
use billow_format::VolumeAsset;
use glam::Vec3;

/// Largest allowed per-pixel, per-channel difference (premultiplied linear, 0–1): a
/// quarter of one 8-bit step.
const MAX_ABS: f32 = 1.0 / 1024.0;

fn staircase() -> VolumeAsset {
    volume_from_fn([64, 64, 64], true, |x, y, z| {
        // Three 18 × 8 × 8 steps along x, each 6 voxels higher and deeper than the last;
        // consecutive steps touch and overlap in y and z, so cuts between them have
        // content on both sides.
        let on = (0..3u32).any(|k| {
            (4 + 18 * k..22 + 18 * k).contains(&x)
                && (4 + 6 * k..12 + 6 * k).contains(&y)
                && (4 + 6 * k..12 + 6 * k).contains(&z)
        });
        if !on {
            return [0; 4];
        }
        // Varying colour and opacity so that misplaced texels show.
        let a = 96 + ((x * 7 + y * 3 + z * 5) % 128) as u8;
        let r = (u32::from(a) * (x * 4) / 255) as u8;
        let g = (u32::from(a) * (y * 4) / 255) as u8;
        let b = (u32::from(a) * (z * 4) / 255) as u8;
        [r, g, b, a]
    })
}

fn depth_range(asset: &VolumeAsset, cam: &Camera) -> (f32, f32) {
    let view = cam.view();
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for c in &asset.cells {
        for p in &c.pos {
            let d = -to_view(&view, Vec3::from(*p)).z;
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    (lo, hi)
}

struct Views {
    cams: Vec<(String, Camera)>,
}

fn views() -> Views {
    let bounds = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let mut cams = Vec::new();
    for (name, dir) in [
        ("-z", Vec3::NEG_Z),
        ("+x", Vec3::X),
        ("-x-y-z", Vec3::new(-1.0, -1.0, -1.0).normalize()),
    ] {
        for (f, px) in [(1.0f32, 128u32), (4.0, 160), (16.0, 512)] {
            let cam = Camera::framed(&bounds, dir, std::f32::consts::FRAC_PI_4, px, px, f);
            cams.push((format!("{name}@{f}x"), cam));
        }
    }
    Views { cams }
}

fn render(asset: &VolumeAsset, cam: &Camera, range: (f32, f32)) -> (ImageF32, f32) {
    let vol = DecodedVolume::decode(asset).unwrap();
    let r = render_decoded_in_depth_range(
        &vol,
        asset.level_dims(0),
        &asset.cells,
        cam,
        &SlicerParams::default(),
        Some(range),
    )
    .unwrap();
    let lod_max = (r.stats.max_spacing / r.stats.voxel_size).log2();
    (r.image, lod_max)
}

fn max_abs(a: &ImageF32, b: &ImageF32) -> f32 {
    a.data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max)
}

fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("emptyspace_render");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Worst difference over the views, after writing a diff image for each view above the
/// tolerance when `diff_on_fail`.
fn worst(src: &VolumeAsset, pruned: &VolumeAsset, tag: &str, diff_on_fail: bool) -> f32 {
    let mut worst = 0.0f32;
    for (name, cam) in &views().cams {
        let range = depth_range(src, cam);
        let (a, lod_a) = render(src, cam, range);
        let (b, _) = render(pruned, cam, range);
        assert!(
            lod_a <= 2.0 + 1e-3,
            "{name}: the view samples level {lod_a:.2}, beyond the 3 exact levels"
        );
        assert!(a.coverage() > 0.0, "{name}: the source renders nothing");
        let d = max_abs(&a, &b);
        if d > MAX_ABS && diff_on_fail {
            let path = out_dir().join(format!("{tag}_{}.png", name.replace(['@', '.'], "_")));
            write_comparisons_png(&a, &[&b], 16.0, &path).unwrap();
            eprintln!("{name}: max |Δ| = {d}; diff image {}", path.display());
        }
        println!("{tag} {name}: max abs diff {d:.2e}");
        worst = worst.max(d);
    }
    worst
}

fn options(apron: bool) -> EmptySpaceOptions {
    EmptySpaceOptions {
        exact_levels: 3,
        cell_cost: 0.0,
        apron,
        ..Default::default()
    }
}

#[test]
fn pruning_changes_no_pixel_beyond_a_quarter_of_an_8_bit_step() {
    let src = staircase();
    let p = prune(&src, &options(true)).unwrap();
    assert!(
        p.stats.boxes >= 2,
        "the test needs brick borders: {:?}",
        p.stats
    );
    assert!(!p.stats.kept_whole && p.stats.saving > 0.3, "{:?}", p.stats);
    let d = worst(&src, &p.asset, "apron", true);
    assert!(
        d <= MAX_ABS,
        "max |Δ| {d} > {MAX_ABS} (diff images in {})",
        out_dir().display()
    );
}

#[test]
fn an_apron_less_packing_shows_seams_in_the_same_comparison() {
    let src = staircase();
    let p = prune(&src, &options(false)).unwrap();
    assert!(p.stats.boxes >= 2 && !p.stats.kept_whole, "{:?}", p.stats);
    let d = worst(&src, &p.asset, "no_apron", false);
    assert!(
        d > 10.0 * MAX_ABS,
        "without aprons the renders should differ visibly at brick borders, max |Δ| = {d}"
    );
}
