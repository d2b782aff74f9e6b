//! `billow eval` as one call: [`evaluate()`] renders a source mesh's reference and a volume
//! or billboard-cloud [`Asset`] from every view (under every light of a set, for every LOD
//! level of a cloud), compares them and returns the typed [`Evaluation`] — per-view
//! results, means, means by distance and by light, the asset's GPU bytes and the notes
//! that qualify the numbers. The choices that decide the numbers are the
//! [`EvaluateOptions`]; the reference's lighting follows the asset's own unless told
//! otherwise ([`ReferenceLighting`]). Nothing here prints or writes files: progress and the
//! images go to [`EvaluateHooks`] (docs/eval.md, "From Rust").
//!
//! ```no_run
//! use std::path::Path;
//!
//! use billow_core::camera::{view_set, ViewDirections};
//! use billow::eval::evaluate::{evaluate, Asset, EvaluateHooks, EvaluateOptions};
//! use billow::import::{import, ImportOptions};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = import(Path::new("tree.gltf"), &ImportOptions::default())?.scene;
//! let asset = Asset::from_container(billow_format::read_file(Path::new("tree.billow"))?)?;
//! // `billow eval tree.gltf tree.billow --size 64x64 --views axes`: 1×, 4×, 16×.
//! let options = EvaluateOptions {
//!     width: 64,
//!     height: 64,
//!     views: view_set(ViewDirections::Axes),
//!     ..EvaluateOptions::default()
//! };
//! let e = evaluate(&scene, &asset, &options, &mut EvaluateHooks::default())?;
//! println!("mean RMSE {:.4}, notes {:?}", e.levels[0].mean.rmse, e.notes);
//! # Ok(())
//! # }
//! ```

use super::limits::{
    distance_factor_ok, image_side_ok, spacing_factor_ok, MAX_DISTANCE_FACTOR, MAX_IMAGE_SIDE,
    SPACING_FACTOR,
};
use std::ops::ControlFlow;
use std::time::Instant;

use billow_core::gpu_memory::{cloud_gpu_bytes, volume_gpu_bytes, GpuBytes};
use billow_format::{AssetKind, BakedLight, CloudAsset, CloudError, Container, VolumeAsset};

use super::cloud_render::{CloudRenderer, PreparedCloud};
use super::lighting::{EvalLight, Lighting};
use super::metrics::ImageError;
use super::slicer::SlicerParams;
use super::suite::{
    mean_errors, means_by_distance, means_by_light, reference_lighting, DistanceMeans, EvalOptions,
    Evaluator, LightMeans, MeanErrors, PreparedAsset, ReferenceView, ViewResult, EVAL_FOV_Y,
};
use super::volume_shadow::shadowable;
use super::{EvalError, ImageF32};
use crate::scene::Scene;
use billow_core::camera::ViewSpec;
use billow_core::slicing::Spacing;

/// What [`evaluate()`] compares with the mesh: a volume or a billboard cloud.
// One value per evaluation, never in a collection: boxing the cloud would only make callers
// write `Box::new`.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Asset {
    Volume(VolumeAsset),
    Cloud(CloudAsset),
}

impl Asset {
    /// The asset of a file's container: a cloud when its header says so, a volume otherwise
    /// (a container of another kind is the volume reader's error).
    pub fn from_container(c: Container) -> Result<Asset, CloudError> {
        Ok(match c.header.kind {
            AssetKind::Cloud => Asset::Cloud(CloudAsset::from_container(c)?),
            _ => Asset::Volume(VolumeAsset::from_container(c)?),
        })
    }
}

/// The lighting the reference (and, where it can follow, the asset) is rendered under.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum ReferenceLighting {
    /// The lighting the asset was baked with (`billow eval --lighting auto`): a volume's
    /// baked AO and runtime shading ([`reference_lighting`]), a cloud's baked light
    /// ([`Lighting::for_cloud`]); a note when it cannot be reproduced.
    #[default]
    Own,
    /// Unlit (`--lighting unlit`); a note when the asset has baked lighting.
    Unlit,
    /// Each light of the set in turn, as `billow view` lights each kind (`--light`,
    /// `--lights`, `--ambient`, `--shadows`; [`Evaluator::set_light`]); the means are over
    /// the set. Every light has the same ambient; `shadows`: the reference (and a cloud's
    /// kept mesh) is ray-traced with shadows, a plain volume is shadowed by its own
    /// transmittance towards the light ([`super::volume_shadow`]), pruned and shell
    /// volumes are drawn unshadowed (noted).
    Lights {
        lights: Vec<EvalLight>,
        shadows: bool,
    },
}

