//! The accuracy-versus-cost sweep behind `make accuracy`: regenerates `docs/accuracy.md`
//! and its plots (`docs/accuracy/*.svg`, written by hand: no plotting dependency).
//!
//! `cargo run --release --example accuracy -- [REPORT.md] [--quick]`
//!
//! For each mesh (the bundled oak; `../shared/assets/spot_cow/spot.obj` and
//! `../shared/assets/stanford_bunny/bunny.obj` when `../shared` exists), one factor at a
//! time is varied from the baseline (128³, 4×4 supersampling, `opaque`, adaptive slicing
//! with bias 1): voxel resolution 32/64/128/256, supersampling 1/2/4, combine
//! mean/max/opaque, slice spacing adaptive 0.5/1/2 and uniform (one level-0 voxel, always
//! MIP level 0). Each volume is rendered from every view of the evaluation set (14
//! directions × 1/4/16× the framed distance, 128×128, see docs/eval.md) and compared with
//! the 16-spp reference. `--quick` uses 64×64 images, the axis views and no 256³.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::camera::{view_set, ViewDirections};
use billow::eval::slicer::Spacing;
use billow::eval::suite::{
    mean_errors, means_by_distance, EvalOptions, Evaluator, MeanErrors, PreparedAsset,
    ReferenceView, ViewResult,
};
use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, CombineFn, Preset, Resolution, VoxelizeOptions};
use billow_format::VolumeAsset;

#[derive(Clone, Copy, Debug, PartialEq)]
enum SpacingKind {
    Adaptive(f32),
    /// Multiples of the level-0 voxel.
    Uniform(f32),
}

#[derive(Clone, Debug)]
struct Config {
    family: &'static str,
    label: String,
    res: u32,
    ss: u32,
    combine: Preset,
    spacing: SpacingKind,
}

const BASE_RES: u32 = 128;
const BASE_SS: u32 = 4;
const BASE_COMBINE: Preset = Preset::Opaque;
/// Each configuration is rendered this many times; the fastest run's time is reported.
const RENDER_REPEATS: usize = 3;

fn configs(quick: bool) -> Vec<Config> {
    let base = |family: &'static str, label: String| Config {
        family,
        label,
        res: BASE_RES,
        ss: BASE_SS,
        combine: BASE_COMBINE,
        spacing: SpacingKind::Adaptive(1.0),
    };
    let mut out = Vec::new();
    let resolutions: &[u32] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256]
    };
    for &r in resolutions {
        out.push(Config {
            res: r,
            ..base("resolution", format!("{r}³"))
        });
    }
    for ss in [1, 2, 4] {
        out.push(Config {
            ss,
            ..base("supersampling", format!("ss {ss}×{ss}"))
        });
    }
    for c in [Preset::Mean, Preset::Max, Preset::Opaque] {
        out.push(Config {
            combine: c,
            ..base("combine", c.name().to_string())
        });
    }
    for s in [
        SpacingKind::Adaptive(0.5),
        SpacingKind::Adaptive(1.0),
        SpacingKind::Adaptive(2.0),
        SpacingKind::Uniform(1.0),
    ] {
        let label = match s {
            SpacingKind::Adaptive(b) => format!("adaptive {b}"),
            SpacingKind::Uniform(v) => format!("uniform {v} voxel"),
        };
        out.push(Config {
            spacing: s,
            ..base("spacing", label)
        });
    }
    out
}

/// One configuration's measurements on one mesh.
#[derive(Clone, Debug)]
struct Row {
    config: Config,
    bake_s: f64,
    bytes: u64,
    /// Mean slicer seconds per view.
    render_s: f64,
    slices: f64,
    fragments: f64,
    mean: MeanErrors,
    /// (factor, asset means) per distance.
    by_distance: Vec<(f32, MeanErrors)>,
}

struct MeshReport {
    name: String,
    path: String,
    triangles: usize,
    reference_s: f64,
    raster: MeanErrors,
    raster_by_distance: Vec<(f32, MeanErrors)>,
    rows: Vec<Row>,
}

