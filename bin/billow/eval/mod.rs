//! `billow eval SOURCE ASSET`: how close a volume or billboard-cloud asset looks to its
//! source mesh, view by view, against a supersampled ray-traced reference (docs/eval.md).
//! Volumes here, clouds in [`cloud`].

mod cloud;

use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::camera::{parse_direction, view_directions, views_of, ViewDirections, ViewSpec};
use billow::eval::image::comparisons_png_bytes;
use billow::eval::lighting::{parse_light_set, EvalLight, LightSetError, Lighting};
use billow::eval::slicer::{SlicerParams, Spacing};
use billow::eval::suite::{
    mean_errors, means_by_distance, means_by_light, reference_lighting, view_file_stem,
    DistanceMeans, EvalOptions, Evaluator, LightMeans, MeanErrors, PreparedAsset, ViewResult,
    EVAL_FOV_Y,
};
use billow::import::{import, ImportOptions, Imported};
use billow_format::{read_file, AssetKind, Container, VolumeAsset};
use glam::Vec3;
use serde::Serialize;

use crate::exit::{usage, CliError, Code};
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
    /// Reference samples per pixel: a square number (1, 4, 9, 16, …, 256), stratified.
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
    /// asset was baked with: its baked AO at each hit point, or unlit) or unlit.
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
    /// With --light/--lights: shadows in the reference (ray traced towards the light) and in
    /// the cloud's kept mesh; volumes are drawn unshadowed (noted).
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
pub(crate) fn lights_json(lights: Option<&[EvalLight]>, results: &[ViewResult]) -> Vec<LightJson> {
    let Some(lights) = lights else {
        return Vec::new();
    };
    means_by_light(results)
        .into_iter()
        .filter_map(|m| {
            let l = lights.iter().find(|l| l.name == m.light)?;
            Some(LightJson {
                name: l.name.clone(),
                dir: l.dir.to_array(),
                ambient: l.ambient,
                means: m,
            })
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

pub(crate) fn bad(flag: &str, e: impl std::fmt::Display) -> CliError {
    CliError::new(Code::BadParameter, format!("{flag}: {e}"))
}

/// `--light`/`--lights`/`--ambient`: the lights to evaluate under, or `None` (the asset's
/// own lighting, `--lighting`).
pub(crate) fn parse_lights(args: &Args) -> Result<Option<Vec<EvalLight>>, CliError> {
    if !(args.ambient.is_finite() && (0.0..=1.0).contains(&args.ambient)) {
        return Err(bad(
            "--ambient",
            format!("{} is out of range (0 to 1)", args.ambient),
        ));
    }
    let vector = |flag: &str, text: &str| -> Result<Vec3, CliError> {
        let v: Vec<f32> = text
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| usage(flag, format!("'{text}': {e} (expected X,Y,Z)")))?;
        match v[..] {
            [x, y, z] => Ok(Vec3::new(x, y, z)),
            _ => Err(usage(flag, format!("'{text}': expected X,Y,Z"))),
        }
    };
    let light = |flag: &str, name: String, dir: Vec3| {
        EvalLight::new(name, dir, args.ambient).ok_or_else(|| {
            bad(
                flag,
                format!("({}, {}, {}) is not a direction", dir.x, dir.y, dir.z),
            )
        })
    };
    if let Some(l) = &args.light {
        let dir = vector("--light", l)?;
        return Ok(Some(vec![light("--light", "light".into(), dir)?]));
    }
    let Some(set) = &args.lights else {
        if args.shadows {
            return Err(usage("--shadows", "needs --light or --lights"));
        }
        return Ok(None);
    };
    parse_light_set(set, args.ambient)
        .map(Some)
        .map_err(|e| match e {
            LightSetError::Syntax(m) => usage("--lights", m),
            LightSetError::NotADirection(m) => bad("--lights", m),
        })
}

/// `WxH`, each 1..=4096.
pub fn parse_size(s: &str) -> Result<(u32, u32), CliError> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| usage("--size", format!("'{s}': expected WxH, e.g. 128x128")))?;
    let p = |v: &str| -> Result<u32, CliError> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|e| usage("--size", format!("'{s}': {e}")))?;
        if !(1..=4096).contains(&n) {
            return Err(bad(
                "--size",
                format!("'{s}': each side must be 1 to 4096 pixels"),
            ));
        }
        Ok(n)
    };
    Ok((p(w)?, p(h)?))
}

