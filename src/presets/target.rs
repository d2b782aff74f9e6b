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

use std::time::Instant;

use billow_format::{CloudAsset, VolumeAsset};
use serde::Serialize;

use super::{resolve_cloud, resolve_volume, CloudFlags, CloudSettings, Preset};
use super::{VolumeFlags, VolumeSettings};
use crate::eval::cloud_render::{CloudRenderer, PreparedCloud};
use crate::eval::lighting::{light_set, EvalLight, Lighting};
use crate::eval::metrics::{compare, ImageError};
use crate::eval::suite::{
    mean_errors, reference_lighting, EvalOptions, Evaluator, PreparedAsset, ReferenceView,
    EVAL_FOV_Y,
};
use crate::eval::EvalError;
use crate::scene::Scene;
use crate::voxelize::{Resolution, MAX_AXIS};
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

/// A measured bake ([`search`]'s `measure`).
#[derive(Debug)]
pub struct Measured<A> {
    pub asset: A,
    pub score: Score,
    pub bytes: u64,
}

/// Bakes a candidate and scores it ([`search`]).
pub type Measure<'f, S, A, E> = &'f mut dyn FnMut(&Candidate<S>) -> Result<Measured<A>, E>;

/// Hears of each trial as it is measured ([`search`]).
pub type OnTrial<'f> = &'f mut dyn FnMut(&Trial);

/// Bakes a setting and says how many bytes the asset writes ([`search_volume`],
/// [`search_cloud`]).
pub type Bake<'f, S, T, E> = &'f mut dyn FnMut(&S) -> Result<(T, u64), E>;

/// A family of settings ordered by cost, with the presets on it: the search moves along
/// one parameter ([`Space::position`]) and keeps the others of the preset above.
pub trait Space {
    type Settings: Clone + PartialEq;

    /// The presets' settings, cheapest first, without repeats.
    fn ladder(&self) -> Vec<Candidate<Self::Settings>>;

    /// Where `s` lies on the searched parameter, increasing with the cost; `None` when
    /// the parameter is fixed (an explicit flag): then only the ladder is measured.
    fn position(&self, s: &Self::Settings) -> Option<f64>;

    /// The candidate at `x` on the parameter, rounded to its grid, with `base`'s other
    /// settings; `None` outside the parameter's range.
    fn at(&self, base: &Candidate<Self::Settings>, x: f64) -> Option<Candidate<Self::Settings>>;
}

/// A point measured by the search: its candidate, place and outcome.
struct Point<S> {
    candidate: Candidate<S>,
    /// `(position, ladder index)`: the cost order (probes take index 0).
    rank: (f64, usize),
    error: f64,
    met: bool,
}

/// The search's state: what was measured, and the cheapest asset that met the target.
struct State<'m, S, A, E> {
    target: &'m TargetOptions,
    measure: Measure<'m, S, A, E>,
    on_trial: OnTrial<'m>,
    points: Vec<Point<S>>,
    trials: Vec<Trial>,
    best: Option<(usize, A, Score)>,
}

impl<S: Clone + PartialEq, A, E> State<'_, S, A, E> {
    fn full(&self) -> bool {
        self.trials.len() >= self.target.max_bakes
    }

    fn measured(&self, s: &S) -> bool {
        self.points.iter().any(|p| p.candidate.settings == *s)
    }

    /// Bakes and measures `c`; returns whether it met the target.
    fn run(
        &mut self,
        c: &Candidate<S>,
        rank: (f64, usize),
        phase: Phase,
    ) -> Result<bool, SearchError<E>> {
        let t = Instant::now();
        let m = (self.measure)(c).map_err(SearchError::Bake)?;
        // NaN never meets a target.
        let met = m.score.error <= self.target.error;
        let trial = Trial {
            label: c.label.clone(),
            preset: c.preset,
            phase,
            error: m.score.error,
            by_distance: m.score.by_distance.clone(),
            met,
            bytes: m.bytes,
            seconds: t.elapsed().as_secs_f64(),
        };
        (self.on_trial)(&trial);
        self.trials.push(trial);
        self.points.push(Point {
            candidate: c.clone(),
            rank,
            error: m.score.error,
            met,
        });
        let i = self.points.len() - 1;
        let cheaper = self
            .best
            .as_ref()
            .is_none_or(|(b, _, _)| lt(rank, self.points[*b].rank));
        if met && cheaper {
            self.best = Some((i, m.asset, m.score));
        }
        Ok(met)
    }
}

