//! The sweep's bakes and their scores: the volume and cloud bakes of a grid of settings on
//! one mesh, each scored like `billow eval`, turned into [`Point`]s; and the counting child
//! that re-runs one bake under callgrind ([`instr`]).

use std::collections::BTreeMap;
use std::time::Instant;

use billow::bbcloud::{bake as bake_cloud, BbcloudOptions};
use billow::compress::{compress_cloud, compress_volume};
use billow::eval::cloud_render::{CloudRenderer, PreparedCloud};
use billow::eval::lighting::Lighting;
use billow::eval::suite::{
    mean_errors, EvalOptions, Evaluator, MeanErrors, PreparedAsset, ReferenceView, ViewResult,
};
use billow::scene::Scene;
use billow::voxelize::{voxelize, CombineFn, Resolution, VoxelizeOptions};
use billow_core::camera::{view_directions, views_of, ViewDirections};
use billow_core::slicing::Spacing;

use super::{instr, Point, DISTANCES, TREE};

fn by_distance(results: &[ViewResult]) -> [f64; 3] {
    DISTANCES.map(|f| {
        mean_errors(
            results
                .iter()
                .filter(|r| r.distance_factor == f)
                .map(|r| &r.asset),
        )
        .rmse
    })
}

fn summarise(results: &[ViewResult], render_s: f64) -> (f64, f64, MeanErrors, [f64; 3]) {
    let n = results.len().max(1) as f64;
    (
        results.iter().map(|r| r.fragments as f64).sum::<f64>() / n,
        render_s / n,
        mean_errors(results.iter().map(|r| &r.asset)),
        by_distance(results),
    )
}

fn references(evaluator: &Evaluator) -> Result<Vec<ReferenceView>, String> {
    views_of(view_directions(ViewDirections::Axes), &DISTANCES)
        .iter()
        .map(|v| evaluator.reference(v))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())
}

/// `billow voxelize`'s bake of foliage at `res`, `ss` (its default `--align`).
fn volume_options(res: u32, ss: u32) -> VoxelizeOptions {
    VoxelizeOptions {
        resolution: Resolution::Longest(res),
        supersample: ss,
        combine: CombineFn::Preset(billow::voxelize::Preset::Opaque),
        normals: false,
        align: 1 << res.trailing_zeros().min(3),
        ..VoxelizeOptions::default()
    }
}

/// A volume baked, optionally compressed, and scored at each bias.
pub(crate) struct VolumeBake {
    res: u32,
    ss: u32,
    bc: bool,
    bake_s: f64,
    bake_instr: Option<u64>,
    bytes: u64,
    /// (bias, fragments/view, render s/view, mean, by distance)
    at: Vec<(f32, f64, f64, MeanErrors, [f64; 3])>,
}

/// The counting child's words for a volume bake (`volume RES SS bc|none`).
fn volume_words(res: u32, ss: u32, bc: bool) -> Vec<String> {
    let c = if bc { "bc" } else { "none" };
    vec!["volume".into(), res.to_string(), ss.to_string(), c.into()]
}

/// The counting child's words for a cloud bake (`cloud ε N ATLAS`).
fn cloud_words(o: &BbcloudOptions) -> Vec<String> {
    vec![
        "cloud".into(),
        o.epsilon.to_string(),
        o.samples.to_string(),
        o.atlas_size.to_string(),
    ]
}

/// A counting child's bake: the volume or the cloud as the sweep bakes it (compressed as
/// the words say), output dropped.
pub(crate) fn count_child(scene: &Scene, words: &[String]) {
    let num = |i: usize| words[i].parse::<u32>().expect("a number");
    match words[0].as_str() {
        "volume" => {
            let volume =
                voxelize(scene, &volume_options(num(1), num(2)), &|_, _| {}).expect("bake");
            let mut asset = volume.into_asset("billow pareto", None, BTreeMap::new());
            if words[3] == "bc" {
                asset.header.set_compress("bc7");
                compress_volume(&mut asset);
            }
        }
        "cloud" => {
            let opts = cloud_options(words[1].parse().expect("ε"), num(2), num(3));
            let (mut asset, _) =
                bake_cloud(scene, &opts, "billow pareto", None, &|_, _| {}).expect("bake");
            asset.header.set_compress("bc7");
            compress_cloud(&mut asset);
        }
        w => panic!("unknown bake {w}"),
    }
}