fn bake(
    scene: &billow::scene::Scene,
    res: u32,
    ss: u32,
    combine: Preset,
) -> Result<(VolumeAsset, f64), String> {
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        supersample: ss,
        combine: CombineFn::Preset(combine),
        ..VoxelizeOptions::default()
    };
    let t = Instant::now();
    let volume = voxelize(scene, &opts, &|_, _| {}).map_err(|e| e.to_string())?;
    let s = t.elapsed().as_secs_f64();
    Ok((
        volume.into_asset("billow accuracy", None, BTreeMap::new()),
        s,
    ))
}

fn run_mesh(name: &str, path: &Path, shown: &str, quick: bool) -> Result<MeshReport, String> {
    eprintln!("{name}: importing {}", path.display());
    let scene = import(path, &ImportOptions::default()).map_err(|e| e.to_string())?;
    let size = if quick { 64 } else { 128 };
    let views = view_set(if quick {
        ViewDirections::Axes
    } else {
        ViewDirections::All
    });
    let mut evaluator = Evaluator::new(
        &scene,
        EvalOptions {
            width: size,
            height: size,
            ..EvalOptions::default()
        },
    )
    .map_err(|e| e.to_string())?;
    let t = Instant::now();
    let refs: Vec<ReferenceView> = views
        .iter()
        .map(|v| evaluator.reference(v))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let reference_s = t.elapsed().as_secs_f64();
    let raster_errors: Vec<_> = refs
        .iter()
        .filter_map(|r| r.raster_1spp.as_ref().map(|x| x.1))
        .collect();
    let mut factors: Vec<f32> = Vec::new();
    for v in &views {
        if !factors.contains(&v.distance_factor) {
            factors.push(v.distance_factor);
        }
    }
    let raster_by_distance = factors
        .iter()
        .map(|&f| {
            let errs = refs
                .iter()
                .filter(|r| r.spec.distance_factor == f)
                .filter_map(|r| r.raster_1spp.as_ref().map(|x| &x.1));
            (f, mean_errors(errs))
        })
        .collect();

    let mut cache: BTreeMap<(u32, u32, &'static str), (PreparedAsset, f64, u64)> = BTreeMap::new();
    let mut rows = Vec::new();
    for c in configs(quick) {
        let key = (c.res, c.ss, c.combine.name());
        let (prepared, bake_s, bytes) = match cache.entry(key) {
            Entry::Occupied(e) => &*e.into_mut(),
            Entry::Vacant(e) => {
                eprintln!("{name}: baking {}³ ss {} {}", c.res, c.ss, c.combine.name());
                let (asset, s) = bake(&scene, c.res, c.ss, c.combine)?;
                let bytes = asset.to_bytes().map_err(|e| e.to_string())?.len() as u64;
                let prepared = PreparedAsset::new(&asset).map_err(|e| e.to_string())?;
                &*e.insert((prepared, s, bytes))
            }
        };
        evaluator.options.slicer.spacing = match c.spacing {
            SpacingKind::Adaptive(bias) => Spacing::Adaptive { bias },
            SpacingKind::Uniform(v) => Spacing::Uniform {
                spacing: v * prepared.voxel_size().unwrap_or(1.0),
            },
        };
        // Render times are small and the machine is shared: the minimum of three runs.
        let mut results: Vec<ViewResult> = Vec::new();
        let mut render_s = f64::INFINITY;
        for _ in 0..RENDER_REPEATS {
            results = refs
                .iter()
                .map(|r| evaluator.asset(prepared, r).map(|x| x.0))
                .collect::<Result<_, _>>()
                .map_err(|e| e.to_string())?;
            render_s = render_s.min(results.iter().map(|r| r.seconds.asset).sum::<f64>());
        }
        let n = results.len().max(1) as f64;
        let row = Row {
            bake_s: *bake_s,
            bytes: *bytes,
            render_s: render_s / n,
            slices: results.iter().map(|r| r.slices as f64).sum::<f64>() / n,
            fragments: results.iter().map(|r| r.fragments as f64).sum::<f64>() / n,
            mean: mean_errors(results.iter().map(|r| &r.asset)),
            by_distance: means_by_distance(&results)
                .into_iter()
                .map(|d| (d.distance_factor, d.asset))
                .collect(),
            config: c,
        };
        eprintln!(
            "{name}: {:<18} rmse {:.4} psnr {:.2} render {:.3} s",
            row.config.label, row.mean.rmse, row.mean.psnr, row.render_s
        );
        rows.push(row);
    }
    Ok(MeshReport {
        name: name.to_string(),
        path: shown.to_string(),
        triangles: scene.triangles.len(),
        reference_s,
        raster: mean_errors(&raster_errors),
        raster_by_distance,
        rows,
    })
}

// ---------------------------------------------------------------------------------------
// SVG plots, by hand.

const FAMILIES: [(&str, &str); 4] = [
    ("resolution", "#1f77b4"),
    ("supersampling", "#ff7f0e"),
    ("combine", "#2ca02c"),
    ("spacing", "#d62728"),
];

struct Panel<'a> {
    x_label: &'a str,
    x: fn(&Row) -> f64,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn nice_label(v: f64) -> String {
    if v >= 1e6 {
        format!("{:.0}M", v / 1e6)
    } else if v >= 1e3 {
        format!("{:.0}k", v / 1e3)
    } else if v >= 1.0 {
        format!("{v:.0}")
    } else if v >= 0.01 {
        format!("{v:.2}")
    } else {
        format!("{v:.0e}")
    }
}

/// Three panels (error against bake time, asset bytes, render time), log x, linear y.
fn plot(mesh: &MeshReport) -> String {
    let panels = [
        Panel {
            x_label: "bake time (s)",
            x: |r| r.bake_s,
        },
        Panel {
            x_label: "asset size (bytes)",
            x: |r| r.bytes as f64,
        },
        Panel {
            x_label: "render time per view (s, CPU slicer, best of 3)",
            x: |r| r.render_s,
        },
    ];
    let (pw, ph) = (380.0, 300.0);
    let (ml, mr, mt, mb) = (56.0, 14.0, 40.0, 46.0);
    let width = 3.0 * pw;
    let height = ph + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="100%" height="100%" fill="white"/><text x="{}" y="18" font-size="14" text-anchor="middle">{}: mean RMSE (premultiplied RGBA, 1×/4×/16× views) against cost — lower left is better</text>"#,
        width / 2.0,
        esc(&mesh.name)
    );
    let y_max = mesh
        .rows
        .iter()
        .map(|r| r.mean.rmse)
        .fold(mesh.raster.rmse, f64::max)
        * 1.1;
    for (pi, p) in panels.iter().enumerate() {
        let x0 = pi as f64 * pw;
        let (ax, ay, aw, ah) = (x0 + ml, mt, pw - ml - mr, ph - mt - mb + 20.0);
        let xs: Vec<f64> = mesh.rows.iter().map(|r| (p.x)(r).max(1e-6)).collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min).log10();
        let hi = xs.iter().copied().fold(0.0, f64::max).log10();
        let (lo, hi) = (lo - 0.15, hi + 0.15);
        let px = |v: f64| ax + (v.max(1e-6).log10() - lo) / (hi - lo) * aw;
        let py = |v: f64| ay + ah - v / y_max * ah;
        let _ = writeln!(
            s,
            r##"<rect x="{ax}" y="{ay}" width="{aw}" height="{ah}" fill="none" stroke="#888"/>"##
        );
        // x ticks at 1, 2, 5 × 10^k.
        for k in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(k);
                let l = v.log10();
                if l < lo || l > hi {
                    continue;
                }
                let x = px(v);
                let _ = writeln!(
                    s,
                    r##"<line x1="{x:.1}" y1="{ay}" x2="{x:.1}" y2="{:.1}" stroke="#eee"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                    ay + ah,
                    ay + ah + 14.0,
                    nice_label(v)
                );
            }
        }
        for i in 0..=4 {
            let v = y_max * f64::from(i) / 4.0;
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" text-anchor="end">{v:.3}</text>"##,
                ax + aw,
                ax - 4.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            ax + aw / 2.0,
            ay + ah + 32.0,
            esc(p.x_label)
        );
        if pi == 0 {
            let _ = writeln!(
                s,
                r#"<text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle">mean RMSE</text>"#,
                x0 + 14.0,
                ay + ah / 2.0
            );
        }
        // The mesh drawn with 1 sample per pixel.
        let y = py(mesh.raster.rmse);
        let _ = writeln!(
            s,
            r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#555" stroke-dasharray="5,4"/><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#555">mesh, 1 spp (no AA)</text>"##,
            ax + aw,
            ax + aw - 4.0,
            y - 4.0
        );
        for (family, colour) in FAMILIES {
            let pts: Vec<(f64, f64, &str)> = mesh
                .rows
                .iter()
                .filter(|r| r.config.family == family)
                .map(|r| (px((p.x)(r)), py(r.mean.rmse), r.config.label.as_str()))
                .collect();
            let path: Vec<String> = pts
                .iter()
                .map(|(x, y, _)| format!("{x:.1},{y:.1}"))
                .collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-opacity="0.5"/>"#,
                path.join(" ")
            );
            for (x, y, label) in pts {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.5" fill="{colour}"/><text x="{:.1}" y="{:.1}" font-size="9" fill="{colour}">{}</text>"#,
                    x + 5.0,
                    y - 4.0,
                    esc(label)
                );
            }
        }
    }
    // Legend.
    for (i, (family, colour)) in FAMILIES.iter().enumerate() {
        let x = 60.0 + i as f64 * 150.0;
        let y = height - 10.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{x}" cy="{:.1}" r="4" fill="{colour}"/><text x="{:.1}" y="{y:.1}">{family}</text>"#,
            y - 4.0,
            x + 8.0
        );
    }
    s.push_str("</svg>\n");
    s
}

