//! The billboard-cloud sweep on the oak: error against bake time and texture bytes for
//! ε (`--epsilon`), N (`--samples`) and the texel density, one at a time from the default
//! bake; and a 4-level LOD chain (Lacewell et al. 2006, Figures 4–5): billboards per level
//! and each level's error against the viewing distance.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use billow::bbcloud::{bake, BbcloudOptions};
use billow::eval::cloud_render::{CloudRenderer, PreparedCloud};
use billow::eval::lighting::Lighting;
use billow::eval::suite::{
    mean_errors, EvalOptions, Evaluator, MeanErrors, ReferenceView, ViewResult,
};
use billow::import::{import, ImportOptions};
use billow_core::camera::{view_directions, views_of, ViewDirections, ViewSpec};
use billow_format::CloudAsset;

use crate::plot::{charts_svg, Chart, Series};

const COLOURS: [&str; 6] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
];
/// Distances of the LOD figure (multiples of the framed distance).
const CHAIN_DISTANCES: [f32; 6] = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
const CHAIN_LODS: u32 = 4;

/// One bake of the sweep, rendered at LOD 0.
pub(crate) struct CloudRow {
    family: &'static str,
    label: String,
    bake_s: f64,
    /// Instructions of the bake, import excluded, one thread ([`crate::instr`]); `None`
    /// where callgrind could not count (and with `--quick`).
    bake_instr: Option<u64>,
    /// LOD 0's atlases, all MIP levels.
    texture_bytes: u64,
    billboards: usize,
    density: f32,
    render_s: f64,
    /// Billboard fragments shaded per view (mean; load-independent render cost).
    fragments: f64,
    mean: MeanErrors,
    by_distance: Vec<(f32, MeanErrors)>,
}

/// One level of the LOD chain.
pub(crate) struct ChainLevel {
    lod: usize,
    billboards: usize,
    epsilon: f32,
    density: f32,
    texture_bytes: u64,
    by_distance: Vec<(f32, MeanErrors)>,
}

pub(crate) struct CloudReport {
    path: String,
    rows: Vec<CloudRow>,
    chain: Vec<ChainLevel>,
    raster_by_distance: Vec<(f32, MeanErrors)>,
    views: usize,
    size: u32,
    reference_s: f64,
    total_s: f64,
}

fn by_distance(results: &[ViewResult], factors: &[f32]) -> Vec<(f32, MeanErrors)> {
    factors
        .iter()
        .map(|&f| {
            let e = results
                .iter()
                .filter(|r| r.distance_factor == f)
                .map(|r| &r.asset);
            (f, mean_errors(e))
        })
        .collect()
}

/// The counting child's words for a bake of `o` (`cloud ε N DENSITY|budget`): the knobs
/// [`configs`] turns, read back by [`count_child`].
fn words(o: &BbcloudOptions) -> Vec<String> {
    vec![
        "cloud".into(),
        o.epsilon.to_string(),
        o.samples.to_string(),
        o.texel_density
            .map_or_else(|| "budget".to_string(), |d| d.to_string()),
    ]
}

/// A counting child's bake ([`words`], [`crate::instr`]).
pub(crate) fn count_child(scene: &billow::scene::Scene, words: &[String]) {
    let opts = BbcloudOptions {
        epsilon: words[0].parse().expect("ε"),
        samples: words[1].parse().expect("N"),
        texel_density: (words[2] != "budget").then(|| words[2].parse().expect("a density")),
        ..BbcloudOptions::default()
    };
    bake(scene, &opts, "billow accuracy", None, &|_, _| {}).expect("bake");
}

fn configs() -> Vec<(&'static str, String, BbcloudOptions)> {
    let base = BbcloudOptions::default();
    let mut out = Vec::new();
    for e in [0.01f32, 0.02, 0.04, 0.08, 0.16] {
        let label = format!("ε {e}{}", if e == base.epsilon { " (default)" } else { "" });
        out.push((
            "epsilon",
            label,
            BbcloudOptions {
                epsilon: e,
                ..base.clone()
            },
        ));
    }
    for n in [25u32, 100, 500, 2000] {
        let label = format!("N {n}{}", if n == base.samples { " (default)" } else { "" });
        out.push((
            "samples",
            label,
            BbcloudOptions {
                samples: n,
                ..base.clone()
            },
        ));
    }
    out.push(("texel density", "budget (default)".into(), base.clone()));
    for d in [1.0f32, 2.0, 4.0, 6.0] {
        let o = BbcloudOptions {
            texel_density: Some(d),
            ..base.clone()
        };
        out.push(("texel density", format!("{d} texels/unit"), o));
    }
    out
}