fn cmp_rank(a: (f64, usize), b: (f64, usize)) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

fn lt(a: (f64, usize), b: (f64, usize)) -> bool {
    cmp_rank(a, b).is_lt()
}

/// Searches `space` for the cheapest measured setting that meets `target` (see the module
/// docs). `measure` bakes a candidate and scores it; `on_trial` hears of each trial as it
/// is measured.
pub fn search<Sp: Space, A, E>(
    space: &Sp,
    target: &TargetOptions,
    measure: Measure<'_, Sp::Settings, A, E>,
    on_trial: OnTrial<'_>,
) -> Result<Found<Sp::Settings, A>, SearchError<E>> {
    target.validate().map_err(SearchError::Target)?;
    let ladder = space.ladder();
    let xs: Vec<Option<f64>> = ladder.iter().map(|c| space.position(&c.settings)).collect();
    let rank = |i: usize| (xs[i].unwrap_or(0.0), i);
    let mut st = State {
        target,
        measure,
        on_trial,
        points: Vec::new(),
        trials: Vec::new(),
        best: None,
    };

    // 1. The ladder, cheapest first, until a preset meets the target.
    let mut passed = None;
    for (i, c) in ladder.iter().enumerate() {
        if st.full() {
            break;
        }
        if st.run(c, rank(i), Phase::Ladder)? {
            passed = Some(i);
            break;
        }
    }
    let falls = st.points.windows(2).all(|w| w[1].error < w[0].error);

    // The other settings of a probe at x: those of the cheapest preset at or above x
    // (below the ladder, the cheapest preset's); above the dearest, none.
    let base = |x: f64| -> Option<&Candidate<Sp::Settings>> {
        let i = xs.iter().position(|p| p.is_some_and(|p| p >= x))?;
        Some(&ladder[i])
    };
    let probe = |x: f64| base(x).and_then(|b| space.at(b, x));

    // 2. The scan, when no preset met the target or the errors did not fall.
    let scan = passed.is_none() || !falls;
    if scan && !st.full() {
        let top = passed.unwrap_or(ladder.len().saturating_sub(1));
        let mut stops: Vec<f64> = xs[..=top.min(xs.len().saturating_sub(1))]
            .iter()
            .flatten()
            .copied()
            .collect();
        stops.sort_by(f64::total_cmp);
        stops.dedup();
        let mut scan: Vec<(f64, Candidate<Sp::Settings>)> = Vec::new();
        for w in stops.windows(2) {
            let (a, b) = (w[0], w[1]);
            for j in 1..=SCAN_PER_SEGMENT {
                let x = a + (b - a) * j as f64 / (SCAN_PER_SEGMENT + 1) as f64;
                let Some(c) = probe(x) else { continue };
                let Some(p) = space.position(&c.settings) else {
                    continue;
                };
                if p > a && p < b && !scan.iter().any(|s| s.1.settings == c.settings) {
                    scan.push((p, c));
                }
            }
        }
        scan.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (p, c) in scan {
            if st.full() {
                break;
            }
            if st.measured(&c.settings) {
                continue;
            }
            if st.run(&c, (p, 0), Phase::Scan)? {
                break;
            }
        }
    }

    // 3. Refinement around the best measured.
    for _ in 0..REFINE_ROUNDS {
        if st.full() {
            break;
        }
        let centre = match &st.best {
            Some((i, _, _)) => *i,
            None => match st
                .points
                .iter()
                .enumerate()
                .filter(|(_, p)| !p.error.is_nan())
                .min_by(|a, b| a.1.error.total_cmp(&b.1.error).then(a.0.cmp(&b.0)))
            {
                Some((i, _)) => i,
                None => break,
            },
        };
        let c = &st.points[centre];
        let met = c.met;
        let Some(xc) = space.position(&c.candidate.settings) else {
            break;
        };
        // Its neighbours in the cost order among the measured (a preset that shares its
        // position, such as a cloud's quality and hero, leaves no room between them).
        let mut order: Vec<usize> = (0..st.points.len()).collect();
        order.sort_by(|&a, &b| cmp_rank(st.points[a].rank, st.points[b].rank));
        let k = order.iter().position(|&i| i == centre).unwrap_or(0);
        let at = |j: Option<usize>| {
            j.and_then(|j| order.get(j))
                .and_then(|&i| space.position(&st.points[i].candidate.settings))
        };
        let (below, above) = (at(k.checked_sub(1)), at(Some(k + 1)));
        let mut targets: Vec<(f64, f64, f64)> = Vec::new(); // (x, lo, hi)
        match (below, above) {
            (Some(b), _) => targets.push(((b + xc) / 2.0, b, xc)),
            // Below the cheapest measured: as far below as the dearer neighbour is above.
            (None, Some(a)) if !met => {
                let x = xc - (a - xc) / 2.0;
                targets.push((x, f64::NEG_INFINITY, xc));
            }
            _ => {}
        }
        if !met {
            if let Some(a) = above {
                targets.push(((xc + a) / 2.0, xc, a));
            }
        }
        let mut probes: Vec<(f64, Candidate<Sp::Settings>)> = Vec::new();
        for (x, lo, hi) in targets {
            let Some(c) = probe(x) else { continue };
            let Some(p) = space.position(&c.settings) else {
                continue;
            };
            if p > lo && p < hi && !st.measured(&c.settings) {
                probes.push((p, c));
            }
        }
        if probes.is_empty() {
            break;
        }
        for (p, c) in probes {
            if st.full() {
                break;
            }
            st.run(&c, (p, 0), Phase::Refine)?;
        }
    }

    let State {
        points,
        trials,
        best,
        ..
    } = st;
    match best {
        Some((i, asset, score)) => Ok(Found {
            candidate: points[i].candidate.clone(),
            asset,
            score,
            trials,
        }),
        None => {
            let b = trials
                .iter()
                .filter(|t| !t.error.is_nan())
                .min_by(|a, b| a.error.total_cmp(&b.error));
            Err(SearchError::Target(TargetError::Unreachable {
                target: target.error,
                measure: target.describe(),
                best: b.map_or(f64::NAN, |t| t.error),
                best_label: b.map_or_else(|| "nothing".into(), |t| t.label.clone()),
                trials,
            }))
        }
    }
}

