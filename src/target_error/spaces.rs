//! The two spaces searched: a volume's `--res`, a cloud's ε, and their entries [`search_volume`] and [`search_cloud`].

use billow_format::{CloudAsset, VolumeAsset};

use crate::eval::EvalError;
use crate::presets::{resolve_cloud, resolve_volume, CloudFlags, CloudSettings, Preset};
use crate::presets::{VolumeFlags, VolumeSettings};
use crate::scene::Scene;
use crate::voxelize::{Resolution, MAX_AXIS};

use super::judge::Judge;
use super::search::*;
use super::types::*;
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
