//! `billow eval SOURCE ASSET`: how close a volume or billboard-cloud asset looks to its
//! source mesh, view by view, against a supersampled ray-traced reference (docs/eval.md).
//! Volumes here, clouds in [`cloud`]; the flags' parsing in [`parse`], the table on
//! stdout in [`table`] (each uses this file's `Args` and JSON records, one way).

mod cloud;
mod parse;
mod table;

pub(crate) use parse::{bad, parse_lights, spp_per_axis};
pub use parse::{parse_distances, parse_size, parse_spacing, parse_views};
use table::print_table;

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::eval::evaluate;
use billow::eval::evaluate::{
    Asset, EvaluateError, EvaluateHooks, EvaluateOptions, EvaluateProgress, Evaluation,
    LightResult, ReferenceLighting, ViewImages, MAX_REFERENCE_SAMPLES,
    REFERENCE_SAMPLES_PER_SECOND,
};
use billow::eval::image::comparisons_png_bytes;
use billow::eval::lighting::EvalLight;
use billow::eval::suite::{
    view_file_stem, DistanceMeans, LightMeans, MeanErrors, ViewResult, EVAL_FOV_Y,
};
use billow::import::{import, ImportOptions, Imported};
use billow_format::{read_file, Container};
use serde::Serialize;

use crate::exit::{CliError, Code};
use crate::output::{print_json, progress, refuse_file_as_folder, warn};
use crate::staged::{out_err, Staged};
use crate::Ctx;

/// Heatmap gain of the difference panels: a difference of 1/4 or more is white.
pub(crate) const DIFF_GAIN: f32 = 4.0;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The source mesh (.gltf, .glb, .obj): the reference is ray-traced from it.
    source: PathBuf,
    /// The asset (.billow) baked from it: a volume or a billboard cloud.
    asset: PathBuf,
    /// Which views: axes (±x ±y ±z), diagonals (the 8 corners), all, or a comma list of
    /// directions (`+x`, `-y`, `+x-y+z`) and exact views (`+x@4x`). Write `--views=-z`
    /// when the list starts with a minus sign.
    #[arg(long, default_value = "axes")]
    views: String,
    /// Distance factors: multiples of the framed distance (the mesh's bounding sphere just
    /// fills the image), each in (0, 1000]; the image size stays the same.
    #[arg(long, default_value = "1,4,16")]
    distances: String,
    /// Image size WxH in pixels, each side 1–4096.
    #[arg(long, default_value = "128x128")]
    size: String,
    /// Reference samples per pixel at the framed distance: a square number (1, 4, 9, 16, …, 256), stratified; f× farther takes f² times as many, up to 256.
    #[arg(long, default_value_t = 16)]
    spp: u32,
    /// Slice spacing of the asset render: adaptive (the paper: one pixel's footprint, never
    /// finer than a voxel), adaptive:BIAS (spacing × BIAS), or uniform[:VOXELS] (a constant
    /// spacing of VOXELS level-0 voxels, default 1, which always samples MIP level 0).
    #[arg(long, default_value = "adaptive")]
    spacing: String,
    /// Write one comparison image per view here (reference | asset | difference | 1-spp
    /// mesh | difference) and eval.json; created if missing. Written atomically.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Lighting of the reference when no --light/--lights is given: auto (the lighting the
    /// asset was baked with: its baked AO at each hit point, or unlit) or unlit (the asset
    /// drawn unlit too: a volume's normals unused).
    #[arg(long, value_enum, default_value_t = LightingArg::Auto)]
    lighting: LightingArg,
    /// Light the reference and the asset by this light, as `billow view` lights each kind:
    /// the mesh with the viewer's two-sided Lambert, a volume with normals by them, a volume
    /// without normals or a baked cloud by their baked colour. X,Y,Z points towards the light.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, conflicts_with_all = ["lights", "lighting"])]
    light: Option<String>,
    /// A set of lights, each evaluated like --light, and the mean over the set: `standard`
    /// (overhead, a low sun from east and west, below; docs/eval.md) or a list
    /// `NAME=X,Y,Z;X,Y,Z;…`.
    #[arg(
        long,
        value_name = "SET",
        allow_hyphen_values = true,
        conflicts_with = "lighting"
    )]
    lights: Option<String>,
    /// Ambient fraction of --light/--lights, 0–1.
    #[arg(long, value_name = "A", default_value_t = billow_core::shading::DEFAULT_AMBIENT)]
    ambient: f32,
    /// With --light/--lights: shadows in the reference (ray traced towards the light), in
    /// the cloud's kept mesh and in a plain volume (its own transmittance towards the
    /// light); pruned and shell volumes are drawn unshadowed (noted).
    #[arg(long)]
    shadows: bool,
    /// Billboard clouds: evaluate only this LOD level, 0–(levels − 1) (0 = finest); default all levels.
    #[arg(long, value_name = "K")]
    lod: Option<usize>,
    /// Treat import warnings (e.g. a missing texture) as errors.
    #[arg(long)]
    strict: bool,
    /// Print one machine-readable JSON document on stdout instead of the table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightingArg {
    Auto,
    Unlit,
}

