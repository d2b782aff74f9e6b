//! The measurements behind docs/emptyspace.md and docs/emptyspace_sweep.md: what
//! `billow emptyspace` saves in texture memory and in CPU rendering work, and what it
//! changes in the image.
//!
//! `cargo run --release --example emptyspace_sweep -- [REPORT.md] [--quick]`
//!
//! Volumes: the bundled oak voxelized at 128³ and 256³ and, when `../shared/assets`
//! exists, the spot cow at 128³ (`voxelize` defaults otherwise). Each is pruned with each
//! setting and both the original and the pruned volume are drawn by the CPU slicer (the
//! eval renderer) from the 6 axis views of the eval view set at 1×, 4× and 16× the framed
//! distance (128×128, framed on the volume's box). Reported per setting: texel bytes and
//! saving, boxes, atlas size, slicer fragments and time summed over the views (relative to
//! the original), and the image difference from the original — **data** (slices placed
//! over the original's depth range, so only the sampled texels differ) and **seen** (each
//! asset sliced over its own cells' range, as a renderer does). `--quick`: 64×64 images,
//! no 256³.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::camera::{to_view, view_set, Camera, ViewDirections};
use billow::emptyspace::{prune, EmptySpaceOptions, EmptySpaceStats};
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_decoded_in_depth_range, SlicerParams};
use billow::eval::volume_sampler::DecodedVolume;
use billow::eval::ImageF32;
use billow::import::{import, ImportOptions};
use billow::scene::Aabb;
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};
use billow_format::VolumeAsset;
use glam::Vec3;

struct Render {
    image: ImageF32,
    fragments: u64,
    seconds: f64,
}

fn depth_range(asset: &VolumeAsset, cam: &Camera) -> Option<(f32, f32)> {
    let view = cam.view();
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for c in &asset.cells {
        for p in &c.pos {
            let d = -to_view(&view, Vec3::from(*p)).z;
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    (lo < hi).then_some((lo, hi))
}

fn render(vol: &DecodedVolume, a: &VolumeAsset, cam: &Camera, range: Option<(f32, f32)>) -> Render {
    let r = render_decoded_in_depth_range(
        vol,
        a.level_dims(0),
        &a.cells,
        cam,
        &SlicerParams::default(),
        range,
    )
    .expect("render");
    Render {
        image: r.image,
        fragments: r.stats.fragments,
        seconds: r.stats.seconds,
    }
}

#[derive(Default, Clone, Copy)]
struct Diff {
    rmse: [f64; 3],
    max_abs: [f32; 3],
}

struct Measured {
    stats: EmptySpaceStats,
    fragments: u64,
    seconds: f64,
    data: Diff,
    seen: Diff,
}

struct Baseline {
    cams: Vec<(f32, Camera)>,
    renders: Vec<Render>,
}

fn cameras(asset: &VolumeAsset, px: u32) -> Vec<(f32, Camera)> {
    let mut b = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    for c in &asset.cells {
        for p in &c.pos {
            b.grow(Vec3::from(*p));
        }
    }
    view_set(ViewDirections::Axes)
        .into_iter()
        .map(|v| {
            let cam = Camera::framed(
                &b,
                v.dir,
                std::f32::consts::FRAC_PI_4,
                px,
                px,
                v.distance_factor,
            );
            (v.distance_factor, cam)
        })
        .collect()
}

fn baseline(asset: &VolumeAsset, px: u32) -> Baseline {
    let vol = DecodedVolume::decode(asset).expect("decode");
    let cams = cameras(asset, px);
    let renders = cams
        .iter()
        .map(|(_, c)| render(&vol, asset, c, None))
        .collect();
    Baseline { cams, renders }
}

fn max_abs(a: &ImageF32, b: &ImageF32) -> f32 {
    a.data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max)
}

fn dist_index(f: f32) -> usize {
    if f < 2.0 {
        0
    } else if f < 8.0 {
        1
    } else {
        2
    }
}

fn measure(src: &VolumeAsset, base: &Baseline, o: &EmptySpaceOptions) -> Measured {
    let p = prune(src, o).expect("prune");
    let vol = DecodedVolume::decode(&p.asset).expect("decode");
    let (mut fragments, mut seconds) = (0u64, 0.0);
    let (mut data, mut seen) = (Diff::default(), Diff::default());
    let mut counts = [0usize; 3];
    for ((f, cam), b) in base.cams.iter().zip(&base.renders) {
        let k = dist_index(*f);
        counts[k] += 1;
        let own = render(&vol, &p.asset, cam, None);
        fragments += own.fragments;
        seconds += own.seconds;
        let e = compare(&b.image, &own.image).expect("same size");
        seen.rmse[k] += e.rmse;
        seen.max_abs[k] = seen.max_abs[k].max(max_abs(&b.image, &own.image));
        let anchored = render(&vol, &p.asset, cam, depth_range(src, cam));
        let e = compare(&b.image, &anchored.image).expect("same size");
        data.rmse[k] += e.rmse;
        data.max_abs[k] = data.max_abs[k].max(max_abs(&b.image, &anchored.image));
    }
    for (k, count) in counts.iter().enumerate() {
        let n = (*count).max(1) as f64;
        data.rmse[k] /= n;
        seen.rmse[k] /= n;
    }
    Measured {
        stats: p.stats,
        fragments,
        seconds,
        data,
        seen,
    }
}

fn bake(path: &Path, res: u32) -> Result<VolumeAsset, String> {
    let scene = import(path, &ImportOptions::default()).map_err(|e| e.to_string())?;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        ..VoxelizeOptions::default()
    };
    let v = voxelize(&scene, &opts, &|_, _| {}).map_err(|e| e.to_string())?;
    Ok(v.into_asset("billow emptyspace_sweep", None, BTreeMap::new()))
}