/// The counting child's mesh: the bundled files, or the generated tree.
pub(crate) fn load(mesh: &str) -> Scene {
    if mesh == TREE {
        billow::procgen::leafy_tree(1500, 9, 1)
    } else {
        instr::imported(mesh)
    }
}

/// Counts the instructions of each bake (`words` of each) on `mesh` when `count`.
fn counts(mesh: &str, count: bool, jobs: &[Vec<String>]) -> Vec<Option<u64>> {
    if !count {
        return vec![None; jobs.len()];
    }
    eprintln!(
        "counting the instructions of {} bakes on {mesh}",
        jobs.len()
    );
    instr::bake_counts(mesh, jobs)
}

fn cloud_options(epsilon: f32, samples: u32, atlas_size: u32) -> BbcloudOptions {
    BbcloudOptions {
        epsilon,
        samples,
        atlas_size,
        ..BbcloudOptions::default()
    }
}

/// The volume bakes of `grid` on `scene` (`mesh`: its name for the counting child),
/// each raw and BC7, scored at each bias.
pub(crate) fn volume_bakes(
    scene: &Scene,
    (mesh, count): (&str, bool),
    size: u32,
    grid: &[(u32, u32)],
    biases: &[f32],
    name: &str,
) -> Result<Vec<VolumeBake>, String> {
    let mut evaluator = Evaluator::new(
        scene,
        EvalOptions {
            width: size,
            height: size,
            raster_1spp: false,
            lighting: Lighting::Unlit,
            ..EvalOptions::default()
        },
    )
    .map_err(|e| e.to_string())?;
    let refs = references(&evaluator)?;
    let mut out = Vec::new();
    for &(res, ss) in grid {
        let t = Instant::now();
        let volume =
            voxelize(scene, &volume_options(res, ss), &|_, _| {}).map_err(|e| e.to_string())?;
        let raw = volume.into_asset("billow pareto", None, BTreeMap::new());
        let bake_s = t.elapsed().as_secs_f64();
        for bc in [false, true] {
            let mut asset = raw.clone();
            let t = Instant::now();
            let blocks = bc.then(|| {
                asset.header.set_compress("bc7");
                compress_volume(&mut asset)
            });
            let compress_s = t.elapsed().as_secs_f64();
            let bytes = asset
                .to_bytes_with(blocks.as_ref())
                .map_err(|e| e.to_string())?
                .len() as u64;
            let prepared = PreparedAsset::new(&asset).map_err(|e| e.to_string())?;
            let mut at = Vec::new();
            for &bias in biases {
                evaluator.options.slicer.spacing = Spacing::Adaptive { bias };
                // The machine is shared: the faster of two renders.
                let mut best = f64::INFINITY;
                let mut results = Vec::new();
                for _ in 0..2 {
                    results = refs
                        .iter()
                        .map(|r| evaluator.asset(&prepared, r).map(|x| x.0))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|e| e.to_string())?;
                    best = best.min(results.iter().map(|r| r.seconds.asset).sum::<f64>());
                }
                let (fr, rs, mean, bd) = summarise(&results, best);
                eprintln!(
                    "{name}: {res}³ ss {ss} {} bias {bias}: rmse {:.4} {:.2} MiB",
                    if bc { "bc" } else { "none" },
                    mean.rmse,
                    bytes as f64 / 1048576.0
                );
                at.push((bias, fr, rs, mean, bd));
            }
            out.push(VolumeBake {
                res,
                ss,
                bc,
                bake_s: bake_s + compress_s,
                bake_instr: None,
                bytes,
                at,
            });
        }
    }
    let jobs: Vec<Vec<String>> = out
        .iter()
        .map(|b| volume_words(b.res, b.ss, b.bc))
        .collect();
    for (b, n) in out.iter_mut().zip(counts(mesh, count, &jobs)) {
        b.bake_instr = n;
    }
    Ok(out)
}

