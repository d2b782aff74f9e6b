//! `billow voxelize IN -o OUT.billow`: a volumetric billboard from a mesh (VB paper §3.2).
//! The steps: the flags checked ([`plan`]), the outputs refused before any work, the mesh
//! read ([`read_input`]), the bake (bin/billow/voxelize_bake.rs), the outputs written
//! together ([`write_outputs`]) and the summary (bin/billow/voxelize_summary.rs).

use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::compress::Compression;
use billow::export::{
    check_slices, ktx2_bytes_with, slice_bytes, slice_file_name, SliceFormat, Supercompression,
};
use billow::import::{import, ImportOptions, ImportReport, Imported};
use billow::presets::{resolve_volume, Preset, ResolvedVolume, VolumeFlags, VolumeSettings};
use billow::provenance::{source_info, with_companions};
use billow::scene::Scene;
use billow::target_error::TargetOptions;
use billow::voxelize::{
    check_align, check_bounds, default_align, memory_limit_bytes, Bake, Baked, CombineFn,
    Resolution, VoxelizeOptions,
};
use billow_core::Aabb;
use billow_format::{SourceInfo, VolumeAsset, VolumeBlocks};
use glam::Vec3;

use crate::bake_steps::{
    imported, parse_compress, parse_preset, print_summary, refuse_outputs, settings_preset,
    settings_source,
};
use crate::depfile;
use crate::exit::{bad, option_error, usage, CliError, Code};
use crate::output::{peak_rss_bytes, warn};
use crate::staged::{out_err, Staged};
use crate::target::{target_options, TargetSummary};
use crate::voxelize_args::{Args, NormalsArg};
use crate::voxelize_bake::{bake_once, bake_to_target, BakeRun};
use crate::voxelize_summary::{print_text, Seconds, SettingsFrom, Summary};
use crate::Ctx;

/// `--res` → a validated [`Resolution`].
fn parse_res(res: &str) -> Result<Resolution, CliError> {
    let resolution: Resolution = res
        .parse()
        .map_err(|e| CliError::new(Code::from(&e), format!("--res: {e}")))?;
    resolution
        .validate()
        .map_err(|e| CliError::new(Code::from(&e), format!("--res: {e}")))?;
    Ok(resolution)
}

pub fn options(
    resolution: Resolution,
    supersample: u32,
    combine: &str,
    normals: bool,
    margin: f32,
) -> Result<VoxelizeOptions, CliError> {
    let combine: CombineFn = combine
        .parse()
        .map_err(|e| CliError::new(Code::from(&e), format!("--combine: {e}")))?;
    billow::voxelize::grid::check_margin(margin).map_err(|e| bad("--margin", e))?;
    Ok(VoxelizeOptions {
        resolution,
        supersample,
        combine,
        normals,
        margin,
        ..VoxelizeOptions::default()
    })
}

/// `minx,miny,minz,maxx,maxy,maxz` → a box, checked by the library's rule
/// ([`check_bounds`]: finite, min < max on every axis).
fn parse_bounds(s: &str) -> Result<Aabb, CliError> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| usage("--bounds", format!("'{s}': {e}")))?;
    if v.len() != 6 {
        return Err(usage(
            "--bounds",
            format!("'{s}': expected six numbers minx,miny,minz,maxx,maxy,maxz"),
        ));
    }
    let (min, max) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
    let bounds = Aabb { min, max };
    check_bounds(&bounds).map_err(|e| bad("--bounds", format!("'{s}': {e}")))?;
    Ok(bounds)
}

/// `--bake`, `--ao-rays`, `--ao-distance` → [`Bake`], checked by the library's rule
/// ([`Bake::validate`]).
fn parse_bake(bake: &str, rays: u32, distance: Option<f32>) -> Result<Bake, CliError> {
    let bake = match bake {
        "none" if distance.is_some() => {
            return Err(bad(
                "--ao-distance",
                "applies to --bake ao only (nothing would use it); add --bake ao or drop it",
            ))
        }
        "none" => Bake::None,
        "ao" => Bake::Ao { rays, distance },
        other => {
            return Err(usage(
                "--bake",
                format!("expected none or ao, got '{other}'"),
            ))
        }
    };
    bake.validate().map_err(option_error)?;
    Ok(bake)
}