/// Bakes, renders and compares everything for the mesh at `path` (the oak).
pub(crate) fn run(
    path: &Path,
    shown: &str,
    quick: bool,
    count: bool,
) -> Result<CloudReport, String> {
    let start = Instant::now();
    let scene = import(path, &ImportOptions::default())
        .map_err(|e| e.to_string())?
        .scene;
    let size = if quick { 64 } else { 128 };
    let lighting = Lighting::for_cloud(&billow::bbcloud::params(&BbcloudOptions::default()))?;
    let evaluator = Evaluator::new(
        &scene,
        EvalOptions {
            width: size,
            height: size,
            lighting,
            ..EvalOptions::default()
        },
    )
    .map_err(|e| e.to_string())?;
    let dirs = view_directions(ViewDirections::Axes);
    let sweep_views = views_of(dirs.clone(), &[1.0, 4.0, 16.0]);
    let chain_views: Vec<ViewSpec> = views_of(dirs, &CHAIN_DISTANCES);
    let t = Instant::now();
    let refs = |views: &[ViewSpec]| -> Result<Vec<ReferenceView>, String> {
        views
            .iter()
            .map(|v| evaluator.reference(v))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())
    };
    let chain_refs = refs(&chain_views)?;
    // The sweep's views are a subset of the chain's.
    let sweep_refs: Vec<&ReferenceView> = chain_refs
        .iter()
        .filter(|r| sweep_views.iter().any(|v| v.name == r.spec.name))
        .collect();
    let reference_s = t.elapsed().as_secs_f64();
    let eval = |asset: &CloudAsset, lod: usize, refs: &[&ReferenceView]| {
        let prepared = PreparedCloud::new(asset).map_err(|e| e.to_string())?;
        let renderer = CloudRenderer::new(&prepared, lighting).map_err(|e| e.to_string())?;
        let results: Vec<ViewResult> = refs
            .iter()
            .map(|r| evaluator.cloud(&renderer, &prepared, lod, r).map(|x| x.0))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        let bytes = prepared.texture_bytes(asset, lod);
        Ok::<_, String>((results, bytes, prepared.texel_density(lod)))
    };
    let mut rows = Vec::new();
    // Each row's bake, in the counting child's words (the rows share the default's).
    let mut row_keys = Vec::new();
    let mut cache: BTreeMap<Vec<String>, (CloudAsset, f64)> = BTreeMap::new();
    for (family, label, opts) in configs() {
        let key = words(&opts);
        if !cache.contains_key(&key) {
            eprintln!("cloud: baking {label}");
            let t = Instant::now();
            let (asset, _) = bake(&scene, &opts, "billow accuracy", None, &|_, _| {})
                .map_err(|e| e.to_string())?;
            cache.insert(key.clone(), (asset, t.elapsed().as_secs_f64()));
        }
        let (asset, bake_s) = &cache[&key];
        let (results, texture_bytes, density) = eval(asset, 0, &sweep_refs)?;
        let row = CloudRow {
            family,
            label,
            bake_s: *bake_s,
            bake_instr: None,
            texture_bytes,
            billboards: asset.levels[0].billboard_count as usize,
            density,
            render_s: results.iter().map(|r| r.seconds.asset).sum::<f64>() / results.len() as f64,
            fragments: results.iter().map(|r| r.fragments as f64).sum::<f64>()
                / results.len() as f64,
            mean: mean_errors(results.iter().map(|r| &r.asset)),
            by_distance: by_distance(&results, &[1.0, 4.0, 16.0]),
        };
        eprintln!(
            "cloud: {:<22} rmse {:.4} {} billboards",
            row.label, row.mean.rmse, row.billboards
        );
        rows.push(row);
        row_keys.push(key);
    }
    if count {
        let jobs: Vec<Vec<String>> = cache.keys().cloned().collect();
        eprintln!("cloud: counting the instructions of {} bakes", jobs.len());
        let counts = crate::instr::bake_counts(&path.display().to_string(), &jobs);
        for (row, key) in rows.iter_mut().zip(&row_keys) {
            row.bake_instr = jobs.iter().position(|j| j == key).and_then(|i| counts[i]);
        }
    }
    eprintln!("cloud: baking the {CHAIN_LODS}-level chain");
    let opts = BbcloudOptions {
        lods: CHAIN_LODS,
        ..BbcloudOptions::default()
    };
    let (asset, _) =
        bake(&scene, &opts, "billow accuracy", None, &|_, _| {}).map_err(|e| e.to_string())?;
    let all: Vec<&ReferenceView> = chain_refs.iter().collect();
    let mut chain = Vec::new();
    for (lod, l) in asset.levels.iter().enumerate() {
        let (results, texture_bytes, density) = eval(&asset, lod, &all)?;
        chain.push(ChainLevel {
            lod,
            billboards: l.billboard_count as usize,
            epsilon: l.epsilon,
            density,
            texture_bytes,
            by_distance: by_distance(&results, &CHAIN_DISTANCES),
        });
    }
    let raster_by_distance = CHAIN_DISTANCES
        .iter()
        .map(|&f| {
            let e = chain_refs
                .iter()
                .filter(|r| r.spec.distance_factor == f)
                .filter_map(|r| r.raster_1spp.as_ref().map(|x| &x.1));
            (f, mean_errors(e))
        })
        .collect();
    Ok(CloudReport {
        path: shown.to_string(),
        rows,
        chain,
        raster_by_distance,
        views: sweep_refs.len(),
        size,
        reference_s,
        total_s: start.elapsed().as_secs_f64(),
    })
}

