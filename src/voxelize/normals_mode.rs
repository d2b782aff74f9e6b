//! Which normals a bake stores: `on` (Toksvig's mean, lit one-sided), `moments` (the
//! diagonal of their second moment, lit two-sided like the viewer's meshes), `off`, or
//! `auto` — the moments, with the mean normals' coherence ([`toksvig::normal_coherence`] at
//! level [`toksvig::AUTO_NORMALS_LEVEL`]) judged before the bake to tell a closed surface,
//! which keeps its level 0 unthinned, from foliage (docs/voxelize.md, "Normals"); given up,
//! with a reason, when they alone would exceed the memory limit.
//! The one place this rule lives: [`super::bake()`] (what `billow voxelize` calls, dense
//! and `--prune`d) bakes through [`bake_with_normals`], as may a Rust caller that drives
//! [`super::voxelize()`] or [`super::voxelize_sparse`] itself.

use std::time::Instant;

use super::toksvig::{self, NormalsJudgement};
use super::{VoxelizeError, VoxelizeOptions};
use crate::scene::Scene;

/// Which normals a bake stores.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalsMode {
    /// The moments, with the surface judged by the mean's coherence (the default).
    #[default]
    Auto,
    /// Toksvig's mean normals (one-sided lighting).
    On,
    /// The diagonal of the normals' second moment (two-sided lighting).
    Moments,
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
    /// Normals were stored (the mean, or with `moments` their second moments).
    pub kept: bool,
    /// The stored normals are second moments ([`super::VoxelizeOptions::moments`]).
    pub moments: bool,
    /// `Auto`: the coherence judged (on a coarse bake, or for a volume of one MIP level on a
    /// bake with mean normals); at least [`toksvig::AUTO_NORMALS_MIN_COHERENCE`] makes the
    /// volume a surface that keeps its level 0 ([`VoxelizeOptions::surface`]). `None` when
    /// nothing was judged (`On`, `Moments`, `Off`, a memory refusal) or the judged level was
    /// empty.
    pub coherence: Option<f32>,
    /// `Auto` without normals for memory.
    pub refused: Option<MemoryRefusal>,
    /// Seconds the coarse judgement took (0 when judged on the bake).
    pub judge_seconds: f64,
}

/// Bakes `scene` with `bake` (a dense or brick-sparse voxelize of it, given the options to
/// use), storing normals as `mode` says. `Auto` stores the moments, and judges before the
/// bake whether the volume is a closed surface whose level 0 keeps its opacity
/// ([`VoxelizeOptions::surface`]): on a coarse bake ([`toksvig::judge_normals`]), or for a
/// volume of one MIP level on a bake with mean normals of its own. `Moments` and `Off`
/// judge the surface on the coarse bake too (not for one MIP level); `On` on its own mean
/// normals. It bakes without normals
/// when they alone take the bake past `opts.memory_limit`. `judged` reads a finished bake's
/// coherence and whether it stored normals. `opts` is left as the last bake used it
/// (`normals` false where they were given up, `moments` when they are moments), so that the
/// header records what was done.
pub fn bake_with_normals<T>(
    scene: &Scene,
    opts: &mut VoxelizeOptions,
    mode: NormalsMode,
    bake: impl Fn(&VoxelizeOptions) -> Result<T, VoxelizeError>,
    judged: impl Fn(&T) -> (Option<f32>, bool),
) -> Result<(T, NormalsOutcome), VoxelizeError> {
    let mut out = NormalsOutcome::default();
    opts.normals = mode != NormalsMode::Off;
    opts.moments = matches!(mode, NormalsMode::Auto | NormalsMode::Moments);
    opts.surface = None;
    let mut on_the_bake = false;
    // The coarse judgement's surface verdict, which `Off` would reach too.
    let mut judged_surface = None;
    if matches!(mode, NormalsMode::Moments | NormalsMode::Off) {
        // Not judged for the normals, but whether a closed surface keeps its level 0 is
        // the same question: a closed mesh thinned to its coverage opens (the spot with
        // `off`: k = 0.14, holes and bands). A volume of one level, or a judgement past the
        // memory limit, is left to the bake (not a surface without mean normals).
        if let Ok(NormalsJudgement::Coarse(k)) = toksvig::judge_normals(scene, opts) {
            opts.surface = Some(toksvig::keeps(k));
        }
    }
    if mode == NormalsMode::Auto {
        let start = Instant::now();
        match toksvig::judge_normals(scene, opts) {
            Err(VoxelizeError::TooMuchMemory { limit_gib, .. }) => {
                out.refused = Some(MemoryRefusal::Judging { limit_gib });
                opts.normals = false;
                opts.moments = false;
            }
            Err(e) => return Err(e),
            Ok(NormalsJudgement::Coarse(k)) => {
                out.coherence = k;
                opts.surface = Some(toksvig::keeps(k));
                judged_surface = opts.surface;
            }
            Ok(NormalsJudgement::OnTheBake) => {
                // One MIP level: judged on a bake with mean normals, then baked with moments.
                on_the_bake = true;
                opts.moments = false;
            }
        }
        out.judge_seconds = start.elapsed().as_secs_f64();
    }
    let bake_or_refuse = |opts: &mut VoxelizeOptions, out: &mut NormalsOutcome| match bake(opts) {
        Err(VoxelizeError::TooMuchMemory {
            needed_gib,
            limit_gib,
            ..
        }) if mode == NormalsMode::Auto && opts.normals => {
            // Given up: baked exactly as `Off` would bake it.
            opts.normals = false;
            opts.moments = false;
            opts.surface = judged_surface;
            out.coherence = None;
            out.refused = Some(MemoryRefusal::Baking {
                needed_gib,
                limit_gib,
            });
            bake(opts)
        }
        r => r,
    };
    let mut baked = bake_or_refuse(opts, &mut out)?;
    if on_the_bake && opts.normals {
        let (k, _) = judged(&baked);
        out.coherence = k;
        opts.surface = Some(toksvig::keeps(k));
        opts.moments = true;
        baked = bake_or_refuse(opts, &mut out)?;
    }
    let (_, stored) = judged(&baked);
    out.kept = stored;
    opts.normals &= stored;
    opts.moments &= stored;
    out.moments = opts.moments;
    Ok((baked, out))
}
