//! Scene files (RON, docs/viewer.md): camera, light, volume assets with instances,
//! meshes, an optional ground plane, `shadows`. Unknown fields are errors; every
//! problem is reported as `FILE: field: problem` ([`ViewError::Scene`]). Paths are
//! relative to the scene file.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use serde::Deserialize;

use crate::limits::{
    check_background, check_dissolve, check_fov, is_colour, COLOUR, DISSOLVE_OCTAVES, FOV_DEG,
};
use crate::ViewError;

#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Absent: framed on the content like the eval's views.
    #[serde(default)]
    pub camera: Option<CameraDesc>,
    #[serde(default)]
    pub light: LightDesc,
    #[serde(default)]
    pub volumes: Vec<VolumeDesc>,
    #[serde(default)]
    pub clouds: Vec<CloudDesc>,
    #[serde(default)]
    pub meshes: Vec<MeshDesc>,
    #[serde(default)]
    pub ground: Option<GroundDesc>,
    /// Opaque background colour (linear RGB) behind everything; absent: transparent in
    /// screenshots, a sky blue in the window.
    #[serde(default)]
    pub background: Option<[f32; 3]>,
    /// Directional shadow map: meshes, clouds and volumes cast; meshes, clouds and
    /// volume slices receive.
    #[serde(default)]
    pub shadows: bool,
    /// Particle systems (spherical billboards; `crate::particles`).
    #[serde(default)]
    pub particles: Vec<crate::particles::ParticleSystemDesc>,
    /// How the particle layer is made (resolution fraction, shimmer, motion blur).
    #[serde(default)]
    pub particle_layer: crate::particle_pass::ParticleLayerDesc,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "up_y")]
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "fov45")]
    pub fov_deg: f32,
    /// Clip distances; absent: from the content's bounding sphere.
    #[serde(default)]
    pub near: Option<f32>,
    #[serde(default)]
    pub far: Option<f32>,
}

fn up_y() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn fov45() -> f32 {
    45.0
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Direction *towards* the light.
    pub direction: [f32; 3],
    #[serde(default = "ambient03")]
    pub ambient: f32,
}

fn ambient03() -> f32 {
    0.3
}

impl Default for LightDesc {
    fn default() -> Self {
        LightDesc {
            direction: billow_core::shading::DEFAULT_LIGHT.to_array(),
            ambient: billow_core::shading::DEFAULT_AMBIENT,
        }
    }
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VolumeDesc {
    /// A `.billow` volume asset.
    pub asset: PathBuf,
    /// Default: one instance at the origin.
    #[serde(default = "one_instance")]
    pub instances: Vec<Transform>,
    /// Cells deformed over time (wind sway by height, `crate::animate`).
    #[serde(default)]
    pub animation: Option<crate::animate::Sway>,
}

fn one_instance() -> Vec<Transform> {
    vec![Transform::default()]
}

/// A billboard-cloud asset (`billow bbcloud`) with its instances and LOD distances.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CloudDesc {
    /// A `.billow` cloud asset.
    pub asset: PathBuf,
    #[serde(default = "one_instance")]
    pub instances: Vec<Transform>,
    /// Distances (from the eye to an instance's centre) where the level changes: the
    /// foliage mesh → billboard level 0 → level 1 …, one per change, increasing.
    /// Absent: `2·Z₀, 4·Z₀, …` with `Z₀` the distance at which the cloud fills the view.
    #[serde(default)]
    pub lod_distances: Option<Vec<f32>>,
    /// Fraction of each distance over which vertices morph toward the parent level
    /// (0 = switch abruptly).
    #[serde(default = "quarter")]
    pub transition: f32,
    /// Half-width, in octaves of distance, of the dithered dissolve around each switch
    /// (0 = switch in one frame; `cloud_pass` module docs).
    #[serde(default = "default_dissolve")]
    pub dissolve: f32,
}

fn quarter() -> f32 {
    0.25
}

fn default_dissolve() -> f32 {
    crate::cloud_pass::DEFAULT_DISSOLVE
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// glTF / GLB / OBJ, imported with billow's importer.
    pub path: PathBuf,
    #[serde(default)]
    pub transform: Transform,
}

