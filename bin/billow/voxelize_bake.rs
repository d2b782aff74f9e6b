//! The bake step of `billow voxelize` (bin/billow/voxelize.rs): one bake (dense, or
//! `--prune`d brick-sparse) compressed as asked, and the `--target-error` search over such
//! bakes.

use std::collections::BTreeMap;
use std::time::Instant;

use billow::compress::{compress_volume, encode_volume, Compression};
use billow::emptyspace::{prune, prune_sparse, EmptySpaceOptions, EmptySpaceStats};
use billow::presets::target::{search_volume, TargetOptions, Trial};
use billow::presets::{VolumeFlags, VolumeSettings};
use billow::provenance::tool_version;
use billow::voxelize::{
    bake_params, bake_params_for, bake_with_normals, default_align, voxelize, voxelize_sparse,
    CombineFn, MemoryRefusal, NormalsMode, NormalsOutcome, Stage, VoxelizeOptions,
};

use crate::exit::{voxelize_error, CliError, Code};
use crate::output::{progress, warn};
use crate::progress::{self, Monotone};
use crate::target::{search_failed, trial_line, TargetSummary};
use crate::voxelize_args::{Args, NormalsArg};
use crate::Ctx;

/// One bake, compressed as asked: what is written and what the summary reports.
pub(crate) struct Baked {
    /// With BC7, its texels are the blocks' decoding only where something reads them after
    /// the write (`--target-error`'s judge, `--slices`); otherwise they are the bake's own,
    /// and only `blocks` is written.
    pub(crate) asset: billow_format::VolumeAsset,
    pub(crate) blocks: Option<billow_format::VolumeBlocks>,
    pub(crate) stats: billow::voxelize::VoxelizeStats,
    pub(crate) dims: [u32; 3],
    pub(crate) mip_count: u32,
    pub(crate) coherence: Option<f32>,
    pub(crate) pruned: Option<EmptySpaceStats>,
    /// `--normals auto`'s coarse bake.
    pub(crate) judge_s: f64,
    pub(crate) compress_s: f64,
    /// Warnings the bake printed (also listed in `--json`).
    pub(crate) notes: Vec<String>,
}

/// Bakes with `opts` (dense or `--prune`d) and compresses as `compression` says. With
/// `--target-error` (whose judge renders the asset) or `--slices`, the asset in memory is
/// then what a reader of the file gets (BC7 blocks decoded back); otherwise a BC7 bake's
/// texels stay the bake's own, which nothing after the write reads.
pub(crate) fn bake_once(
    scene: &billow::scene::Scene,
    opts: &mut VoxelizeOptions,
    args: &Args,
    compression: Compression,
    ctx: &Ctx,
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<Baked, CliError> {
    let bar = Monotone::new(progress(ctx, progress::LEN, "voxelize"));
    let report = |stage: Stage, f: f32| {
        bar.set(progress::voxelize_fraction(stage, f), || {
            format!("{stage:?}").to_lowercase()
        });
    };
    let notes = std::cell::RefCell::new(Vec::new());
    let note = |m: &str| {
        warn(ctx, &format!("{input}: {m}"));
        notes.borrow_mut().push(m.to_string());
    };
    let hooks = Hooks {
        report: &report,
        note: &note,
    };
    let mode = match args.normals {
        NormalsArg::Auto => NormalsMode::Auto,
        NormalsArg::On => NormalsMode::On,
        NormalsArg::Moments => NormalsMode::Moments,
        NormalsArg::Off => NormalsMode::Off,
    };
    let mut pruned = None;
    let (mut asset, stats, dims, mip_count, normals) = if args.prune {
        let (asset, stats, dims, mips, normals, ps) =
            bake_pruned(scene, opts, mode, compression, hooks, input, source)?;
        bar.finish();
        if let Some(n) = &ps.note {
            note(n);
        }
        pruned = Some(ps);
        (asset, stats, dims, mips, normals)
    } else {
        let baked = bake_dense(scene, opts, mode, hooks, input, source)?;
        bar.finish();
        baked
    };
    let compress_start = Instant::now();
    let blocks = (compression == Compression::Bc).then(|| {
        asset.header.set_compress("bc7");
        if args.target.target_error.is_some() || args.slices.is_some() {
            compress_volume(&mut asset)
        } else {
            encode_volume(&asset)
        }
    });
    Ok(Baked {
        asset,
        blocks,
        stats,
        dims,
        mip_count,
        coherence: normals.coherence,
        pruned,
        judge_s: normals.judge_seconds,
        compress_s: compress_start.elapsed().as_secs_f64(),
        notes: notes.into_inner(),
    })
}

/// Where a bake reports: progress by stage, and warnings.
#[derive(Clone, Copy)]
pub(crate) struct Hooks<'a> {
    pub(crate) report: &'a dyn Fn(Stage, f32),
    pub(crate) note: &'a dyn Fn(&str),
}

