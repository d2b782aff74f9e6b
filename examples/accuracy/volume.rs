//! The volume sweep: one setting at a time varied from the baseline, every volume
//! rendered from every view of the evaluation set and compared with the reference.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use billow::eval::suite::{
    mean_errors, means_by_distance, EvalOptions, Evaluator, MeanErrors, PreparedAsset,
    ReferenceView, ViewResult,
};
use billow::import::{import, ImportOptions};
use billow::voxelize::{voxelize, CombineFn, Preset, Resolution, VoxelizeOptions};
use billow_core::camera::{view_set, ViewDirections};
use billow_core::slicing::Spacing;
use billow_format::VolumeAsset;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SpacingKind {
    Adaptive(f32),
    /// Multiples of the level-0 voxel.
    Uniform(f32),
}

#[derive(Clone, Debug)]
pub(crate) struct Config {
    pub(crate) family: &'static str,
    pub(crate) label: String,
    pub(crate) res: u32,
    pub(crate) ss: u32,
    pub(crate) combine: Preset,
    pub(crate) spacing: SpacingKind,
}

pub(crate) const BASE_RES: u32 = 128;
pub(crate) const BASE_SS: u32 = 4;
pub(crate) const BASE_COMBINE: Preset = Preset::Opaque;
/// Each configuration is rendered this many times; the fastest run's time is reported.
pub(crate) const RENDER_REPEATS: usize = 3;

pub(crate) fn configs(quick: bool) -> Vec<Config> {
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
pub(crate) struct Row {
    pub(crate) config: Config,
    pub(crate) bake_s: f64,
    /// Instructions of the bake, import excluded, one thread ([`crate::instr`]); `None`
    /// where callgrind could not count (and with `--quick`).
    pub(crate) bake_instr: Option<u64>,
    pub(crate) bytes: u64,
    /// Mean slicer seconds per view.
    pub(crate) render_s: f64,
    pub(crate) slices: f64,
    pub(crate) fragments: f64,
    pub(crate) mean: MeanErrors,
    /// (factor, asset means) per distance.
    pub(crate) by_distance: Vec<(f32, MeanErrors)>,
}

pub(crate) struct MeshReport {
    pub(crate) name: String,
    pub(crate) path: String,
    pub(crate) triangles: usize,
    pub(crate) reference_s: f64,
    pub(crate) raster: MeanErrors,
    pub(crate) raster_by_distance: Vec<(f32, MeanErrors)>,
    pub(crate) rows: Vec<Row>,
}

pub(crate) fn bake(
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

pub(crate) fn run_mesh(
    name: &str,
    path: &Path,
    shown: &str,
    quick: bool,
    count: bool,
) -> Result<MeshReport, String> {
    eprintln!("{name}: importing {}", path.display());
    let scene = import(path, &ImportOptions::default())
        .map_err(|e| e.to_string())?
        .scene;
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
            bake_instr: None,
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
    if count {
        let keys: Vec<(u32, u32, Preset)> = cache
            .keys()
            .map(|&(res, ss, c)| (res, ss, preset(c)))
            .collect();
        eprintln!("{name}: counting the instructions of {} bakes", keys.len());
        let jobs: Vec<Vec<String>> = keys
            .iter()
            .map(|&(res, ss, c)| {
                vec![
                    "volume".into(),
                    res.to_string(),
                    ss.to_string(),
                    c.name().to_string(),
                ]
            })
            .collect();
        let counts = crate::instr::bake_counts(&path.display().to_string(), &jobs);
        for r in &mut rows {
            let key = (r.config.res, r.config.ss, r.config.combine);
            r.bake_instr = keys.iter().position(|k| *k == key).and_then(|i| counts[i]);
        }
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

/// A counting child's bake (`volume RES SS COMBINE`, [`crate::instr`]).
pub(crate) fn count_child(scene: &billow::scene::Scene, words: &[String]) {
    let num = |i: usize| words[i].parse::<u32>().expect("a number");
    bake(scene, num(0), num(1), preset(&words[2])).expect("bake");
}

pub(crate) fn preset(name: &str) -> Preset {
    [Preset::Mean, Preset::Max, Preset::Min, Preset::Opaque]
        .into_iter()
        .find(|p| p.name() == name)
        .expect("a combine preset's name")
}
