//! Named bake settings (`--preset draft|balanced|quality|hero`) and how explicit flags
//! override them; the search behind `--target-error` is [`crate::target_error`].
//!
//! Each preset is a point of the measured Pareto front of a combined sweep
//! (`examples/pareto_sweep.rs`, docs/accuracy.md "Pareto fronts and presets"): on the
//! bundled oak, the cheapest setting for its error, and no setting measured cheaper in
//! both bake time and bytes scored lower. The ladder [`Preset::LADDER`] is ordered by
//! cost (each step roughly 8× the bytes of a volume, several times the bake of a cloud),
//! cheapest first.
//!
//! A preset names only parameters that trade accuracy for cost: for volumes the
//! resolution and the supersampling, for clouds ε, N and the atlas size (which sets the
//! texel density). Everything else (`--combine`, `--normals`, `--compress`, lighting, LOD
//! count) keeps its own default or flag. An explicit flag always wins over the preset
//! ([`resolve_volume`], [`resolve_cloud`]); without a preset the defaults are the
//! commands' long-standing defaults ([`VolumeSettings::default`],
//! [`CloudSettings::default`]).

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use crate::voxelize::Resolution;

/// A named point of the accuracy/cost front.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// Previews and distant instances: the cheapest point that still beats the aliasing of
    /// the mesh drawn without anti-aliasing at a distance.
    Draft,
    /// Where the front bends: most of the accuracy for a small part of the cost.
    Balanced,
    /// The commands' defaults.
    Quality,
    /// The lowest error measured, whatever it costs.
    Hero,
}

impl Preset {
    /// Every preset, cheapest first: the order `--target-error` tries them in.
    pub const LADDER: [Preset; 4] = [
        Preset::Draft,
        Preset::Balanced,
        Preset::Quality,
        Preset::Hero,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Draft => "draft",
            Preset::Balanced => "balanced",
            Preset::Quality => "quality",
            Preset::Hero => "hero",
        }
    }

    /// The volume settings this preset names (`billow voxelize --preset`).
    pub fn volume(self) -> VolumeSettings {
        // On the oak's bake-time and bytes fronts at the default slice spacing, raw and BC7
        // alike: 4×4 supersampling beat every coarser sampling at the next resolution up
        // (docs/accuracy.md, "Pareto fronts and presets").
        let (res, supersample) = match self {
            Preset::Draft => (32, 4),
            Preset::Balanced => (64, 4),
            Preset::Quality => (128, 4),
            Preset::Hero => (256, 4),
        };
        VolumeSettings {
            resolution: Resolution::Longest(res),
            supersample,
        }
    }

    /// The billboard-cloud settings this preset names (`billow bbcloud --preset`).
    pub fn cloud(self) -> CloudSettings {
        // On the oak's bake-time, bytes and fragment fronts (hero: the lowest error
        // measured); quality is the defaults.
        let (epsilon, samples, atlas_size) = match self {
            Preset::Draft => (0.08, 100, 512),
            Preset::Balanced => (0.08, 500, 1024),
            Preset::Quality => (0.04, 500, 2048),
            Preset::Hero => (0.04, 500, 4096),
        };
        CloudSettings {
            epsilon,
            samples,
            atlas_size,
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A preset name that is not one of [`Preset::LADDER`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown preset '{0}': expected draft, balanced, quality or hero")]
pub struct PresetParseError(pub String);

impl FromStr for Preset {
    type Err = PresetParseError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Preset::LADDER
            .into_iter()
            .find(|p| p.name() == s.trim())
            .ok_or_else(|| PresetParseError(s.to_string()))
    }
}

/// The volume parameters a preset sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolumeSettings {
    pub resolution: Resolution,
    /// K×K coverage samples per voxel column.
    pub supersample: u32,
}

impl Default for VolumeSettings {
    /// `billow voxelize`'s defaults without a preset: 128 voxels along the longest axis,
    /// 4×4 supersampling.
    fn default() -> Self {
        VolumeSettings {
            resolution: Resolution::Longest(128),
            supersample: 4,
        }
    }
}

/// The billboard-cloud parameters a preset sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudSettings {
    /// Slab half-width ε in foliage bounding-sphere radii.
    pub epsilon: f32,
    /// Candidate planes per billboard (N).
    pub samples: u32,
    /// Largest atlas side in texels; the texel density is the most that fits.
    pub atlas_size: u32,
}

impl Default for CloudSettings {
    /// `billow bbcloud`'s defaults without a preset: ε 0.04, N 500, 2048² atlases.
    fn default() -> Self {
        CloudSettings {
            epsilon: 0.04,
            samples: 500,
            atlas_size: 2048,
        }
    }
}

/// Where each resolved value came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// The command's default (no preset, no flag).
    Default,
    /// The preset.
    Preset,
    /// An explicit flag.
    Flag,
    /// Chosen by the `--target-error` search ([`crate::target_error::search`]).
    Target,
}

fn pick<T: Copy>(flag: Option<T>, preset: Option<T>, default: T) -> (T, Source) {
    match (flag, preset) {
        (Some(v), _) => (v, Source::Flag),
        (None, Some(v)) => (v, Source::Preset),
        (None, None) => (default, Source::Default),
    }
}

/// Explicit volume flags; `None` = not given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VolumeFlags {
    pub resolution: Option<Resolution>,
    pub supersample: Option<u32>,
}

