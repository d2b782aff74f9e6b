//! `billow voxelize IN -o OUT.billow`: a volumetric billboard from a mesh (VB paper §3.2).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use billow::compress::{compress_volume, Compression};
use billow::emptyspace::{prune, prune_sparse, EmptySpaceOptions, EmptySpaceStats};
use billow::export::ktx2::ZSTD_LEVELS;
use billow::export::{
    check_slices, ktx2_bytes_with, slice_bytes, slice_file_name, SliceFormat, Supercompression,
};
use billow::import::{import, ImportOptions};
use billow::provenance::{source_info, tool_version, with_companions};
use billow::scene::Aabb;
use billow::voxelize::{
    bake_params, bake_params_for, voxelize, voxelize_sparse, Bake, CombineFn, Resolution, Stage,
    VoxelizeOptions,
};
use glam::Vec3;
use serde::Serialize;

use crate::depfile;
use crate::exit::{usage, CliError, Code};
use crate::output::{
    peak_rss_bytes, print_json, progress, refuse_clobbering, refuse_clobbering_read,
    refuse_file_as_folder, warn,
};
use crate::progress::{self, Monotone};
use crate::staged::{out_err, Staged};
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to bake: .gltf, .glb or .obj (+ .mtl).
    input: PathBuf,
    /// Where to write the volume asset (.billow). Written atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// Voxels along the longest axis (others in proportion), or exactly XxYxZ (e.g. 256x128x128);
    /// each axis 1–2048, and the estimated memory must fit.
    #[arg(long, default_value = "128")]
    res: String,
    /// K: K×K coverage samples per voxel column, 1–8; gives thin parts fractional opacity.
    #[arg(long, default_value_t = 4)]
    supersample: u32,
    /// How the six directional volumes merge: opaque (max opacity, averaged colour: keeps thin
    /// leaves and closed surfaces solid), mean (the paper's neutral average), max, min, or
    /// expr:<expression over px nx py ny pz nz> (see docs/voxelize.md).
    #[arg(long, default_value = "opaque")]
    combine: String,
    /// Normals (Toksvig-filtered MIPs) for runtime shading: auto (bake them, keep them only
    /// for a smooth solid surface, drop them for thin or fuzzy ones such as foliage and fur;
    /// see docs/voxelize.md), on (a bare --normals), or off. With normals the colour is
    /// albedo and viewers shade it under the scene light.
    #[arg(long, value_enum, value_name = "WHEN", default_value_t = NormalsArg::Auto,
          num_args = 0..=1, default_missing_value = "on")]
    normals: NormalsArg,
    /// Number of MIP levels, 1–the full chain (default: the full chain down to 1×1×1).
    #[arg(long)]
    mips: Option<u32>,
    /// Empty border around the mesh, in voxels, 0–64.
    #[arg(long, default_value_t = 0.5)]
    margin: f32,
    /// Round every side of the grid up to a multiple of N voxels, 1–2048 (the box grows evenly with
    /// empty voxels). `billow emptyspace` needs even sides, and sides that are multiples of
    /// 2^k to prune MIP levels 1..k as well. Default: with `--res N` and no `--bounds`, the
    /// largest of 8, 4, 2, 1 that divides N (so the longest axis stays N: 8 for 128, 256, 512);
    /// with `--res XxYxZ` or `--bounds`, 1 (the grid is exactly as asked).
    #[arg(long)]
    align: Option<u32>,
    /// Bake exactly this box, `minx,miny,minz,maxx,maxy,maxz` (no margin), e.g. `0,0,0,1,1,1`
    /// for a tileable volume texture used by `billow shell`.
    #[arg(long)]
    bounds: Option<String>,
    /// Texel storage: none (raw RGBA8, readable by format 1.0/1.1 readers; the default
    /// until `billow emptyspace` writes compressed bricks) or bc (BC7 blocks, one byte per
    /// texel, format 1.2). --ktx2 carries the same blocks.
    #[arg(long, default_value = "none")]
    compress: String,
    /// Also write the volume as a KTX2 3D texture with its MIP chain (premultiplied, sRGB).
    #[arg(long, value_name = "FILE")]
    ktx2: Option<PathBuf>,
    /// Supercompress the --ktx2 file's levels with Zstandard at this level, 1–22
    /// (`supercompressionScheme` 2; a loader inflates each level before upload). Needs --ktx2.
    #[arg(long, value_name = "LEVEL")]
    ktx2_zstd: Option<i32>,
    /// Also write every slice of one MIP level (see --slice-level) into this folder.
    #[arg(long, value_name = "DIR")]
    slices: Option<PathBuf>,
    /// MIP level whose slices --slices writes, 0–(MIP levels − 1).
    #[arg(long, default_value_t = 0)]
    slice_level: u32,
    /// Slice image format: png (8-bit, straight alpha) or exr (float, premultiplied).
    #[arg(long, default_value = "png")]
    slice_format: String,
    /// Baked lighting multiplied into the colour: none, or ao (ambient occlusion traced
    /// against the source mesh; see docs/voxelize.md).
    #[arg(long, default_value = "none")]
    bake: String,
    /// Rays per voxel for --bake ao, 1–4096.
    #[arg(long, default_value_t = billow::voxelize::DEFAULT_AO_RAYS)]
    ao_rays: u32,
    /// Occlusion distance for --bake ao, in scene units, > 0 (default: 0.2 × the grid's diagonal).
    #[arg(long)]
    ao_distance: Option<f32>,
    /// Treat import warnings (e.g. a missing texture) as errors.
    #[arg(long)]
    strict: bool,
    /// Write the pruned volume (what `billow emptyspace --compress none` makes of the
    /// volume, byte for byte) straight from the brick-sparse working set, without ever
    /// holding the dense volume: for large grids (1024³). Not with --ktx2, --slices or
    /// --compress bc.
    #[arg(long)]
    prune: bool,
    /// Refuse grids whose estimated peak memory (an upper bound, often several times the
    /// real peak) exceeds this many GiB, > 0.
    #[arg(long, value_name = "GIB", default_value_t = 16.0)]
    memory_limit: f64,
    /// Also write a Makefile rule listing every file the bake read (the mesh, its buffers,
    /// textures and material libraries) as prerequisites of the outputs; committed with them.
    #[arg(long, value_name = "FILE")]
    depfile: Option<PathBuf>,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Seconds {
    import: f64,
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

/// `--normals`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalsArg {
    Auto,
    On,
    Off,
}