/// Everything that decides [`evaluate()`]'s numbers (`billow eval`'s flags).
#[derive(Clone, Debug, PartialEq)]
pub struct EvaluateOptions {
    /// Image size in pixels (`--size`).
    pub width: u32,
    pub height: u32,
    /// Vertical field of view, radians ([`EVAL_FOV_Y`]).
    pub fov_y: f32,
    /// Reference samples per pixel per axis, 1–16 (`--spp` = its square).
    pub reference_per_axis: u32,
    /// The volume slicer's spacing (`--spacing`): [`Spacing::Uniform`] here counts
    /// **level-0 voxels** of the asset (world units when it has no voxel size). Unused for
    /// clouds.
    pub spacing: Spacing,
    /// The views, in order (`--views`, `--distances`; [`billow_core::camera::views_of`]).
    pub views: Vec<ViewSpec>,
    pub lighting: ReferenceLighting,
    /// Billboard clouds: only this LOD level (`--lod`); `None`: every level. A volume
    /// refuses `Some`.
    pub lod: Option<usize>,
}

impl Default for EvaluateOptions {
    /// `billow eval`'s defaults but no views: 128 × 128, 45°, 16 spp, adaptive spacing,
    /// the asset's own lighting, every LOD level.
    fn default() -> Self {
        EvaluateOptions {
            width: 128,
            height: 128,
            fov_y: EVAL_FOV_Y,
            reference_per_axis: 4,
            spacing: Spacing::Adaptive { bias: 1.0 },
            views: Vec::new(),
            lighting: ReferenceLighting::Own,
            lod: None,
        }
    }
}

/// Most reference samples ([`EvaluateOptions::reference_samples`]) `billow eval` traces:
/// 10¹⁰, about 80 minutes at [`REFERENCE_SAMPLES_PER_SECOND`] (it refuses more before any
/// work; [`evaluate()`] itself does not).
pub const MAX_REFERENCE_SAMPLES: f64 = 1e10;
/// Reference samples per second assumed for time estimates (measured: the oak, release
/// build, a few cores).
pub const REFERENCE_SAMPLES_PER_SECOND: f64 = 2e6;

impl EvaluateOptions {
    /// The reference renders: views × lights (one light without a set).
    pub fn references(&self) -> usize {
        let lights = match &self.lighting {
            ReferenceLighting::Lights { lights, .. } => lights.len(),
            _ => 1,
        };
        self.views.len() * lights
    }

    /// The reference's samples, what its cost grows with: pixels × samples per pixel ×
    /// [`Self::references`].
    pub fn reference_samples(&self) -> f64 {
        let spp = self.reference_per_axis * self.reference_per_axis;
        f64::from(self.width) * f64::from(self.height) * f64::from(spp) * self.references() as f64
    }
}

/// Progress of [`evaluate()`]: `done` of `total` asset renders (views × lights × LOD
/// levels) are finished, the last of `view`.
#[derive(Clone, Copy, Debug)]
pub struct EvaluateProgress<'a> {
    pub done: usize,
    pub total: usize,
    pub view: &'a str,
}

/// One view's images (for comparison pictures): the reference, the asset's render (one per
/// LOD level evaluated, finest first; one for a volume) and the mesh at 1 spp.
pub struct ViewImages<'a> {
    /// The light of the view (with [`ReferenceLighting::Lights`]).
    pub light: Option<&'a EvalLight>,
    pub view: &'a ViewSpec,
    pub reference: &'a ImageF32,
    pub assets: &'a [ImageF32],
    pub raster_1spp: Option<&'a ImageF32>,
}

