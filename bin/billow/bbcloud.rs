//! `billow bbcloud IN -o OUT.billow`: a stochastic billboard cloud (Lacewell et al. 2006)
//! of a mesh's foliage, plus its other triangles kept as a mesh.

use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::bbcloud::{
    self as bb, bake, check_ambient, check_view_strength, estimate, BbcloudOptions, BbcloudStats,
    Estimate, Flatten, Shading, Stage, ViewDirs, ViewPreference,
};
use billow::compress::{compress_cloud, Compression};
use billow::export::gltf::cloud_gltf_bytes_with;
use billow::export::straight;
use billow::export::{GltfAlpha, GltfContainer, GltfOptions};
use billow::import::{import, ImportOptions, ImportReport, Imported};
use billow::presets::{resolve_cloud, CloudFlags, CloudSettings, Preset, ResolvedCloud, Source};
use billow::provenance::{source_info_all, tool_version};
use billow::target_error::{search_cloud, short, TargetOptions};
use billow_format::{CloudAsset, CloudBlocks};
use glam::Vec3;
use serde::Serialize;

use crate::bake_steps::{
    imported, parse_compress, parse_preset, print_summary, refuse_outputs, settings_preset,
    settings_source,
};
use crate::bbcloud_args::{Args, GltfAlphaArg};
use crate::depfile;
use crate::exit::{bad, bbcloud_error, usage, CliError, Code};
use crate::output::{progress, warn};
use crate::progress::{self, Monotone};
use crate::staged::{out_err, Staged};
use crate::target::{run_search, target_options, TargetSummary};
use crate::Ctx;

/// Where the resolved ε, N and atlas size came from.
#[derive(Serialize)]
struct SettingsFrom {
    epsilon: Source,
    samples: Source,
    atlas_size: Source,
}

#[derive(Serialize)]
struct Summary<'a> {
    input: String,
    output: String,
    /// The preset the settings came from (with --target-error: the chosen one's).
    preset: Option<Preset>,
    /// The resolved --epsilon, --samples and --atlas-size.
    epsilon: f32,
    samples: u32,
    atlas_size: u32,
    settings_from: SettingsFrom,
    /// With --target-error: what was tried and chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    target: Option<TargetSummary>,
    seed: u64,
    billboards_per_lod: Vec<usize>,
    atlas_fill_per_lod: Vec<f64>,
    texels: u64,
    bytes: u64,
    /// Texture bytes `billow view` holds on a device that samples BC7 blocks, and on one
    /// that does not (`billow_core::gpu_memory`; equal for `--compress none`).
    gpu_bytes: u64,
    gpu_bytes_no_bc: u64,
    mip_levels: u32,
    normal_map: bool,
    /// How triangles were laid onto their billboards (`--flatten`).
    flatten: &'static str,
    stats: &'a BbcloudStats,
    estimate: Estimate,
    seconds_import: f64,
    compress: String,
    seconds_compress: f64,
    seconds_write: f64,
    seconds_export: f64,
    gltf: Option<String>,
    atlas_files: Vec<String>,
    seconds_total: f64,
    warnings: Vec<String>,
}

fn parse_light(s: &str) -> Result<Vec3, CliError> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| usage("--light", format!("'{s}': {e}")))?;
    let l = match v[..] {
        [x, y, z] => Vec3::new(x, y, z),
        _ => return Err(usage("--light", format!("'{s}': expected x,y,z"))),
    };
    if !l.is_finite() || l.length() == 0.0 {
        return Err(bad(
            "--light",
            format!("'{s}': must be finite and non-zero"),
        ));
    }
    Ok(l.normalize())
}

/// An axis token (`+x`, `-z`, `y`) or `x,y,z`, normalised.
fn parse_dir(flag: &str, s: &str) -> Result<Vec3, CliError> {
    let t = s.trim().to_ascii_lowercase();
    let axis = |c: &str| match c {
        "x" => Some(Vec3::X),
        "y" => Some(Vec3::Y),
        "z" => Some(Vec3::Z),
        _ => None,
    };
    let v = if let Some(a) = t.strip_prefix('+').and_then(axis).or_else(|| axis(&t)) {
        a
    } else if let Some(a) = t.strip_prefix('-').and_then(axis) {
        -a
    } else {
        let c: Vec<f32> = t
            .split(',')
            .map(|p| p.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| usage(flag, format!("'{s}': expected ±x, ±y, ±z or x,y,z")))?;
        match c[..] {
            [x, y, z] => Vec3::new(x, y, z),
            _ => return Err(usage(flag, format!("'{s}': expected ±x, ±y, ±z or x,y,z"))),
        }
    };
    if !v.is_finite() || v.length() == 0.0 {
        return Err(bad(flag, format!("'{s}': must be finite and non-zero")));
    }
    Ok(v.normalize() + Vec3::ZERO) // + 0: no negative zeros in the recorded header
}

