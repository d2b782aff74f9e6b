//! `--target-error E`: the cheapest measured setting whose error meets `E` on this mesh.
//!
//! **The measure** ([`Judge`]) is `billow eval`'s, over a ladder of distances and under a
//! set of lights. Per distance factor `F` of [`TargetOptions::distances`] (default 1, 4
//! and 16 times the framed distance), the mean over the six axis views — and, with
//! [`TargetOptions::lights`], over every light of the set — of the **covered RMSE**
//! ([`ImageError::rmse_covered`](crate::eval::metrics::ImageError::rmse_covered): the RMSE
//! on premultiplied linear RGBA over the pixels either image covers) between the asset
//! (CPU slicer or cloud renderer, the cloud's finest level) and the 16-spp ray-traced
//! reference of the source mesh. The covered RMSE does not shrink with the empty background
//! as the object gets smaller on screen (the whole-frame RMSE of the oak falls from 0.040
//! at 1× to 0.003 at 16× while its coverage is 32 % too dense there), so errors at
//! different distances compare. The error of a setting is then the **worst** of the
//! per-distance errors ([`Weighting::Worst`], the default) or their mean
//! ([`Weighting::Mean`]). Without lights the reference is lit as `billow eval --lighting
//! auto` lights the asset (like compared with like); with lights, as `billow eval --lights`
//! does: the mesh under each scene light, the asset as the viewer draws it. `billow eval
//! SOURCE ASSET --views axes --distances 1,4,16 --size WxH [--lights standard]` of the
//! written asset reports the same numbers (`by_distance[].asset.rmse_covered`). The judge
//! renders each reference view once per (light, distance) and scores every candidate
//! against them.
//!
//! **The search** ([`search`], [`search_volume`], [`search_cloud`]) moves along one
//! parameter of a [`Space`] (a volume's `--res`, a cloud's ε) on which the presets lie,
//! cheapest first, and keeps the cheapest *measured* candidate that meets `E`, never an
//! interpolated one:
//!
//! 1. **Ladder.** The presets, cheapest first, until one meets `E`.
//! 2. **Scan.** When none met `E`, or the errors along the measured presets did not fall
//!    strictly (the error is not monotone in the cost), [`SCAN_PER_SEGMENT`] settings
//!    evenly spaced between each pair of neighbouring presets (up to the one that met `E`,
//!    else up to the dearest), cheapest first, until one meets `E`.
//! 3. **Refine.** [`REFINE_ROUNDS`] rounds around the best measured so far: between it and
//!    its cheaper measured neighbour (the midpoint, rounded to the parameter's grid) when it
//!    meets `E`; on both sides (and below the cheapest preset) when nothing does. When the
//!    presets' errors fall and one meets `E`, this is the bisection between it and the
//!    cheaper preset that missed.
//!
//! At most [`TargetOptions::max_bakes`] ([`MAX_BAKES`]) settings are baked; nothing is
//! dearer than the dearest preset. Every bake is a [`Trial`] (error per distance, bytes,
//! seconds), reported as it is measured and kept in [`Found::trials`] or, when none meets
//! `E`, in [`TargetError::Unreachable`], which names the best.

mod judge;
mod search;
mod spaces;
#[cfg(test)]
mod tests;
mod types;

pub use judge::Judge;
pub use search::{search, Bake, OnTrial, Space};
pub use spaces::{
    describe_cloud, describe_volume, search_cloud, search_volume, short, CloudSpace, VolumeSpace,
};
pub use types::*;