/// What [`evaluate()`] tells its caller as it goes (`default()`: nothing). Each hook may stop the evaluation
/// ([`ControlFlow::Break`], then [`EvaluateError::Stopped`]).
#[derive(Default)]
pub struct EvaluateHooks<'a> {
    /// After each asset render.
    pub progress: Option<ProgressHook<'a>>,
    /// After each view, with its images (`None`: the images are dropped as they come).
    pub images: Option<ImagesHook<'a>>,
}

/// [`EvaluateHooks::progress`].
pub type ProgressHook<'a> = &'a mut dyn FnMut(EvaluateProgress) -> ControlFlow<()>;
/// [`EvaluateHooks::images`].
pub type ImagesHook<'a> = &'a mut dyn FnMut(ViewImages) -> ControlFlow<()>;

/// Why [`evaluate()`] failed; each says which side.
#[derive(Debug, thiserror::Error)]
pub enum EvaluateError {
    /// The source mesh cannot be evaluated against (no triangles, an invalid lighting).
    #[error(transparent)]
    Source(EvalError),
    /// Rendering the reference failed.
    #[error(transparent)]
    Reference(EvalError),
    /// Preparing or rendering the asset failed.
    #[error(transparent)]
    Asset(EvalError),
    /// The asset's header lighting parameters do not read.
    #[error("{0}")]
    AssetHeader(String),
    /// [`EvaluateOptions::lod`] names a level the cloud does not have.
    #[error("LOD {lod}: the cloud has {levels} LOD levels (0 to {})", levels.saturating_sub(1))]
    NoSuchLod { lod: usize, levels: usize },
    /// [`EvaluateOptions::lod`] for a volume.
    #[error("a LOD level applies to billboard-cloud assets only")]
    LodOfVolume,
    /// Options that do not make an evaluation (no views, no lights, mixed ambients).
    #[error("{0}")]
    InvalidOption(String),
    /// A hook returned [`ControlFlow::Break`].
    #[error("stopped by the caller")]
    Stopped,
}

/// The reference's lighting as evaluated.
#[derive(Clone, Debug, PartialEq)]
pub struct EvaluatedLighting {
    /// The asset's own lighting: a volume's `bake` (`none` when absent), a cloud's baked
    /// light (`x,y,z`, `unlit`, or unknown).
    pub asset: String,
    /// The reference's lighting (with lights: [`Lighting::Scene`] with a placeholder light,
    /// each light of the set being set in turn).
    pub reference: Lighting,
    /// The reference lighting in words, with its parameters.
    pub reference_details: String,
}

/// One light of [`ReferenceLighting::Lights`] and its means.
#[derive(Clone, Debug, PartialEq)]
pub struct LightResult {
    pub light: EvalLight,
    pub means: LightMeans,
}

/// One LOD level of a cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudLevelInfo {
    pub lod: usize,
    pub billboards: usize,
    /// Slab half-width of the plane search, world units.
    pub epsilon: f32,
    /// Texels per world unit.
    pub texel_density: f32,
    /// Bytes of this level's atlases, all MIP levels.
    pub texture_bytes: u64,
}

/// The results of one asset render set: the volume, or one LOD level of a cloud.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelEvaluation {
    /// `None` for a volume.
    pub cloud: Option<CloudLevelInfo>,
    /// Light-major, then in the views' order.
    pub views: Vec<ViewResult>,
    pub mean: MeanErrors,
    pub by_distance: Vec<DistanceMeans>,
    /// With lights: each light and its means (`mean` is then over the set).
    pub by_light: Vec<LightResult>,
    /// Asset-render seconds, all views.
    pub seconds: f64,
    pub slices: usize,
    pub fragments: u64,
}

/// Seconds spent by [`evaluate()`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EvaluationSeconds {
    /// Decoding the asset for rendering.
    pub prepare: f64,
    pub reference: f64,
    pub asset: f64,
    pub raster_1spp: f64,
    pub total: f64,
}

/// What [`evaluate()`] measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// A volume's level-0 texture size (its atlas when pruned); `None` for a cloud.
    pub volume_dims: Option<[u32; 3]>,
    pub lighting: EvaluatedLighting,
    /// What qualifies the numbers (lighting the reference does not reproduce, shadows).
    pub notes: Vec<String>,
    /// Texture bytes `billow view` holds for the asset (`billow_core::gpu_memory`).
    pub gpu_bytes: GpuBytes,
    /// The volume's results, or a cloud's per LOD level evaluated.
    pub levels: Vec<LevelEvaluation>,
    /// The mesh at 1 spp against the reference, over every view (and light).
    pub raster_1spp: MeanErrors,
    /// Reference renders (views × lights).
    pub references: usize,
    pub seconds: EvaluationSeconds,
}