fn parse_view(s: &str, up: Vec3, strength: f32) -> Result<ViewPreference, CliError> {
    check_view_strength(strength).map_err(|e| bbcloud_error(s, &e))?;
    let dirs = if s.trim().eq_ignore_ascii_case("horizontal") {
        ViewDirs::Horizontal { up }
    } else {
        let mut d = Vec::new();
        for part in s.split(';').filter(|p| !p.trim().is_empty()) {
            match parse_dir("--view-dirs", part) {
                Ok(v) => d.push(v),
                // "+z,+x": axes separated by commas.
                Err(e) => {
                    for a in part.split(',') {
                        match parse_dir("--view-dirs", a) {
                            Ok(v) => d.push(v),
                            Err(_) => return Err(e),
                        }
                    }
                }
            }
        }
        if d.is_empty() || d.len() > bb::MAX_VIEW_DIRS {
            return Err(bad(
                "--view-dirs",
                format!("'{s}': 1 to {} directions", bb::MAX_VIEW_DIRS),
            ));
        }
        ViewDirs::Directions(d)
    };
    Ok(ViewPreference { dirs, strength })
}

/// What the flags ask for, checked before any work (the bake's own options apart).
struct Plan {
    preset: Option<Preset>,
    flags: CloudFlags,
    resolved: ResolvedCloud,
    target: Option<TargetOptions>,
    compression: Compression,
    gltf_container: GltfContainer,
}

/// `--preset` and the settings it resolves, `--target-error`, `--compress` and `--gltf`'s
/// container, in the order their errors are reported.
fn plan(args: &Args) -> Result<Plan, CliError> {
    let preset = parse_preset(args.preset.as_deref())?;
    let flags = CloudFlags {
        epsilon: args.epsilon,
        samples: args.samples,
        atlas_size: args.atlas_size,
    };
    let resolved = resolve_cloud(preset, &flags);
    let target = target_options(&args.target)?;
    let compression = parse_compress(&args.compress)?;
    let gltf_container = args
        .gltf
        .as_deref()
        .map(|p| {
            GltfContainer::from_path(p).ok_or_else(|| {
                usage(
                    "--gltf",
                    format!(
                        "{}: the name must end in .glb (binary glTF) or .gltf (JSON glTF)",
                        p.display()
                    ),
                )
            })
        })
        .transpose()?
        .unwrap_or_default();
    Ok(Plan {
        preset,
        flags,
        resolved,
        target,
        compression,
        gltf_container,
    })
}

/// The bake's options from `settings` (the resolved ε, N and atlas size) and the flags;
/// warns when a normal map is baked with lighting.
fn bake_options(
    args: &Args,
    ctx: &Ctx,
    settings: &CloudSettings,
) -> Result<BbcloudOptions, CliError> {
    let input_shown = args.input.display().to_string();
    // Before the import: the library checks it again.
    check_ambient(args.ambient).map_err(|e| bbcloud_error(&input_shown, &e))?;
    let light = if args.unlit {
        None
    } else {
        Some(parse_light(&args.light)?)
    };
    let up = parse_dir("--up", &args.up)?;
    let flatten: Flatten = args.flatten.parse().map_err(|e| usage("--flatten", e))?;
    let view = args
        .view_dirs
        .as_deref()
        .map(|s| parse_view(s, up, args.view_strength))
        .transpose()?;
    let opts = BbcloudOptions {
        epsilon: settings.epsilon,
        samples: settings.samples,
        seed: args.seed,
        lods: args.lods,
        atlas_size: settings.atlas_size,
        texel_density: args.texel_density,
        shading: Shading {
            light,
            ambient: args.ambient,
        },
        supersample: args.supersample,
        foliage: args.foliage.clone(),
        max_extent: args.max_extent,
        up,
        view,
        normal_map: args.normal_map,
        mip_levels: args.mip_levels,
        flatten,
        ..BbcloudOptions::default()
    };
    if args.normal_map && light.is_some() {
        warn(
            ctx,
            "--normal-map with baked lighting: a viewer that uses the normal map lights the \
             billboards again; bake with --unlit for runtime lighting",
        );
    }
    Ok(opts)
}