#[derive(Serialize)]
struct Summary {
    input: String,
    output: String,
    dims: [u32; 3],
    mip_count: u32,
    combine: String,
    supersample: u32,
    normals: bool,
    /// `--normals auto`: the coherence the choice was made on (see docs/voxelize.md).
    normal_coherence: Option<f32>,
    compress: String,
    triangles: usize,
    non_empty_voxels: u64,
    fragments: u64,
    bytes: u64,
    /// With --prune: what the empty-space removal did (as `billow emptyspace --json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    prune: Option<EmptySpaceStats>,
    peak_memory_bytes: Option<u64>,
    seconds: Seconds,
    warnings: Vec<String>,
}

fn bad(flag: &str, e: impl std::fmt::Display) -> CliError {
    CliError::new(Code::BadParameter, format!("{flag}: {e}"))
}

pub fn options(
    res: &str,
    supersample: u32,
    combine: &str,
    normals: bool,
    margin: f32,
) -> Result<VoxelizeOptions, CliError> {
    let resolution: Resolution = res
        .parse()
        .map_err(|e| CliError::new(Code::from(&e), format!("--res: {e}")))?;
    resolution
        .validate()
        .map_err(|e| CliError::new(Code::from(&e), format!("--res: {e}")))?;
    let combine: CombineFn = combine
        .parse()
        .map_err(|e| CliError::new(Code::from(&e), format!("--combine: {e}")))?;
    if !(margin.is_finite() && (0.0..=64.0).contains(&margin)) {
        return Err(bad(
            "--margin",
            format!("must be between 0 and 64 voxels, got {margin}"),
        ));
    }
    Ok(VoxelizeOptions {
        resolution,
        supersample,
        combine,
        normals,
        margin,
        ..VoxelizeOptions::default()
    })
}

