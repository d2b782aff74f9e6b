//! `--target-error E`: the cheapest setting whose measured error meets `E` on this mesh.
//!
//! **The measure** is `billow eval`'s: the mean, over the six axis views at one stated
//! distance factor ([`TargetOptions::distance`], a multiple of the framed distance), of the
//! RMSE on premultiplied linear RGBA between the asset (CPU slicer or cloud renderer, at
//! the finest level) and the 16-spp ray-traced reference of the source mesh, with the
//! reference lighting `billow eval --lighting auto` picks for the asset. The [`Judge`]
//! renders each lighting's reference views once and scores every candidate against them,
//! so `billow eval SOURCE ASSET --views axes --distances D --size WxH` of the written
//! asset reports the same number.
//!
//! **The search** ([`search`]) bakes the candidates of a ladder cheapest first and stops at
//! the first that meets `E` (the presets' costs grow geometrically, so the cheaper tries
//! cost less than the last one); then, between the last candidate that failed and the one
//! that met `E`, it bisects one parameter (the volume's resolution, the cloud's ε) a few
//! times and keeps the cheapest candidate that still meets `E` — bake at low cost, eval,
//! refine. The error is assumed to fall as the cost rises along the ladder and between two
//! neighbours; the result is the cheapest *measured* candidate that meets `E`, never one
//! that was not measured. When none meets `E`, [`TargetError::Unreachable`] names the best.

use std::time::Instant;

use billow_format::{CloudAsset, VolumeAsset};
use serde::Serialize;

use super::Preset;
use crate::camera::{view_directions, views_of, ViewDirections, ViewSpec};
use crate::eval::cloud_render::{CloudRenderer, PreparedCloud};
use crate::eval::lighting::Lighting;
use crate::eval::suite::{
    mean_errors, reference_lighting, EvalOptions, Evaluator, PreparedAsset, ReferenceView,
    EVAL_FOV_Y,
};
use crate::eval::EvalError;
use crate::scene::Scene;

/// Reference samples per pixel per axis: 4 × 4 = 16, `billow eval`'s default `--spp`.
pub const TARGET_SPP_PER_AXIS: u32 = 4;

/// Bisection steps between the last failing and the first passing candidate.
pub const REFINE_STEPS: u32 = 2;

/// What `--target-error` aims at and where it measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetOptions {
    /// The largest acceptable mean RMSE, > 0.
    pub error: f64,
    /// The view distance, a multiple of the framed distance, in (0, 1000].
    pub distance: f32,
    /// Image size of the views, each side 1–4096.
    pub width: u32,
    pub height: u32,
}

impl Default for TargetOptions {
    /// At the framed distance (the closest, hardest view), 128 × 128 like `billow eval`.
    fn default() -> Self {
        TargetOptions {
            error: 0.02,
            distance: 1.0,
            width: 128,
            height: 128,
        }
    }
}

impl TargetOptions {
    pub fn validate(&self) -> Result<(), TargetError> {
        if !(self.error.is_finite() && self.error > 0.0) {
            return Err(TargetError::InvalidTarget(format!(
                "the target RMSE must be a positive number, got {}",
                self.error
            )));
        }
        if !(self.distance.is_finite() && self.distance > 0.0 && self.distance <= 1000.0) {
            return Err(TargetError::InvalidTarget(format!(
                "the distance factor must be above 0 and at most 1000, got {}",
                self.distance
            )));
        }
        if !((1..=4096).contains(&self.width) && (1..=4096).contains(&self.height)) {
            return Err(TargetError::InvalidTarget(format!(
                "the image size {}x{} must be 1 to 4096 pixels a side",
                self.width, self.height
            )));
        }
        Ok(())
    }

    /// The views the error is measured on: the six axis directions at [`Self::distance`].
    pub fn views(&self) -> Vec<ViewSpec> {
        views_of(view_directions(ViewDirections::Axes), &[self.distance])
    }
}

/// Why `--target-error` chose nothing.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TargetError {
    #[error("{0}")]
    InvalidTarget(String),
    /// Every candidate was baked and measured and none met the target.
    #[error(
        "no setting reaches RMSE {target} at {distance}x the framed distance: the best \
         measured, {best_label}, scored {best:.4} ({tried} settings tried; nothing was written)"
    )]
    Unreachable {
        target: f64,
        distance: f32,
        best: f64,
        best_label: String,
        tried: usize,
    },
}

/// One setting the search may bake.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate<S> {
    /// What it is, e.g. `balanced` or `balanced, res 48`.
    pub label: String,
    /// The preset it is (or was refined from).
    pub preset: Option<Preset>,
    pub settings: S,
}