/// Imports the mesh, refusing outputs that would replace a file it read; returns it with
/// its provenance.
fn read_input(
    args: &Args,
    ctx: &Ctx,
    outputs: &[(&str, &Path)],
    input: &str,
) -> Result<(Imported, billow_format::SourceInfo), CliError> {
    let options = ImportOptions {
        strict: args.strict,
    };
    let imported = imported(
        &args.input,
        input,
        import(&args.input, &options),
        outputs,
        ctx,
    )?;
    depfile::check_read(args.depfile.as_deref(), &imported.report.files)?;
    let source = source_info_all(&args.input, &imported.report.files)
        .map_err(|e| CliError::new(Code::InputIo, format!("{input}: cannot read: {e}")))?;
    Ok((imported, source))
}

/// An atlas PNG: its file name and bytes.
type AtlasPng = (String, Vec<u8>);
/// The `--gltf` file: its path and bytes.
type Glb<'a> = Option<(&'a PathBuf, Vec<u8>)>;

/// The exports, encoded before anything is written so a failure leaves no output: the
/// atlas PNGs (once for both the .glb and the `--atlas` dump) and the `--gltf` file.
fn export<'a>(
    args: &'a Args,
    plan: &Plan,
    asset: &CloudAsset,
    scene: &billow::scene::Scene,
) -> Result<(Vec<AtlasPng>, Glb<'a>), CliError> {
    let pngs = if args.atlas.is_some() || args.gltf.is_some() {
        let place = args
            .atlas
            .as_ref()
            .or(args.gltf.as_ref())
            .expect("one of them");
        straight::atlas_pngs(asset).map_err(|e| {
            CliError::new(
                Code::Internal,
                format!("{}: cannot encode PNG: {e}", place.display()),
            )
        })?
    } else {
        Vec::new()
    };
    let glb = match &args.gltf {
        None => None,
        Some(path) => {
            let opts = GltfOptions {
                alpha: match args.gltf_alpha {
                    GltfAlphaArg::Mask => GltfAlpha::Mask { cutoff: 0.5 },
                    GltfAlphaArg::Blend => GltfAlpha::Blend,
                },
                container: plan.gltf_container,
                source: Some(scene),
            };
            let png_bytes: Vec<Vec<u8>> = pngs.iter().map(|(_, b)| b.clone()).collect();
            let bytes = cloud_gltf_bytes_with(asset, &opts, Some(&png_bytes))
                .map_err(|e| CliError::new(Code::Internal, format!("{}: {e}", path.display())))?;
            Some((path, bytes))
        }
    };
    Ok((pngs, glb))
}

/// The files the command writes, each with its flag (`--atlas` apart: a folder).
fn outputs(args: &Args) -> Vec<(&'static str, &Path)> {
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(args.gltf.as_deref().map(|g| ("--gltf", g)));
    outputs.extend(args.depfile.as_deref().map(|g| ("--depfile", g)));
    outputs
}

/// The cloud as written and its BC7 blocks: the compressed copy `--target-error` measured
/// already, else `asset` compressed as `--compress` says.
fn compressed_asset(
    mut asset: CloudAsset,
    compressed: Option<(Box<CloudAsset>, CloudBlocks)>,
    compression: Compression,
) -> (CloudAsset, Option<CloudBlocks>) {
    let blocks = match compressed {
        Some((c, b)) => {
            asset = *c;
            Some(b)
        }
        None => (compression == Compression::Bc).then(|| {
            asset.header.set_compress("bc7");
            compress_cloud(&mut asset)
        }),
    };
    (asset, blocks)
}