/// The asset prepared for rendering, with what depends on its kind.
enum Prepared<'a> {
    Volume(&'a VolumeAsset, PreparedAsset),
    Cloud(&'a CloudAsset, PreparedCloud, Vec<usize>),
}

impl Prepared<'_> {
    /// The LOD levels evaluated: `None` for a volume.
    fn lods(&self) -> Vec<Option<usize>> {
        match self {
            Prepared::Volume(..) => vec![None],
            Prepared::Cloud(_, _, lods) => lods.iter().copied().map(Some).collect(),
        }
    }
}

/// The reference lighting of the asset's own choice, its note and the asset's lighting name,
/// and whether the asset's colours carry lighting.
fn own_lighting(
    asset: &Prepared,
    unlit: bool,
) -> Result<(Lighting, Option<String>, String, bool), EvaluateError> {
    match asset {
        Prepared::Volume(a, _) => {
            let bake = a.header.volume_bake();
            let lit = bake != billow_format::VolumeBake::None;
            let (lighting, note) = if unlit {
                let note = lit.then(|| {
                    format!(
                        "the asset has baked lighting (bake={}) but --lighting unlit: the \
                         errors include the lighting difference",
                        bake.name()
                    )
                });
                (Lighting::Unlit, note)
            } else {
                reference_lighting(a).map_err(EvaluateError::Asset)?
            };
            Ok((lighting, note, bake.name().to_string(), lit))
        }
        Prepared::Cloud(a, _, _) => {
            let baked = a.header.baked_light().map_err(EvaluateError::AssetHeader)?;
            // The colours are final (baked under a light, recorded or not) unless baked unlit.
            let lit = !baked.is_unlit();
            let name = match baked {
                BakedLight::Unlit => "unlit".to_string(),
                BakedLight::Directional { .. } => a
                    .header
                    .params
                    .get(billow_format::param::LIGHT)
                    .cloned()
                    .unwrap_or_default(),
                BakedLight::Unknown => "unknown (no light key: the colours are final)".into(),
            };
            let (lighting, note) = if unlit {
                let note = lit.then(|| {
                    "the cloud has baked lighting but --lighting unlit: the errors include the \
                     lighting difference"
                        .to_string()
                });
                (Lighting::Unlit, note)
            } else {
                let l =
                    Lighting::for_cloud(&a.header.params).map_err(EvaluateError::AssetHeader)?;
                (l, None)
            };
            Ok((lighting, note, name, lit))
        }
    }
}

/// The reference lighting, its note and its details under `options.lighting`.
fn choose_lighting(
    asset: &Prepared,
    lighting: &ReferenceLighting,
) -> Result<(EvaluatedLighting, Option<String>), EvaluateError> {
    let unlit = *lighting == ReferenceLighting::Unlit;
    let (own, note, name, lit) = own_lighting(asset, unlit)?;
    let ReferenceLighting::Lights { lights, shadows } = lighting else {
        let details = own.describe();
        return Ok((
            EvaluatedLighting {
                asset: name,
                reference: own,
                reference_details: details,
            },
            note,
        ));
    };
    let ambient = lights[0].ambient;
    let reference = Lighting::Scene {
        light: glam::Vec3::ZERO,
        ambient,
        shadows: *shadows,
    };
    let note = match asset {
        Prepared::Volume(_, p) => shadows.then(|| {
            if shadowable(&p.volume, &p.cells) {
                "--shadows: the reference is ray traced with shadows; the CPU slicer shadows \
                 the volume by its own transmittance towards the light (a coarse MIP level \
                 marched), not by the viewer's shadow map"
                    .to_string()
            } else {
                "--shadows: the reference and meshes are shadowed, the CPU slicer draws \
                 pruned and shell volumes unshadowed: the errors include the shadows"
                    .to_string()
            }
        }),
        Prepared::Cloud(..) => lit.then(|| {
            "the cloud's billboards carry the lighting they were baked with: under another \
             light the errors include the difference"
                .to_string()
        }),
    };
    let details = format!(
        "the viewer's mesh lighting: ambient {ambient} + two-sided diffuse{}, under each of the \
         {} light(s) in `lights`",
        if *shadows { ", ray-traced shadows" } else { "" },
        lights.len()
    );
    Ok((
        EvaluatedLighting {
            asset: name,
            reference,
            reference_details: details,
        },
        note,
    ))
}

