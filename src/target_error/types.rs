//! `--target-error`'s options, trials, scores and errors (the module docs: [`super`]).

use serde::Serialize;

use crate::eval::lighting::{light_set, EvalLight};
use crate::eval::EvalError;
use crate::presets::Preset;
use billow_core::camera::{view_directions, views_of, ViewDirections, ViewSpec};
use billow_core::shading::DEFAULT_AMBIENT;

/// Reference samples per pixel per axis: 4 × 4 = 16, `billow eval`'s default `--spp`.
pub const TARGET_SPP_PER_AXIS: u32 = 4;

/// The distance factors measured by default: the framed distance and 4 and 16 times it.
pub const DEFAULT_DISTANCES: [f32; 3] = [1.0, 4.0, 16.0];

/// Settings scanned between two neighbouring presets (step 2 of the search).
pub const SCAN_PER_SEGMENT: usize = 3;

/// Rounds of refinement around the best measured setting (step 3 of the search).
pub const REFINE_ROUNDS: usize = 2;

/// The most settings one search bakes by default ([`TargetOptions::max_bakes`]): the four
/// presets, three scans in each of the three gaps between them, and three refinements.
pub const MAX_BAKES: usize = 16;

/// The grid of a volume's searched `--res`: multiples of 8 (so the default `--align` keeps
/// the longest axis at the asked resolution).
pub const RES_STEP: u32 = 8;

/// How the per-distance errors make one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Weighting {
    /// The largest: a setting meets `E` only when it does at every distance.
    #[default]
    Worst,
    /// The mean over the distances (each weighs the same).
    Mean,
}

impl Weighting {
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Worst => "worst",
            Weighting::Mean => "mean",
        }
    }

    /// One error of the per-distance errors (NaN if any is NaN or there is none).
    pub fn apply(self, errors: &[f64]) -> f64 {
        if errors.is_empty() || errors.iter().any(|e| e.is_nan()) {
            return f64::NAN;
        }
        match self {
            Weighting::Worst => errors.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Weighting::Mean => errors.iter().sum::<f64>() / errors.len() as f64,
        }
    }
}

impl std::str::FromStr for Weighting {
    type Err = TargetError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "worst" => Ok(Weighting::Worst),
            "mean" => Ok(Weighting::Mean),
            other => Err(TargetError::InvalidTarget(format!(
                "unknown weighting '{other}': expected worst or mean"
            ))),
        }
    }
}

/// What `--target-error` aims at and where it measures.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetOptions {
    /// The largest acceptable error (the covered RMSE, weighted over the distances), > 0.
    pub error: f64,
    /// The view distances, multiples of the framed distance, each in (0, 1000]; 1 to 16
    /// of them, no repeats.
    pub distances: Vec<f32>,
    /// How the per-distance errors make one.
    pub weighting: Weighting,
    /// The lights every view is judged under (the mean over them); `None`: the asset's own
    /// lighting, as `billow eval --lighting auto` (one light's cost).
    pub lights: Option<Vec<EvalLight>>,
    /// Image size of the views, each side 1–4096.
    pub width: u32,
    pub height: u32,
    /// The most settings baked, ≥ 1 (the presets come first).
    pub max_bakes: usize,
}

impl Default for TargetOptions {
    /// [`DEFAULT_DISTANCES`], the worst of them, the `standard` light set (ambient 0.3),
    /// 128 × 128 like `billow eval`, [`MAX_BAKES`]; `error` 0.1.
    fn default() -> Self {
        TargetOptions {
            error: 0.1,
            distances: DEFAULT_DISTANCES.to_vec(),
            weighting: Weighting::Worst,
            lights: light_set("standard", DEFAULT_AMBIENT),
            width: 128,
            height: 128,
            max_bakes: MAX_BAKES,
        }
    }
}

impl TargetOptions {
    pub fn validate(&self) -> Result<(), TargetError> {
        let bad = |m: String| Err(TargetError::InvalidTarget(m));
        if !(self.error.is_finite() && self.error > 0.0) {
            return bad(format!(
                "the target error must be a positive number, got {}",
                self.error
            ));
        }
        if self.distances.is_empty() || self.distances.len() > 16 {
            return bad(format!("1 to 16 distances, got {}", self.distances.len()));
        }
        for (i, &d) in self.distances.iter().enumerate() {
            if !(d.is_finite() && d > 0.0 && d <= 1000.0) {
                return bad(format!(
                    "the distance factor must be above 0 and at most 1000, got {d}"
                ));
            }
            if self.distances[..i].contains(&d) {
                return bad(format!("the distance factor {d} is listed twice"));
            }
        }
        if let Some(l) = &self.lights {
            if l.is_empty() || l.len() > 16 {
                return bad(format!("1 to 16 lights, got {}", l.len()));
            }
        }
        if !((1..=4096).contains(&self.width) && (1..=4096).contains(&self.height)) {
            return bad(format!(
                "the image size {}x{} must be 1 to 4096 pixels a side",
                self.width, self.height
            ));
        }
        if self.max_bakes == 0 {
            return bad("at least one bake".into());
        }
        Ok(())
    }

