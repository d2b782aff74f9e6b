//! The whole `billow voxelize` bake as one call, [`bake()`]: the voxelization with normals
//! as asked ([`bake_with_normals`]), dense or pruned of its empty space (`--prune`: brick
//! sparse through [`voxelize_sparse`] and [`prune_sparse`], or for an expression or custom
//! combine, whose pyramids are dense anyway, [`voxelize`] and [`prune`]), the header's
//! bake parameters ([`bake_params`]), and the BC7 blocks ([`encode_volume`] or
//! [`compress_volume`]). The CLI is a thin adapter over it (progress bar, warnings,
//! exit codes); a Rust program gets the same bytes from the same options.
//!
//! The library never prints: progress, warnings and the point between the bake and the
//! prune go through [`BakeHooks`].

use std::collections::BTreeMap;
use std::time::Instant;

use billow_format::{SourceInfo, VolumeAsset, VolumeBlocks};

use super::asset::{bake_params, bake_params_for};
use super::normals_mode::{bake_with_normals, MemoryRefusal, NormalsMode, NormalsOutcome};
use super::sparse::voxelize_sparse;
use super::{
    default_align, voxelize, CombineFn, Preset, Resolution, Stage, VoxelizeError, VoxelizeOptions,
    VoxelizeStats,
};
use crate::compress::{compress_volume, encode_volume, Compression};
use crate::emptyspace::{
    prune, prune_sparse, EmptySpaceError, EmptySpaceOptions, EmptySpaceStats, Pruned,
};
use crate::provenance::tool_version;
use crate::scene::Scene;

/// What [`bake()`] does: `billow voxelize`'s options.
#[derive(Clone, Debug)]
pub struct BakeOptions {
    /// The voxelization. Its `normals`, `moments` and `surface` are set from
    /// [`BakeOptions::normals`] ([`bake_with_normals`]); [`Baked::options`] says what was
    /// used. [`BakeOptions::at`] (and `default()`, at 128) sets what `billow voxelize`
    /// does without flags, which differs from [`VoxelizeOptions::default`] in the combine
    /// (`opaque`, not the paper's `mean`) and the alignment ([`default_align`]: 8 for
    /// `--res 128`).
    pub voxelize: VoxelizeOptions,
    /// Which normals to store (`--normals`; default `Auto`).
    pub normals: NormalsMode,
    /// Remove the empty space (`--prune`), with `billow emptyspace`'s defaults: bricks laid
    /// out for BC7 blocks when compressing, `voxelize.memory_limit` for the atlases.
    pub prune: bool,
    /// BC7 blocks (the default) or raw RGBA8 (`--compress`).
    pub compression: Compression,
    /// With BC7: replace the asset's texels with the blocks' decoding
    /// ([`compress_volume`]), i.e. what a reader of the file gets, for a caller that reads
    /// them after the bake (an evaluation, slices). `false` (the default) keeps the bake's
    /// own texels ([`encode_volume`]), cheaper when only the file is written.
    pub decode_blocks: bool,
    /// The header's `tool` (default [`tool_version`], `"billow X.Y.Z"`).
    pub tool: String,
    /// The header's source (the input's name and checksum, see
    /// [`crate::provenance::source_info`]).
    pub source: Option<SourceInfo>,
    /// Header parameters added after the bake's own ([`bake_params`] and
    /// `normal_coherence`), which they may override.
    pub params: BTreeMap<String, String>,
}

impl BakeOptions {
    /// What `billow voxelize MESH -o OUT --res <resolution>` does with no other flag: the
    /// `opaque` combine, the grid aligned as [`default_align`] says, normals `Auto`, BC7,
    /// no prune, `tool` [`tool_version`]. Add the mesh's [`BakeOptions::source`] (the
    /// CLI records [`crate::provenance::source_info_all`] of the files the import read)
    /// and the file is the CLI's, byte for byte (tests/cli_bake_api.rs).
    pub fn at(resolution: Resolution) -> Self {
        BakeOptions {
            voxelize: VoxelizeOptions {
                resolution,
                combine: CombineFn::Preset(Preset::Opaque),
                align: default_align(&resolution, false),
                ..VoxelizeOptions::default()
            },
            normals: NormalsMode::default(),
            prune: false,
            compression: Compression::default(),
            decode_blocks: false,
            tool: tool_version(),
            source: None,
            params: BTreeMap::new(),
        }
    }
}