pub(crate) fn volume_points(bakes: &[VolumeBake]) -> Vec<Point> {
    let mut pts = Vec::new();
    for b in bakes {
        for &(bias, fr, rs, mean, bd) in &b.at {
            let c = if b.bc { "bc" } else { "none" };
            pts.push(Point {
                group: format!("{}³", b.res),
                hollow: b.bc,
                label: format!("{}³ ss{} {c} b{bias}", b.res, b.ss),
                bake_s: b.bake_s,
                bake_instr: b.bake_instr,
                bytes: b.bytes,
                fragments: fr,
                render_s: rs,
                mean,
                by_distance: bd,
                extra: vec![
                    format!("{}³", b.res),
                    format!("{0}×{0}", b.ss),
                    c.to_string(),
                    format!("{bias}"),
                ],
                subset: (bias == 1.0).then_some(c),
            });
        }
    }
    pts
}

/// A cloud baked as `billow bbcloud` writes it (BC7) and scored at LOD 0.
pub(crate) struct CloudBake {
    opts: BbcloudOptions,
    bake_s: f64,
    bake_instr: Option<u64>,
    bytes: u64,
    billboards: u64,
    density: f32,
    fragments: f64,
    render_s: f64,
    mean: MeanErrors,
    by_distance: [f64; 3],
}

pub(crate) fn cloud_bakes(
    scene: &Scene,
    (mesh, count): (&str, bool),
    size: u32,
    grid: &[(f32, u32, u32)],
    name: &str,
) -> Result<Vec<CloudBake>, String> {
    let lighting = Lighting::for_cloud(&billow::bbcloud::params(&BbcloudOptions::default()))?;
    let evaluator = Evaluator::new(
        scene,
        EvalOptions {
            width: size,
            height: size,
            raster_1spp: false,
            lighting,
            ..EvalOptions::default()
        },
    )
    .map_err(|e| e.to_string())?;
    let refs = references(&evaluator)?;
    let mut out = Vec::new();
    for &(epsilon, samples, atlas_size) in grid {
        let opts = cloud_options(epsilon, samples, atlas_size);
        let t = Instant::now();
        let (mut asset, _) = bake_cloud(scene, &opts, "billow pareto", None, &|_, _| {})
            .map_err(|e| e.to_string())?;
        asset.header.set_compress("bc7");
        let blocks = compress_cloud(&mut asset);
        let bake_s = t.elapsed().as_secs_f64();
        let bytes = asset
            .to_bytes_with(Some(&blocks))
            .map_err(|e| e.to_string())?
            .len() as u64;
        let prepared = PreparedCloud::new(&asset).map_err(|e| e.to_string())?;
        let renderer = CloudRenderer::new(&prepared, lighting).map_err(|e| e.to_string())?;
        let results = refs
            .iter()
            .map(|r| evaluator.cloud(&renderer, &prepared, 0, r).map(|x| x.0))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        let render = results.iter().map(|r| r.seconds.asset).sum::<f64>();
        let (fragments, render_s, mean, by_distance) = summarise(&results, render);
        eprintln!(
            "{name}: cloud ε {epsilon} N {samples} atlas {atlas_size}: rmse {:.4}, {} billboards, {:.1} s",
            mean.rmse, asset.levels[0].billboard_count, bake_s
        );
        out.push(CloudBake {
            billboards: u64::from(asset.levels[0].billboard_count),
            density: prepared.texel_density(0),
            opts,
            bake_s,
            bake_instr: None,
            bytes,
            fragments,
            render_s,
            mean,
            by_distance,
        });
    }
    let jobs: Vec<Vec<String>> = out.iter().map(|b| cloud_words(&b.opts)).collect();
    for (b, n) in out.iter_mut().zip(counts(mesh, count, &jobs)) {
        b.bake_instr = n;
    }
    Ok(out)
}

pub(crate) fn cloud_points(bakes: &[CloudBake]) -> Vec<Point> {
    bakes
        .iter()
        .map(|b| Point {
            group: format!("ε {}", b.opts.epsilon),
            hollow: b.opts.samples < 500,
            label: format!(
                "ε{} N{} {}²",
                b.opts.epsilon, b.opts.samples, b.opts.atlas_size
            ),
            bake_s: b.bake_s,
            bake_instr: b.bake_instr,
            bytes: b.bytes,
            fragments: b.fragments,
            render_s: b.render_s,
            mean: b.mean,
            by_distance: b.by_distance,
            extra: vec![
                format!("{}", b.opts.epsilon),
                b.opts.samples.to_string(),
                format!("{}²", b.opts.atlas_size),
                format!("{:.2}", b.density),
                b.billboards.to_string(),
            ],
            subset: None,
        })
        .collect()
}