#[derive(Serialize)]
pub(crate) struct Seconds {
    import: f64,
    read_asset: f64,
    reference: f64,
    asset: f64,
    raster_1spp: f64,
    total: f64,
}

#[derive(Serialize)]
pub(crate) struct LightingJson {
    /// The asset's `bake` parameter (`none` when absent).
    asset: String,
    /// `unlit` or `ao` (see `--lighting`).
    reference: &'static str,
    /// The reference lighting with its parameters.
    reference_details: String,
}

#[derive(Serialize)]
pub(crate) struct Means {
    asset: MeanErrors,
    raster_1spp: MeanErrors,
}

#[derive(Serialize)]
struct Summary {
    source: String,
    asset: String,
    asset_dims: [u32; 3],
    asset_params: std::collections::BTreeMap<String, String>,
    /// Texture bytes `billow view` holds for the asset on a device that samples BC7
    /// blocks, and on one that does not (`billow_core::gpu_memory`).
    gpu_bytes: u64,
    gpu_bytes_no_bc: u64,
    size: [u32; 2],
    fov_y_degrees: f32,
    reference_spp: u32,
    spacing: String,
    lighting: LightingJson,
    notes: Vec<String>,
    views: Vec<ViewResult>,
    mean: Means,
    by_distance: Vec<DistanceMeans>,
    /// With --light/--lights: each light and its means (`mean` is then over the set).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    lights: Vec<LightJson>,
    slices: usize,
    fragments: u64,
    seconds: Seconds,
    images: Vec<String>,
}

/// One light of `--light`/`--lights` in the JSON, with its means.
#[derive(Serialize)]
pub(crate) struct LightJson {
    name: String,
    dir: [f32; 3],
    ambient: f32,
    #[serde(flatten)]
    means: LightMeans,
}

/// The lights' JSON entries (empty without `--light`/`--lights`).
pub(crate) fn lights_json(by_light: Vec<LightResult>) -> Vec<LightJson> {
    by_light
        .into_iter()
        .map(|l| LightJson {
            name: l.light.name,
            dir: l.light.dir.to_array(),
            ambient: l.light.ambient,
            means: l.means,
        })
        .collect()
}

/// The `--out` image name of a view under a light (`overhead_pz_1x`), or of the view alone.
pub(crate) fn image_stem(light: Option<&EvalLight>, view: &str) -> String {
    match light {
        Some(l) => view_file_stem(&format!("{}_{view}", l.name)),
        None => view_file_stem(view),
    }
}