impl Default for BakeOptions {
    /// [`BakeOptions::at`] the default resolution (128 along the longest side): `billow
    /// voxelize` without flags.
    fn default() -> Self {
        BakeOptions::at(Resolution::default())
    }
}

/// Where [`bake()`] reports. [`BakeHooks::default`] is silent.
#[derive(Clone, Copy)]
pub struct BakeHooks<'a> {
    /// Progress by stage, a fraction in [0, 1] (from the calling thread only).
    pub progress: &'a dyn Fn(Stage, f32),
    /// Warnings: an `Auto` bake left without normals for memory, the prune's note.
    pub note: &'a dyn Fn(&str),
    /// With `prune`: called after the bake, which has freed its working set, and before
    /// the prune allocates its atlases (the CLI hands freed memory back to the system).
    pub between: Option<&'a dyn Fn()>,
}

fn no_progress(_: Stage, _: f32) {}
fn no_note(_: &str) {}

impl Default for BakeHooks<'_> {
    fn default() -> Self {
        BakeHooks {
            progress: &no_progress,
            note: &no_note,
            between: None,
        }
    }
}

/// A finished bake: the asset to write and what the bake did.
#[derive(Debug)]
pub struct Baked {
    /// The (pruned) volume, its header saying what was done (`normals`, `emptyspace`,
    /// `compress = bc7`…). With BC7 its texels are the blocks' decoding only with
    /// [`BakeOptions::decode_blocks`]; otherwise they are the bake's own and only `blocks`
    /// goes to the file ([`VolumeAsset::with_parts_with`]).
    pub asset: VolumeAsset,
    /// The BC7 blocks, with [`Compression::Bc`].
    pub blocks: Option<VolumeBlocks>,
    pub stats: VoxelizeStats,
    /// The voxel grid's dims and MIP levels (before any prune).
    pub dims: [u32; 3],
    pub mip_count: u32,
    /// What was decided about the normals (coherence, memory refusal, judging seconds).
    pub normals: NormalsOutcome,
    /// With `prune`: what the empty-space removal did (its seconds included).
    pub pruned: Option<EmptySpaceStats>,
    /// The voxelize options as the bake used them (`normals` false where they were given
    /// up, `moments` when the normals are moments, `surface` as judged).
    pub options: VoxelizeOptions,
    /// Seconds spent on BC7 (0 without).
    pub compress_seconds: f64,
}

/// Why [`bake()`] failed. The messages do not name the input: a caller adds it.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Voxelize(#[from] VoxelizeError),
    #[error(transparent)]
    Prune(#[from] EmptySpaceError),
}

/// Bakes `scene` as `billow voxelize` does (see the module docs): normals as
/// `opts.normals` says, pruned with `opts.prune`, compressed as `opts.compression` says.
/// The asset is byte for byte what the CLI writes for the same options.
pub fn bake(scene: &Scene, opts: &BakeOptions, hooks: &BakeHooks) -> Result<Baked, BakeError> {
    opts.voxelize.validate()?;
    let mut vo = opts.voxelize.clone();
    let (mut asset, stats, dims, mip_count, normals, pruned) = if opts.prune {
        let es = EmptySpaceOptions {
            bc_blocks: opts.compression == Compression::Bc,
            memory_limit: vo.memory_limit,
            ..EmptySpaceOptions::default()
        };
        let (p, stats, dims, mips, normals) = if matches!(vo.combine, CombineFn::Preset(_)) {
            bake_pruned(scene, &mut vo, opts, hooks, &es)?
        } else {
            // Expressions and custom functions give dense levels: prune the dense volume.
            let (asset, stats, dims, mips, normals) = bake_dense(scene, &mut vo, opts, hooks)?;
            if let Some(f) = hooks.between {
                f();
            }
            (prune(&asset, &es)?, stats, dims, mips, normals)
        };
        if let Some(n) = &p.stats.note {
            (hooks.note)(n);
        }
        (p.asset, stats, dims, mips, normals, Some(p.stats))
    } else {
        let (asset, stats, dims, mips, normals) = bake_dense(scene, &mut vo, opts, hooks)?;
        (asset, stats, dims, mips, normals, None)
    };
    let compress_start = Instant::now();
    let blocks = (opts.compression == Compression::Bc).then(|| {
        asset.header.set_compress("bc7");
        if opts.decode_blocks {
            compress_volume(&mut asset)
        } else {
            encode_volume(&mut asset)
        }
    });
    Ok(Baked {
        asset,
        blocks,
        stats,
        dims,
        mip_count,
        normals,
        pruned,
        options: vo,
        compress_seconds: compress_start.elapsed().as_secs_f64(),
    })
}