/// One bake the search measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Trial {
    pub label: String,
    pub preset: Option<Preset>,
    /// Mean RMSE over the target's views.
    pub error: f64,
    pub met: bool,
    /// Bake and measure, wall time.
    pub seconds: f64,
}

/// What the search chose.
#[derive(Debug)]
pub struct Found<S, A> {
    pub candidate: Candidate<S>,
    /// The chosen bake, as measured.
    pub asset: A,
    pub error: f64,
    /// Every bake, in the order measured.
    pub trials: Vec<Trial>,
}

/// A search that did not find: the target's error, or the bake's.
#[derive(Debug)]
pub enum SearchError<E> {
    Target(TargetError),
    Bake(E),
}

/// Proposes a candidate between a failing `lo` and a passing `hi`, or `None` ([`search`]).
pub type Refine<'f, S> = &'f dyn Fn(&Candidate<S>, &Candidate<S>) -> Option<Candidate<S>>;

/// Bakes a candidate and returns the asset and its error ([`search`]).
pub type Measure<'f, S, A, E> = &'f mut dyn FnMut(&Candidate<S>) -> Result<(A, f64), E>;

/// Measures the ladder cheapest first and refines (see the module docs). `measure` bakes a
/// candidate and returns the asset and its error; `refine(lo, hi)` proposes a candidate
/// between a failing `lo` and a passing `hi`, or `None` when there is none.
pub fn search<S, A, E>(
    ladder: Vec<Candidate<S>>,
    target: &TargetOptions,
    refine: Refine<'_, S>,
    measure: Measure<'_, S, A, E>,
) -> Result<Found<S, A>, SearchError<E>> {
    target.validate().map_err(SearchError::Target)?;
    let mut trials: Vec<Trial> = Vec::new();
    let mut run = |c: &Candidate<S>, trials: &mut Vec<Trial>| {
        let t = Instant::now();
        let (asset, error) = measure(c).map_err(SearchError::Bake)?;
        // NaN never meets a target.
        let met = error <= target.error;
        trials.push(Trial {
            label: c.label.clone(),
            preset: c.preset,
            error,
            met,
            seconds: t.elapsed().as_secs_f64(),
        });
        Ok::<_, SearchError<E>>((asset, error, met))
    };
    let mut failed: Option<Candidate<S>> = None;
    for c in ladder {
        let (asset, error, met) = run(&c, &mut trials)?;
        if !met {
            failed = Some(c);
            continue;
        }
        let mut best = (c, asset, error);
        if let Some(mut lo) = failed {
            for _ in 0..REFINE_STEPS {
                let Some(m) = refine(&lo, &best.0) else { break };
                let (asset, error, met) = run(&m, &mut trials)?;
                if met {
                    best = (m, asset, error);
                } else {
                    lo = m;
                }
            }
        }
        return Ok(Found {
            candidate: best.0,
            asset: best.1,
            error: best.2,
            trials,
        });
    }
    let best = trials
        .iter()
        .min_by(|a, b| a.error.total_cmp(&b.error))
        .cloned();
    Err(SearchError::Target(TargetError::Unreachable {
        target: target.error,
        distance: target.distance,
        best: best.as_ref().map_or(f64::NAN, |t| t.error),
        best_label: best.map_or_else(|| "nothing".into(), |t| t.label),
        tried: trials.len(),
    }))
}

/// Scores assets of one source mesh against its reference views (see the module docs).
pub struct Judge<'a> {
    scene: &'a Scene,
    target: TargetOptions,
    views: Vec<ViewSpec>,
    /// One evaluator and its reference views per reference lighting met so far.
    cache: Vec<(Lighting, Evaluator<'a>, Vec<ReferenceView>)>,
}

impl<'a> Judge<'a> {
    pub fn new(scene: &'a Scene, target: &TargetOptions) -> Self {
        Judge {
            scene,
            target: *target,
            views: target.views(),
            cache: Vec::new(),
        }
    }

    /// The index in the cache of `lighting`'s evaluator, rendering its references first.
    fn prepare(&mut self, lighting: Lighting) -> Result<usize, EvalError> {
        if let Some(i) = self.cache.iter().position(|c| c.0 == lighting) {
            return Ok(i);
        }
        let options = EvalOptions {
            width: self.target.width,
            height: self.target.height,
            fov_y: EVAL_FOV_Y,
            reference_per_axis: TARGET_SPP_PER_AXIS,
            raster_1spp: false,
            lighting,
            ..EvalOptions::default()
        };
        let evaluator = Evaluator::new(self.scene, options)?;
        let refs = self
            .views
            .iter()
            .map(|v| evaluator.reference(v))
            .collect::<Result<Vec<_>, _>>()?;
        self.cache.push((lighting, evaluator, refs));
        Ok(self.cache.len() - 1)
    }