/// The sweep plot (error against bake time and texture bytes) and the LOD figure.
pub(crate) fn plots(r: &CloudReport) -> (String, String) {
    let families = ["epsilon", "samples", "texel density"];
    let series = |x: fn(&CloudRow) -> f64| -> Vec<Series> {
        families
            .iter()
            .enumerate()
            .map(|(i, f)| Series {
                name: f.to_string(),
                colour: COLOURS[i],
                points: r
                    .rows
                    .iter()
                    .filter(|row| row.family == *f)
                    .map(|row| (x(row), row.mean.rmse, row.label.replace(" (default)", "*")))
                    .collect(),
                dashed: false,
            })
            .collect()
    };
    let chart = |x_label: &str, x: fn(&CloudRow) -> f64| Chart {
        x_label: x_label.into(),
        y_label: "mean RMSE".into(),
        log_x: true,
        log_y: false,
        series: series(x),
    };
    let counted = r.rows.iter().all(|row| row.bake_instr.is_some());
    let bake = if counted {
        chart("bake instructions (callgrind, one thread)", |r| {
            r.bake_instr.unwrap_or(0) as f64
        })
    } else {
        chart("bake time (s)", |r| r.bake_s)
    };
    let sweep = charts_svg(
        "Oak billboard cloud (LOD 0): mean RMSE against cost — * = default",
        &[
            bake,
            chart("texture bytes (LOD 0 atlases with MIPs)", |r| {
                r.texture_bytes as f64
            }),
            chart("fragments shaded per view (CPU cloud renderer)", |r| {
                r.fragments
            }),
        ],
    );
    let counts = Chart {
        x_label: "LOD level".into(),
        y_label: "billboards".into(),
        log_x: false,
        log_y: false,
        series: vec![Series {
            name: "billboards per level".into(),
            colour: COLOURS[0],
            points: r
                .chain
                .iter()
                .map(|l| (l.lod as f64, l.billboards as f64, l.billboards.to_string()))
                .collect(),
            dashed: false,
        }],
    };
    let mut err_series: Vec<Series> = r
        .chain
        .iter()
        .map(|l| Series {
            name: format!("LOD {} ({} billboards)", l.lod, l.billboards),
            colour: COLOURS[(l.lod + 1) % COLOURS.len()],
            points: l
                .by_distance
                .iter()
                .map(|d| (f64::from(d.0), d.1.rmse, String::new()))
                .collect(),
            dashed: false,
        })
        .collect();
    err_series.push(Series {
        name: "mesh, 1 spp".into(),
        colour: "#555",
        points: r
            .raster_by_distance
            .iter()
            .map(|d| (f64::from(d.0), d.1.rmse, String::new()))
            .collect(),
        dashed: true,
    });
    let errors = Chart {
        x_label: "distance (× framed)".into(),
        y_label: "mean RMSE".into(),
        log_x: true,
        log_y: true,
        series: err_series,
    };
    let lods = charts_svg(
        "Oak LOD chain (after Lacewell et al. Figs. 4–5): billboards per level, error per level against distance",
        &[counts, errors],
    );
    (sweep, lods)
}

