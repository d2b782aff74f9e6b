//! `billow voxelize IN -o OUT.billow`: a volumetric billboard from a mesh (VB paper §3.2).

use std::path::PathBuf;
use std::time::Instant;

use billow::compress::Compression;
use billow::emptyspace::EmptySpaceStats;
use billow::export::ktx2::ZSTD_LEVELS;
use billow::export::{
    check_slices, ktx2_bytes_with, slice_bytes, slice_file_name, SliceFormat, Supercompression,
};
use billow::import::{import, ImportOptions, Imported};
use billow::presets::{resolve_volume, Preset, Source, VolumeFlags};
use billow::provenance::{source_info, with_companions};
use billow::voxelize::{default_align, Bake, Baked, CombineFn, Resolution, VoxelizeOptions};
use billow_core::Aabb;
use glam::Vec3;
use serde::Serialize;

use crate::depfile;
use crate::exit::{usage, CliError, Code};
use crate::output::{
    peak_rss_bytes, print_json, refuse_clobbering, refuse_clobbering_read, refuse_file_as_folder,
    warn,
};
use crate::staged::{out_err, Staged};
use crate::target::{target_options, TargetSummary};
use crate::voxelize_args::{Args, NormalsArg};
use crate::voxelize_bake::{bake_once, bake_to_target, BakeRun};
use crate::Ctx;

#[derive(Serialize)]
struct Seconds {
    import: f64,
    /// `--normals auto`'s judgement: a bake at the judged level's size.
    judge_normals: f64,
    rasterize: f64,
    bake: f64,
    mip: f64,
    combine: f64,
    quantize: f64,
    compress: f64,
    /// With --prune: the empty-space removal.
    prune: f64,
    write: f64,
    total: f64,
}

/// Where the resolved `--res` and `--supersample` came from.
#[derive(Serialize)]
struct SettingsFrom {
    resolution: Source,
    supersample: Source,
}

#[derive(Serialize)]
struct Summary {
    input: String,
    output: String,
    /// The preset the settings came from (with --target-error: the chosen one's).
    preset: Option<Preset>,
    /// The resolved --res.
    resolution: String,
    settings_from: SettingsFrom,
    /// With --target-error: what was tried and chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    target: Option<TargetSummary>,
    dims: [u32; 3],
    mip_count: u32,
    combine: String,
    supersample: u32,
    normals: bool,
    /// The stored normals are the diagonal of their second moment (`--normals moments`, or
    /// `auto` on a thin or fuzzy surface).
    normal_moments: bool,
    /// `--normals auto`: the coherence the choice was made on (see docs/voxelize.md).
    normal_coherence: Option<f32>,
    compress: String,
    triangles: usize,
    non_empty_voxels: u64,
    fragments: u64,
    bytes: u64,
    /// Texture bytes `billow view` holds on a device that samples BC7 blocks, and on one
    /// that does not (`billow_core::gpu_memory`; equal for `--compress none`).
    gpu_bytes: u64,
    gpu_bytes_no_bc: u64,
    /// With --prune: what the empty-space removal did (as `billow emptyspace --json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    prune: Option<EmptySpaceStats>,
    /// The estimate `--memory-limit` was checked against (docs/voxelize.md, "Memory").
    estimated_peak_memory_bytes: u64,
    peak_memory_bytes: Option<u64>,
    seconds: Seconds,
    warnings: Vec<String>,
}

fn bad(flag: &str, e: impl std::fmt::Display) -> CliError {
    CliError::new(Code::BadParameter, format!("{flag}: {e}"))
}

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

/// `minx,miny,minz,maxx,maxy,maxz` → a box with min < max on every axis.
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
    if v.iter().any(|x| !x.is_finite()) {
        return Err(bad(
            "--bounds",
            format!("'{s}': expected six finite numbers minx,miny,minz,maxx,maxy,maxz"),
        ));
    }
    let (min, max) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
    if !min.cmplt(max).all() {
        return Err(bad(
            "--bounds",
            format!("'{s}': min must be below max on every axis"),
        ));
    }
    Ok(Aabb { min, max })
}