/// `billow voxelize`'s space: the presets' `--res` and `--supersample` under the explicit
/// flags; the search moves `--res` (longest axis) in multiples of [`RES_STEP`], unless
/// `--res` is given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VolumeSpace {
    pub flags: VolumeFlags,
}

/// `--res N --supersample K`.
/// The presets cheapest first as candidates (`settings` of each, labelled with the preset
/// and `describe`), neighbours with equal settings once.
fn preset_ladder<S: PartialEq>(
    settings: impl Fn(Preset) -> S,
    describe: impl Fn(&S) -> String,
) -> Vec<Candidate<S>> {
    let mut ladder: Vec<Candidate<S>> = Preset::LADDER
        .iter()
        .map(|&p| {
            let s = settings(p);
            Candidate {
                label: format!("{p} ({})", describe(&s)),
                preset: Some(p),
                settings: s,
            }
        })
        .collect();
    ladder.dedup_by(|a, b| a.settings == b.settings);
    ladder
}

pub fn describe_volume(s: &VolumeSettings) -> String {
    format!("--res {} --supersample {}", s.resolution, s.supersample)
}

impl Space for VolumeSpace {
    type Settings = VolumeSettings;

    fn ladder(&self) -> Vec<Candidate<VolumeSettings>> {
        preset_ladder(
            |p| resolve_volume(Some(p), &self.flags).settings,
            describe_volume,
        )
    }

    fn position(&self, s: &VolumeSettings) -> Option<f64> {
        match (self.flags.resolution, s.resolution) {
            (None, Resolution::Longest(n)) => Some(f64::from(n)),
            _ => None,
        }
    }

    fn at(&self, base: &Candidate<VolumeSettings>, x: f64) -> Option<Candidate<VolumeSettings>> {
        self.position(&base.settings)?;
        if !x.is_finite() {
            return None;
        }
        let n = (x / f64::from(RES_STEP)).round() * f64::from(RES_STEP);
        if n < f64::from(RES_STEP) || n > f64::from(MAX_AXIS) {
            return None;
        }
        let settings = VolumeSettings {
            resolution: Resolution::Longest(n as u32),
            ..base.settings
        };
        Some(Candidate {
            label: describe_volume(&settings),
            preset: None,
            settings,
        })
    }
}