    /// The views the error is measured on: the six axis directions at each distance.
    pub fn views(&self) -> Vec<ViewSpec> {
        views_of(view_directions(ViewDirections::Axes), &self.distances)
    }

    /// What the error is, in words: `covered RMSE, worst of 1x, 4x, 16x, mean over 4
    /// lights (overhead, sun-east, sun-west, below)`.
    pub fn describe(&self) -> String {
        let d: Vec<String> = self.distances.iter().map(|d| format!("{d}x")).collect();
        let over = if self.distances.len() == 1 {
            format!("at {}", d[0])
        } else {
            format!("{} of {}", self.weighting.name(), d.join(", "))
        };
        let lights = match &self.lights {
            None => "lit as the asset was baked".to_string(),
            Some(l) => {
                let names: Vec<&str> = l.iter().map(|l| l.name.as_str()).collect();
                format!(
                    "mean over {} light{} ({})",
                    l.len(),
                    if l.len() == 1 { "" } else { "s" },
                    names.join(", ")
                )
            }
        };
        format!("covered RMSE, {over}, {lights}")
    }
}

/// Why `--target-error` chose nothing.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TargetError {
    #[error("{0}")]
    InvalidTarget(String),
    /// Every candidate was baked and measured and none met the target.
    #[error(
        "no setting reaches {target} ({measure}): the best measured, {best_label}, scored \
         {best:.4} ({tried} settings tried; nothing was written)",
        tried = trials.len()
    )]
    Unreachable {
        target: f64,
        /// [`TargetOptions::describe`].
        measure: String,
        best: f64,
        best_label: String,
        /// Every bake, in the order measured.
        trials: Vec<Trial>,
    },
}

/// One setting the search may bake.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate<S> {
    /// What it is, e.g. `balanced (--res 64 --supersample 4)` or `--res 40 --supersample 4`.
    pub label: String,
    /// The preset it is, if it is one.
    pub preset: Option<Preset>,
    pub settings: S,
}

/// The error at one distance factor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DistanceError {
    pub distance: f32,
    /// The mean covered RMSE over the views (and lights) at this distance: what is judged.
    pub error: f64,
    /// The mean whole-frame RMSE (`billow eval`'s `rmse`).
    pub rmse: f64,
    /// The mean signed relative coverage difference (positive: denser than the mesh).
    pub coverage_rel_diff: f64,
}

/// A setting's measured error.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Score {
    /// The per-distance errors weighted ([`Weighting`]).
    pub error: f64,
    /// In the order of [`TargetOptions::distances`].
    pub by_distance: Vec<DistanceError>,
}

impl Score {
    /// A score from per-distance errors.
    pub fn new(by_distance: Vec<DistanceError>, weighting: Weighting) -> Self {
        let e: Vec<f64> = by_distance.iter().map(|d| d.error).collect();
        Score {
            error: weighting.apply(&e),
            by_distance,
        }
    }

    /// The distance whose error is the largest (`None` when there is none or one is NaN).
    pub fn worst_distance(&self) -> Option<f32> {
        self.by_distance
            .iter()
            .filter(|d| !d.error.is_nan())
            .max_by(|a, b| a.error.total_cmp(&b.error))
            .map(|d| d.distance)
    }
}

/// Which step of the search measured a trial.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Ladder,
    Scan,
    Refine,
}

/// One bake the search measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Trial {
    pub label: String,
    pub preset: Option<Preset>,
    pub phase: Phase,
    /// The weighted error ([`Score::error`]).
    pub error: f64,
    pub by_distance: Vec<DistanceError>,
    pub met: bool,
    /// The asset's size as written.
    pub bytes: u64,
    /// Bake and measure, wall time.
    pub seconds: f64,
}

/// What the search chose.
#[derive(Debug)]
pub struct Found<S, A> {
    pub candidate: Candidate<S>,
    /// The chosen bake, as measured.
    pub asset: A,
    pub score: Score,
    /// Every bake, in the order measured.
    pub trials: Vec<Trial>,
}

/// A search that did not find: the target's error, the bake's, or the judge's.
#[derive(Debug)]
pub enum SearchError<E> {
    Target(TargetError),
    Bake(E),
    Judge(EvalError),
}

/// A measured bake ([`search`](super::search::search)'s `measure`).
#[derive(Debug)]
pub struct Measured<A> {
    pub asset: A,
    pub score: Score,
    pub bytes: u64,
}

/// Bakes a candidate and scores it ([`search`](super::search::search)).
pub type Measure<'f, S, A, E> = &'f mut dyn FnMut(&Candidate<S>) -> Result<Measured<A>, E>;
