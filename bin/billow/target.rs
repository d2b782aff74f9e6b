//! `--target-error` and its flags, shared by `billow voxelize` and `billow bbcloud`: the
//! parsing, the per-trial lines and the JSON. The search and the judge are the library's
//! (`billow::target_error`).

use billow::eval::lighting::{parse_light_set, LightSetError};
use billow::presets::Preset;
use billow::target_error::{
    DistanceError, Found, SearchError, TargetError, TargetOptions, Trial, Weighting,
};
use billow_core::shading::DEFAULT_AMBIENT;
use serde::Serialize;

use crate::exit::{usage, CliError, Code};
use crate::output::print_json;

/// The flags of `--target-error`.
#[derive(clap::Args, Debug)]
pub(crate) struct TargetArgs {
    /// Bake the cheapest measured setting whose error is at most E (docs/cli.md, "Presets
    /// and --target-error"): `billow eval`'s covered RMSE over the six axis views at each
    /// of --target-distances (the worst of them), under --target-lights. Tries the presets
    /// cheapest first; when none meets E or their errors do not fall, scans and refines
    /// the parameter they vary (voxelize: --res, bbcloud: --epsilon), at most 16 bakes.
    /// Exit 10 (and no file) when none does. Explicit flags stay fixed.
    #[arg(long, value_name = "E")]
    pub(crate) target_error: Option<f64>,
    /// The view distances of --target-error, multiples of the framed distance, each in
    /// (0, 1000], 1 to 16 of them (--target-distance F: one).
    #[arg(
        long,
        value_name = "F,F,...",
        default_value = "1,4,16",
        requires = "target_error",
        alias = "target-distance"
    )]
    pub(crate) target_distances: String,
    /// How --target-error makes one error of the per-distance errors: worst (a setting
    /// meets E at every distance) or mean.
    #[arg(long, value_enum, value_name = "HOW", default_value_t = WeightingArg::Worst,
          requires = "target_error")]
    pub(crate) target_weighting: WeightingArg,
    /// The lights of --target-error (the mean over them): standard (overhead, a low sun
    /// from east and west, below: docs/eval.md, "Lights"), a list NAME=X,Y,Z;X,Y,Z;…, or
    /// auto (the asset's own lighting, as `billow eval --lighting auto`: a quarter of the
    /// reference cost).
    #[arg(
        long,
        value_name = "SET",
        default_value = "standard",
        allow_hyphen_values = true,
        requires = "target_error"
    )]
    pub(crate) target_lights: String,
    /// The image size WxH of --target-error (16-spp reference, as `billow eval`).
    #[arg(
        long,
        value_name = "WxH",
        default_value = "128x128",
        requires = "target_error"
    )]
    pub(crate) target_size: String,
}

/// `--target-weighting`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WeightingArg {
    Worst,
    Mean,
}

/// The target the flags ask for, checked before any work; `None` without `--target-error`.
pub(crate) fn target_options(a: &TargetArgs) -> Result<Option<TargetOptions>, CliError> {
    let Some(error) = a.target_error else {
        return Ok(None);
    };
    let (width, height) = crate::eval::parse_size(&a.target_size).map_err(|e| CliError {
        message: e.message.replacen("--size", "--target-size", 1),
        ..e
    })?;
    let distances: Vec<f32> = a
        .target_distances
        .split(',')
        .map(|d| d.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| {
            usage(
                "--target-distances",
                format!("'{}': {e} (expected F,F,...)", a.target_distances),
            )
        })?;
    let lights = match a.target_lights.trim() {
        "auto" => None,
        set => Some(parse_light_set(set, DEFAULT_AMBIENT).map_err(|e| match e {
            LightSetError::Syntax(_) if !set.contains(',') => usage(
                "--target-lights",
                format!("'{set}': expected standard, auto or NAME=X,Y,Z;…"),
            ),
            LightSetError::Syntax(m) => usage("--target-lights", m),
            LightSetError::NotADirection(m) => {
                CliError::new(Code::BadParameter, format!("--target-lights: {m}"))
            }
        })?),
    };
    let t = TargetOptions {
        error,
        distances,
        weighting: match a.target_weighting {
            WeightingArg::Worst => Weighting::Worst,
            WeightingArg::Mean => Weighting::Mean,
        },
        lights,
        width,
        height,
        ..TargetOptions::default()
    };
    t.validate().map_err(|e| {
        let flag = if !(error.is_finite() && error > 0.0) {
            "--target-error"
        } else if t.lights.as_ref().is_some_and(|l| l.len() > 16) {
            "--target-lights"
        } else {
            "--target-distances"
        };
        CliError::new(Code::from(&e), format!("{flag}: {e}"))
    })?;
    Ok(Some(t))
}

/// `12.3 KiB`, `4.56 MiB`.
fn size(bytes: u64) -> String {
    let b = bytes as f64;
    if b < f64::from(1u32 << 20) {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{:.2} MiB", b / f64::from(1u32 << 20))
    }
}

/// The line printed on stderr per trial: `--target-error: balanced (--res 64
/// --supersample 4): 0.1035 (1x 0.0986, 4x 0.0920, 16x 0.1035), misses 0.1, 45.9 KiB,
/// 0.81 s`.
pub(crate) fn trial_line(target: f64, t: &Trial) -> String {
    let per: Vec<String> = t
        .by_distance
        .iter()
        .map(|d| format!("{}x {:.4}", d.distance, d.error))
        .collect();
    format!(
        "--target-error: {}: {:.4} ({}), {} {target}, {}, {:.2} s",
        t.label,
        t.error,
        per.join(", "),
        if t.met { "meets" } else { "misses" },
        size(t.bytes),
        t.seconds
    )
}