/// `translate · rotate_y · scale` (uniform scale > 0).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    #[serde(default)]
    pub translate: [f32; 3],
    /// Rotation about +Y, degrees.
    #[serde(default)]
    pub rotate_y_deg: f32,
    #[serde(default = "one")]
    pub scale: f32,
}

fn one() -> f32 {
    1.0
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translate: [0.0; 3],
            rotate_y_deg: 0.0,
            scale: 1.0,
        }
    }
}

impl Transform {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            Quat::from_rotation_y(self.rotate_y_deg.to_radians()),
            Vec3::from(self.translate),
        )
    }
}

/// A square ground plane `y = height`, centred on `centre` (x, z), side `size`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GroundDesc {
    pub size: f32,
    #[serde(default)]
    pub height: f32,
    #[serde(default)]
    pub centre: [f32; 2],
    /// Linear RGB.
    #[serde(default = "grey")]
    pub color: [f32; 3],
}

fn grey() -> [f32; 3] {
    [0.35, 0.35, 0.3]
}

impl SceneFile {
    /// Reads, parses and validates `path`; asset and mesh paths are made relative to
    /// the scene file's folder and must exist.
    pub fn load(path: &Path) -> Result<SceneFile, ViewError> {
        let file = path.display().to_string();
        let err = |problem: String| ViewError::Scene {
            file: file.clone(),
            problem,
        };
        let missing = |problem: String| ViewError::SceneInput {
            file: file.clone(),
            problem,
        };
        let text =
            std::fs::read_to_string(path).map_err(|e| missing(format!("cannot read: {e}")))?;
        let mut scene = Self::parse(&text).map_err(&err)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for (i, v) in scene.volumes.iter_mut().enumerate() {
            v.asset = dir.join(&v.asset);
            if !v.asset.is_file() {
                return Err(missing(format!(
                    "volumes[{i}].asset: {} does not exist",
                    v.asset.display()
                )));
            }
        }
        for (i, c) in scene.clouds.iter_mut().enumerate() {
            c.asset = dir.join(&c.asset);
            if !c.asset.is_file() {
                return Err(missing(format!(
                    "clouds[{i}].asset: {} does not exist",
                    c.asset.display()
                )));
            }
        }
        for (i, m) in scene.meshes.iter_mut().enumerate() {
            m.path = dir.join(&m.path);
            if !m.path.is_file() {
                return Err(missing(format!(
                    "meshes[{i}].path: {} does not exist",
                    m.path.display()
                )));
            }
        }
        Ok(scene)
    }

