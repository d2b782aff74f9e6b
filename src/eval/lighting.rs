//! The lighting of the reference renderer, chosen to match the lighting an asset was baked
//! with, so that like is compared with like.
//!
//! - [`Lighting::Unlit`] (the default): base colour × texture × vertex colour.
//! - [`Lighting::Ao`]: the voxelizer's baked ambient occlusion (`--bake ao`,
//!   `src/voxelize/ao.rs`) evaluated **at the hit point** instead of at the voxel centre:
//!   the same estimator (`AoRays::ambient_occlusion`: same ray count, full-sphere
//!   stratified directions, `t_min` = half the asset's voxel diagonal, the asset's AO
//!   distance and seed), with the random stream of the asset voxel that contains the hit
//!   point ([`voxel_stream`]), so the reference and the bake draw the same directions and
//!   differ only in where the rays start. The colour is multiplied by AO; alpha unchanged.
//! - [`Lighting::Diffuse`]: the billboard-cloud bake's ambient + diffuse term
//!   (`src/bbcloud/bake.rs`), `albedo · (ambient + (1 − ambient) · |N·L|)` with the
//!   interpolated shading normal: the viewer's mesh-pass model (two-sided Lambert, leaf
//!   cards lit from either side; `viewer/src/shaders/mesh.wgsl`), so a mesh drawn by the
//!   viewer and its billboards baked with the same light look alike.
//!
//! - [`Lighting::Volume`]: the runtime shading of a volume that carries normals
//!   ([`billow_core::shading::volume_diffuse_factor`]): `albedo · (ambient + (1 − ambient) · max(n·L, 0))`, the
//!   **one-sided** Lambert of the interpolated shading normal, turned towards the viewer on
//!   the back face of a double-sided triangle (as the voxelizer captures it,
//!   `src/voxelize/fragments.rs`). The CPU slicer ([`super::slicer`]) and the viewer's
//!   volume pass (`viewer/src/shaders/volume.wgsl`) shade with the voxel's
//!   Toksvig-filtered normal instead; see [`billow_core::shading::volume_diffuse_factor`].
//!
//! [`Lighting::for_volume`] and [`Lighting::for_cloud`] read the choice from an asset's
//! header parameters (`bake`, `ao_rays`, `ao_distance`, `ao_seed`; `light`, `ambient`) and,
//! for volumes, whether it stores normals.
//!
//! One light for everything without a scene file: [`DEFAULT_LIGHT`] and
//! [`DEFAULT_AMBIENT`], the viewer's defaults (`viewer/src/render.rs`, checked by
//! `viewer/tests/volume_shading.rs`).

use std::collections::BTreeMap;

use billow_format::{NormalKind, VolumeBake};
use glam::Vec3;

use crate::voxelize::{
    AoRays, GridSpec, AO_SEED, DEFAULT_AO_RAYS, DEFAULT_DISTANCE_FRACTION, MAX_AO_RAYS,
};

pub use crate::voxelize::voxel_stream;

use billow_core::shading::{DEFAULT_AMBIENT, DEFAULT_LIGHT};

/// The scene light a volume is shaded with: unit direction towards the light, ambient.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeLight {
    pub dir: Vec3,
    pub ambient: f32,
}

impl Default for VolumeLight {
    /// [`DEFAULT_LIGHT`] (normalised), [`DEFAULT_AMBIENT`].
    fn default() -> Self {
        VolumeLight {
            dir: DEFAULT_LIGHT.normalize(),
            ambient: DEFAULT_AMBIENT,
        }
    }
}

/// How the reference shades a hit (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Lighting {
    #[default]
    Unlit,
    /// Baked AO of a volume on `grid` (its level-0 voxel grid); `shaded`: the volume also
    /// stores normals, so the AO-darkened albedo is shaded at runtime too
    /// ([`Lighting::Volume`]'s factor, multiplied).
    Ao {
        rays: AoRays,
        grid: GridSpec,
        shaded: Option<VolumeLight>,
        /// With `shaded`: the volume stores normal moments (SPEC §8.4a), lit two-sided like
        /// the mesh ([`Lighting::Diffuse`]'s factor) instead of [`Lighting::Volume`]'s.
        two_sided: bool,
    },
    /// Ambient + diffuse with `light` the unit direction towards the light.
    Diffuse { light: Vec3, ambient: f32 },
    /// Ambient + one-sided diffuse: a volume with normals, shaded at runtime.
    Volume { light: Vec3, ambient: f32 },
    /// The mesh as `billow view` draws it under a scene light, whatever the asset: base
    /// colour × (ambient + (1 − ambient) · visibility · |n·L|), the two-sided Lambert of the
    /// interpolated shading normal (`viewer/src/shaders/mesh.wgsl`); materials marked
    /// unlit (`KHR_materials_unlit`) are not shaded. `shadows`: visibility is the
    /// transmittance of a ray from the hit towards the light (opaque and alpha-tested
    /// surfaces block it, blended ones let `1 − α` through); without, 1.
    Scene {
        light: Vec3,
        ambient: f32,
        shadows: bool,
    },
}