/// The best measured setting.
#[derive(Serialize)]
pub(crate) struct Best {
    pub(crate) label: String,
    pub(crate) error: f64,
}

/// What `--target-error` measured and chose (`--json`'s `target`).
#[derive(Serialize)]
pub(crate) struct TargetSummary {
    /// E.
    pub(crate) error: f64,
    /// What the error is, in words.
    pub(crate) measure: String,
    pub(crate) distances: Vec<f32>,
    pub(crate) weighting: Weighting,
    /// The lights' names; empty: the asset's own lighting (`--target-lights auto`).
    pub(crate) lights: Vec<String>,
    pub(crate) size: [u32; 2],
    pub(crate) max_bakes: usize,
    /// The chosen setting, e.g. `balanced (--res 64 --supersample 4)` or `--res 40
    /// --supersample 4`; `null` when none met E.
    pub(crate) chosen: Option<String>,
    pub(crate) chosen_preset: Option<Preset>,
    /// Its measured error (≤ `error`).
    pub(crate) measured_error: Option<f64>,
    /// Its error per distance.
    pub(crate) by_distance: Vec<DistanceError>,
    /// The lowest error measured.
    pub(crate) best: Option<Best>,
    /// Every bake measured, in order.
    pub(crate) trials: Vec<Trial>,
}

impl TargetSummary {
    fn of(t: &TargetOptions, trials: &[Trial]) -> Self {
        let best = trials
            .iter()
            .filter(|t| !t.error.is_nan())
            .min_by(|a, b| a.error.total_cmp(&b.error))
            .map(|t| Best {
                label: t.label.clone(),
                error: t.error,
            });
        TargetSummary {
            error: t.error,
            measure: t.describe(),
            distances: t.distances.clone(),
            weighting: t.weighting,
            lights: t.lights.iter().flatten().map(|l| l.name.clone()).collect(),
            size: [t.width, t.height],
            max_bakes: t.max_bakes,
            chosen: None,
            chosen_preset: None,
            measured_error: None,
            by_distance: Vec::new(),
            best,
            trials: trials.to_vec(),
        }
    }

    pub(crate) fn new<S, A>(t: &TargetOptions, found: &Found<S, A>) -> Self {
        TargetSummary {
            chosen: Some(found.candidate.label.clone()),
            chosen_preset: found.candidate.preset,
            measured_error: Some(found.score.error),
            by_distance: found.score.by_distance.clone(),
            ..Self::of(t, &found.trials)
        }
    }

    /// The line printed on stderr: the choice and its measured error.
    pub(crate) fn line(&self) -> String {
        format!(
            "--target-error {}: chose {} ({:.4}: {}; {} bake(s) measured)",
            self.error,
            self.chosen.as_deref().unwrap_or("nothing"),
            self.measured_error.unwrap_or(f64::NAN),
            self.measure,
            self.trials.len()
        )
    }
}

/// The `--json` document of a search that found nothing (exit 10).
#[derive(Serialize)]
struct Unreached<'a> {
    input: &'a str,
    output: &'a str,
    /// Nothing was written.
    written: bool,
    /// The error line (without `error: `).
    error: &'a str,
    target: TargetSummary,
}

/// A failed search as the command's error; with `--json` (`json`: the input and output
/// as shown), the document of an unreachable target is printed first, so that stdout
/// still holds every trial.
pub(crate) fn search_failed<E: Into<CliError>>(
    e: SearchError<E>,
    target: &TargetOptions,
    json: Option<(&str, &str)>,
    input: &str,
) -> CliError {
    match e {
        SearchError::Target(t) => {
            let err = CliError::new(Code::from(&t), format!("--target-error: {t}"));
            if let (TargetError::Unreachable { trials, .. }, Some((input, output))) = (&t, json) {
                let doc = Unreached {
                    input,
                    output,
                    written: false,
                    error: &err.message,
                    target: TargetSummary::of(target, trials),
                };
                if let Err(e) = print_json(&doc) {
                    return e;
                }
            }
            err
        }
        SearchError::Bake(e) => e.into(),
        SearchError::Judge(e) => CliError::new(Code::from(&e), format!("{input}: {e}")),
    }
}

/// Runs a `--target-error` search (`search` is given the printer of each trial's line on
/// stderr): the chosen bake and what was tried, or the failure as [`search_failed`] says
/// (`json`: the command's `--json`; `input`, `output`: as shown).
pub(crate) fn run_search<S, A, E: Into<CliError>>(
    target: &TargetOptions,
    ctx: &crate::Ctx,
    (json, input, output): (bool, &str, &std::path::Path),
    search: impl FnOnce(&mut dyn FnMut(&Trial)) -> Result<Found<S, A>, SearchError<E>>,
) -> Result<(A, TargetSummary), CliError> {
    let mut on_trial = |t: &Trial| {
        if !ctx.quiet {
            eprintln!("{}", trial_line(target.error, t));
        }
    };
    let found = search(&mut on_trial).map_err(|e| {
        let output = output.display().to_string();
        search_failed(e, target, json.then_some((input, &output)), input)
    })?;
    let summary = TargetSummary::new(target, &found);
    Ok((found.asset, summary))
}