fn check(options: &EvaluateOptions) -> Result<(), EvaluateError> {
    let bad = |m: &str| Err(EvaluateError::InvalidOption(m.to_string()));
    if options.views.is_empty() {
        return bad("no views");
    }
    if !(image_side_ok(options.width) && image_side_ok(options.height)) {
        return bad(&format!(
            "an image of {}x{}: each side must be 1 to {MAX_IMAGE_SIDE} pixels",
            options.width, options.height
        ));
    }
    if let Some(v) = options
        .views
        .iter()
        .find(|v| !distance_factor_ok(v.distance_factor))
    {
        return bad(&format!(
            "view {} at {}x: a factor must be above 0 and at most {MAX_DISTANCE_FACTOR}",
            v.name, v.distance_factor
        ));
    }
    let factor = match options.spacing {
        Spacing::Adaptive { bias } => bias,
        Spacing::Uniform { spacing } => spacing,
    };
    if !spacing_factor_ok(factor) {
        return bad(&format!(
            "a spacing factor of {factor}: it must be between {} and {}",
            SPACING_FACTOR.0, SPACING_FACTOR.1
        ));
    }
    if let ReferenceLighting::Lights { lights, .. } = &options.lighting {
        let Some(first) = lights.first() else {
            return bad("an empty light set");
        };
        if lights.iter().any(|l| l.ambient != first.ambient) {
            return bad("the lights of a set have different ambients");
        }
    }
    Ok(())
}

fn prepare<'a>(asset: &'a Asset, lod: Option<usize>) -> Result<Prepared<'a>, EvaluateError> {
    match asset {
        Asset::Volume(v) => {
            if lod.is_some() {
                return Err(EvaluateError::LodOfVolume);
            }
            let p = PreparedAsset::new(v).map_err(EvaluateError::Asset)?;
            Ok(Prepared::Volume(v, p))
        }
        Asset::Cloud(c) => {
            let p = PreparedCloud::new(c).map_err(EvaluateError::Asset)?;
            let levels = p.level_count();
            let lods = match lod {
                Some(k) if k < levels => vec![k],
                Some(lod) => return Err(EvaluateError::NoSuchLod { lod, levels }),
                None => (0..levels).collect(),
            };
            Ok(Prepared::Cloud(c, p, lods))
        }
    }
}

/// Renders `asset` and `scene` from every view of `options` (under every light, for every
/// LOD level evaluated) and compares them, as `billow eval` does (docs/eval.md): the
/// numbers are the CLI's for the same options.
pub fn evaluate(
    scene: &Scene,
    asset: &Asset,
    options: &EvaluateOptions,
    hooks: &mut EvaluateHooks,
) -> Result<Evaluation, EvaluateError> {
    let start = Instant::now();
    check(options)?;
    let prepared = prepare(asset, options.lod)?;
    let prepare_s = start.elapsed().as_secs_f64();
    let (lighting, note) = choose_lighting(&prepared, &options.lighting)?;
    let evaluator = Evaluator::new(scene, evaluator_options(options, &prepared, &lighting))
        .map_err(EvaluateError::Source)?;
    let lods = prepared.lods();
    let Rendered {
        per_level,
        raster,
        mut seconds,
    } = render_views(evaluator, &prepared, options, &lods, hooks)?;
    seconds.prepare = prepare_s;

    let set: Vec<EvalLight> = match &options.lighting {
        ReferenceLighting::Lights { lights, .. } => lights.clone(),
        _ => Vec::new(),
    };
    let levels = lods
        .iter()
        .zip(per_level)
        .map(|(lod, views)| level(&prepared, *lod, views, &set))
        .collect();
    let (gpu_bytes, volume_dims) = match &prepared {
        Prepared::Volume(a, p) => (
            volume_gpu_bytes(a, a.header.compress().is_some()),
            Some(p.dims0),
        ),
        Prepared::Cloud(a, _, _) => (cloud_gpu_bytes(a, a.header.compress().is_some()), None),
    };
    seconds.total = start.elapsed().as_secs_f64();
    Ok(Evaluation {
        volume_dims,
        lighting,
        notes: note.into_iter().collect(),
        gpu_bytes,
        levels,
        raster_1spp: mean_errors(&raster),
        references: raster.len(),
        seconds,
    })
}

