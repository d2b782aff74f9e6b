//! Whether a bake stores normals: `on`, `off`, or `auto` — judged on how coherent they
//! are ([`toksvig::normal_coherence`] at level [`toksvig::AUTO_NORMALS_LEVEL`]; docs/voxelize.md,
//! "Normals"), and given up, with a reason, when they alone would exceed the memory limit.
//! The one place this rule lives: `billow voxelize` (dense and `--prune`d) and any Rust
//! caller bake through [`bake_with_normals`].

use std::time::Instant;

use super::toksvig::{self, NormalsJudgement};
use super::{VoxelizeError, VoxelizeOptions};
use crate::scene::Scene;

/// Whether a bake stores normals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalsMode {
    /// Kept where one normal per voxel describes the surface (the default).
    #[default]
    Auto,
    On,
    Off,
}

/// Why an `Auto` bake has no normals although it was not judged to drop them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MemoryRefusal {
    /// Even the coarse judgement would exceed the limit (GiB): baked without normals.
    Judging { limit_gib: f64 },
    /// The bake with normals would need `needed_gib`, more than `limit_gib`: baked again
    /// without them.
    Baking { needed_gib: f64, limit_gib: f64 },
}

/// What a bake decided about its normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NormalsOutcome {
    /// The normals were stored.
    pub kept: bool,
    /// `Auto`: the coherence judged — on a coarse bake for grids of at least
    /// [`toksvig::AUTO_NORMALS_COARSE_MIN_VOXELS`], else on the bake itself; `None` when
    /// nothing was judged (`On`, `Off`, a memory refusal) or the judged level was empty.
    pub coherence: Option<f32>,
    /// `Auto` without normals for memory.
    pub refused: Option<MemoryRefusal>,
    /// Seconds the coarse judgement took (0 when judged on the bake).
    pub judge_seconds: f64,
}

/// Bakes `scene` with `bake` (a dense or brick-sparse voxelize of it, given the options to
/// use), storing normals as `mode` says. `Auto` judges before the bake on a coarse one
/// ([`toksvig::judge_normals`]) for big grids and on the bake itself otherwise
/// ([`VoxelizeOptions::judge_normals`]), and bakes without normals when they alone take
/// the bake past `opts.memory_limit`. `judged` reads a finished bake's coherence and
/// whether it stored normals. `opts` is left as the bake used it (`normals` false once
/// they were dropped), so that the header records what was done.
pub fn bake_with_normals<T>(
    scene: &Scene,
    opts: &mut VoxelizeOptions,
    mode: NormalsMode,
    bake: impl Fn(&VoxelizeOptions) -> Result<T, VoxelizeError>,
    judged: impl Fn(&T) -> (Option<f32>, bool),
) -> Result<(T, NormalsOutcome), VoxelizeError> {
    let mut out = NormalsOutcome::default();
    opts.normals = mode != NormalsMode::Off;
    opts.judge_normals = false;
    let mut coarse = None;
    if mode == NormalsMode::Auto {
        let start = Instant::now();
        match toksvig::judge_normals(scene, opts) {
            Err(VoxelizeError::TooMuchMemory { limit_gib, .. }) => {
                out.refused = Some(MemoryRefusal::Judging { limit_gib });
                opts.normals = false;
            }
            Err(e) => return Err(e),
            Ok(NormalsJudgement::Coarse(k)) => {
                coarse = Some(k);
                opts.normals = toksvig::keeps(k);
            }
            Ok(NormalsJudgement::OnTheBake) => opts.judge_normals = true,
        }
        out.judge_seconds = start.elapsed().as_secs_f64();
    }
    let baked = match bake(opts) {
        Err(VoxelizeError::TooMuchMemory {
            needed_gib,
            limit_gib,
            ..
        }) if mode == NormalsMode::Auto && opts.normals => {
            opts.normals = false;
            opts.judge_normals = false;
            out.refused = Some(MemoryRefusal::Baking {
                needed_gib,
                limit_gib,
            });
            bake(opts)?
        }
        r => r?,
    };
    let (coherence, stored) = judged(&baked);
    out.kept = stored;
    out.coherence = match coarse {
        Some(k) => k,
        None if opts.judge_normals => coherence,
        None => None,
    };
    opts.normals &= stored;
    Ok((baked, out))
}