/// Warns of an `Auto` bake left without normals for memory.
fn note_refusal(outcome: &NormalsOutcome, note: &dyn Fn(&str)) {
    match outcome.refused {
        Some(MemoryRefusal::Baking {
            needed_gib,
            limit_gib,
        }) => note(&format!(
            "--normals auto: baked without normals, which would need about {needed_gib:.1} GiB, more than --memory-limit {limit_gib:.1}; raise it to keep them"
        )),
        Some(MemoryRefusal::Judging { limit_gib }) => note(&format!(
            "--normals auto: baked without normals, since even judging them would need more than --memory-limit {limit_gib:.1}"
        )),
        None => {}
    }
}

/// A bake the `--target-error` search measured: what it wrote, and with which options.
pub(crate) struct Tried {
    pub(crate) baked: Baked,
    pub(crate) opts: VoxelizeOptions,
}

impl AsRef<billow_format::VolumeAsset> for Tried {
    fn as_ref(&self) -> &billow_format::VolumeAsset {
        &self.baked.asset
    }
}

/// `--target-error`: the library's search ([`search_volume`]), each candidate baked as
/// asked here ([`bake_once`]) and its trial printed. Returns the chosen bake, its options
/// and what was tried; with `--json`, a target none meets still prints its trials.
#[allow(clippy::too_many_arguments)]
pub(crate) fn bake_to_target(
    scene: &billow::scene::Scene,
    opts: &VoxelizeOptions,
    args: &Args,
    flags: &VolumeFlags,
    target: &TargetOptions,
    compression: Compression,
    ctx: &Ctx,
    input: &str,
    source: &billow_format::SourceInfo,
) -> Result<(Baked, VoxelizeOptions, TargetSummary), CliError> {
    let mut bake = |s: &VolumeSettings| {
        let mut o = opts.clone();
        o.resolution = s.resolution;
        o.supersample = s.supersample;
        o.align = args
            .align
            .unwrap_or_else(|| default_align(&o.resolution, args.bounds.is_some()));
        let baked = bake_once(scene, &mut o, args, compression, ctx, input, source.clone())?;
        let bytes = baked
            .asset
            .with_parts_with(baked.blocks.as_ref(), |parts| {
                parts.iter().map(|p| p.len() as u64).sum::<u64>()
            })
            .map_err(|e| CliError::new(Code::Internal, e))?;
        Ok::<_, CliError>((Tried { baked, opts: o }, bytes))
    };
    let mut on_trial = |t: &Trial| {
        if !ctx.quiet {
            eprintln!("{}", trial_line(target.error, t));
        }
    };
    let found = search_volume(scene, flags, target, &mut bake, &mut on_trial).map_err(|e| {
        let output = args.output.display().to_string();
        search_failed(e, target, args.json.then_some((input, &output)), input)
    })?;
    let summary = TargetSummary::new(target, &found);
    let Tried { baked, opts } = found.asset;
    Ok((baked, opts, summary))
}