/// What the flags ask for, checked before any work: the bake's options and the outputs'
/// formats.
struct Plan {
    preset: Option<Preset>,
    flags: VolumeFlags,
    resolved: ResolvedVolume,
    target: Option<TargetOptions>,
    opts: VoxelizeOptions,
    compression: Compression,
    supercompression: Supercompression,
    slice_format: SliceFormat,
}

/// Every flag checked, in the order their errors are reported.
fn plan(args: &Args) -> Result<Plan, CliError> {
    let preset = parse_preset(args.preset.as_deref())?;
    let flags = VolumeFlags {
        resolution: args.res.as_deref().map(parse_res).transpose()?,
        supersample: args.supersample,
    };
    let resolved = resolve_volume(preset, &flags);
    let target = target_options(&args.target)?;
    let mut opts = volume_options(args, &resolved.settings)?;
    let compression = parse_compress(&args.compress)?;
    let supercompression = parse_zstd(args)?;
    if let Some(b) = &args.bounds {
        opts.bounds = Some(parse_bounds(b)?);
    }
    let slice_format = match args.slice_format.as_str() {
        "png" => SliceFormat::Png8,
        "exr" => SliceFormat::Exr,
        other => {
            return Err(usage(
                "--slice-format",
                format!("expected png or exr, got '{other}'"),
            ))
        }
    };
    check_prune(args)?;
    Ok(Plan {
        preset,
        flags,
        resolved,
        target,
        opts,
        compression,
        supercompression,
        slice_format,
    })
}

/// The bake's options from `settings` (the resolved `--res`, `--supersample`) and the
/// flags: `--combine`, `--margin`, `--mips`, `--align`, `--bake`, `--memory-limit`.
fn volume_options(args: &Args, settings: &VolumeSettings) -> Result<VoxelizeOptions, CliError> {
    let mut opts = options(
        settings.resolution,
        settings.supersample,
        &args.combine,
        args.normals != NormalsArg::Off,
        args.margin,
    )?;
    opts.mip_levels = args.mips;
    if let Some(align) = args.align {
        check_align(align).map_err(option_error)?;
    }
    opts.align = args
        .align
        .unwrap_or_else(|| default_align(&opts.resolution, args.bounds.is_some()));
    opts.bake = parse_bake(&args.bake, args.ao_rays, args.ao_distance)?;
    opts.memory_limit = memory_limit_bytes(args.memory_limit).map_err(option_error)?;
    Ok(opts)
}

/// `--ktx2-zstd LEVEL` (with `--ktx2`).
fn parse_zstd(args: &Args) -> Result<Supercompression, CliError> {
    match args.ktx2_zstd {
        None => Ok(Supercompression::None),
        Some(_) if args.ktx2.is_none() => Err(usage("--ktx2-zstd", "needs --ktx2 FILE")),
        Some(l) => Supercompression::zstd(l).map_err(|e| bad("--ktx2-zstd", e)),
    }
}

/// `--prune` writes the pruned asset only: not with `--ktx2` or `--slices`.
fn check_prune(args: &Args) -> Result<(), CliError> {
    if !args.prune {
        return Ok(());
    }
    let other = if args.ktx2.is_some() {
        Some("--ktx2")
    } else if args.slices.is_some() {
        Some("--slices")
    } else {
        None
    };
    match other {
        Some(flag) => Err(usage(
            "--prune",
            format!("writes the pruned asset only and cannot be combined with {flag}"),
        )),
        None => Ok(()),
    }
}

/// The files the command writes, each with its flag (`--slices` apart: a folder).
fn outputs(args: &Args) -> Vec<(&'static str, &Path)> {
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(args.ktx2.as_deref().map(|k| ("--ktx2", k)));
    outputs.extend(args.depfile.as_deref().map(|k| ("--depfile", k)));
    outputs
}