/// One light of an evaluation: a name for tables, the unit direction towards the light,
/// the ambient fraction.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalLight {
    pub name: String,
    pub dir: Vec3,
    pub ambient: f32,
}

impl EvalLight {
    /// A light towards `dir` (normalised; `None` when it is not a direction).
    pub fn new(name: impl Into<String>, dir: Vec3, ambient: f32) -> Option<Self> {
        let dir = dir.try_normalize()?;
        (dir.is_finite() && (0.0..=1.0).contains(&ambient)).then(|| EvalLight {
            name: name.into(),
            dir,
            ambient,
        })
    }
}

/// The named light sets of `billow eval --lights` (docs/eval.md, "Lights").
pub const LIGHT_SETS: &[&str] = &["standard"];

/// The light set `name` with `ambient` ([`LIGHT_SETS`]): `standard` is the sun overhead,
/// a low sun from two sides (east and west, 20° above the horizon, a little off the view
/// axes) and a light from below. Two-sided foliage is lit alike by `L` and `−L`, so the
/// two low suns differ otherwise (the second is not the first's opposite), and overhead
/// and below tell one-sided surfaces (solids) apart from two-sided ones (leaves).
pub fn light_set(name: &str, ambient: f32) -> Option<Vec<EvalLight>> {
    let lights: &[(&str, Vec3)] = match name {
        "standard" => &[
            ("overhead", Vec3::new(0.0, 1.0, 0.0)),
            ("sun-east", Vec3::new(0.94, 0.34, 0.1)),
            ("sun-west", Vec3::new(-0.94, 0.34, 0.25)),
            ("below", Vec3::new(0.0, -1.0, 0.0)),
        ],
        _ => return None,
    };
    lights
        .iter()
        .map(|(n, d)| EvalLight::new(*n, *d, ambient))
        .collect()
}

/// Why a light set's text names no lights ([`parse_light_set`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LightSetError {
    /// Not a set name, and not a list `NAME=X,Y,Z;X,Y,Z;…` (a usage error).
    #[error("{0}")]
    Syntax(String),
    /// A listed vector that is not a direction (zero, not finite).
    #[error("{0}")]
    NotADirection(String),
}

/// A light set as `billow eval --lights` and `--target-lights` write it: a named set of
/// [`LIGHT_SETS`] ([`light_set`]) or a list `NAME=X,Y,Z;X,Y,Z;…` (unnamed lights are
/// `light1`, `light2`, …), every light with `ambient`.
pub fn parse_light_set(text: &str, ambient: f32) -> Result<Vec<EvalLight>, LightSetError> {
    if let Some(lights) = light_set(text.trim(), ambient) {
        return Ok(lights);
    }
    if !text.contains(',') {
        return Err(LightSetError::Syntax(format!(
            "'{text}': expected {} or NAME=X,Y,Z;…",
            LIGHT_SETS.join(", ")
        )));
    }
    let mut out = Vec::new();
    for (i, item) in text.split(';').filter(|i| !i.trim().is_empty()).enumerate() {
        let (name, v) = match item.split_once('=') {
            Some((n, v)) => (n.trim().to_string(), v),
            None => (format!("light{}", i + 1), item),
        };
        let c: Vec<f32> = v
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| LightSetError::Syntax(format!("'{v}': {e} (expected X,Y,Z)")))?;
        let [x, y, z] = c[..] else {
            return Err(LightSetError::Syntax(format!("'{v}': expected X,Y,Z")));
        };
        let dir = Vec3::new(x, y, z);
        out.push(EvalLight::new(name, dir, ambient).ok_or_else(|| {
            LightSetError::NotADirection(format!("({x}, {y}, {z}) is not a direction"))
        })?);
    }
    if out.is_empty() {
        return Err(LightSetError::Syntax(format!("'{text}': no lights")));
    }
    Ok(out)
}

fn num<T: std::str::FromStr>(
    params: &BTreeMap<String, String>,
    key: &str,
) -> Result<Option<T>, String>
where
    T::Err: std::fmt::Display,
{
    params
        .get(key)
        .map(|v| {
            v.trim()
                .parse::<T>()
                .map_err(|e| format!("header parameter {key}='{v}': {e}"))
        })
        .transpose()
}