/// `billow bbcloud`'s space: the presets' ε, N and atlas size under the explicit flags;
/// the search moves ε geometrically (three significant digits), unless `--epsilon` is
/// given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CloudSpace {
    pub flags: CloudFlags,
}

/// `0.04`, `1e-30`: a number as a person would write it.
pub fn short(x: f32) -> String {
    if x == 0.0 || x.abs() >= 1e-3 {
        x.to_string()
    } else {
        format!("{x:e}")
    }
}

/// `--epsilon E --samples N --atlas-size A`.
pub fn describe_cloud(s: &CloudSettings) -> String {
    format!(
        "--epsilon {} --samples {} --atlas-size {}",
        short(s.epsilon),
        s.samples,
        s.atlas_size
    )
}

impl Space for CloudSpace {
    type Settings = CloudSettings;

    fn ladder(&self) -> Vec<Candidate<CloudSettings>> {
        preset_ladder(
            |p| resolve_cloud(Some(p), &self.flags).settings,
            describe_cloud,
        )
    }

    /// −ln ε: a smaller ε costs more.
    fn position(&self, s: &CloudSettings) -> Option<f64> {
        (self.flags.epsilon.is_none() && s.epsilon > 0.0).then(|| -f64::from(s.epsilon).ln())
    }

    fn at(&self, base: &Candidate<CloudSettings>, x: f64) -> Option<Candidate<CloudSettings>> {
        self.position(&base.settings)?;
        let e = (-x).exp();
        if !(e.is_finite() && e > 0.0) {
            return None;
        }
        let k = 10f64.powi(2 - e.log10().floor() as i32);
        let e = ((e * k).round() / k) as f32;
        if !(e > 0.0 && e <= 2.0) {
            return None;
        }
        let settings = CloudSettings {
            epsilon: e,
            ..base.settings
        };
        Some(Candidate {
            label: describe_cloud(&settings),
            preset: None,
            settings,
        })
    }
}

/// The volume search: [`search`] over [`VolumeSpace`] with each bake scored by a
/// [`Judge`]. `bake` makes the asset of a setting and says how many bytes it writes; the
/// asset as a reader of the file gets it (BC7 decoded) is what is judged.
pub fn search_volume<T: AsRef<VolumeAsset>, E>(
    scene: &Scene,
    flags: &VolumeFlags,
    target: &TargetOptions,
    bake: Bake<'_, VolumeSettings, T, E>,
    on_trial: OnTrial<'_>,
) -> Result<Found<VolumeSettings, T>, SearchError<E>> {
    target.validate().map_err(SearchError::Target)?;
    let mut judge = Judge::new(scene, target);
    judge.prepare().map_err(SearchError::Judge)?;
    let mut measure = |c: &Candidate<VolumeSettings>| -> Result<Measured<T>, Either<E>> {
        let (asset, bytes) = bake(&c.settings).map_err(Either::Bake)?;
        let score = judge.volume(asset.as_ref()).map_err(Either::Judge)?;
        Ok(Measured {
            asset,
            score,
            bytes,
        })
    };
    unpack(search(
        &VolumeSpace { flags: *flags },
        target,
        &mut measure,
        on_trial,
    ))
}

/// The cloud search: [`search`] over [`CloudSpace`], each bake's finest level scored by a
/// [`Judge`] (see [`search_volume`]).
pub fn search_cloud<T: AsRef<CloudAsset>, E>(
    scene: &Scene,
    flags: &CloudFlags,
    target: &TargetOptions,
    bake: Bake<'_, CloudSettings, T, E>,
    on_trial: OnTrial<'_>,
) -> Result<Found<CloudSettings, T>, SearchError<E>> {
    target.validate().map_err(SearchError::Target)?;
    let mut judge = Judge::new(scene, target);
    judge.prepare().map_err(SearchError::Judge)?;
    let mut measure = |c: &Candidate<CloudSettings>| -> Result<Measured<T>, Either<E>> {
        let (asset, bytes) = bake(&c.settings).map_err(Either::Bake)?;
        let score = judge.cloud(asset.as_ref()).map_err(Either::Judge)?;
        Ok(Measured {
            asset,
            score,
            bytes,
        })
    };
    unpack(search(
        &CloudSpace { flags: *flags },
        target,
        &mut measure,
        on_trial,
    ))
}

/// A bake's error or the judge's, inside [`search`].
enum Either<E> {
    Bake(E),
    Judge(EvalError),
}