// ---------------------------------------------------------------------------------------
// The report.

fn mib(b: u64) -> f64 {
    b as f64 / f64::from(1u32 << 20)
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn find<'a>(m: &'a MeshReport, family: &str, label: &str) -> Option<&'a Row> {
    m.rows
        .iter()
        .find(|r| r.config.family == family && r.config.label == label)
}

fn table(m: &MeshReport) -> String {
    let mut s = String::new();
    let dist = |r: &Row, f: f32| {
        r.by_distance
            .iter()
            .find(|d| d.0 == f)
            .map(|d| d.1)
            .unwrap_or_default()
    };
    let _ = writeln!(
        s,
        "| sweep | setting | bake s | asset MiB | render ms/view | slices/view | fragments/view | RMSE | PSNR dB | SSIM | RMSE 1× / 4× / 16× | coverage 1× / 4× / 16× |"
    );
    let _ = writeln!(
        s,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|"
    );
    for r in &m.rows {
        let (a, b, c) = (dist(r, 1.0), dist(r, 4.0), dist(r, 16.0));
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.2} | {:.1} | {:.0} | {:.0} | {:.4} | {:.2} | {:.3} | {:.4} / {:.4} / {:.4} | {:+.0}% / {:+.0}% / {:+.0}% |",
            r.config.family,
            r.config.label,
            r.bake_s,
            mib(r.bytes),
            1e3 * r.render_s,
            r.slices,
            r.fragments,
            r.mean.rmse,
            r.mean.psnr,
            r.mean.ssim_luma,
            a.rmse,
            b.rmse,
            c.rmse,
            100.0 * a.coverage_rel_diff,
            100.0 * b.coverage_rel_diff,
            100.0 * c.coverage_rel_diff,
        );
    }
    let rd = |f: f32| {
        m.raster_by_distance
            .iter()
            .find(|d| d.0 == f)
            .map(|d| d.1)
            .unwrap_or_default()
    };
    let (a, b, c) = (rd(1.0), rd(4.0), rd(16.0));
    let _ = writeln!(
        s,
        "| mesh, 1 spp | no anti-aliasing | – | – | – | – | – | {:.4} | {:.2} | {:.3} | {:.4} / {:.4} / {:.4} | {:+.0}% / {:+.0}% / {:+.0}% |",
        m.raster.rmse,
        m.raster.psnr,
        m.raster.ssim_luma,
        a.rmse,
        b.rmse,
        c.rmse,
        100.0 * a.coverage_rel_diff,
        100.0 * b.coverage_rel_diff,
        100.0 * c.coverage_rel_diff,
    );
    s
}