/// `--bake`, `--ao-rays`, `--ao-distance` → [`Bake`].
fn parse_bake(bake: &str, rays: u32, distance: Option<f32>) -> Result<Bake, CliError> {
    match bake {
        "none" if distance.is_some() => Err(bad(
            "--ao-distance",
            "applies to --bake ao only (nothing would use it); add --bake ao or drop it",
        )),
        "none" => Ok(Bake::None),
        "ao" => {
            if !(1..=billow::voxelize::MAX_AO_RAYS).contains(&rays) {
                return Err(bad(
                    "--ao-rays",
                    format!(
                        "must be between 1 and {}, got {rays}",
                        billow::voxelize::MAX_AO_RAYS
                    ),
                ));
            }
            if let Some(d) = distance {
                if !(d.is_finite() && d > 0.0) {
                    return Err(bad(
                        "--ao-distance",
                        format!("must be a positive number, got {d}"),
                    ));
                }
            }
            Ok(Bake::Ao { rays, distance })
        }
        other => Err(usage(
            "--bake",
            format!("expected none or ao, got '{other}'"),
        )),
    }
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let start = Instant::now();
    let preset = args
        .preset
        .as_deref()
        .map(str::parse::<Preset>)
        .transpose()
        .map_err(|e| usage("--preset", e))?;
    let flags = VolumeFlags {
        resolution: args.res.as_deref().map(parse_res).transpose()?,
        supersample: args.supersample,
    };
    let resolved = resolve_volume(preset, &flags);
    let target = target_options(&args.target)?;
    let mut opts = options(
        resolved.settings.resolution,
        resolved.settings.supersample,
        &args.combine,
        args.normals != NormalsArg::Off,
        args.margin,
    )?;
    opts.mip_levels = args.mips;
    if let Some(align) = args.align {
        if !(1..=billow::voxelize::MAX_AXIS).contains(&align) {
            return Err(bad(
                "--align",
                format!(
                    "must be between 1 and {} voxels, got {align}",
                    billow::voxelize::MAX_AXIS,
                ),
            ));
        }
    }
    opts.align = args
        .align
        .unwrap_or_else(|| default_align(&opts.resolution, args.bounds.is_some()));
    opts.bake = parse_bake(&args.bake, args.ao_rays, args.ao_distance)?;
    if !(args.memory_limit.is_finite() && args.memory_limit > 0.0) {
        return Err(bad(
            "--memory-limit",
            format!(
                "must be a positive number of GiB, got {}",
                args.memory_limit
            ),
        ));
    }
    opts.memory_limit = (args.memory_limit * (1u64 << 30) as f64).min(u64::MAX as f64) as u64;
    let compression: Compression = args.compress.parse().map_err(|e| usage("--compress", e))?;
    let supercompression = match args.ktx2_zstd {
        None => Supercompression::None,
        Some(_) if args.ktx2.is_none() => {
            return Err(usage("--ktx2-zstd", "needs --ktx2 FILE"));
        }
        Some(l) if !ZSTD_LEVELS.contains(&l) => {
            return Err(bad(
                "--ktx2-zstd",
                format!(
                    "must be a Zstandard level {}–{}, got {l}",
                    ZSTD_LEVELS.start(),
                    ZSTD_LEVELS.end()
                ),
            ));
        }
        Some(l) => Supercompression::Zstd(l),
    };
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
    if args.prune {
        let other = if args.ktx2.is_some() {
            Some("--ktx2")
        } else if args.slices.is_some() {
            Some("--slices")
        } else {
            None
        };
        if let Some(flag) = other {
            return Err(usage(
                "--prune",
                format!("writes the pruned asset only and cannot be combined with {flag}"),
            ));
        }
    }
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(args.ktx2.as_deref().map(|k| ("--ktx2", k)));
    outputs.extend(args.depfile.as_deref().map(|k| ("--depfile", k)));
    refuse_clobbering(&[&args.input], &outputs)?;
    if let Some(dir) = &args.slices {
        refuse_file_as_folder("--slices", dir)?;
    }
    let mut named: Vec<&std::path::Path> = outputs.iter().map(|(_, p)| *p).collect();
    named.push(&args.input);
    depfile::check(args.depfile.as_deref(), &named)?;
    let input = args.input.display().to_string();

    // The input's checksum (provenance) is computed beside the import, which is mostly
    // single-threaded; an import error is still the one reported first.
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
    let Imported { scene, report } = scene.map_err(|e| CliError::new(Code::from(&e), &e))?;
    refuse_clobbering_read(&args.input, &report.files, &outputs)?;
    for w in &report.warnings {
        warn(ctx, &format!("{input}: {}", w.message));
    }
    let source = source
        .and_then(|s| with_companions(&args.input, s, &report.files))
        .map_err(|e| CliError::new(Code::InputIo, format!("{input}: cannot read: {e}")))?;
    depfile::check(
        args.depfile.as_deref(),
        &report
            .files
            .iter()
            .map(PathBuf::as_path)
            .collect::<Vec<_>>(),
    )?;
    let mut warnings: Vec<String> = report.messages();
    if let Some(b) = opts.bounds {
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
    let import_s = start.elapsed().as_secs_f64();

    let (run, target_summary) = match &target {
        None => (
            bake_once(&scene, &opts, &args, compression, ctx, &input, source)?,
            None,
        ),
        Some(t) => {
            let (run, summary) = bake_to_target(
                &scene,
                &opts,
                &args,
                &flags,
                t,
                compression,
                ctx,
                &input,
                &source,
            )?;
            (run, Some(summary))
        }
    };
    let BakeRun { baked, notes } = run;
    let Baked {
        asset,
        blocks,
        stats,
        dims,
        mip_count,
        normals,
        pruned: pruned_stats,
        options,
        compress_seconds: compress_s,
    } = baked;
    // As the bake used them (the normals it kept, the chosen settings of --target-error).
    opts = options;
    warnings.extend(notes);
    let gpu = billow_core::gpu_memory::volume_gpu_bytes(&asset, blocks.is_some());
    let write_start = Instant::now();
    // All outputs go to temporary files first and are renamed into place together, -o last
    // (see staged.rs): a failure or a kill leaves the old outputs as they were.
    let mut stage = Staged::new(&args.output);
    // Streamed from the texel data (no file-sized copy in memory).
    let bytes = asset
        .with_parts_with(blocks.as_ref(), |parts| {
            let len = parts.iter().map(|p| p.len() as u64).sum::<u64>();
            stage.stage_parts(&args.output, parts).map(|()| len)
        })
        .map_err(|e| CliError::new(Code::Internal, e))?
        .map_err(|e| out_err(&args.output, e))?;
    if let Some(path) = &args.ktx2 {
        let ktx = ktx2_bytes_with(&asset, blocks.as_ref(), supercompression, path)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        stage.stage(path, &ktx).map_err(|e| out_err(path, e))?;
    }
    let mut written: Vec<PathBuf> = Vec::new();
    if let Some(dir) = &args.slices {
        let depth = check_slices(&asset, args.slice_level, dir)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        stage.create_dir(dir).map_err(|e| out_err(dir, e))?;
        for z in 0..depth {
            let path = dir.join(slice_file_name(z, slice_format));
            let png = slice_bytes(&asset, args.slice_level, z, slice_format, &path)
                .map_err(|e| CliError::new(Code::from(&e), e))?;
            stage.stage(&path, &png).map_err(|e| out_err(&path, e))?;
            written.push(path);
        }
    }
    if let Some(d) = &args.depfile {
        let mut targets = vec![args.output.as_path()];
        targets.extend(args.ktx2.as_deref());
        targets.extend(written.iter().map(PathBuf::as_path));
        let text = depfile::render(&targets, &args.input, &report.files, &report.missing)?;
        stage.stage(d, text.as_bytes()).map_err(|e| out_err(d, e))?;
    }
    stage.commit_or_fail()?;
    let write_s = write_start.elapsed().as_secs_f64();

    let prune_s = pruned_stats.as_ref().map_or(0.0, |p| p.seconds);
    let by_target = target_summary.is_some();
    let from = |s: Source| if by_target { Source::Target } else { s };
    let summary = Summary {
        input,
        output: args.output.display().to_string(),
        preset: target_summary
            .as_ref()
            .map_or(preset, |t: &TargetSummary| t.chosen_preset),
        resolution: opts.resolution.to_string(),
        settings_from: SettingsFrom {
            resolution: from(resolved.resolution_from),
            supersample: from(resolved.supersample_from),
        },
        target: target_summary,
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
        prune: pruned_stats,
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
            compress: compress_s,
            prune: prune_s,
            write: write_s,
            total: start.elapsed().as_secs_f64(),
        },
        warnings,
    };
    if let (Some(t), false) = (&summary.target, ctx.quiet) {
        eprintln!("{}", t.line());
    }
    if args.json {
        print_json(&summary)?;
    } else if !ctx.quiet {
        eprintln!(
            "{}: {}x{}x{} voxels, {} MIP levels, {} non-empty, {:.1} MiB in {:.2} s",
            summary.output,
            dims[0],
            dims[1],
            dims[2],
            mip_count,
            stats.non_empty_voxels,
            bytes as f64 / (1 << 20) as f64,
            summary.seconds.total
        );
        for line in summary_lines(&summary, args.normals) {
            eprintln!("  {line}");
        }
    }
    Ok(())
}