/// Reads an asset's container (Volume or Cloud; a newer format is exit 5).
pub fn read_asset(path: &Path) -> Result<Container, CliError> {
    read_file(path).map_err(|e| CliError::new(Code::from(&e), e))
}

/// The source mesh, imported (warnings printed).
pub(crate) fn import_source(args: &Args, ctx: &Ctx) -> Result<Imported, CliError> {
    let imported = import(
        &args.source,
        &ImportOptions {
            strict: args.strict,
        },
    )
    .map_err(|e| CliError::new(Code::from(&e), &e))?;
    for w in &imported.report.warnings {
        warn(ctx, &format!("{}: {}", args.source.display(), w.message));
    }
    Ok(imported)
}

/// The `--out` folder's files, staged: written as the views are rendered, renamed into
/// place together (eval.json last) when all are there ([`finish_out`]).
pub(crate) fn create_out(args: &Args) -> Result<Option<Staged>, CliError> {
    let Some(dir) = &args.out else {
        return Ok(None);
    };
    let mut stage = Staged::new(&dir.join("eval.json"));
    stage.create_dir(dir).map_err(|e| {
        CliError::new(
            Code::OutputIo,
            format!("{}: cannot create folder: {e}", dir.display()),
        )
    })?;
    Ok(Some(stage))
}

/// Stages one comparison image of `--out`.
pub(crate) fn stage_png(
    stage: &mut Option<Staged>,
    path: &Path,
    reference: &billow::eval::image::ImageF32,
    tests: &[&billow::eval::image::ImageF32],
) -> Result<(), CliError> {
    if let Some(stage) = stage {
        let png = comparisons_png_bytes(reference, tests, DIFF_GAIN, path)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        stage.stage(path, &png).map_err(|e| out_err(path, e))?;
    }
    Ok(())
}

/// Stages `eval.json` and commits every file of the `--out` folder, then prints the JSON
/// or the table.
pub(crate) fn emit<S: Serialize>(
    args: &Args,
    stage: Option<Staged>,
    summary: &S,
    table: fn(&S),
) -> Result<(), CliError> {
    if let (Some(dir), Some(mut stage)) = (&args.out, stage) {
        let json = serde_json::to_vec_pretty(summary)
            .map_err(|e| CliError::new(Code::Internal, format!("cannot encode JSON: {e}")))?;
        let path = dir.join("eval.json");
        stage.stage(&path, &json).map_err(|e| out_err(&path, e))?;
        stage.commit_or_fail()?;
    }
    if args.json {
        print_json(summary)
    } else {
        table(summary);
        Ok(())
    }
}

/// A note (also a warning on stderr) when `source` is not the file the asset was baked
/// from: the asset records the source's name and hash (covering the files read beside it).
pub(crate) fn source_note(
    ctx: &Ctx,
    args: &Args,
    source: &Imported,
    recorded: Option<&billow_format::SourceInfo>,
) -> Option<String> {
    let recorded = recorded?;
    let actual = billow::provenance::source_info_all(&args.source, &source.report.files).ok()?;
    if actual.sha256 == recorded.sha256 {
        return None;
    }
    let note = format!(
        "{} is not the source {} was baked from: the asset records {} (SHA-256 {}…), this \
         source hashes to {}… (the comparison may be meaningless)",
        args.source.display(),
        args.asset.display(),
        recorded.file_name,
        &recorded.sha256[..recorded.sha256.len().min(12)],
        &actual.sha256[..12]
    );
    warn(ctx, &note);
    Some(note)
}