/// Data-driven observations for one mesh.
fn findings(m: &MeshReport) -> String {
    let mut s = String::new();
    let best_of = |family: &str| {
        m.rows
            .iter()
            .filter(|r| r.config.family == family)
            .min_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse))
    };
    let base = find(m, "combine", BASE_COMBINE.name());
    let Some(base) = base else { return s };
    let _ = writeln!(
        s,
        "- Baseline (128³, ss 4×4, opaque, adaptive 1): RMSE {:.4}, PSNR {:.1} dB, {:.2} s bake, {:.1} MiB; the mesh at 1 spp: RMSE {:.4} ({}).",
        base.mean.rmse,
        base.mean.psnr,
        base.bake_s,
        mib(base.bytes),
        m.raster.rmse,
        if base.mean.rmse < m.raster.rmse {
            format!("the volume is {:.0}% lower", 100.0 * (1.0 - base.mean.rmse / m.raster.rmse))
        } else {
            format!("the volume is {:.0}% higher", 100.0 * (base.mean.rmse / m.raster.rmse - 1.0))
        }
    );
    for family in ["resolution", "supersampling", "combine", "spacing"] {
        if let Some(b) = best_of(family) {
            let worst = m
                .rows
                .iter()
                .filter(|r| r.config.family == family)
                .max_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse))
                .unwrap();
            let _ = writeln!(
                s,
                "- {family}: lowest error {} (RMSE {:.4}), highest {} ({:.4}).",
                b.config.label, b.mean.rmse, worst.config.label, worst.mean.rmse
            );
        }
    }
    s
}