fn fmt_diff(d: &Diff) -> String {
    format!(
        "{:.1e} / {:.1e} / {:.1e} | {:.3} / {:.3} / {:.3}",
        d.rmse[0], d.rmse[1], d.rmse[2], d.max_abs[0], d.max_abs[1], d.max_abs[2]
    )
}

const HEADER: &str = "| setting | boxes | atlas | MiB before → after | saving | voxels kept | fragments | render time | data RMSE 1× / 4× / 16× \\| max \\|Δ\\| | seen RMSE 1× / 4× / 16× \\| max \\|Δ\\| |\n|---|---:|---|---|---:|---:|---:|---:|---|---|\n";

fn row(label: &str, m: &Measured, base_frags: u64, base_secs: f64) -> String {
    let s = &m.stats;
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    format!(
        "| {label} | {} | {}×{}×{}{} | {:.2} → {:.2} | {:.0}% | {:.0}% | {:.2}× | {:.2}× | {} | {} |\n",
        s.boxes,
        s.atlas_dims[0],
        s.atlas_dims[1],
        s.atlas_dims[2],
        if s.kept_whole { " (whole)" } else { "" },
        mib(s.texel_bytes_before),
        mib(s.texel_bytes_after),
        100.0 * s.saving,
        100.0 * s.voxels_kept as f64 / s.voxels_before.max(1) as f64,
        m.fragments as f64 / base_frags.max(1) as f64,
        m.seconds / base_secs.max(1e-9),
        fmt_diff(&m.data),
        fmt_diff(&m.seen),
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let report = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map_or(PathBuf::from("docs/emptyspace_sweep.md"), PathBuf::from);
    let px = if quick { 64 } else { 128 };
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let oak = repo.join("fixtures/oak/eztree_oak_medium.gltf");
    let cow = repo.join("../shared/assets/spot_cow/spot.obj");
    let mut inputs: Vec<(String, PathBuf, u32)> = vec![("oak 128³".into(), oak.clone(), 128)];
    if !quick {
        inputs.push(("oak 256³".into(), oak.clone(), 256));
    }
    if cow.exists() {
        inputs.push(("spot cow 128³".into(), cow, 128));
    } else {
        eprintln!("../shared/assets/spot_cow/spot.obj not found: the cow is skipped");
    }
    let start = Instant::now();
    let mut md = String::new();
    md.push_str("# Empty-space removal: measurements and sweep\n\n");
    md.push_str("**Generated by `cargo run --release --example emptyspace_sweep`** (`examples/emptyspace_sweep.rs`); do not edit by hand. Method and reading guide: [emptyspace.md](emptyspace.md).\n\n");
    let _ = writeln!(
        md,
        "Views: the 6 axis directions of the eval view set × 1×, 4×, 16× the framed distance, {px}×{px}, CPU slicer with the paper's adaptive spacing and linear MIP filtering. *fragments* and *render time* are the pruned volume's totals over the 18 views divided by the original's (below 1: faster). *data*: slices at the original's depths (only the texels differ); *seen*: each asset sliced over its own depth range. RMSE over premultiplied linear RGBA, mean over the 6 views of a distance; max |Δ| = largest per-pixel channel difference over those views. Machine: 2 shared cores; times are single runs and noisy — fragments are the machine-independent measure.\n"
    );
    for (name, path, res) in &inputs {
        let src = match bake(path, *res) {
            Ok(a) => a,
            Err(e) => {
                eprintln!("{name}: {e}");
                continue;
            }
        };
        let d = src.level_dims(0);
        let base = baseline(&src, px);
        let base_frags: u64 = base.renders.iter().map(|r| r.fragments).sum();
        let base_secs: f64 = base.renders.iter().map(|r| r.seconds).sum();
        let _ = write!(
            md,
            "\n## {name} ({}×{}×{} voxels, {} MIP levels)\n\nOriginal: {base_frags} fragments, {:.3} s over the 18 views.\n\n### Exact levels (`--exact-levels`, other settings default)\n\n{HEADER}",
            d[0],
            d[1],
            d[2],
            src.levels.len(),
            base_secs
        );
        for e in 1..=4 {
            let o = EmptySpaceOptions {
                exact_levels: e,
                ..Default::default()
            };
            let m = measure(&src, &base, &o);
            md.push_str(&row(
                &format!("exact levels {e}"),
                &m,
                base_frags,
                base_secs,
            ));
            eprintln!("{name} E={e}: saving {:.3}", m.stats.saving);
        }
        if name.starts_with("oak 128") {
            md.push_str("\n### Threshold (`--threshold`, exact levels 1)\n\n");
            md.push_str(HEADER);
            for t in [0u8, 4, 16, 64] {
                let o = EmptySpaceOptions {
                    exact_levels: 1,
                    threshold: t,
                    ..Default::default()
                };
                let m = measure(&src, &base, &o);
                md.push_str(&row(&format!("threshold {t}"), &m, base_frags, base_secs));
            }
            md.push_str("\n### Minimum box and per-box cost (`--min-box`, `--cell-cost`, exact levels 1)\n\n");
            md.push_str(HEADER);
            for (mb, w) in [
                (0u32, 0.0f64),
                (0, 4096.0),
                (4, 4096.0),
                (8, 4096.0),
                (16, 4096.0),
                (0, 32768.0),
            ] {
                let o = EmptySpaceOptions {
                    exact_levels: 1,
                    min_box: mb,
                    cell_cost: w,
                    ..Default::default()
                };
                let m = measure(&src, &base, &o);
                md.push_str(&row(
                    &format!("min box {mb}, cell cost {w}"),
                    &m,
                    base_frags,
                    base_secs,
                ));
            }
        }
    }
    let _ = writeln!(md, "\nWhole sweep: {:.0} s.", start.elapsed().as_secs_f64());
    std::fs::write(&report, md).expect("write report");
    eprintln!("wrote {}", report.display());
}