/// `--align` when not given: with `--res N` (and no `--bounds`) the largest of 8, 4, 2, 1 that
/// divides `N`, so that `billow emptyspace` can prune the output (it needs even sides; 8
/// lets it brick MIP levels 0–2, and keeps levels 0 and 1 in whole 4×4 blocks for block
/// compression) while the longest axis stays `N`; 1 for an exact `XxYxZ` or `--bounds`.
fn default_align(res: &Resolution, bounds: &Option<String>) -> u32 {
    match res {
        Resolution::Longest(n) if bounds.is_none() => 1 << n.trailing_zeros().min(3),
        _ => 1,
    }
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
    let mut opts = options(
        &args.res,
        args.supersample,
        &args.combine,
        args.normals != NormalsArg::Off,
        args.margin,
    )?;
    opts.mip_levels = args.mips;
    let align = args
        .align
        .unwrap_or_else(|| default_align(&opts.resolution, &args.bounds));
    if !(1..=billow::voxelize::MAX_AXIS).contains(&align) {
        return Err(bad(
            "--align",
            format!(
                "must be between 1 and {} voxels, got {align}",
                billow::voxelize::MAX_AXIS,
            ),
        ));
    }
    opts.align = align;
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
        } else if compression == Compression::Bc {
            Some("--compress bc")
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
    let scene = scene.map_err(|e| CliError::new(Code::from(&e), &e))?;
    refuse_clobbering_read(&args.input, &scene.files, &outputs)?;
    for w in &scene.warnings {
        warn(ctx, &format!("{input}: {}", w.message));
    }
    let source = source
        .and_then(|s| with_companions(&args.input, s, &scene.files))
        .map_err(|e| CliError::new(Code::InputIo, format!("{input}: cannot read: {e}")))?;
    depfile::check(
        args.depfile.as_deref(),
        &scene.files.iter().map(PathBuf::as_path).collect::<Vec<_>>(),
    )?;
    let mut warnings: Vec<String> = scene.warnings.iter().map(|w| w.message.clone()).collect();
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

    let bar = Monotone::new(progress(ctx, progress::LEN, "voxelize"));
    let report = |stage: Stage, f: f32| {
        bar.set(progress::voxelize_fraction(stage, f), || {
            format!("{stage:?}").to_lowercase()
        });
    };
    let mut pruned_stats = None;
    let (mut asset, stats, dims, mip_count, coherence) = if args.prune {
        let (asset, stats, dims, mips, coherence, ps) =
            bake_pruned(&scene, &mut opts, args.normals, &report, &input, source)?;
        bar.finish();
        if let Some(note) = &ps.note {
            warn(ctx, &format!("{input}: {note}"));
        }
        pruned_stats = Some(ps);
        (asset, stats, dims, mips, coherence)
    } else {
        let baked = bake_dense(&scene, &mut opts, args.normals, &report, &input, source)?;
        bar.finish();
        baked
    };
    let compress_start = Instant::now();
    let blocks = (compression == Compression::Bc).then(|| {
        asset.header.set_compress("bc7");
        compress_volume(&mut asset)
    });
    let compress_s = compress_start.elapsed().as_secs_f64();
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
        let text = depfile::render(&targets, &args.input, &scene.files)?;
        stage.stage(d, text.as_bytes()).map_err(|e| out_err(d, e))?;
    }
    stage.commit_or_fail()?;
    let write_s = write_start.elapsed().as_secs_f64();

    let prune_s = pruned_stats.as_ref().map_or(0.0, |p| p.seconds);
    let summary = Summary {
        input,
        output: args.output.display().to_string(),
        dims,
        mip_count,
        combine: opts.combine.to_string(),
        supersample: opts.supersample,
        normals: opts.normals,
        normal_coherence: coherence,
        compress: args.compress.clone(),
        triangles: stats.triangles,
        non_empty_voxels: stats.non_empty_voxels,
        fragments: stats.fragments,
        bytes,
        prune: pruned_stats,
        peak_memory_bytes: peak_rss_bytes(),
        seconds: Seconds {
            import: import_s,
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
    }
    Ok(())
}

