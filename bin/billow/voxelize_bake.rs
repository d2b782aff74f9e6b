//! The bake step of `billow voxelize` (bin/billow/voxelize.rs): one bake through the
//! library's [`billow::voxelize::bake`] (dense, or `--prune`d brick-sparse, compressed as
//! asked) with the command's progress bar, warnings and exit codes, and the
//! `--target-error` search over such bakes.

use billow::compress::Compression;
use billow::presets::{VolumeFlags, VolumeSettings};
use billow::target_error::{search_volume, TargetOptions};
use billow::voxelize::{
    bake, default_align, BakeError, BakeHooks, BakeOptions, Baked, NormalsMode, Stage,
    VoxelizeOptions,
};

use crate::exit::{voxelize_error, CliError, Code};
use crate::output::{progress, warn};
use crate::progress::{self, Monotone};
use crate::target::{run_search, TargetSummary};
use crate::voxelize_args::{Args, NormalsArg};
use crate::Ctx;

/// One bake and the warnings it printed (also listed in `--json`).
pub(crate) struct BakeRun {
    pub(crate) baked: Baked,
    pub(crate) notes: Vec<String>,
}

/// Bakes with `opts` as the flags say ([`bake`]: dense or `--prune`d, normals as
/// `--normals` says, compressed as `compression` says). With `--target-error` (whose judge
/// renders the asset) or `--slices`, the asset in memory is then what a reader of the file
/// gets (BC7 blocks decoded back); otherwise a BC7 bake's texels stay the bake's own, which
/// nothing after the write reads. [`Baked::options`] are the options as the bake used them.
pub(crate) fn bake_once(
    scene: &billow::scene::Scene,
    opts: &VoxelizeOptions,
    args: &Args,
    compression: Compression,
    ctx: &Ctx,
    input: &str,
    source: billow_format::SourceInfo,
) -> Result<BakeRun, CliError> {
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
    let hooks = BakeHooks {
        progress: &report,
        note: &note,
        // The bake freed its working set: the prune's atlases come after.
        between: Some(&crate::alloc::release_free_memory),
    };
    let options = BakeOptions {
        voxelize: opts.clone(),
        normals: match args.normals {
            NormalsArg::Auto => NormalsMode::Auto,
            NormalsArg::On => NormalsMode::On,
            NormalsArg::Moments => NormalsMode::Moments,
            NormalsArg::Off => NormalsMode::Off,
        },
        prune: args.prune,
        compression,
        decode_blocks: args.target.target_error.is_some() || args.slices.is_some(),
        source: Some(source),
        ..BakeOptions::default()
    };
    let baked = bake(scene, &options, &hooks).map_err(|e| match e {
        BakeError::Voxelize(e) => voxelize_error(input, &e),
        BakeError::Prune(e) => CliError::new(Code::from(&e), format!("{input}: {e}")),
    });
    bar.finish();
    Ok(BakeRun {
        baked: baked?,
        notes: notes.into_inner(),
    })
}

/// A bake the `--target-error` search measured (its options as [`Baked::options`]).
pub(crate) struct Tried(BakeRun);

impl AsRef<billow_format::VolumeAsset> for Tried {
    fn as_ref(&self) -> &billow_format::VolumeAsset {
        &self.0.baked.asset
    }
}

/// `--target-error`: the library's search ([`search_volume`]), each candidate baked as
/// asked here ([`bake_once`]) and its trial printed. Returns the chosen bake (its options
/// in [`Baked::options`]) and what was tried; with `--json`, a target none meets still
/// prints its trials.
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
) -> Result<(BakeRun, TargetSummary), CliError> {
    let mut bake_one = |s: &VolumeSettings| {
        let mut o = opts.clone();
        o.resolution = s.resolution;
        o.supersample = s.supersample;
        o.align = args
            .align
            .unwrap_or_else(|| default_align(&o.resolution, args.bounds.is_some()));
        let run = bake_once(scene, &o, args, compression, ctx, input, source.clone())?;
        let baked = &run.baked;
        let bytes = baked
            .asset
            .with_parts_with(baked.blocks.as_ref(), |parts| {
                parts.iter().map(|p| p.len() as u64).sum::<u64>()
            })
            .map_err(|e| CliError::new(Code::Internal, e))?;
        Ok::<_, CliError>((Tried(run), bytes))
    };
    let (Tried(run), summary) =
        run_search(target, ctx, (args.json, input, &args.output), |on_trial| {
            search_volume(scene, flags, target, &mut bake_one, on_trial)
        })?;
    Ok((run, summary))
}