/// The header's parameters: the bake's own, `normal_coherence` when judged, then the
/// caller's.
fn params_with(
    normals: &NormalsOutcome,
    opts: &BakeOptions,
    own: impl FnOnce(&BTreeMap<String, String>) -> BTreeMap<String, String>,
) -> BTreeMap<String, String> {
    let mut extra = BTreeMap::new();
    if let Some(k) = normals.coherence {
        extra.insert("normal_coherence".to_string(), format!("{k:.3}"));
    }
    extra.extend(opts.params.iter().map(|(k, v)| (k.clone(), v.clone())));
    own(&extra)
}

/// The dense bake ([`voxelize`] through [`bake_with_normals`]) and its asset.
fn bake_dense(
    scene: &Scene,
    vo: &mut VoxelizeOptions,
    opts: &BakeOptions,
    hooks: &BakeHooks,
) -> Result<(VolumeAsset, VoxelizeStats, [u32; 3], u32, NormalsOutcome), VoxelizeError> {
    let (volume, normals) = bake_with_normals(
        scene,
        vo,
        opts.normals,
        |o| voxelize(scene, o, hooks.progress),
        |v| (v.normal_coherence, v.normals.is_some()),
    )?;
    note_refusal(&normals, hooks.note);
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let params = params_with(&normals, opts, |extra| bake_params(&volume, vo, extra));
    let asset = volume.into_asset(&opts.tool, opts.source.clone(), params);
    Ok((asset, stats, dims, mips, normals))
}

/// The brick-sparse bake ([`voxelize_sparse`] through [`bake_with_normals`]) pruned by
/// [`prune_sparse`]: no level is ever dense.
fn bake_pruned(
    scene: &Scene,
    vo: &mut VoxelizeOptions,
    opts: &BakeOptions,
    hooks: &BakeHooks,
    es: &EmptySpaceOptions,
) -> Result<(Pruned, VoxelizeStats, [u32; 3], u32, NormalsOutcome), BakeError> {
    let (volume, normals) = bake_with_normals(
        scene,
        vo,
        opts.normals,
        |o| voxelize_sparse(scene, o, hooks.progress),
        |v| (v.normal_coherence, v.has_normals()),
    )?;
    note_refusal(&normals, hooks.note);
    let (stats, dims, mips) = (volume.stats, volume.dims(), volume.mip_count());
    let params = params_with(&normals, opts, |extra| {
        bake_params_for(&volume.grid, vo, extra)
    });
    let shell = volume.asset_shell(&opts.tool, opts.source.clone(), params);
    // The bake freed its working set (dropped normals too): the prune's atlases come after.
    if let Some(f) = hooks.between {
        f();
    }
    let p = prune_sparse(&shell, volume.levels, es)?;
    Ok((p, stats, dims, mips, normals))
}

/// Warns of an `Auto` bake left without normals for memory. The text names the CLI's
/// options (`--normals auto`, `--memory-limit`): [`NormalsMode::Auto`] and
/// [`VoxelizeOptions::memory_limit`].
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