/// The mesh as imported, its report, its provenance and the warnings the summary lists.
struct Input {
    scene: Scene,
    report: ImportReport,
    source: SourceInfo,
    warnings: Vec<String>,
}

/// Imports the mesh (its checksum computed beside the import, which is mostly
/// single-threaded; an import error is still the one reported first), refusing outputs
/// that would replace a file it read, and warns when `--bounds` misses it.
fn read_input(
    args: &Args,
    ctx: &Ctx,
    outputs: &[(&str, &Path)],
    bounds: Option<Aabb>,
    input: &str,
) -> Result<Input, CliError> {
    let (scene, source) = std::thread::scope(|scope| {
        let source = scope.spawn(|| source_info(&args.input));
        let scene = import(
            &args.input,
            &ImportOptions {
                strict: args.strict,
            },
        );
        (scene, source.join().expect("checksum thread panicked"))
    });
    let Imported { scene, report } = imported(&args.input, input, scene, outputs, ctx)?;
    let source = source
        .and_then(|s| with_companions(&args.input, s, &report.files))
        .map_err(|e| CliError::new(Code::InputIo, format!("{input}: cannot read: {e}")))?;
    depfile::check_read(args.depfile.as_deref(), &report.files)?;
    let mut warnings: Vec<String> = report.messages();
    if let Some(b) = bounds {
        let m = scene.bounds;
        if !scene.triangles.is_empty() && (b.max.cmplt(m.min).any() || b.min.cmpgt(m.max).any()) {
            let w = format!(
                "--bounds {}: the box misses the mesh (its bounds are {:?}..{:?}): the volume \
                 will be empty",
                args.bounds.as_deref().unwrap_or_default(),
                m.min.to_array(),
                m.max.to_array()
            );
            warn(ctx, &format!("{input}: {w}"));
            warnings.push(w);
        }
    }
    Ok(Input {
        scene,
        report,
        source,
        warnings,
    })
}

/// Writes every output: to temporary files first, renamed into place together, -o last
/// (see staged.rs), so a failure or a kill leaves the old outputs as they were. Returns
/// the asset's size in bytes.
fn write_outputs(
    args: &Args,
    plan: &Plan,
    (asset, blocks): (&VolumeAsset, Option<&VolumeBlocks>),
    report: &ImportReport,
) -> Result<u64, CliError> {
    let mut stage = Staged::new(&args.output);
    // Streamed from the texel data (no file-sized copy in memory).
    let bytes = asset
        .with_parts_with(blocks, |parts| {
            let len = parts.iter().map(|p| p.len() as u64).sum::<u64>();
            stage.stage_parts(&args.output, parts).map(|()| len)
        })
        .map_err(|e| CliError::new(Code::Internal, e))?
        .map_err(|e| out_err(&args.output, e))?;
    if let Some(path) = &args.ktx2 {
        let ktx = ktx2_bytes_with(asset, blocks, plan.supercompression, path)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        stage.stage(path, &ktx).map_err(|e| out_err(path, e))?;
    }
    let mut written: Vec<PathBuf> = Vec::new();
    if let Some(dir) = &args.slices {
        let depth = check_slices(asset, args.slice_level, dir)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        stage.create_dir(dir).map_err(|e| out_err(dir, e))?;
        for z in 0..depth {
            let path = dir.join(slice_file_name(z, plan.slice_format));
            let png = slice_bytes(asset, args.slice_level, z, plan.slice_format, &path)
                .map_err(|e| CliError::new(Code::from(&e), e))?;
            stage.stage(&path, &png).map_err(|e| out_err(&path, e))?;
            written.push(path);
        }
    }
    let targets = (
        args.output.as_path(),
        args.ktx2.as_deref(),
        written.as_slice(),
    );
    depfile::commit(stage, args.depfile.as_deref(), targets, &args.input, report)?;
    Ok(bytes)
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let start = Instant::now();
    let plan = plan(&args)?;
    let outputs = outputs(&args);
    let slices = args.slices.as_deref().map(|d| ("--slices", d));
    refuse_outputs(&args.input, &outputs, slices, args.depfile.as_deref(), None)?;
    let input = args.input.display().to_string();
    let Input {
        scene,
        report,
        source,
        warnings,
    } = read_input(&args, ctx, &outputs, plan.opts.bounds, &input)?;
    let import_s = start.elapsed().as_secs_f64();

    let (opts, compression) = (&plan.opts, plan.compression);
    let (run, target) = match &plan.target {
        None => (
            bake_once(&scene, opts, &args, compression, ctx, &input, source)?,
            None,
        ),
        Some(t) => {
            let (run, summary) = bake_to_target(
                &scene,
                opts,
                &args,
                &plan.flags,
                t,
                compression,
                ctx,
                &input,
                &source,
            )?;
            (run, Some(summary))
        }
    };
    let gpu =
        billow_core::gpu_memory::volume_gpu_bytes(&run.baked.asset, run.baked.blocks.is_some());
    let write_start = Instant::now();
    let bytes = write_outputs(
        &args,
        &plan,
        (&run.baked.asset, run.baked.blocks.as_ref()),
        &report,
    )?;
    let write_s = write_start.elapsed().as_secs_f64();
    let times = (import_s, write_s, start);
    let summary = summary(
        &args,
        &plan,
        input,
        (run, target),
        (bytes, gpu),
        times,
        warnings,
    );
    print_summary(ctx, args.json, summary.target.as_ref(), &summary, || {
        print_text(&summary, args.normals)
    })
}