/// Writes every file: to a temporary name first, all renamed into place only when all are
/// written, so a failure leaves no new file (and no new folder) behind. Returns the atlas
/// PNGs written, as shown.
fn write_outputs(
    args: &Args,
    bytes: &[u8],
    (pngs, glb): (&[AtlasPng], Glb),
    report: &ImportReport,
) -> Result<Vec<String>, CliError> {
    let mut stage = Staged::new(&args.output);
    let mut atlas_paths = Vec::new();
    if let Some(dir) = &args.atlas {
        stage.create_dir(dir).map_err(|e| {
            CliError::new(
                Code::OutputIo,
                format!("{}: cannot create directory: {e}", dir.display()),
            )
        })?;
        for (name, png) in pngs {
            let p = dir.join(name);
            stage.stage(&p, png).map_err(|e| out_err(&p, e))?;
            atlas_paths.push(p);
        }
    }
    if let Some((path, glb)) = &glb {
        stage.stage(path, glb).map_err(|e| out_err(path, e))?;
    }
    stage
        .stage(&args.output, bytes)
        .map_err(|e| out_err(&args.output, e))?;
    let targets = (
        args.output.as_path(),
        args.gltf.as_deref(),
        atlas_paths.as_slice(),
    );
    depfile::commit(stage, args.depfile.as_deref(), targets, &args.input, report)?;
    Ok(atlas_paths
        .iter()
        .map(|p| p.display().to_string())
        .collect())
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let start = Instant::now();
    let plan = plan(&args)?;
    let outputs = outputs(&args);
    let atlas = args.atlas.as_deref();
    let depfile = args.depfile.as_deref();
    refuse_outputs(
        &args.input,
        &outputs,
        atlas.map(|d| ("--atlas", d)),
        depfile,
        atlas,
    )?;
    let mut opts = bake_options(&args, ctx, &plan.resolved.settings)?;
    let input = args.input.display().to_string();
    let (Imported { scene, report }, source) = read_input(&args, ctx, &outputs, &input)?;
    let seconds_import = start.elapsed().as_secs_f64();

    let (cloud, target) = match &plan.target {
        None => (
            bake_once(&scene, &opts, &args, ctx, &input, source, None)?,
            None,
        ),
        Some(t) => {
            let (cloud, chosen, summary) = bake_to_target(
                &scene,
                &opts,
                &args,
                &plan.flags,
                t,
                plan.compression,
                ctx,
                &input,
                &source,
            )?;
            opts = chosen;
            (cloud, Some(summary))
        }
    };
    let Cloud {
        asset,
        stats,
        cost,
        compressed,
    } = cloud;

    let export_start = Instant::now();
    let (pngs, glb) = export(&args, &plan, &asset, &scene)?;
    let seconds_export = export_start.elapsed().as_secs_f64();

    let compress_start = Instant::now();
    let (asset, blocks) = compressed_asset(asset, compressed, plan.compression);
    let seconds_compress = compress_start.elapsed().as_secs_f64();
    let gpu = billow_core::gpu_memory::cloud_gpu_bytes(&asset, blocks.is_some());
    let write_start = Instant::now();
    let bytes = asset
        .to_bytes_with(blocks.as_ref())
        .map_err(|e| CliError::new(Code::Internal, e))?;
    let atlas_files = write_outputs(&args, &bytes, (&pngs, glb), &report)?;
    let seconds_write = write_start.elapsed().as_secs_f64();

    let from = |s| settings_source(target.as_ref(), s);
    let summary = Summary {
        input,
        output: args.output.display().to_string(),
        preset: settings_preset(target.as_ref(), plan.preset),
        epsilon: opts.epsilon,
        samples: opts.samples,
        atlas_size: opts.atlas_size,
        settings_from: SettingsFrom {
            epsilon: from(plan.resolved.epsilon_from),
            samples: from(plan.resolved.samples_from),
            atlas_size: from(plan.resolved.atlas_size_from),
        },
        target,
        seed: args.seed,
        mip_levels: args.mip_levels,
        normal_map: args.normal_map,
        flatten: opts.flatten.name(),
        billboards_per_lod: stats.levels.iter().map(|l| l.billboards).collect(),
        atlas_fill_per_lod: stats.levels.iter().map(|l| l.fill).collect(),
        texels: stats.levels.iter().map(|l| l.texels).sum(),
        bytes: bytes.len() as u64,
        gpu_bytes: gpu.with_bc,
        gpu_bytes_no_bc: gpu.without_bc,
        stats: &stats,
        estimate: cost,
        seconds_import,
        compress: args.compress.clone(),
        seconds_compress,
        seconds_write,
        seconds_export,
        gltf: args.gltf.as_ref().map(|p| p.display().to_string()),
        atlas_files,
        seconds_total: start.elapsed().as_secs_f64(),
        warnings: report.messages(),
    };
    print_summary(ctx, args.json, summary.target.as_ref(), &summary, || {
        print_text(&summary)
    })
}

/// The summary on stderr: what the bake made, its size and time, and its GPU memory.
fn print_text(s: &Summary) {
    eprintln!(
        "{}: {} foliage triangles -> billboards per LOD {:?}, atlas fill {:?}, {} kept triangles, {:.1} MiB in {:.2} s",
        s.output,
        s.stats.foliage_triangles,
        s.billboards_per_lod,
        s.atlas_fill_per_lod.iter().map(|f| format!("{:.1}%", 100.0 * f)).collect::<Vec<_>>(),
        s.stats.kept_triangles,
        s.bytes as f64 / (1 << 20) as f64,
        s.seconds_total
    );
    eprintln!(
        "  {}",
        crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc)
    );
}