/// What the plain-text summary says below its first line: the settings and where each
/// came from, what `--normals` decided and why, and what `--prune` saved.
fn summary_lines(s: &Summary, normals: NormalsArg) -> Vec<String> {
    use billow::voxelize::toksvig::AUTO_NORMALS_MIN_COHERENCE;
    let from = |src: Source| match src {
        Source::Default => "default",
        Source::Preset => "preset",
        Source::Flag => "flag",
        Source::Target => "--target-error",
    };
    let mut lines = vec![format!(
        "settings: {}--res {} ({}), --supersample {} ({}), --combine {}, --compress {}",
        s.preset
            .map_or(String::new(), |p| format!("--preset {p}: ")),
        s.resolution,
        from(s.settings_from.resolution),
        s.supersample,
        from(s.settings_from.supersample),
        s.combine,
        s.compress
    )];
    const LIT: &str = "viewers light the albedo two-sided, like its mesh";
    lines.push(match (normals, s.normals, s.normal_coherence) {
        (NormalsArg::Auto, true, Some(k)) if k >= AUTO_NORMALS_MIN_COHERENCE => format!(
            "normals: moments (--normals auto; coherence {k:.2} ≥ {AUTO_NORMALS_MIN_COHERENCE}: \
             a closed surface, level 0 kept as baked; {LIT})"
        ),
        (NormalsArg::Auto, true, Some(k)) => format!(
            "normals: moments (--normals auto; coherence {k:.2} < {AUTO_NORMALS_MIN_COHERENCE}: \
             thin or fuzzy, such as foliage, level 0 thinned to the mesh's coverage; {LIT})"
        ),
        (NormalsArg::Auto, true, None) => {
            format!("normals: moments (--normals auto; nothing at the judged level; {LIT})")
        }
        (NormalsArg::Auto, false, _) => {
            "normals: none (--normals auto: given up, see the warning above)".to_string()
        }
        (_, true, _) if s.normal_moments => format!("normals: moments (--normals moments; {LIT})"),
        (_, true, _) => {
            "normals: mean (--normals on: Toksvig's mean normal, lit one-sided)".to_string()
        }
        (_, false, _) => "normals: none (--normals off)".to_string(),
    });
    lines.push(crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc));
    if let Some(p) = &s.prune {
        lines.push(if p.kept_whole {
            format!(
                "prune: kept whole ({})",
                p.note.as_deref().unwrap_or("no brick layout was smaller")
            )
        } else {
            format!(
                "prune: texels {:.1} → {:.1} MiB ({:.0} % saved), {} boxes, {} LOD bands",
                p.texel_bytes_before as f64 / (1 << 20) as f64,
                p.texel_bytes_after as f64 / (1 << 20) as f64,
                p.saving * 100.0,
                p.boxes,
                p.bands.len()
            )
        });
    }
    lines
}