/// The dense bake: [`voxelize`] (retried without normals when `--normals auto` and the
/// estimate refuses them), `--normals auto` judged at [`AUTO_NORMALS_LEVEL`], and the asset.
/// Returns the asset, the bake's statistics, the grid's dims and MIP count and the normal
/// coherence `--normals auto` judged.
#[allow(clippy::type_complexity)]
fn bake_dense(
    scene: &billow::scene::Scene,
    opts: &mut VoxelizeOptions,
    normals: NormalsArg,
    report: &dyn Fn(Stage, f32),
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<
    (
        billow_format::VolumeAsset,
        billow::voxelize::VoxelizeStats,
        [u32; 3],
        u32,
        Option<f32>,
    ),
    CliError,
> {
    use billow::voxelize::toksvig::{
        normal_coherence, AUTO_NORMALS_LEVEL, AUTO_NORMALS_MIN_COHERENCE,
    };
    let mut volume = voxelize(scene, opts, report)
        .or_else(|e| match e {
            // auto: normals are an option, not a requirement; without them the bake may fit.
            billow::voxelize::VoxelizeError::TooMuchMemory { .. }
                if normals == NormalsArg::Auto =>
            {
                opts.normals = false;
                voxelize(scene, opts, report)
            }
            e => Err(e),
        })
        .map_err(|e| CliError::new(Code::from(&e), format!("{input}: {e}")))?;
    // auto: keep the normals only where one normal per voxel describes the surface.
    let mut coherence = None;
    if normals == NormalsArg::Auto {
        if let Some(n) = volume.normals.as_ref() {
            let l = AUTO_NORMALS_LEVEL.min(volume.levels.len().saturating_sub(1));
            let k = volume
                .levels
                .get(l)
                .zip(n.get(l))
                .and_then(|(c, n)| normal_coherence(c, n));
            coherence = k;
            if k.is_none_or(|k| k < AUTO_NORMALS_MIN_COHERENCE) {
                volume.normals = None;
                opts.normals = false;
            }
        }
    }
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let mut extra = BTreeMap::new();
    if let Some(k) = coherence {
        extra.insert("normal_coherence".to_string(), format!("{k:.3}"));
    }
    let params = bake_params(&volume, opts, &extra);
    let asset = volume.into_asset(&tool_version(), Some(source), params);
    Ok((asset, stats, dims, mips, coherence))
}

/// `voxelize --prune`: the volume brick-sparse ([`voxelize_sparse`]), pruned by
/// [`prune_sparse`] with `billow emptyspace`'s defaults; with an expression or custom
/// combine (whose pyramids are dense anyway), the dense volume pruned by [`prune`]. Returns
/// the pruned asset, the bake's statistics, the grid's dims and MIP count, the normal
/// coherence `--normals auto` judged, and the prune's statistics.
#[allow(clippy::type_complexity)]
fn bake_pruned(
    scene: &billow::scene::Scene,
    opts: &mut VoxelizeOptions,
    normals: NormalsArg,
    report: &dyn Fn(Stage, f32),
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<
    (
        billow_format::VolumeAsset,
        billow::voxelize::VoxelizeStats,
        [u32; 3],
        u32,
        Option<f32>,
        EmptySpaceStats,
    ),
    CliError,
> {
    use billow::voxelize::toksvig::{AUTO_NORMALS_LEVEL, AUTO_NORMALS_MIN_COHERENCE};
    use billow::voxelize::VoxelizeError;
    let err = |e: VoxelizeError| CliError::new(Code::from(&e), format!("{input}: {e}"));
    let perr = |e: billow::emptyspace::EmptySpaceError| {
        CliError::new(Code::from(&e), format!("{input}: {e}"))
    };
    let es = EmptySpaceOptions::default();
    let keep = |k: Option<f32>| !k.is_none_or(|k| k < AUTO_NORMALS_MIN_COHERENCE);
    if !matches!(opts.combine, CombineFn::Preset(_)) {
        // Expressions and custom functions keep dense pyramids: prune the dense volume.
        let (asset, stats, dims, mips, coherence) =
            bake_dense(scene, opts, normals, report, input, source)?;
        let p = prune(&asset, &es).map_err(perr)?;
        return Ok((p.asset, stats, dims, mips, coherence, p.stats));
    }
    let mut volume = voxelize_sparse(scene, opts, report)
        .or_else(|e| match e {
            VoxelizeError::TooMuchMemory { .. } if normals == NormalsArg::Auto => {
                opts.normals = false;
                voxelize_sparse(scene, opts, report)
            }
            e => Err(e),
        })
        .map_err(err)?;
    let mut coherence = None;
    if normals == NormalsArg::Auto && volume.has_normals() {
        let l = AUTO_NORMALS_LEVEL.min(volume.levels.len().saturating_sub(1));
        let k = volume.normal_coherence(l);
        coherence = k;
        if !keep(k) {
            volume.drop_normals();
            opts.normals = false;
        }
    }
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let mut extra = BTreeMap::new();
    if let Some(k) = coherence {
        extra.insert("normal_coherence".to_string(), format!("{k:.3}"));
    }
    let params = bake_params_for(&volume.grid, opts, &extra);
    let shell = volume.asset_shell(&tool_version(), Some(source), params);
    let p = prune_sparse(&shell, volume.levels, &es).map_err(perr)?;
    Ok((p.asset, stats, dims, mips, coherence, p.stats))
}