fn report(meshes: &[MeshReport], skipped: &[String], total_s: f64, quick: bool) -> String {
    let mut s = String::new();
    let threads = rayon::current_num_threads();
    s.push_str("# Accuracy against cost\n\n");
    s.push_str(
        "How close a volumetric billboard looks to its source mesh, and what it costs to bake, \
         store and draw, as each bake or render setting varies. **Generated by `make accuracy`** \
         (`examples/accuracy.rs`); do not edit by hand — change the generator and rerun.\n\n",
    );
    let _ = writeln!(
        s,
        "Measured on {} with {threads} threads; the whole sweep took {:.0} s{}.\n",
        cpu_model(),
        total_s,
        if quick {
            " (`--quick`: 64×64, axis views, no 256³)"
        } else {
            ""
        }
    );
    s.push_str("## Method\n\n");
    s.push_str(
        "- **Error**: `billow eval`'s metrics (docs/eval.md): each volume is drawn by the CPU \
         slicer (the paper's §3.3 algorithm, the GPU viewer's reference) and compared with a \
         16-spp ray-traced reference of the mesh, unlit, at 128×128 from all 14 directions of \
         the view set (6 axes, 8 diagonals) at 1×, 4× and 16× the framed distance (42 views; \
         45° field of view; at 16× the object is about 8 pixels wide). RMSE is on premultiplied \
         linear RGBA over the whole image, averaged over the views; PSNR is that of the mean \
         MSE; SSIM on luma; coverage is the relative difference of the summed alpha (+ = the \
         volume is more opaque than the mesh).\n\
         - **Baseline**: 128³ (voxels along the longest axis), 4×4 coverage samples per voxel \
         column, `opaque` combine, adaptive slicing with bias 1 (one pixel's footprint, never \
         finer than a voxel). Each sweep varies one setting from the baseline.\n\
         - **Uniform** spacing is one level-0 voxel at every depth, so it always samples MIP \
         level 0 (what a slicer without distance-dependent MIP selection does).\n\
         - **Costs**: bake = `voxelize` wall time, one run (release build, import excluded); \
         asset = the `.billow` file size; render = CPU slicer wall time per view, the best of \
         three runs (a proxy for the GPU's fill cost; fragments = volume samples shaded per \
         view, the machine-independent measure). The machine is shared, so times of a few \
         milliseconds are noisy; compare fragments for rendering cost.\n\
         - **Mesh, 1 spp**: the same reference renderer with one sample at each pixel centre, \
         i.e. the mesh drawn without anti-aliasing: the error the volume should beat at a \
         distance (the paper's claim).\n\n",
    );
    for m in meshes {
        let _ = writeln!(
            s,
            "## {} (`{}`, {} triangles)\n",
            m.name, m.path, m.triangles
        );
        let _ = writeln!(
            s,
            "![{} accuracy against cost](accuracy/{}.svg)\n",
            m.name,
            m.name.to_lowercase().replace(' ', "_")
        );
        s.push_str(&table(m));
        let _ = writeln!(
            s,
            "\nReference rendering (42 views at 16 spp + 42 at 1 spp): {:.1} s.\n",
            m.reference_s
        );
        s.push_str(&findings(m));
        s.push('\n');
    }
    for sk in skipped {
        let _ = writeln!(s, "- skipped: {sk}");
    }
    if !skipped.is_empty() {
        s.push('\n');
    }
    s.push_str(include_str!("accuracy_advice.md"));
    s
}