impl Lighting {
    /// `unlit`, `ao` or `diffuse`.
    pub fn name(&self) -> &'static str {
        match self {
            Lighting::Unlit => "unlit",
            Lighting::Ao { .. } => "ao",
            Lighting::Diffuse { .. } => "diffuse",
            Lighting::Volume { .. } => "volume",
            Lighting::Scene { .. } => "scene",
        }
    }

    /// A one-line description with the parameters.
    pub fn describe(&self) -> String {
        match self {
            Lighting::Unlit => "unlit".into(),
            Lighting::Ao { rays, shaded, .. } => format!(
                "ambient occlusion at the hit point ({} rays, distance {}, seed {}){}",
                rays.rays,
                rays.t_max,
                rays.seed,
                shaded.map_or(String::new(), |l| format!(
                    " × ambient {} + one-sided diffuse, light towards ({}, {}, {})",
                    l.ambient, l.dir.x, l.dir.y, l.dir.z
                ))
            ),
            Lighting::Diffuse { light, ambient } => format!(
                "ambient {ambient} + diffuse, light towards ({}, {}, {})",
                light.x, light.y, light.z
            ),
            Lighting::Volume { light, ambient } => format!(
                "ambient {ambient} + one-sided diffuse (the volume's runtime shading), light \
                 towards ({}, {}, {})",
                light.x, light.y, light.z
            ),
            Lighting::Scene {
                light,
                ambient,
                shadows,
            } => format!(
                "the viewer's mesh lighting: ambient {ambient} + two-sided diffuse, light \
                 towards ({:.3}, {:.3}, {:.3}){}",
                light.x,
                light.y,
                light.z,
                if *shadows { ", ray-traced shadows" } else { "" }
            ),
        }
    }

    /// The reference lighting of a volume asset: its header `params`, its bounds (the voxel
    /// grid's box), level-0 `dims` and whether it stores normals (then its colour is albedo
    /// shaded at runtime: [`Lighting::Volume`] with the default light, or on top of baked
    /// AO). Returns a note when the asset's `bake` is not one the reference reproduces (the
    /// reference then stays unlit).
    pub fn for_volume(
        params: &BTreeMap<String, String>,
        min: Vec3,
        max: Vec3,
        dims: [u32; 3],
        normals: Option<NormalKind>,
    ) -> Result<(Lighting, Option<String>), String> {
        match billow_format::VolumeBake::read(params) {
            VolumeBake::None if normals.is_some() => {
                let l = VolumeLight::default();
                let (light, ambient) = (l.dir, l.ambient);
                Ok((
                    if normals == Some(NormalKind::Moments) {
                        // Moments light two-sided: the mesh's own model.
                        Lighting::Diffuse { light, ambient }
                    } else {
                        Lighting::Volume { light, ambient }
                    },
                    None,
                ))
            }
            VolumeBake::None => Ok((Lighting::Unlit, None)),
            VolumeBake::Ao => {
                if dims.contains(&0)
                    || !(min.is_finite() && max.is_finite())
                    || !(max.cmpgt(min).all())
                {
                    return Err("AO asset with an empty voxel grid".into());
                }
                let d = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
                let grid = GridSpec {
                    dims,
                    min,
                    voxel: (max - min) / d,
                };
                let rays: u32 = num(params, "ao_rays")?.unwrap_or(DEFAULT_AO_RAYS);
                if !(1..=MAX_AO_RAYS).contains(&rays) {
                    return Err(format!(
                        "header parameter ao_rays={rays} is out of range (1 to {MAX_AO_RAYS})"
                    ));
                }
                let distance: f32 = num(params, "ao_distance")?
                    .unwrap_or(DEFAULT_DISTANCE_FRACTION * (max - min).length());
                if !(distance.is_finite() && distance > 0.0) {
                    return Err(format!(
                        "header parameter ao_distance={distance} must be > 0"
                    ));
                }
                let mut ao = AoRays::for_grid(&grid, rays, distance);
                ao.seed = num(params, "ao_seed")?.unwrap_or(AO_SEED);
                Ok((
                    Lighting::Ao {
                        rays: ao,
                        grid,
                        shaded: normals.map(|_| VolumeLight::default()),
                        two_sided: normals == Some(NormalKind::Moments),
                    },
                    None,
                ))
            }
            VolumeBake::Other(other) => Ok((
                Lighting::Unlit,
                Some(format!(
                    "the asset has baked lighting (bake={other}) that the reference does not \
                     reproduce: the reference is unlit and the errors include the lighting \
                     difference"
                )),
            )),
        }
    }

    /// The reference lighting of a billboard-cloud asset: its baked light
    /// ([`billow_format::BakedLight`], header `light` = `x,y,z` with `ambient`, or `unlit`);
    /// unlit for an unlit bake and for one whose light was not recorded (SPEC §9: the
    /// reference cannot reproduce a light nobody recorded).
    pub fn for_cloud(params: &BTreeMap<String, String>) -> Result<Lighting, String> {
        Ok(match billow_format::BakedLight::read(params)? {
            billow_format::BakedLight::Directional { dir, ambient } => Lighting::Diffuse {
                light: Vec3::from(dir),
                ambient,
            },
            billow_format::BakedLight::Unlit | billow_format::BakedLight::Unknown => {
                Lighting::Unlit
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use billow_core::shading::{diffuse_factor, volume_diffuse_factor};

    #[test]
    fn volume_params() {
        let mut p = BTreeMap::new();
        let (min, max) = (Vec3::ZERO, Vec3::new(2.0, 4.0, 8.0));
        assert_eq!(
            Lighting::for_volume(&p, min, max, [2, 4, 8], None)
                .unwrap()
                .0,
            Lighting::Unlit
        );
        p.insert("bake".into(), "ao".into());
        p.insert("ao_rays".into(), "7".into());
        p.insert("ao_distance".into(), "1.5".into());
        let (l, note) = Lighting::for_volume(&p, min, max, [2, 4, 8], None).unwrap();
        assert!(note.is_none());
        let Lighting::Ao {
            rays, grid, shaded, ..
        } = l
        else {
            panic!("{l:?}")
        };
        assert_eq!((rays.rays, rays.t_max, rays.seed), (7, 1.5, AO_SEED));
        assert_eq!(grid.voxel, Vec3::ONE);
        assert_eq!(shaded, None);
        assert!((rays.t_min - 0.5 * 3f32.sqrt()).abs() < 1e-6);
        let (l, note) =
            Lighting::for_volume(&p, min, max, [2, 4, 8], Some(NormalKind::Mean)).unwrap();
        assert!(
            matches!(
                l,
                Lighting::Ao {
                    shaded: Some(_),
                    ..
                }
            ) && note.is_none()
        );
        p.insert("ao_rays".into(), "many".into());
        assert!(Lighting::for_volume(&p, min, max, [2, 4, 8], None).is_err());
        p.insert("bake".into(), "gi".into());
        let (l, note) = Lighting::for_volume(&p, min, max, [2, 4, 8], None).unwrap();
        assert_eq!(l, Lighting::Unlit);
        assert!(note.unwrap().contains("bake=gi"));
    }

    #[test]
    fn volumes_with_normals_are_lit_one_sided() {
        let p = BTreeMap::new();
        let (l, note) =
            Lighting::for_volume(&p, Vec3::ZERO, Vec3::ONE, [2, 2, 2], Some(NormalKind::Mean))
                .unwrap();
        assert!(note.is_none());
        assert_eq!(
            l,
            Lighting::Volume {
                light: DEFAULT_LIGHT.normalize(),
                ambient: DEFAULT_AMBIENT
            }
        );
        // One-sided, shortened normals attenuate, shadows scale the diffuse term only.
        assert_eq!(volume_diffuse_factor(Vec3::Y, Vec3::Y, 0.25, 1.0), 1.0);
        assert_eq!(volume_diffuse_factor(-Vec3::Y, Vec3::Y, 0.25, 1.0), 0.25);
        assert_eq!(volume_diffuse_factor(Vec3::Y * 0.5, Vec3::Y, 0.2, 1.0), 0.6);
        assert_eq!(volume_diffuse_factor(Vec3::ZERO, Vec3::Y, 0.2, 1.0), 0.2);
        assert_eq!(volume_diffuse_factor(Vec3::Y, Vec3::Y, 0.2, 0.5), 0.6);
    }

    #[test]
    fn cloud_params() {
        let mut p = BTreeMap::new();
        assert_eq!(Lighting::for_cloud(&p).unwrap(), Lighting::Unlit);
        p.insert("light".into(), "0,2,0".into());
        p.insert("ambient".into(), "0.25".into());
        let l = Lighting::for_cloud(&p).unwrap();
        assert_eq!(
            l,
            Lighting::Diffuse {
                light: Vec3::Y,
                ambient: 0.25
            }
        );
        assert_eq!(diffuse_factor(Vec3::Y, Vec3::Y, 0.25), 1.0);
        assert_eq!(diffuse_factor(-Vec3::Y, Vec3::Y, 0.25), 1.0);
        assert_eq!(diffuse_factor(Vec3::X, Vec3::Y, 0.25), 0.25);
        p.insert("light".into(), "0,0".into());
        assert!(Lighting::for_cloud(&p).is_err());
    }
}