/// The suite's options: a uniform spacing in the volume's voxels made world units; with
/// lights, an unlit start (each light of the set is set before any render); unlit, the
/// slicer draws volumes unlit too (their normals unused).
fn evaluator_options(
    options: &EvaluateOptions,
    prepared: &Prepared,
    lighting: &EvaluatedLighting,
) -> EvalOptions {
    let mut spacing = options.spacing;
    if let (Spacing::Uniform { spacing: s }, Prepared::Volume(_, p)) = (&mut spacing, prepared) {
        *s *= p.voxel_size().unwrap_or(1.0);
    }
    let lighting = match &options.lighting {
        ReferenceLighting::Lights { .. } => Lighting::Unlit,
        _ => lighting.reference,
    };
    EvalOptions {
        width: options.width,
        height: options.height,
        fov_y: options.fov_y,
        reference_per_axis: options.reference_per_axis,
        slicer: SlicerParams {
            spacing,
            // Unlit: the asset's albedo too (a volume's normals unused), so that an unlit
            // reference is compared with what is stored, not with the default light.
            light: match options.lighting {
                ReferenceLighting::Unlit => None,
                _ => SlicerParams::default().light,
            },
            ..SlicerParams::default()
        },
        raster_1spp: true,
        lighting,
    }
}

/// What [`render_views`] measured.
struct Rendered {
    /// Per level (of `lods`) its results, light-major.
    per_level: Vec<Vec<ViewResult>>,
    /// The 1-spp errors, one per reference.
    raster: Vec<ImageError>,
    seconds: EvaluationSeconds,
}

/// Every view under every light, every level of `lods`.
fn render_views(
    mut evaluator: Evaluator,
    prepared: &Prepared,
    options: &EvaluateOptions,
    lods: &[Option<usize>],
    hooks: &mut EvaluateHooks,
) -> Result<Rendered, EvaluateError> {
    let (lights, shadows): (Vec<Option<&EvalLight>>, bool) = match &options.lighting {
        ReferenceLighting::Lights { lights, shadows } => {
            (lights.iter().map(Some).collect(), *shadows)
        }
        _ => (vec![None], false),
    };
    let total = options.views.len() * lights.len() * lods.len();
    let mut per_level: Vec<Vec<ViewResult>> = vec![Vec::new(); lods.len()];
    let mut raster: Vec<ImageError> = Vec::new();
    let mut seconds = EvaluationSeconds::default();
    let stop = |flow: ControlFlow<()>| match flow {
        ControlFlow::Continue(()) => Ok(()),
        ControlFlow::Break(()) => Err(EvaluateError::Stopped),
    };
    for light in &lights {
        if let Some(l) = light {
            evaluator
                .set_light(l, shadows)
                .map_err(EvaluateError::Reference)?;
        }
        // The kept mesh is drawn as the viewer draws meshes: lit like the reference.
        let renderer = match prepared {
            Prepared::Cloud(_, p, _) => Renderer::Cloud(
                p,
                Box::new(
                    CloudRenderer::new(p, evaluator.options.lighting)
                        .map_err(EvaluateError::Asset)?,
                ),
            ),
            Prepared::Volume(_, p) => Renderer::Volume(p),
        };
        for spec in &options.views {
            let reference = evaluator
                .reference(spec)
                .map_err(EvaluateError::Reference)?;
            seconds.reference += reference.seconds;
            let mut images = Vec::new();
            for (i, lod) in lods.iter().enumerate() {
                let (result, image) = render(&evaluator, &renderer, *lod, &reference)?;
                seconds.asset += result.seconds.asset;
                per_level[i].push(result);
                if hooks.images.is_some() {
                    images.push(image);
                }
                if let Some(f) = hooks.progress.as_mut() {
                    let done = per_level.iter().map(Vec::len).sum();
                    let view = &spec.name;
                    stop(f(EvaluateProgress { done, total, view }))?;
                }
            }
            if let Some((_, err, s)) = &reference.raster_1spp {
                raster.push(*err);
                seconds.raster_1spp += s;
            }
            if let Some(f) = hooks.images.as_mut() {
                stop(f(ViewImages {
                    light: *light,
                    view: spec,
                    reference: &reference.image,
                    assets: &images,
                    raster_1spp: reference.raster_1spp.as_ref().map(|r| &r.0),
                }))?;
            }
        }
    }
    Ok(Rendered {
        per_level,
        raster,
        seconds,
    })
}