fn main() {
    let mut out = PathBuf::from("docs/accuracy.md");
    let mut quick = false;
    for a in std::env::args().skip(1) {
        if a == "--quick" {
            quick = true;
        } else {
            out = PathBuf::from(a);
        }
    }
    let start = Instant::now();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shared = root.join("../shared/assets");
    let oak = "fixtures/oak/eztree_oak_medium.gltf";
    let mut meshes = vec![("Oak".to_string(), root.join(oak), oak.to_string())];
    let mut skipped = Vec::new();
    for (name, rel) in [
        ("Spot", "spot_cow/spot.obj"),
        ("Bunny", "stanford_bunny/bunny.obj"),
    ] {
        let p = shared.join(rel);
        if p.is_file() {
            meshes.push((name.to_string(), p, format!("../shared/assets/{rel}")));
        } else {
            skipped.push(format!(
                "{name}: `../shared/assets/{rel}` not found (run where `../shared` exists)"
            ));
        }
    }
    let mut reports = Vec::new();
    for (name, path, shown) in &meshes {
        match run_mesh(name, path, shown, quick) {
            Ok(r) => reports.push(r),
            Err(e) => {
                eprintln!("{name}: {e}");
                skipped.push(format!("{name}: {e}"));
            }
        }
    }
    let plot_dir = out.parent().unwrap_or(Path::new(".")).join("accuracy");
    std::fs::create_dir_all(&plot_dir).expect("create the plot folder");
    for m in &reports {
        let p = plot_dir.join(format!("{}.svg", m.name.to_lowercase().replace(' ', "_")));
        billow_format::write_atomic(&p, plot(m).as_bytes()).expect("write plot");
    }
    // Relative paths in the report assume the plots sit next to it in `accuracy/`.
    let text = report(&reports, &skipped, start.elapsed().as_secs_f64(), quick);
    billow_format::write_atomic(&out, text.as_bytes()).expect("write report");
    eprintln!(
        "wrote {} and {} plots in {:.0} s",
        out.display(),
        reports.len(),
        start.elapsed().as_secs_f64()
    );
}