/// Refuses (exit 8) an eval whose reference would trace more than
/// [`MAX_REFERENCE_SAMPLES`], and warns with the expected time above a minute; before any
/// work.
fn check_cost(ctx: &Ctx, args: &Args, options: &EvaluateOptions) -> Result<(), CliError> {
    let (w, h, views) = (options.width, options.height, options.references());
    let samples = options.reference_samples();
    let seconds = samples / REFERENCE_SAMPLES_PER_SECOND;
    // Float images (reference, asset, 1-spp mesh, panels) per view: about 100 bytes a pixel.
    let mib = f64::from(w) * f64::from(h) * 100.0 / f64::from(1u32 << 20);
    if samples > MAX_REFERENCE_SAMPLES {
        return Err(bad(
            "--size",
            format!(
                "{}x{} px x {} spp x {views} views = {samples:.1e} reference samples, about \
                 {:.0} min and {mib:.0} MiB per view, more than the limit of {:.0e} samples; \
                 lower --size, --spp or the number of --views/--distances (nothing was done)",
                w,
                h,
                args.spp,
                seconds / 60.0,
                MAX_REFERENCE_SAMPLES
            ),
        ));
    }
    if seconds > 60.0 {
        warn(
            ctx,
            &format!(
                "{w}x{h} px x {} spp x {views} views = {samples:.1e} reference samples: \
                 expect roughly {:.0} s",
                args.spp, seconds
            ),
        );
    }
    Ok(())
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let start = Instant::now();
    let mut options = parse_options(&args)?;
    check_cost(ctx, &args, &options)?;
    // Reject a bad --spacing before the (slow) work.
    options.spacing = parse_spacing(&args.spacing)?;
    if let Some(dir) = &args.out {
        refuse_file_as_folder("--out", dir)?;
    }
    let source = import_source(&args, ctx)?;
    let import_s = start.elapsed().as_secs_f64();
    let t = Instant::now();
    let asset = Asset::from_container(read_asset(&args.asset)?)
        .map_err(|e| CliError::new(Code::from(&e), format!("{}: {e}", args.asset.display())))?;
    let read_s = t.elapsed().as_secs_f64();
    let (recorded, params) = match &asset {
        Asset::Volume(v) => (v.header.source.as_ref(), &v.header.params),
        Asset::Cloud(c) => (c.header.source.as_ref(), &c.header.params),
    };
    let mut stage = create_out(&args)?;
    let mismatch = source_note(ctx, &args, &source, recorded);

    let bar = progress(ctx, 0, "eval");
    let mut on_progress = |p: EvaluateProgress| {
        bar.set_length(p.total as u64);
        bar.set_message(p.view.to_string());
        bar.set_position(p.done as u64);
        ControlFlow::Continue(())
    };
    let mut images = Vec::new();
    let mut staging: Result<(), CliError> = Ok(());
    let mut on_images = |v: ViewImages| {
        let Some(dir) = &args.out else {
            return ControlFlow::Continue(());
        };
        let path = dir.join(format!("{}.png", image_stem(v.light, &v.view.name)));
        let tests: Vec<_> = v.assets.iter().chain(v.raster_1spp).collect();
        staging = stage_png(&mut stage, &path, v.reference, &tests);
        images.push(path.display().to_string());
        if staging.is_ok() {
            ControlFlow::Continue(())
        } else {
            ControlFlow::Break(())
        }
    };
    let mut hooks = EvaluateHooks {
        progress: Some(&mut on_progress),
        images: match args.out {
            Some(_) => Some(&mut on_images),
            None => None,
        },
    };
    let evaluated = evaluate(&source.scene, &asset, &options, &mut hooks);
    bar.finish_and_clear();
    staging?;
    let e = evaluated.map_err(|e| evaluate_error(&args, e))?;
    let head = Head {
        notes: mismatch
            .into_iter()
            .chain(e.notes.iter().cloned())
            .collect(),
        lighting: LightingJson {
            asset: e.lighting.asset.clone(),
            reference: e.lighting.reference.name(),
            reference_details: e.lighting.reference_details.clone(),
        },
        seconds: Seconds {
            import: import_s,
            read_asset: read_s + e.seconds.prepare,
            reference: e.seconds.reference,
            asset: e.seconds.asset,
            raster_1spp: e.seconds.raster_1spp,
            total: start.elapsed().as_secs_f64(),
        },
        params: params.clone(),
        images,
    };
    match &asset {
        Asset::Volume(_) => volume_output(&args, &options, head, e, stage),
        Asset::Cloud(_) => cloud::output(&args, &options, head, e, stage),
    }
}