fn unpack<S, T, E>(
    r: Result<Found<S, T>, SearchError<Either<E>>>,
) -> Result<Found<S, T>, SearchError<E>> {
    r.map_err(|e| match e {
        SearchError::Target(t) => SearchError::Target(t),
        SearchError::Judge(j) => SearchError::Judge(j),
        SearchError::Bake(Either::Bake(b)) => SearchError::Bake(b),
        SearchError::Bake(Either::Judge(j)) => SearchError::Judge(j),
    })
}

/// The reference views of one lighting, rendered once.
struct Context<'a> {
    evaluator: Evaluator<'a>,
    refs: Vec<ReferenceView>,
}

/// Scores assets of one source mesh against its reference views (see the module docs).
pub struct Judge<'a> {
    scene: &'a Scene,
    target: TargetOptions,
    views: Vec<ViewSpec>,
    /// One context per light of [`TargetOptions::lights`], rendered on first use.
    lit: Vec<Context<'a>>,
    /// Without lights: one context per reference lighting met so far.
    auto: Vec<(Lighting, Context<'a>)>,
}

impl<'a> Judge<'a> {
    pub fn new(scene: &'a Scene, target: &TargetOptions) -> Self {
        Judge {
            scene,
            target: target.clone(),
            views: target.views(),
            lit: Vec::new(),
            auto: Vec::new(),
        }
    }