/// The volume settings a bake uses, and where each came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResolvedVolume {
    pub preset: Option<Preset>,
    pub settings: VolumeSettings,
    pub resolution_from: Source,
    pub supersample_from: Source,
}

/// Flags over the preset over the defaults.
pub fn resolve_volume(preset: Option<Preset>, flags: &VolumeFlags) -> ResolvedVolume {
    let p = preset.map(Preset::volume);
    let d = VolumeSettings::default();
    let (resolution, resolution_from) =
        pick(flags.resolution, p.map(|p| p.resolution), d.resolution);
    let (supersample, supersample_from) =
        pick(flags.supersample, p.map(|p| p.supersample), d.supersample);
    ResolvedVolume {
        preset,
        settings: VolumeSettings {
            resolution,
            supersample,
        },
        resolution_from,
        supersample_from,
    }
}

/// Explicit cloud flags; `None` = not given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CloudFlags {
    pub epsilon: Option<f32>,
    pub samples: Option<u32>,
    pub atlas_size: Option<u32>,
}

/// The cloud settings a bake uses, and where each came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedCloud {
    pub preset: Option<Preset>,
    pub settings: CloudSettings,
    pub epsilon_from: Source,
    pub samples_from: Source,
    pub atlas_size_from: Source,
}

/// Flags over the preset over the defaults.
pub fn resolve_cloud(preset: Option<Preset>, flags: &CloudFlags) -> ResolvedCloud {
    let p = preset.map(Preset::cloud);
    let d = CloudSettings::default();
    let (epsilon, epsilon_from) = pick(flags.epsilon, p.map(|p| p.epsilon), d.epsilon);
    let (samples, samples_from) = pick(flags.samples, p.map(|p| p.samples), d.samples);
    let (atlas_size, atlas_size_from) =
        pick(flags.atlas_size, p.map(|p| p.atlas_size), d.atlas_size);
    ResolvedCloud {
        preset,
        settings: CloudSettings {
            epsilon,
            samples,
            atlas_size,
        },
        epsilon_from,
        samples_from,
        atlas_size_from,
    }
}

/// The Pareto front of `(cost, error)` points, both to be minimised: the indices of the
/// points no other point beats in both (ties in both keep the first), ordered by cost. A
/// point with a NaN coordinate is never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan())
        .collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0)
            .then(pa.1.total_cmp(&pb.1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_keeps_the_points_nothing_beats_in_both() {
        let p = [
            (1.0, 5.0),
            (2.0, 3.0),
            (2.5, 4.0),
            (3.0, 3.0),
            (4.0, 1.0),
            (0.5, f64::NAN),
        ];
        assert_eq!(pareto_front(&p), [0, 1, 4]);
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(pareto_front(&[(1.0, 1.0), (1.0, 1.0)]), [0]);
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for p in Preset::LADDER {
            assert_eq!(p.name().parse::<Preset>(), Ok(p));
        }
        assert!("fast".parse::<Preset>().is_err());
    }

    #[test]
    fn the_ladder_is_ordered_by_cost() {
        let v: Vec<_> = Preset::LADDER.iter().map(|p| p.volume()).collect();
        let voxels = |s: &VolumeSettings| match s.resolution {
            Resolution::Longest(n) => n,
            Resolution::Exact(d) => d[0].max(d[1]).max(d[2]),
        };
        for w in v.windows(2) {
            assert!(voxels(&w[0]) <= voxels(&w[1]) && w[0].supersample <= w[1].supersample);
            assert_ne!(w[0], w[1]);
        }
        let c: Vec<_> = Preset::LADDER.iter().map(|p| p.cloud()).collect();
        for w in c.windows(2) {
            assert!(w[0].epsilon >= w[1].epsilon && w[0].atlas_size <= w[1].atlas_size);
            assert!(w[0].samples <= w[1].samples && w[0] != w[1]);
        }
    }

    #[test]
    fn flags_override_the_preset_which_overrides_the_defaults() {
        let r = resolve_volume(None, &VolumeFlags::default());
        assert_eq!(r.settings, VolumeSettings::default());
        assert_eq!(r.resolution_from, Source::Default);
        let r = resolve_volume(Some(Preset::Draft), &VolumeFlags::default());
        assert_eq!(r.settings, Preset::Draft.volume());
        assert_eq!(r.supersample_from, Source::Preset);
        let flags = VolumeFlags {
            resolution: Some(Resolution::Longest(96)),
            supersample: None,
        };
        let r = resolve_volume(Some(Preset::Hero), &flags);
        assert_eq!(r.settings.resolution, Resolution::Longest(96));
        assert_eq!(r.resolution_from, Source::Flag);
        assert_eq!(r.settings.supersample, Preset::Hero.volume().supersample);
        let c = resolve_cloud(
            Some(Preset::Draft),
            &CloudFlags {
                samples: Some(7),
                ..CloudFlags::default()
            },
        );
        assert_eq!(c.settings.samples, 7);
        assert_eq!(c.settings.epsilon, Preset::Draft.cloud().epsilon);
        assert_eq!(
            (c.samples_from, c.epsilon_from),
            (Source::Flag, Source::Preset)
        );
        assert_eq!(
            resolve_cloud(None, &CloudFlags::default()).settings,
            CloudSettings::default()
        );
    }
}