/// `1,4,16`: positive finite factors up to 1000.
pub fn parse_distances(s: &str) -> Result<Vec<f32>, CliError> {
    let mut out: Vec<f32> = Vec::new();
    for part in s.split(',') {
        let f: f32 = part
            .trim()
            .parse()
            .map_err(|e| usage("--distances", format!("'{part}': {e}")))?;
        if !(f.is_finite() && f > 0.0 && f <= 1000.0) {
            return Err(bad(
                "--distances",
                format!("'{part}': a factor must be above 0 and at most 1000"),
            ));
        }
        if !out.contains(&f) {
            out.push(f);
        }
    }
    Ok(out)
}

/// See `--views`.
pub fn parse_views(s: &str, distances: &[f32]) -> Result<Vec<ViewSpec>, CliError> {
    let mut out: Vec<ViewSpec> = Vec::new();
    let mut push = |v: ViewSpec| {
        if !out.iter().any(|o| o.name == v.name) {
            out.push(v);
        }
    };
    for item in s.split(',').map(str::trim) {
        let set = match item {
            "axes" => Some(ViewDirections::Axes),
            "diagonals" => Some(ViewDirections::Diagonals),
            "all" => Some(ViewDirections::All),
            _ => None,
        };
        if let Some(set) = set {
            views_of(view_directions(set), distances)
                .into_iter()
                .for_each(&mut push);
            continue;
        }
        let unknown = || {
            usage(
                "--views",
                format!(
                    "unknown view '{item}': expected axes, diagonals, all, a direction like +x or \
                     +x-y+z, or a view like +x@4x"
                ),
            )
        };
        let (dir_name, factor) = match item.split_once('@') {
            Some((d, f)) => {
                let f = f.strip_suffix('x').ok_or_else(unknown)?;
                // A factor out of range is that (8); anything else does not parse (2).
                let f = parse_distances(f).map_err(|e| {
                    if e.code == Code::BadParameter {
                        e
                    } else {
                        unknown()
                    }
                })?;
                (d, Some(f[0]))
            }
            None => (item, None),
        };
        let dir = parse_direction(dir_name).ok_or_else(unknown)?;
        let factors = factor.map_or_else(|| distances.to_vec(), |f| vec![f]);
        views_of(vec![(dir_name.to_string(), dir)], &factors)
            .into_iter()
            .for_each(&mut push);
    }
    Ok(out)
}

/// See `--spacing`; `voxel` is the asset's level-0 voxel size.
pub fn parse_spacing(s: &str, voxel: Option<f32>) -> Result<Spacing, CliError> {
    let (mode, arg) = match s.split_once(':') {
        Some((m, a)) => (m.trim(), Some(a.trim())),
        None => (s.trim(), None),
    };
    let num = |a: Option<&str>| -> Result<f32, CliError> {
        let Some(a) = a else { return Ok(1.0) };
        let v: f32 = a
            .parse()
            .map_err(|e| usage("--spacing", format!("'{s}': {e}")))?;
        if !(v.is_finite() && (0.01..=100.0).contains(&v)) {
            return Err(bad(
                "--spacing",
                format!("'{s}': the factor must be between 0.01 and 100"),
            ));
        }
        Ok(v)
    };
    match mode {
        "adaptive" => Ok(Spacing::Adaptive { bias: num(arg)? }),
        "uniform" => {
            let v = num(arg)?;
            Ok(Spacing::Uniform {
                spacing: v * voxel.unwrap_or(1.0),
            })
        }
        _ => Err(usage(
            "--spacing",
            format!("'{s}': expected adaptive, adaptive:BIAS, uniform or uniform:VOXELS"),
        )),
    }
}