    /// Parses and validates RON text; the error gives the line:column and the path of the
    /// field it is about (`volumes[0].asset`), for syntax errors, unknown and missing fields.
    pub fn parse(text: &str) -> Result<SceneFile, String> {
        // "line:col: [path: ]message"; `?` in a path stands for a segment the error came
        // before (a syntax error) and is left out.
        let located = |e: ron::error::SpannedError, path: &str| {
            let path = path.trim_end_matches(".?").trim_end_matches('?');
            let (line, col) = (e.span.start.line, e.span.start.col);
            match path {
                "" | "." => format!("{line}:{col}: {}", e.code),
                p => format!("{line}:{col}: {p}: {}", e.code),
            }
        };
        let mut de = ron::Deserializer::from_str_with_options(text, &ron::Options::default())
            .map_err(|e| located(e, ""))?;
        let scene: SceneFile = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let path = e.path().to_string();
            located(de.span_error(e.into_inner()), &path)
        })?;
        de.end().map_err(|e| located(de.span_error(e), ""))?;
        scene.validate()?;
        Ok(scene)
    }

    fn validate(&self) -> Result<(), String> {
        let finite3 = |v: &[f32; 3]| v.iter().all(|c| c.is_finite());
        if let Some(c) = &self.camera {
            if !finite3(&c.eye) || !finite3(&c.target) || !finite3(&c.up) {
                return Err("camera: eye, target and up must be finite".into());
            }
            if Vec3::from(c.eye) == Vec3::from(c.target) {
                return Err("camera.target: must differ from camera.eye".into());
            }
            if check_fov(c.fov_deg).is_err() {
                return Err(format!(
                    "camera.fov_deg: {} must be in ({}, {})",
                    c.fov_deg, FOV_DEG.0, FOV_DEG.1
                ));
            }
            if let Some(n) = c.near {
                if !(n > 0.0 && n.is_finite()) {
                    return Err(format!("camera.near: {n} must be > 0"));
                }
            }
            if let Some(f) = c.far {
                if !(f > c.near.unwrap_or(0.0) && f.is_finite()) {
                    return Err(format!("camera.far: {f} must be > near"));
                }
            }
        }
        if !finite3(&self.light.direction) || Vec3::from(self.light.direction).length() == 0.0 {
            return Err("light.direction: must be a finite non-zero vector".into());
        }
        if !(0.0..=1.0).contains(&self.light.ambient) {
            return Err(format!(
                "light.ambient: {} must be in [0, 1]",
                self.light.ambient
            ));
        }
        let check_t = |t: &Transform, at: String| -> Result<(), String> {
            if !(t.scale > 0.0 && t.scale.is_finite()) {
                return Err(format!("{at}.scale: {} must be > 0", t.scale));
            }
            if !finite3(&t.translate) || !t.rotate_y_deg.is_finite() {
                return Err(format!("{at}: translate and rotate_y_deg must be finite"));
            }
            Ok(())
        };
        for (i, v) in self.volumes.iter().enumerate() {
            if v.instances.is_empty() {
                return Err(format!(
                    "volumes[{i}].instances: at least one instance is needed"
                ));
            }
            for (k, t) in v.instances.iter().enumerate() {
                check_t(t, format!("volumes[{i}].instances[{k}]"))?;
            }
            if let Some(a) = &v.animation {
                a.validate()
                    .map_err(|e| format!("volumes[{i}].animation.{e}"))?;
            }
        }
        for (i, p) in self.particles.iter().enumerate() {
            p.validate().map_err(|e| format!("particles[{i}].{e}"))?;
        }
        self.particle_layer
            .validate()
            .map_err(|e| format!("particle_layer.{e}"))?;
        for (i, c) in self.clouds.iter().enumerate() {
            if c.instances.is_empty() {
                return Err(format!(
                    "clouds[{i}].instances: at least one instance is needed"
                ));
            }
            for (k, t) in c.instances.iter().enumerate() {
                check_t(t, format!("clouds[{i}].instances[{k}]"))?;
            }
            if let Some(d) = &c.lod_distances {
                if !d.iter().all(|x| *x > 0.0 && x.is_finite())
                    || !d.windows(2).all(|w| w[0] < w[1])
                {
                    return Err(format!(
                        "clouds[{i}].lod_distances: {d:?} must be positive and increasing"
                    ));
                }
            }
            if check_dissolve(c.dissolve).is_err() {
                return Err(format!(
                    "clouds[{i}].dissolve: {} must be in [{}, {}] octaves",
                    c.dissolve,
                    DISSOLVE_OCTAVES.start(),
                    DISSOLVE_OCTAVES.end()
                ));
            }
            if !(0.0..=1.0).contains(&c.transition) {
                return Err(format!(
                    "clouds[{i}].transition: {} must be in [0, 1]",
                    c.transition
                ));
            }
        }
        for (i, m) in self.meshes.iter().enumerate() {
            check_t(&m.transform, format!("meshes[{i}].transform"))?;
        }
        if let Some(b) = &self.background {
            check_background(*b).map_err(|e| format!("background: {e}"))?;
        }
        if let Some(g) = &self.ground {
            if !(g.size > 0.0 && g.size.is_finite()) {
                return Err(format!("ground.size: {} must be > 0", g.size));
            }
            if !g.height.is_finite() || !g.centre.iter().all(|c| c.is_finite()) {
                return Err("ground: height and centre must be finite".into());
            }
            if !is_colour(g.color) {
                return Err(format!(
                    "ground.color: components must be in [{}, {}]",
                    COLOUR.start(),
                    COLOUR.end()
                ));
            }
        }
        Ok(())
    }
}