/// The dense bake: [`voxelize`] with normals as `mode` says ([`bake_with_normals`]) and
/// the asset. Returns the asset, the bake's statistics, the grid's dims and MIP count and
/// what was decided about the normals.
#[allow(clippy::type_complexity)]
pub(crate) fn bake_dense(
    scene: &billow::scene::Scene,
    opts: &mut VoxelizeOptions,
    mode: NormalsMode,
    hooks: Hooks,
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<
    (
        billow_format::VolumeAsset,
        billow::voxelize::VoxelizeStats,
        [u32; 3],
        u32,
        NormalsOutcome,
    ),
    CliError,
> {
    let Hooks { report, note } = hooks;
    let (volume, normals) = bake_with_normals(
        scene,
        opts,
        mode,
        |o| voxelize(scene, o, report),
        |v| (v.normal_coherence, v.normals.is_some()),
    )
    .map_err(|e| voxelize_error(input, &e))?;
    note_refusal(&normals, note);
    let coherence = normals.coherence;
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let mut extra = BTreeMap::new();
    if let Some(k) = coherence {
        extra.insert("normal_coherence".to_string(), format!("{k:.3}"));
    }
    let params = bake_params(&volume, opts, &extra);
    let asset = volume.into_asset(&tool_version(), Some(source), params);
    Ok((asset, stats, dims, mips, normals))
}

/// `voxelize --prune`: the volume brick-sparse ([`voxelize_sparse`]), pruned by
/// [`prune_sparse`] with `billow emptyspace`'s defaults; with an expression or custom
/// combine (whose pyramids are dense anyway), the dense volume pruned by [`prune`]. Returns
/// the pruned asset, the bake's statistics, the grid's dims and MIP count, what was
/// decided about the normals, and the prune's statistics.
#[allow(clippy::type_complexity)]
fn bake_pruned(
    scene: &billow::scene::Scene,
    opts: &mut VoxelizeOptions,
    mode: NormalsMode,
    compression: Compression,
    hooks: Hooks,
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<
    (
        billow_format::VolumeAsset,
        billow::voxelize::VoxelizeStats,
        [u32; 3],
        u32,
        NormalsOutcome,
        EmptySpaceStats,
    ),
    CliError,
> {
    use billow::voxelize::VoxelizeError;
    let err = |e: VoxelizeError| voxelize_error(input, &e);
    let perr = |e: billow::emptyspace::EmptySpaceError| {
        CliError::new(Code::from(&e), format!("{input}: {e}"))
    };
    let es = EmptySpaceOptions {
        bc_blocks: compression == Compression::Bc,
        memory_limit: opts.memory_limit,
        ..EmptySpaceOptions::default()
    };
    if !matches!(opts.combine, CombineFn::Preset(_)) {
        // Expressions and custom functions give dense levels: prune the dense volume.
        let (asset, stats, dims, mips, normals) =
            bake_dense(scene, opts, mode, hooks, input, source)?;
        let p = prune(&asset, &es).map_err(perr)?;
        return Ok((p.asset, stats, dims, mips, normals, p.stats));
    }
    let Hooks { report, note } = hooks;
    let (volume, normals) = bake_with_normals(
        scene,
        opts,
        mode,
        |o| voxelize_sparse(scene, o, report),
        |v| (v.normal_coherence, v.has_normals()),
    )
    .map_err(err)?;
    note_refusal(&normals, note);
    let coherence = normals.coherence;
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let mut extra = BTreeMap::new();
    if let Some(k) = coherence {
        extra.insert("normal_coherence".to_string(), format!("{k:.3}"));
    }
    let params = bake_params_for(&volume.grid, opts, &extra);
    let shell = volume.asset_shell(&tool_version(), Some(source), params);
    // The bake freed its working set (dropped normals too): the prune's atlases come after.
    crate::alloc::release_free_memory();
    let p = prune_sparse(&shell, volume.levels, &es).map_err(perr)?;
    Ok((p.asset, stats, dims, mips, normals, p.stats))
}