    /// The mean RMSE of a volume asset (as the file would be read back).
    pub fn volume_error(&mut self, asset: &VolumeAsset) -> Result<f64, EvalError> {
        let (lighting, _) = reference_lighting(asset)?;
        let i = self.prepare(lighting)?;
        let (_, evaluator, refs) = &self.cache[i];
        let prepared = PreparedAsset::new(asset)?;
        let errors = refs
            .iter()
            .map(|r| evaluator.asset(&prepared, r).map(|x| x.0.asset))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(mean_errors(&errors).rmse)
    }

    /// The mean RMSE of a billboard cloud's finest level (as the file would be read back).
    pub fn cloud_error(&mut self, asset: &CloudAsset) -> Result<f64, EvalError> {
        let lighting =
            Lighting::for_cloud(&asset.header.params).map_err(EvalError::InvalidAsset)?;
        let i = self.prepare(lighting)?;
        let (_, evaluator, refs) = &self.cache[i];
        let prepared = PreparedCloud::new(asset)?;
        let renderer = CloudRenderer::new(&prepared, lighting)?;
        let errors = refs
            .iter()
            .map(|r| {
                evaluator
                    .cloud(&renderer, &prepared, 0, r)
                    .map(|x| x.0.asset)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(mean_errors(&errors).rmse)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ladder() -> Vec<Candidate<u32>> {
        [8, 16, 32, 64]
            .into_iter()
            .zip(Preset::LADDER)
            .map(|(r, p)| Candidate {
                label: p.name().into(),
                preset: Some(p),
                settings: r,
            })
            .collect()
    }

    fn midpoint(lo: &Candidate<u32>, hi: &Candidate<u32>) -> Option<Candidate<u32>> {
        let m = (lo.settings + hi.settings) / 2;
        (m > lo.settings && m < hi.settings).then(|| Candidate {
            label: format!("res {m}"),
            preset: hi.preset,
            settings: m,
        })
    }

    /// An error that halves per doubling of the "resolution".
    fn measure(c: &Candidate<u32>) -> Result<(u32, f64), ()> {
        Ok((c.settings, 1.0 / f64::from(c.settings)))
    }

    fn target(error: f64) -> TargetOptions {
        TargetOptions {
            error,
            ..TargetOptions::default()
        }
    }

    #[test]
    fn picks_the_first_rung_that_meets_the_target_then_refines_below_it() {
        // 1/16 = 0.0625 fails 0.05, 1/32 meets it; refinement tries 24 (0.0417: meets),
        // then 20 (0.05: meets, equal counts), keeping the cheapest that meets.
        let f = search(ladder(), &target(0.05), &midpoint, &mut measure).unwrap();
        assert_eq!(f.candidate.settings, 20);
        assert_eq!(f.asset, 20);
        assert!(f.error <= 0.05);
        let labels: Vec<_> = f.trials.iter().map(|t| t.label.as_str()).collect();
        assert_eq!(labels, ["draft", "balanced", "quality", "res 24", "res 20"]);
        assert!(!f.trials[1].met && f.trials[2].met);
        // The cheapest rung meeting it: no refinement below the bottom of the ladder.
        let f = search(ladder(), &target(0.5), &midpoint, &mut measure).unwrap();
        assert_eq!((f.candidate.settings, f.trials.len()), (8, 1));
    }

    #[test]
    fn an_unreachable_target_names_the_best_and_a_failed_bake_stops_the_search() {
        match search(ladder(), &target(1e-3), &midpoint, &mut measure) {
            Err(SearchError::Target(TargetError::Unreachable {
                best,
                best_label,
                tried,
                ..
            })) => {
                assert_eq!((best, best_label.as_str(), tried), (1.0 / 64.0, "hero", 4));
            }
            other => panic!("{other:?}"),
        }
        let mut nan = |_: &Candidate<u32>| Ok::<_, ()>((0, f64::NAN));
        assert!(matches!(
            search(ladder(), &target(1.0), &midpoint, &mut nan),
            Err(SearchError::Target(TargetError::Unreachable { .. }))
        ));
        let mut fail = |c: &Candidate<u32>| if c.settings < 32 { measure(c) } else { Err(()) };
        assert!(matches!(
            search(ladder(), &target(1e-3), &midpoint, &mut fail),
            Err(SearchError::Bake(()))
        ));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                search(ladder(), &target(bad), &midpoint, &mut measure),
                Err(SearchError::Target(TargetError::InvalidTarget(_)))
            ));
        }
    }
}