pub(crate) fn spp_per_axis(spp: u32) -> Result<u32, CliError> {
    let n = (1..=16).find(|n| n * n == spp);
    n.ok_or_else(|| {
        bad(
            "--spp",
            format!("{spp} is not a square number from 1 to 256 (e.g. 1, 4, 9, 16, 64)"),
        )
    })
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

/// Stages `eval.json` and commits every file of the `--out` folder.
pub(crate) fn finish_out(
    args: &Args,
    stage: Option<Staged>,
    summary: &impl Serialize,
) -> Result<(), CliError> {
    if let (Some(dir), Some(mut stage)) = (&args.out, stage) {
        let json = serde_json::to_vec_pretty(summary)
            .map_err(|e| CliError::new(Code::Internal, format!("cannot encode JSON: {e}")))?;
        let path = dir.join("eval.json");
        stage.stage(&path, &json).map_err(|e| out_err(&path, e))?;
        stage.commit_or_fail()?;
    }
    Ok(())
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

/// Most reference samples (pixels × spp × views) an eval may trace: 10¹⁰, about 80 minutes at
/// [`REFERENCE_SAMPLES_PER_SECOND`].
pub(crate) const MAX_REFERENCE_SAMPLES: f64 = 1e10;
/// Reference samples per second assumed for the time estimate (measured: the oak, release
/// build, a few cores).
pub(crate) const REFERENCE_SAMPLES_PER_SECOND: f64 = 2e6;

/// Refuses (exit 8) an eval whose reference would trace more than
/// [`MAX_REFERENCE_SAMPLES`], and warns with the expected time above a minute; before any
/// work.
fn check_cost(ctx: &Ctx, args: &Args, views: usize) -> Result<(), CliError> {
    let (w, h) = parse_size(&args.size)?;
    let samples = f64::from(w) * f64::from(h) * f64::from(args.spp) * views as f64;
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
    parse_size(&args.size)?;
    spp_per_axis(args.spp)?;
    let views = parse_views(&args.views, &parse_distances(&args.distances)?)?;
    let lights = parse_lights(&args)?;
    check_cost(
        ctx,
        &args,
        views.len() * lights.as_ref().map_or(1, Vec::len),
    )?;
    // Reject a bad --spacing before the (slow) work.
    parse_spacing(&args.spacing, None)?;
    if let Some(dir) = &args.out {
        refuse_file_as_folder("--out", dir)?;
    }
    let source = import_source(&args, ctx)?;
    let import_s = start.elapsed().as_secs_f64();
    let t = Instant::now();
    let container = read_asset(&args.asset)?;
    if container.header.kind == AssetKind::Cloud {
        return cloud::run(&args, ctx, &source, container, start, import_s, t);
    }
    if args.lod.is_some() {
        return Err(bad("--lod", "applies to billboard-cloud assets only"));
    }
    run_volume(&args, ctx, &source, container, start, import_s, t)
}

fn run_volume(
    args: &Args,
    ctx: &Ctx,
    source: &Imported,
    container: Container,
    start: Instant,
    import_s: f64,
    t: Instant,
) -> Result<(), CliError> {
    let scene = &source.scene;
    let (width, height) = parse_size(&args.size)?;
    let per_axis = spp_per_axis(args.spp)?;
    let views = parse_views(&args.views, &parse_distances(&args.distances)?)?;
    let source_shown = args.source.display().to_string();
    let asset_shown = args.asset.display().to_string();
    let asset = VolumeAsset::from_container(container)
        .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
    let prepared = PreparedAsset::new(&asset)
        .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
    let read_s = t.elapsed().as_secs_f64();
    let spacing = parse_spacing(&args.spacing, prepared.voxel_size())?;
    let (lighting, lighting_note) = match args.lighting {
        LightingArg::Auto => reference_lighting(&asset)
            .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?,
        LightingArg::Unlit => {
            let bake = asset.header.volume_bake();
            let note = (bake != billow_format::VolumeBake::None)
                .then(|| bake.name().to_string())
                .map(|b| {
                    format!(
                        "the asset has baked lighting (bake={b}) but --lighting unlit: the \
                         errors include the lighting difference"
                    )
                });
            (Lighting::Unlit, note)
        }
    };

    let options = EvalOptions {
        width,
        height,
        fov_y: EVAL_FOV_Y,
        reference_per_axis: per_axis,
        slicer: SlicerParams {
            spacing,
            ..SlicerParams::default()
        },
        raster_1spp: true,
        lighting,
    };
    let mut evaluator = Evaluator::new(scene, options)
        .map_err(|e| CliError::new(Code::InvalidInput, format!("{source_shown}: {e}")))?;
    let mut stage = create_out(args)?;
    let mismatch = source_note(ctx, args, source, asset.header.source.as_ref());
    let lights = parse_lights(args)?;
    let (lighting, lighting_note) = match &lights {
        Some(_) => (
            Lighting::Scene {
                light: Vec3::ZERO,
                ambient: args.ambient,
                shadows: args.shadows,
            },
            args.shadows.then(|| {
                "--shadows: the reference and meshes are shadowed, the CPU slicer draws volumes \
                 unshadowed: the errors include the shadows"
                    .to_string()
            }),
        ),
        None => (lighting, lighting_note),
    };
    let light_list: Vec<Option<&EvalLight>> = match &lights {
        Some(l) => l.iter().map(Some).collect(),
        None => vec![None],
    };

    let bar = progress(ctx, (views.len() * light_list.len()) as u64, "eval");
    let mut results = Vec::with_capacity(views.len() * light_list.len());
    let mut images = Vec::new();
    for light in &light_list {
        if let Some(l) = light {
            evaluator
                .set_light(l, args.shadows)
                .map_err(|e| CliError::new(Code::from(&e), format!("{source_shown}: {e}")))?;
        }
        for spec in &views {
            bar.set_message(spec.name.clone());
            let reference = evaluator
                .reference(spec)
                .map_err(|e| CliError::new(Code::from(&e), format!("{source_shown}: {e}")))?;
            let (result, image) = evaluator
                .asset(&prepared, &reference)
                .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
            if let Some(dir) = &args.out {
                let path = dir.join(format!("{}.png", image_stem(*light, &spec.name)));
                let mut tests = vec![&image];
                if let Some((r, _, _)) = &reference.raster_1spp {
                    tests.push(r);
                }
                stage_png(&mut stage, &path, &reference.image, &tests)?;
                images.push(path.display().to_string());
            }
            results.push(result);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();

    let notes: Vec<String> = mismatch.into_iter().chain(lighting_note).collect();
    let sum = |f: &dyn Fn(&ViewResult) -> f64| results.iter().map(f).sum::<f64>();
    let gpu = billow_core::gpu_memory::volume_gpu_bytes(&asset, asset.header.compress().is_some());
    let summary = Summary {
        source: source_shown,
        asset: asset_shown,
        asset_dims: prepared.dims0,
        asset_params: asset.header.params.clone(),
        gpu_bytes: gpu.with_bc,
        gpu_bytes_no_bc: gpu.without_bc,
        size: [width, height],
        fov_y_degrees: EVAL_FOV_Y.to_degrees(),
        reference_spp: args.spp,
        spacing: args.spacing.clone(),
        lighting: LightingJson {
            asset: asset.header.volume_bake().name().to_string(),
            reference: lighting.name(),
            reference_details: reference_details(&lighting, lights.as_deref(), args),
        },
        notes,
        mean: Means {
            asset: mean_errors(results.iter().map(|r| &r.asset)),
            raster_1spp: mean_errors(results.iter().filter_map(|r| r.raster_1spp.as_ref())),
        },
        by_distance: means_by_distance(&results),
        lights: lights_json(lights.as_deref(), &results),
        slices: results.iter().map(|r| r.slices).sum(),
        fragments: results.iter().map(|r| r.fragments).sum(),
        seconds: Seconds {
            import: import_s,
            read_asset: read_s,
            reference: sum(&|r| r.seconds.reference),
            asset: sum(&|r| r.seconds.asset),
            raster_1spp: sum(&|r| r.seconds.raster_1spp),
            total: start.elapsed().as_secs_f64(),
        },
        views: results,
        images,
    };
    finish_out(args, stage, &summary)?;
    if args.json {
        print_json(&summary)?;
    } else {
        print_table(&summary);
    }
    Ok(())
}

/// `(112x128x112)` for a volume, `(grid 112x128x112, pruned into an 84x128x74 atlas)`
/// for a pruned one (its level-0 texture is the atlas, the grid is in its `dims` param).
fn dims_text(s: &Summary) -> String {
    let d = s.asset_dims;
    let atlas = format!("{}x{}x{}", d[0], d[1], d[2]);
    let pruned = s.asset_params.contains_key("emptyspace");
    match s.asset_params.get("dims") {
        Some(grid) if pruned && *grid != atlas => {
            format!("grid {grid}, pruned into an {atlas} atlas")
        }
        _ => atlas,
    }
}

fn print_table(s: &Summary) {
    outln!(
        "{} vs {} ({}), {}x{} px, {} spp reference, spacing {}",
        s.asset,
        s.source,
        dims_text(s),
        s.size[0],
        s.size[1],
        s.reference_spp,
        s.spacing
    );
    outln!(
        "{}",
        crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc)
    );
    for n in &s.notes {
        outln!("note: {n}");
    }
    let totals = (s.seconds.reference, s.seconds.asset, s.slices, s.fragments);
    print_rows(
        &s.views,
        &s.by_distance,
        &s.lights,
        &s.mean,
        totals,
        "slices",
    );
    outln!(
        "RMSE/PSNR on premultiplied linear RGBA; cov% = asset coverage vs reference; lum% = its \
         mean covered luminance vs the reference's; SSIM on luma; FLIP over black. Total {:.2} s.",
        s.seconds.total
    );
}

/// The table of views, per-distance means and the mean; `count` names the 4th timing
/// column (`slices` for volumes, `bboards` for clouds: billboards hit).
pub(crate) fn print_rows(
    views: &[ViewResult],
    by_distance: &[DistanceMeans],
    lights: &[LightJson],
    mean: &Means,
    totals: (f64, f64, usize, u64),
    count: &str,
) {
    // Under lights the view column names the light too (`sun-east +x@4x`).
    let w = if lights.is_empty() { 14 } else { 24 };
    outln!(
        "{:<w$} {:>7} {:>6} {:>6} {:>7} {:>7} {:>6} {:>6} | {:>7} {:>6} {:>6} | {:>7} {:>7} {:>6} {:>9}",
        "view",
        "RMSE",
        "PSNR",
        "|Δα|",
        "cov%",
        "lum%",
        "SSIM",
        "FLIP",
        "1spp",
        "PSNR",
        "SSIM",
        "ref s",
        "asset s",
        count,
        "fragments"
    );
    let row = |name: &str, a: &MeanErrors, r: &MeanErrors, tail: String| {
        outln!(
            "{:<w$} {:>7.4} {:>6.2} {:>6.4} {:>+7.2} {:>+7.2} {:>6.3} {:>6.4} | {:>7.4} {:>6.2} {:>6.3} |{}",
            name,
            a.rmse,
            a.psnr,
            a.mean_abs_alpha,
            100.0 * a.coverage_rel_diff,
            100.0 * a.luminance_rel_diff,
            a.ssim_luma,
            a.flip,
            r.rmse,
            r.psnr,
            r.ssim_luma,
            tail
        );
    };
    let tail =
        |rs: f64, as_: f64, sl: usize, fr: u64| format!(" {rs:>7.2} {as_:>7.2} {sl:>6} {fr:>9}");
    for v in views {
        let a = mean_errors([&v.asset]);
        let r = v
            .raster_1spp
            .as_ref()
            .map_or_else(MeanErrors::default, |e| mean_errors([e]));
        let count = if count == "slices" {
            v.slices
        } else {
            v.polygons
        };
        let t = tail(v.seconds.reference, v.seconds.asset, count, v.fragments);
        let name = match &v.light {
            Some(l) => format!("{l} {}", v.view),
            None => v.view.clone(),
        };
        row(&name, &a, &r, t);
    }
    for m in by_distance {
        let r = m.raster_1spp.unwrap_or_default();
        row(
            &format!("mean @{}x", m.distance_factor),
            &m.asset,
            &r,
            String::new(),
        );
    }
    for l in lights {
        let r = l.means.raster_1spp.unwrap_or_default();
        row(
            &format!("mean {}", l.name),
            &l.means.asset,
            &r,
            String::new(),
        );
    }
    let t = tail(totals.0, totals.1, totals.2, totals.3);
    let name = if lights.is_empty() {
        "mean"
    } else {
        "mean over the lights"
    };
    row(name, &mean.asset, &mean.raster_1spp, t);
}

/// What the JSON says of the reference's lighting: its own description, or with
/// `--light`/`--lights` the set's (the scene lighting's own light is a placeholder there:
/// each light of the set is set in turn).
pub(crate) fn reference_details(
    lighting: &Lighting,
    lights: Option<&[EvalLight]>,
    args: &Args,
) -> String {
    match lights {
        Some(l) => format!(
            "the viewer's mesh lighting: ambient {} + two-sided diffuse{}, under each of the \
             {} light(s) in `lights`",
            args.ambient,
            if args.shadows {
                ", ray-traced shadows"
            } else {
                ""
            },
            l.len()
        ),
        None => lighting.describe(),
    }
}