/// What both kinds' outputs take from the run besides the [`Evaluation`].
pub(crate) struct Head {
    notes: Vec<String>,
    lighting: LightingJson,
    seconds: Seconds,
    params: std::collections::BTreeMap<String, String>,
    images: Vec<String>,
}

/// The options of the flags (the spacing is checked later, after the cost).
fn parse_options(args: &Args) -> Result<EvaluateOptions, CliError> {
    let (width, height) = parse_size(&args.size)?;
    let reference_per_axis = spp_per_axis(args.spp)?;
    let views = parse_views(&args.views, &parse_distances(&args.distances)?)?;
    let lighting = match (parse_lights(args)?, args.lighting) {
        (Some(lights), _) => ReferenceLighting::Lights {
            lights,
            shadows: args.shadows,
        },
        (None, LightingArg::Auto) => ReferenceLighting::Own,
        (None, LightingArg::Unlit) => ReferenceLighting::Unlit,
    };
    Ok(EvaluateOptions {
        width,
        height,
        fov_y: EVAL_FOV_Y,
        reference_per_axis,
        views,
        lighting,
        lod: args.lod,
        ..EvaluateOptions::default()
    })
}

/// The exit code and message of each failure, naming the file it comes from.
fn evaluate_error(args: &Args, e: EvaluateError) -> CliError {
    let (source, asset) = (args.source.display(), args.asset.display());
    match e {
        EvaluateError::Source(e) => CliError::new(Code::InvalidInput, format!("{source}: {e}")),
        EvaluateError::Reference(e) => CliError::new(Code::from(&e), format!("{source}: {e}")),
        EvaluateError::Asset(e) => CliError::new(Code::from(&e), format!("{asset}: {e}")),
        EvaluateError::AssetHeader(m) => CliError::new(Code::InvalidInput, format!("{asset}: {m}")),
        EvaluateError::NoSuchLod { lod, levels } => bad(
            "--lod",
            format!(
                "{lod}: {asset} has {levels} LOD levels (0 to {})",
                levels - 1
            ),
        ),
        EvaluateError::LodOfVolume => bad("--lod", "applies to billboard-cloud assets only"),
        e @ (EvaluateError::InvalidOption(_) | EvaluateError::Stopped) => {
            CliError::new(Code::Internal, e)
        }
    }
}

/// The volume's JSON and table.
fn volume_output(
    args: &Args,
    options: &EvaluateOptions,
    head: Head,
    e: Evaluation,
    stage: Option<Staged>,
) -> Result<(), CliError> {
    let [level] = <[_; 1]>::try_from(e.levels)
        .map_err(|_| CliError::new(Code::Internal, "a volume's evaluation has one level"))?;
    let summary = Summary {
        source: args.source.display().to_string(),
        asset: args.asset.display().to_string(),
        asset_dims: e.volume_dims.unwrap_or_default(),
        asset_params: head.params,
        gpu_bytes: e.gpu_bytes.with_bc,
        gpu_bytes_no_bc: e.gpu_bytes.without_bc,
        size: [options.width, options.height],
        fov_y_degrees: options.fov_y.to_degrees(),
        reference_spp: args.spp,
        spacing: args.spacing.clone(),
        lighting: head.lighting,
        notes: head.notes,
        mean: Means {
            asset: level.mean,
            raster_1spp: e.raster_1spp,
        },
        by_distance: level.by_distance,
        lights: lights_json(level.by_light),
        slices: level.slices,
        fragments: level.fragments,
        seconds: head.seconds,
        views: level.views,
        images: head.images,
    };
    emit(args, stage, &summary, print_table)
}