/// One bake: the cloud, its statistics and the estimate it was checked against; with
/// `measure_compressed` = bc, also the compressed copy (what a reader of the file gets)
/// and its blocks.
struct Cloud {
    asset: CloudAsset,
    stats: BbcloudStats,
    cost: Estimate,
    compressed: Option<(Box<CloudAsset>, CloudBlocks)>,
}

/// Estimates (refusing atlases over the limit, warning about a long search) and bakes.
fn bake_once(
    scene: &billow::scene::Scene,
    opts: &BbcloudOptions,
    args: &Args,
    ctx: &Ctx,
    input: &str,
    source: billow_format::SourceInfo,
    measure_compressed: Option<Compression>,
) -> Result<Cloud, CliError> {
    // What the bake will cost, before any heavy work: refused when the atlases would be
    // too large, a warning with the expected time when the plane search will be long.
    let cost = estimate(scene, opts).map_err(|e| bbcloud_error(input, &e))?;
    cost.check_atlases(opts)
        .map_err(|e| bad(&format!("--{}", e.option().replace('_', "-")), e))?;
    if cost.slow_search() {
        warn(
            ctx,
            &format!(
                "{input}: about {} billboards per level from {} foliage triangles: the plane \
                 search will take roughly {:.0} s ({:.1e} candidate tests; --epsilon {} and \
                 --max-extent {} set it, the defaults take a few seconds)",
                cost.billboards,
                cost.foliage_triangles,
                cost.search_seconds,
                cost.search_tests,
                short(opts.epsilon),
                args.max_extent.map_or("none".into(), short)
            ),
        );
    }

    let bar = Monotone::new(progress(ctx, progress::LEN, "bbcloud"));
    let report = |stage: Stage, f: f32| {
        bar.set(
            progress::bbcloud_fraction(stage, f, opts.lods),
            || match stage {
                Stage::Search { level } => format!("plane search, LOD {level}"),
                Stage::Render => "billboard textures".to_string(),
                Stage::Pack => "atlases".to_string(),
            },
        );
    };
    let (asset, stats) = bake(scene, opts, &tool_version(), Some(source), &report)
        .map_err(|e| bbcloud_error(input, &e))?;
    bar.finish();

    let compressed = (measure_compressed == Some(Compression::Bc)).then(|| {
        let mut c = asset.clone();
        c.header.set_compress("bc7");
        let blocks = compress_cloud(&mut c);
        (Box::new(c), blocks)
    });
    Ok(Cloud {
        asset,
        stats,
        cost,
        compressed,
    })
}

/// A bake the `--target-error` search measured: the cloud and its options.
struct Tried {
    cloud: Cloud,
    opts: BbcloudOptions,
}

impl AsRef<CloudAsset> for Tried {
    /// What a reader of the file gets: the compressed copy, when there is one.
    fn as_ref(&self) -> &CloudAsset {
        self.cloud
            .compressed
            .as_ref()
            .map_or(&self.cloud.asset, |c| &*c.0)
    }
}

/// `--target-error`: the library's search ([`search_cloud`]), each candidate baked as
/// asked here ([`bake_once`]) and its trial printed. Returns the chosen bake, its options
/// and what was tried; with `--json`, a target none meets still prints its trials.
#[allow(clippy::too_many_arguments)]
fn bake_to_target(
    scene: &billow::scene::Scene,
    opts: &BbcloudOptions,
    args: &Args,
    flags: &CloudFlags,
    target: &TargetOptions,
    compression: Compression,
    ctx: &Ctx,
    input: &str,
    source: &billow_format::SourceInfo,
) -> Result<(Cloud, BbcloudOptions, TargetSummary), CliError> {
    let mut bake = |s: &CloudSettings| {
        let o = BbcloudOptions {
            epsilon: s.epsilon,
            samples: s.samples,
            atlas_size: s.atlas_size,
            ..opts.clone()
        };
        let cloud = bake_once(
            scene,
            &o,
            args,
            ctx,
            input,
            source.clone(),
            Some(compression),
        )?;
        let bytes = match &cloud.compressed {
            Some((c, blocks)) => c.to_bytes_with(Some(blocks)),
            None => cloud.asset.to_bytes_with(None),
        }
        .map_err(|e| CliError::new(Code::Internal, e))?
        .len() as u64;
        Ok::<_, CliError>((Tried { cloud, opts: o }, bytes))
    };
    let (Tried { cloud, opts }, summary) =
        run_search(target, ctx, (args.json, input, &args.output), |on_trial| {
            search_cloud(scene, flags, target, &mut bake, on_trial)
        })?;
    Ok((cloud, opts, summary))
}