/// The markdown section.
pub(crate) fn section(r: &CloudReport) -> String {
    let mut s = String::new();
    let mib = |b: u64| b as f64 / f64::from(1u32 << 20);
    let _ = writeln!(s, "## Oak as a billboard cloud (`{}`)\n", r.path);
    let _ = writeln!(
        s,
        "Baked with `billow bbcloud` (the library's `bbcloud::bake`), lit as by default \
         (ambient 0.35 + diffuse), and drawn by the CPU cloud renderer (`src/eval/cloud_render.rs`, \
         docs/eval.md) against the ambient + diffuse reference, {} views ({}×{}, the 6 axis \
         directions at 1×, 4× and 16×, 16 spp). One setting varies at a time from the default \
         (ε = 0.04 radii, N = 500, texel density from the 2048² atlas budget); LOD 0 only. \
         Bake = wall time of one bake (release, import excluded) and its instructions \
         (G = 10⁹; callgrind, one thread, import excluded: `examples/common/instr.rs`; \
         unlike the time, the same on a loaded machine); texture bytes = LOD 0's atlases \
         with their MIP chains; fragments = billboard samples shaded per view (the CPU \
         renderer's load-independent cost); render = CPU cloud renderer per view. \
         The whole cloud part took {:.0} s (reference {:.1} s).\n",
        r.views, r.size, r.size, r.total_s, r.reference_s
    );
    s.push_str("![Oak cloud accuracy against cost](accuracy/oak_cloud.svg)\n\n");
    s.push_str("| sweep | setting | bake s | bake G instr. | billboards | texels/unit | texture MiB | fragments/view | render s/view | RMSE | PSNR dB | SSIM | FLIP | RMSE 1× / 4× / 16× | covered RMSE 1× / 4× / 16× | coverage 1× / 4× / 16× |\n");
    s.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|\n");
    for row in &r.rows {
        let d = |i: usize| row.by_distance.get(i).map(|x| x.1).unwrap_or_default();
        let instr = crate::instr::giga(row.bake_instr);
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {instr} | {} | {:.2} | {:.1} | {:.0} | {:.2} | {:.4} | {:.2} | {:.3} | {:.4} | {:.4} / {:.4} / {:.4} | {:.4} / {:.4} / {:.4} | {:+.0}% / {:+.0}% / {:+.0}% |",
            row.family, row.label, row.bake_s, row.billboards, row.density, mib(row.texture_bytes),
            row.fragments, row.render_s, row.mean.rmse, row.mean.psnr, row.mean.ssim_luma, row.mean.flip,
            d(0).rmse, d(1).rmse, d(2).rmse,
            d(0).rmse_covered, d(1).rmse_covered, d(2).rmse_covered,
            100.0 * d(0).coverage_rel_diff, 100.0 * d(1).coverage_rel_diff, 100.0 * d(2).coverage_rel_diff
        );
    }
    let _ = writeln!(
        s,
        "\n### LOD chain\n\n`--lods {CHAIN_LODS}` (ε doubles per level, textures halve, the last \
         level is the two-billboard cross), every level drawn at every distance (the 6 axis \
         directions each), as in Lacewell et al.'s Figures 4–5.\n"
    );
    s.push_str("![Oak LOD chain](accuracy/oak_lods.svg)\n\n");
    let head: Vec<String> = CHAIN_DISTANCES.iter().map(|d| format!("{d}×")).collect();
    let _ = writeln!(
        s,
        "| level | billboards | ε (world) | texels/unit | texture MiB | RMSE {} |",
        head.join(" / ")
    );
    s.push_str("|---|---:|---:|---:|---:|---|\n");
    let cells = |v: &[(f32, MeanErrors)]| -> String {
        v.iter()
            .map(|d| format!("{:.4}", d.1.rmse))
            .collect::<Vec<_>>()
            .join(" / ")
    };
    for l in &r.chain {
        let _ = writeln!(
            s,
            "| LOD {} | {} | {:.2} | {:.3} | {:.2} | {} |",
            l.lod,
            l.billboards,
            l.epsilon,
            l.density,
            mib(l.texture_bytes),
            cells(&l.by_distance)
        );
    }
    let _ = writeln!(
        s,
        "| mesh, 1 spp | – | – | – | – | {} |\n",
        cells(&r.raster_by_distance)
    );
    // Data-driven observations.
    for (i, &f) in CHAIN_DISTANCES.iter().enumerate() {
        let best = r
            .chain
            .iter()
            .min_by(|a, b| a.by_distance[i].1.rmse.total_cmp(&b.by_distance[i].1.rmse));
        if let Some(b) = best {
            let _ = write!(
                s,
                "{}at {f}×: lowest error LOD {} ({} billboards)",
                if i == 0 { "- Per distance, " } else { "; " },
                b.lod,
                b.billboards
            );
        }
    }
    s.push_str(".\n");
    for f in ["epsilon", "samples", "texel density"] {
        let rows: Vec<&CloudRow> = r.rows.iter().filter(|x| x.family == f).collect();
        let best = rows
            .iter()
            .min_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse));
        let worst = rows
            .iter()
            .max_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse));
        if let (Some(b), Some(w)) = (best, worst) {
            let _ = writeln!(
                s,
                "- {f}: lowest error {} (RMSE {:.4}, {} billboards, {:.2} s bake), highest {} ({:.4}).",
                b.label, b.mean.rmse, b.billboards, b.bake_s, w.label, w.mean.rmse
            );
        }
    }
    s.push('\n');
    s
}