    fn context(
        &self,
        lighting: Lighting,
        light: Option<&EvalLight>,
    ) -> Result<Context<'a>, EvalError> {
        let options = EvalOptions {
            width: self.target.width,
            height: self.target.height,
            fov_y: EVAL_FOV_Y,
            reference_per_axis: TARGET_SPP_PER_AXIS,
            raster_1spp: false,
            lighting,
            ..EvalOptions::default()
        };
        let mut evaluator = Evaluator::new(self.scene, options)?;
        if let Some(l) = light {
            evaluator.set_light(l, false)?;
        }
        let refs = self
            .views
            .iter()
            .map(|v| evaluator.reference(v))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Context { evaluator, refs })
    }

    /// Renders the light set's reference views now (without lights there is nothing to
    /// render before the first asset names its lighting), so that no trial's time includes
    /// them. The searches call it first.
    pub fn prepare(&mut self) -> Result<(), EvalError> {
        if self.target.lights.is_some() {
            self.lit()?;
        }
        Ok(())
    }

    /// The contexts of the light set, rendering their references on first use.
    fn lit(&mut self) -> Result<&[Context<'a>], EvalError> {
        if self.lit.is_empty() {
            let lights = self.target.lights.clone().unwrap_or_default();
            for l in &lights {
                let c = self.context(Lighting::Unlit, Some(l))?;
                self.lit.push(c);
            }
        }
        Ok(&self.lit)
    }

    /// The context of `lighting` (no light set), rendering its references first.
    fn auto(&mut self, lighting: Lighting) -> Result<&Context<'a>, EvalError> {
        let i = match self.auto.iter().position(|c| c.0 == lighting) {
            Some(i) => i,
            None => {
                let c = self.context(lighting, None)?;
                self.auto.push((lighting, c));
                self.auto.len() - 1
            }
        };
        Ok(&self.auto[i].1)
    }

    /// Per-distance means of `(distance factor, error)` pairs, weighted.
    fn score(&self, errors: &[(f32, ImageError)]) -> Score {
        let by_distance = self
            .target
            .distances
            .iter()
            .map(|&d| {
                let m = mean_errors(errors.iter().filter(|e| e.0 == d).map(|e| &e.1));
                DistanceError {
                    distance: d,
                    error: if m.views == 0 {
                        f64::NAN
                    } else {
                        m.rmse_covered
                    },
                    rmse: m.rmse,
                    coverage_rel_diff: m.coverage_rel_diff,
                }
            })
            .collect();
        Score::new(by_distance, self.target.weighting)
    }

    /// The score of a volume asset (as the file would be read back).
    pub fn volume(&mut self, asset: &VolumeAsset) -> Result<Score, EvalError> {
        let prepared = PreparedAsset::new(asset)?;
        let mut errors = Vec::new();
        if self.target.lights.is_some() {
            let lit = self.lit()?;
            if asset.normals.is_none() {
                // Without normals the slicer draws the baked colour whatever the light:
                // rendered once per view, compared with every light's reference.
                let first = &lit[0];
                for (v, r) in first.refs.iter().enumerate() {
                    let (result, image) = first.evaluator.asset(&prepared, r)?;
                    errors.push((r.spec.distance_factor, result.asset));
                    for c in &lit[1..] {
                        let e = compare(&c.refs[v].image, &image)?;
                        errors.push((r.spec.distance_factor, e));
                    }
                }
            } else {
                for c in lit {
                    for r in &c.refs {
                        let (result, _) = c.evaluator.asset(&prepared, r)?;
                        errors.push((r.spec.distance_factor, result.asset));
                    }
                }
            }
        } else {
            let (lighting, _) = reference_lighting(asset)?;
            let c = self.auto(lighting)?;
            for r in &c.refs {
                let (result, _) = c.evaluator.asset(&prepared, r)?;
                errors.push((r.spec.distance_factor, result.asset));
            }
        }
        Ok(self.score(&errors))
    }

    /// The score of a billboard cloud's finest level (as the file would be read back).
    pub fn cloud(&mut self, asset: &CloudAsset) -> Result<Score, EvalError> {
        let prepared = PreparedCloud::new(asset)?;
        let mut errors = Vec::new();
        let mut judge = |c: &Context<'a>| -> Result<(), EvalError> {
            // The kept mesh is drawn as the viewer draws meshes: lit like the reference.
            let renderer = CloudRenderer::new(&prepared, c.evaluator.options.lighting)?;
            for r in &c.refs {
                let (result, _) = c.evaluator.cloud(&renderer, &prepared, 0, r)?;
                errors.push((r.spec.distance_factor, result.asset));
            }
            Ok(())
        };
        if self.target.lights.is_some() {
            for c in self.lit()? {
                judge(c)?;
            }
        } else {
            let lighting =
                Lighting::for_cloud(&asset.header.params).map_err(EvalError::InvalidAsset)?;
            judge(self.auto(lighting)?)?;
        }
        Ok(self.score(&errors))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn res(c: &Candidate<VolumeSettings>) -> u32 {
        match c.settings.resolution {
            Resolution::Longest(n) => n,
            Resolution::Exact(d) => d[0],
        }
    }

    /// Bakes nothing: the error of a resolution is `table(res)`, its bytes `res³ / 8`.
    fn by_table(
        table: impl Fn(u32) -> f64,
    ) -> impl FnMut(&Candidate<VolumeSettings>) -> Result<Measured<u32>, ()> {
        move |c| {
            let r = res(c);
            let e = table(r);
            Ok(Measured {
                asset: r,
                score: Score::new(
                    vec![DistanceError {
                        distance: 1.0,
                        error: e,
                        rmse: e,
                        coverage_rel_diff: 0.0,
                    }],
                    Weighting::Worst,
                ),
                bytes: u64::from(r).pow(3) / 8,
            })
        }
    }

    fn target(error: f64) -> TargetOptions {
        TargetOptions {
            error,
            ..TargetOptions::default()
        }
    }

    type Outcome = Result<Found<VolumeSettings, u32>, SearchError<()>>;

    fn run(t: &TargetOptions, table: impl Fn(u32) -> f64) -> (Outcome, Vec<u32>) {
        let mut heard = Vec::new();
        let mut measure = by_table(table);
        let r = search(
            &VolumeSpace::default(),
            t,
            &mut measure,
            &mut |t: &Trial| heard.push(t.label.clone()),
        );
        let tried = heard
            .iter()
            .map(|l| {
                let i = l.find("--res ").unwrap() + 6;
                l[i..].split(' ').next().unwrap().parse().unwrap()
            })
            .collect();
        (r, tried)
    }

    /// An error that halves per doubling of the resolution.
    fn smooth(r: u32) -> f64 {
        1.0 / f64::from(r)
    }

    #[test]
    fn a_falling_ladder_is_bisected_between_the_rung_that_missed_and_the_one_that_met() {
        // 1/32 misses 0.02, 1/64 meets it: 48 (0.0208, misses), then 56 (0.0179, meets).
        let (f, tried) = run(&target(0.02), smooth);
        let f = f.unwrap();
        assert_eq!(tried, [32, 64, 48, 56]);
        assert_eq!((f.asset, f.candidate.preset), (56, None));
        assert_eq!(f.candidate.label, "--res 56 --supersample 4");
        let phases: Vec<Phase> = f.trials.iter().map(|t| t.phase).collect();
        use Phase::*;
        assert_eq!(phases, [Ladder, Ladder, Refine, Refine]);
        assert_eq!(f.trials[1].bytes, 64 * 64 * 64 / 8);
        // The cheapest rung meets it: nothing below the bottom of the ladder.
        let (f, tried) = run(&target(0.5), smooth);
        assert_eq!((f.unwrap().asset, tried), (32, vec![32]));
        // A rung that meets the target exactly is kept.
        let (f, _) = run(&target(1.0 / 64.0), smooth);
        assert!(f.unwrap().score.error <= 1.0 / 64.0);
    }

    /// The solid mesh: every preset misses (≥ 0.0713) while --res 96 scores 0.0655.
    fn swinging(r: u32) -> f64 {
        match r {
            32 => 0.0801,
            64 => 0.0713,
            128 => 0.0720,
            256 => 0.0715,
            96 => 0.0655,
            88 => 0.0690,
            80 => 0.0731,
            _ => 0.0750,
        }
    }

    #[test]
    fn when_every_preset_misses_the_search_scans_between_them_and_finds_the_dip() {
        let (f, tried) = run(&target(0.07), swinging);
        let f = f.unwrap();
        // Ladder, then the scan cheapest first up to the first that meets, then the
        // refinement below it (88 meets too and is cheaper; 84 rounds to 80 or 88, both
        // measured).
        assert_eq!(tried, [32, 64, 128, 256, 40, 48, 56, 80, 96, 88]);
        assert_eq!(f.asset, 88);
        assert!(f.trials.iter().filter(|t| t.met).count() == 2);
        assert!(f.trials.len() <= MAX_BAKES);
    }

    #[test]
    fn a_ladder_whose_error_rises_is_scanned_below_the_rung_that_met() {
        // 64 scores worse than 32; 128 meets 0.04; the old bisection (between 64 and 128)
        // would keep 96 or above, the scan finds 40.
        let table = |r: u32| match r {
            32 => 0.050,
            40 => 0.039,
            64 => 0.060,
            128 => 0.035,
            _ => 0.045,
        };
        let (f, tried) = run(&target(0.04), table);
        assert_eq!(f.unwrap().asset, 40);
        assert_eq!(tried, [32, 64, 128, 40]);
    }

    #[test]
    fn an_unreachable_target_holds_every_trial_and_names_the_best() {
        let (r, tried) = run(&target(0.01), swinging);
        match r {
            Err(SearchError::Target(TargetError::Unreachable {
                best,
                best_label,
                trials,
                measure,
                ..
            })) => {
                assert_eq!(
                    (best, best_label.as_str()),
                    (0.0655, "--res 96 --supersample 4")
                );
                assert_eq!(trials.len(), tried.len());
                assert!(trials.len() <= MAX_BAKES, "{tried:?}");
                assert!(trials.iter().all(|t| !t.met));
                // Refined around 96 on both sides.
                assert!(tried.contains(&88) && tried.contains(&104), "{tried:?}");
                assert!(measure.contains("worst of 1x, 4x, 16x"), "{measure}");
                let e = TargetError::Unreachable {
                    target: 0.01,
                    measure,
                    best,
                    best_label,
                    trials,
                }
                .to_string();
                assert!(e.contains("the best measured, --res 96 --supersample 4, scored 0.0655"));
            }
            other => panic!("{:?}", other.map(|f| f.asset)),
        }
        // The budget holds.
        let t = TargetOptions {
            max_bakes: 6,
            ..target(0.01)
        };
        let (r, tried) = run(&t, swinging);
        assert!(matches!(
            r,
            Err(SearchError::Target(TargetError::Unreachable { .. }))
        ));
        assert_eq!(tried.len(), 6);
    }

    #[test]
    fn nan_never_meets_a_failed_bake_stops_and_bad_targets_are_refused() {
        let (r, _) = run(&target(1.0), |_| f64::NAN);
        assert!(matches!(
            r,
            Err(SearchError::Target(TargetError::Unreachable { .. }))
        ));
        let mut fail = |c: &Candidate<VolumeSettings>| {
            if res(c) < 128 {
                by_table(smooth)(c)
            } else {
                Err(())
            }
        };
        assert!(matches!(
            search(
                &VolumeSpace::default(),
                &target(1e-3),
                &mut fail,
                &mut |_| {}
            ),
            Err(SearchError::Bake(()))
        ));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                run(&target(bad), smooth).0,
                Err(SearchError::Target(TargetError::InvalidTarget(_)))
            ));
        }
        for d in [vec![], vec![0.0], vec![1.0, 1.0], vec![2000.0]] {
            let t = TargetOptions {
                distances: d,
                ..target(0.1)
            };
            assert!(t.validate().is_err());
        }
    }

    #[test]
    fn an_explicit_res_pins_the_search_to_the_ladder() {
        let space = VolumeSpace {
            flags: VolumeFlags {
                resolution: Some(Resolution::Longest(48)),
                supersample: None,
            },
        };
        // Every preset has --supersample 4: one candidate left.
        assert_eq!(space.ladder().len(), 1);
        let mut measure = by_table(smooth);
        let r = search(&space, &target(1e-3), &mut measure, &mut |_| {});
        match r {
            Err(SearchError::Target(TargetError::Unreachable { trials, .. })) => {
                assert_eq!(trials.len(), 1)
            }
            other => panic!("{:?}", other.map(|f| f.asset)),
        }
    }

    #[test]
    fn the_cloud_space_scans_epsilon_geometrically_between_the_presets() {
        let space = CloudSpace::default();
        let ladder = space.ladder();
        assert_eq!(ladder.len(), 4);
        let (a, b) = (
            space.position(&ladder[1].settings).unwrap(),
            space.position(&ladder[2].settings).unwrap(),
        );
        let eps: Vec<f32> = (1..=3)
            .map(|j| {
                let x = a + (b - a) * f64::from(j) / 4.0;
                space.at(&ladder[2], x).unwrap().settings.epsilon
            })
            .collect();
        assert_eq!(eps, [0.0673, 0.0566, 0.0476]);
        let c = space.at(&ladder[2], a + (b - a) / 4.0).unwrap();
        assert_eq!(c.label, "--epsilon 0.0673 --samples 500 --atlas-size 2048");
        let pinned = CloudSpace {
            flags: CloudFlags {
                epsilon: Some(0.05),
                ..CloudFlags::default()
            },
        };
        assert!(pinned.position(&ladder[0].settings).is_none());
    }

    #[test]
    fn a_cloud_met_only_by_hero_is_not_refined_along_epsilon() {
        // Quality and hero share ε and differ in the atlas: nothing lies between them on
        // ε, so the search stops at hero after the ladder (as the bisection did).
        let err = |s: &CloudSettings| match (s.atlas_size, s.samples) {
            (512, _) => 0.17,
            (1024, _) => 0.16,
            (2048, _) => 0.127,
            _ => 0.116,
        };
        let mut measure = |c: &Candidate<CloudSettings>| {
            let e = err(&c.settings);
            Ok::<_, ()>(Measured {
                asset: c.settings,
                score: Score::new(
                    vec![DistanceError {
                        distance: 1.0,
                        error: e,
                        rmse: e,
                        coverage_rel_diff: 0.0,
                    }],
                    Weighting::Worst,
                ),
                bytes: 1,
            })
        };
        let f = search(
            &CloudSpace::default(),
            &target(0.12),
            &mut measure,
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(f.candidate.preset, Some(Preset::Hero));
        assert_eq!(f.trials.len(), 4);
    }

    #[test]
    fn weightings_and_descriptions() {
        assert_eq!(Weighting::Worst.apply(&[0.1, 0.3, 0.2]), 0.3);
        assert!((Weighting::Mean.apply(&[0.1, 0.3, 0.2]) - 0.2).abs() < 1e-12);
        assert!(Weighting::Worst.apply(&[0.1, f64::NAN]).is_nan());
        assert!(Weighting::Mean.apply(&[]).is_nan());
        assert_eq!(
            TargetOptions::default().describe(),
            "covered RMSE, worst of 1x, 4x, 16x, mean over 4 lights (overhead, sun-east, \
             sun-west, below)"
        );
        let t = TargetOptions {
            distances: vec![2.0],
            lights: None,
            ..TargetOptions::default()
        };
        assert_eq!(
            t.describe(),
            "covered RMSE, at 2x, lit as the asset was baked"
        );
        assert_eq!("mean".parse::<Weighting>().unwrap(), Weighting::Mean);
        assert!("max".parse::<Weighting>().is_err());
    }
}