/// What draws the asset under the current light.
enum Renderer<'a> {
    Volume(&'a PreparedAsset),
    Cloud(&'a PreparedCloud, Box<CloudRenderer<'a>>),
}

/// Renders the asset (LOD `lod` of a cloud) from `reference`'s view and compares.
fn render(
    evaluator: &Evaluator,
    renderer: &Renderer,
    lod: Option<usize>,
    reference: &ReferenceView,
) -> Result<(ViewResult, ImageF32), EvaluateError> {
    match renderer {
        Renderer::Volume(p) => evaluator.asset(p, reference),
        Renderer::Cloud(p, r) => evaluator.cloud(r, p, lod.unwrap_or(0), reference),
    }
    .map_err(EvaluateError::Asset)
}

/// One level's summary of its views' results.
fn level(
    prepared: &Prepared,
    lod: Option<usize>,
    views: Vec<ViewResult>,
    lights: &[EvalLight],
) -> LevelEvaluation {
    let cloud = match (prepared, lod) {
        (Prepared::Cloud(a, p, _), Some(lod)) => Some(CloudLevelInfo {
            lod,
            billboards: p.billboards(lod),
            epsilon: a.levels[lod].epsilon,
            texel_density: p.texel_density(lod),
            texture_bytes: p.texture_bytes(a, lod),
        }),
        _ => None,
    };
    let by_light = means_by_light(&views)
        .into_iter()
        .filter_map(|means| {
            let light = lights.iter().find(|l| l.name == means.light)?.clone();
            Some(LightResult { light, means })
        })
        .collect();
    LevelEvaluation {
        cloud,
        mean: mean_errors(views.iter().map(|r| &r.asset)),
        by_distance: means_by_distance(&views),
        by_light,
        seconds: views.iter().map(|r| r.seconds.asset).sum(),
        slices: views.iter().map(|r| r.slices).sum(),
        fragments: views.iter().map(|r| r.fragments).sum(),
        views,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use billow_core::camera::{view_set, ViewDirections};

    fn options() -> EvaluateOptions {
        EvaluateOptions {
            views: view_set(ViewDirections::Axes),
            ..EvaluateOptions::default()
        }
    }

    #[test]
    fn options_out_of_range_are_refused() {
        assert!(check(&options()).is_ok());
        let refused = |o: EvaluateOptions, what: &str| match check(&o) {
            Err(EvaluateError::InvalidOption(m)) => assert!(m.contains(what), "{m}"),
            r => panic!("{what}: {r:?}"),
        };
        for (w, h) in [(0, 8), (8, MAX_IMAGE_SIDE + 1)] {
            refused(
                EvaluateOptions {
                    width: w,
                    height: h,
                    ..options()
                },
                "each side must be 1 to 4096 pixels",
            );
        }
        for f in [0.0, -1.0, f32::NAN, MAX_DISTANCE_FACTOR * 1.01] {
            let mut o = options();
            o.views[0].distance_factor = f;
            refused(o, "a factor must be above 0 and at most 1000");
        }
        for spacing in [
            Spacing::Adaptive { bias: 0.001 },
            Spacing::Uniform { spacing: 101.0 },
            Spacing::Adaptive {
                bias: f32::INFINITY,
            },
        ] {
            refused(
                EvaluateOptions {
                    spacing,
                    ..options()
                },
                "must be between 0.01 and 100",
            );
        }
    }
}
