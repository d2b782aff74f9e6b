//! The search along one parameter of a [`Space`] (the module docs: [`super`]).

use std::time::Instant;

use super::types::*;
/// Hears of each trial as it is measured ([`search`]).
pub type OnTrial<'f> = &'f mut dyn FnMut(&Trial);

/// Bakes a setting and says how many bytes the asset writes ([`search_volume`](super::search_volume),
/// [`search_cloud`](super::spaces::search_cloud)).
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