/// The summary of a bake: the settings (as the bake used them) and where they came from,
/// what it made, its sizes and times.
fn summary(
    args: &Args,
    plan: &Plan,
    input: String,
    (run, target): (BakeRun, Option<TargetSummary>),
    (bytes, gpu): (u64, billow_core::gpu_memory::GpuBytes),
    (import_s, write_s, start): (f64, f64, Instant),
    mut warnings: Vec<String>,
) -> Summary {
    let BakeRun { baked, notes } = run;
    let Baked {
        stats,
        dims,
        mip_count,
        normals,
        pruned,
        options: opts,
        compress_seconds,
        ..
    } = baked;
    warnings.extend(notes);
    let prune_s = pruned.as_ref().map_or(0.0, |p| p.seconds);
    let from = |s| settings_source(target.as_ref(), s);
    Summary {
        input,
        output: args.output.display().to_string(),
        preset: settings_preset(target.as_ref(), plan.preset),
        resolution: opts.resolution.to_string(),
        settings_from: SettingsFrom {
            resolution: from(plan.resolved.resolution_from),
            supersample: from(plan.resolved.supersample_from),
        },
        target,
        dims,
        mip_count,
        combine: opts.combine.to_string(),
        supersample: opts.supersample,
        normals: opts.normals,
        normal_moments: opts.normals && opts.moments,
        normal_coherence: normals.coherence,
        compress: args.compress.clone(),
        triangles: stats.triangles,
        non_empty_voxels: stats.non_empty_voxels,
        fragments: stats.fragments,
        bytes,
        gpu_bytes: gpu.with_bc,
        gpu_bytes_no_bc: gpu.without_bc,
        prune: pruned,
        estimated_peak_memory_bytes: stats.estimated_peak_bytes,
        peak_memory_bytes: peak_rss_bytes(),
        seconds: Seconds {
            import: import_s,
            judge_normals: normals.judge_seconds,
            rasterize: stats.seconds.rasterize,
            bake: stats.seconds.bake,
            mip: stats.seconds.mip,
            combine: stats.seconds.combine,
            quantize: stats.seconds.quantize,
            compress: compress_seconds,
            prune: prune_s,
            write: write_s,
            total: start.elapsed().as_secs_f64(),
        },
        warnings,
    }
}
