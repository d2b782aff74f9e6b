//! The evaluation harness behind `billow eval`: a source mesh and a volume asset rendered
//! from the same views and compared (docs/eval.md).
//!
//! - Every view is framed on the **source mesh's** bounds ([`billow_core::camera::Camera::framed`]),
//!   so the reference images do not depend on the asset (its margin, resolution) and can be
//!   reused for many assets of the same mesh ([`Evaluator::reference`]).
//! - Reference: [`ReferenceRenderer`] with `n × n` stratified samples per pixel, unlit or
//!   with the lighting the asset was baked with ([`EvalOptions::lighting`],
//!   [`reference_lighting`]).
//!   Also rendered per view: the mesh with **one sample per pixel** at the pixel centre —
//!   what a rasterizer without anti-aliasing shows — and compared with the same reference,
//!   so the asset's error can be read against the aliasing error of drawing the mesh.
//! - Asset: the CPU slicer ([`render_decoded_with_shadow`]) with the given [`SlicerParams`], its
//!   coverage samples at the reference's stratified points
//!   ([`SlicerParams::coverage_samples`] = `reference_per_axis`): the slicer shades once per
//!   pixel and the cells' edges are anti-aliased as the reference's geometry is.
//! - Metrics: [`compare`] (RMSE/PSNR on premultiplied linear RGBA, alpha coverage, SSIM,
//!   FLIP). Means over views: RMSE, |Δα|, coverage difference, SSIM and FLIP are plain means;
//!   the mean PSNR is the PSNR of the mean MSE (finite unless every view is exact).

use std::sync::{Arc, Mutex};
use std::time::Instant;

use billow_format::{Prism, VolumeAsset};
use glam::Vec3;
use serde::Serialize;

use super::cloud_render::{CloudRenderer, PreparedCloud};
use super::lighting::{EvalLight, Lighting, VolumeLight};
use super::metrics::{compare, ImageError};
use super::reference::{ReferenceRenderer, Sampling};
use super::slicer::{render_decoded_with_shadow, SlicerParams};
use super::volume_sampler::DecodedVolume;
use super::volume_shadow::ShadowGrid;
use super::{EvalError, ImageF32};
use crate::scene::Scene;
use billow_core::camera::{Camera, ViewSpec};
use billow_core::Aabb;

/// Vertical field of view of every evaluation view: 45°.
pub const EVAL_FOV_Y: f32 = std::f32::consts::FRAC_PI_4;

/// How the views are rendered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalOptions {
    pub width: u32,
    pub height: u32,
    pub fov_y: f32,
    /// Reference samples per pixel per axis (`n × n` per pixel) at the framed distance;
    /// farther views take more ([`EvalOptions::samples_per_axis`]).
    pub reference_per_axis: u32,
    pub slicer: SlicerParams,
    /// Also render the mesh with one sample per pixel (the aliasing baseline).
    pub raster_1spp: bool,
    /// Lighting of the reference (and of the 1-spp render).
    pub lighting: Lighting,
}

impl Default for EvalOptions {
    /// 128 × 128, 45°, 4 × 4 = 16 reference samples per pixel, the paper's slicing, 1-spp on.
    fn default() -> Self {
        EvalOptions {
            width: 128,
            height: 128,
            fov_y: EVAL_FOV_Y,
            reference_per_axis: 4,
            slicer: SlicerParams::default(),
            raster_1spp: true,
            lighting: Lighting::Unlit,
        }
    }
}

/// The most samples per pixel per axis a view takes (`16 × 16 = 256` per pixel).
pub const MAX_SAMPLES_PER_AXIS: u32 = 16;

impl EvalOptions {
    /// Samples per pixel per axis of the reference and the asset's render at
    /// `distance_factor` × the framed distance: `reference_per_axis × distance_factor`
    /// (never fewer), at most [`MAX_SAMPLES_PER_AXIS`]. The mesh covers `1/f²` as many
    /// pixels at `f`, so this keeps the samples that fall on it about the same at every
    /// distance: with a fixed 16 per pixel, the oak 2 pixels wide (64×) was measured with
    /// about 60 samples, and both its volume and its cloud read +10 % coverage against it
    /// (+0.6 % and +1.2 % against 256 per pixel). The reference skips the pixels the
    /// mesh's bounds cannot reach, so a far view costs about what the framed one does.
    pub fn samples_per_axis(&self, distance_factor: f32) -> u32 {
        let n = self.reference_per_axis;
        let scaled = (n as f32 * distance_factor).round();
        if scaled > n as f32 {
            (scaled.min(MAX_SAMPLES_PER_AXIS as f32) as u32).max(n)
        } else {
            n
        }
    }
}

/// The reference side of one view (reusable for any asset of the same mesh).
#[derive(Clone, Debug)]
pub struct ReferenceView {
    pub spec: ViewSpec,
    pub camera: Camera,
    pub image: ImageF32,
    pub seconds: f64,
    /// The 1-spp render, its error against `image`, and its time.
    pub raster_1spp: Option<(ImageF32, ImageError, f64)>,
}

/// Seconds spent on one view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ViewSeconds {
    /// The reference (n × n spp ray tracing).
    pub reference: f64,
    /// The asset (CPU slicer, including its decode-free setup).
    pub asset: f64,
    /// The 1-spp mesh render (0 when not rendered).
    pub raster_1spp: f64,
}

/// Everything measured for one view.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ViewResult {
    pub view: String,
    /// The light of [`Evaluator::set_light`] (its name), if one was set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<String>,
    pub dir: [f32; 3],
    pub distance_factor: f32,
    /// The asset against the reference.
    pub asset: ImageError,
    /// The mesh at 1 sample per pixel against the reference.
    pub raster_1spp: Option<ImageError>,
    pub seconds: ViewSeconds,
    pub slices: usize,
    /// Non-empty cell ∩ slice polygons.
    pub polygons: usize,
    /// Shaded pixels (volume samples) of the asset render.
    pub fragments: u64,
    /// World size of one pixel at the target's depth, in level-0 voxels (< 1: magnified).
    pub pixel_in_voxels: f32,
}

/// Means over a set of views (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MeanErrors {
    pub views: usize,
    pub rmse: f64,
    /// Mean RMSE over the covered pixels ([`ImageError::rmse_covered`]).
    pub rmse_covered: f64,
    /// PSNR of the mean MSE.
    pub psnr: f64,
    pub mean_abs_alpha: f64,
    /// Mean of the signed relative coverage differences (negative = too transparent).
    pub coverage_rel_diff: f64,
    pub ssim_luma: f64,
    pub ssim_alpha: f64,
    /// Mean FLIP error.
    pub flip: f64,
    /// Mean of the signed relative differences of the mean covered luminance (positive =
    /// brighter than the mesh).
    pub luminance_rel_diff: f64,
}

/// Means of `errors` (all zeros for an empty set).
pub fn mean_errors<'a>(errors: impl IntoIterator<Item = &'a ImageError>) -> MeanErrors {
    let mut m = MeanErrors::default();
    let mut mse = 0.0;
    for e in errors {
        m.views += 1;
        m.rmse += e.rmse;
        m.rmse_covered += e.rmse_covered;
        mse += e.rmse * e.rmse;
        m.mean_abs_alpha += e.mean_abs_alpha;
        m.coverage_rel_diff += if e.coverage_rel_diff.is_finite() {
            e.coverage_rel_diff
        } else {
            1.0
        };
        m.ssim_luma += e.ssim_luma;
        m.ssim_alpha += e.ssim_alpha;
        m.flip += e.flip;
        m.luminance_rel_diff += if e.luminance_rel_diff.is_finite() {
            e.luminance_rel_diff
        } else {
            1.0
        };
    }
    if m.views == 0 {
        return m;
    }
    let n = m.views as f64;
    m.rmse /= n;
    m.rmse_covered /= n;
    mse /= n;
    m.psnr = if mse > 0.0 {
        -10.0 * mse.log10()
    } else {
        f64::INFINITY
    };
    m.mean_abs_alpha /= n;
    m.coverage_rel_diff /= n;
    m.ssim_luma /= n;
    m.ssim_alpha /= n;
    m.flip /= n;
    m.luminance_rel_diff /= n;
    m
}

/// Means of the asset and of the 1-spp raster over views at one distance factor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DistanceMeans {
    pub distance_factor: f32,
    pub asset: MeanErrors,
    pub raster_1spp: Option<MeanErrors>,
}

/// Per distance factor, in order of first appearance.
pub fn means_by_distance(results: &[ViewResult]) -> Vec<DistanceMeans> {
    let mut factors: Vec<f32> = Vec::new();
    for r in results {
        if !factors.contains(&r.distance_factor) {
            factors.push(r.distance_factor);
        }
    }
    factors
        .into_iter()
        .map(|f| {
            let at: Vec<&ViewResult> = results.iter().filter(|r| r.distance_factor == f).collect();
            let raster: Vec<&ImageError> =
                at.iter().filter_map(|r| r.raster_1spp.as_ref()).collect();
            DistanceMeans {
                distance_factor: f,
                asset: mean_errors(at.iter().map(|r| &r.asset)),
                raster_1spp: (!raster.is_empty()).then(|| mean_errors(raster)),
            }
        })
        .collect()
}

/// Means of the asset and of the 1-spp raster over the views under one light.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightMeans {
    pub light: String,
    pub asset: MeanErrors,
    pub raster_1spp: Option<MeanErrors>,
    /// Per distance factor, under this light.
    pub by_distance: Vec<DistanceMeans>,
}

/// Per light ([`ViewResult::light`]), in order of first appearance; empty when no result
/// names a light.
pub fn means_by_light(results: &[ViewResult]) -> Vec<LightMeans> {
    let mut lights: Vec<&str> = Vec::new();
    for r in results {
        if let Some(l) = r.light.as_deref() {
            if !lights.contains(&l) {
                lights.push(l);
            }
        }
    }
    lights
        .into_iter()
        .map(|l| {
            let at: Vec<ViewResult> = results
                .iter()
                .filter(|r| r.light.as_deref() == Some(l))
                .cloned()
                .collect();
            let raster: Vec<&ImageError> =
                at.iter().filter_map(|r| r.raster_1spp.as_ref()).collect();
            LightMeans {
                light: l.to_string(),
                asset: mean_errors(at.iter().map(|r| &r.asset)),
                raster_1spp: (!raster.is_empty()).then(|| mean_errors(raster)),
                by_distance: means_by_distance(&at),
            }
        })
        .collect()
}

/// The reference lighting that matches a volume asset's baked lighting (header `bake`,
/// see [`Lighting::for_volume`]) or, for an asset with normals, its runtime shading
/// ([`Lighting::Volume`], the light the slicer's [`SlicerParams::light`] defaults to), and
/// a note when its lighting cannot be reproduced.
pub fn reference_lighting(asset: &VolumeAsset) -> Result<(Lighting, Option<String>), EvalError> {
    let b = &asset.header.bounds;
    Lighting::for_volume(
        &asset.header.params,
        Vec3::from(b.min),
        Vec3::from(b.max),
        asset.level_dims(0),
        asset.normals.as_ref().and(asset.normal_kind()),
    )
    .map_err(EvalError::InvalidAsset)
}

/// The bounds every view is framed on: the source mesh's.
pub fn frame_bounds(scene: &Scene) -> Result<Aabb, EvalError> {
    let mut b = Aabb::EMPTY;
    for t in &scene.triangles {
        for v in &t.v {
            if v.position.is_finite() {
                b.grow(v.position);
            }
        }
    }
    if b.is_empty() {
        return Err(EvalError::InvalidParam(
            "the source mesh has no triangles".into(),
        ));
    }
    Ok(b)
}

/// A source mesh prepared for evaluation (BVH built once).
pub struct Evaluator<'a> {
    renderer: ReferenceRenderer<'a>,
    bounds: Aabb,
    pub options: EvalOptions,
    /// The name of the light of [`Evaluator::set_light`].
    light: Option<String>,
}

/// A decoded asset ready to render from many views.
pub struct PreparedAsset {
    pub volume: DecodedVolume,
    pub dims0: [u32; 3],
    pub cells: Vec<Prism>,
    /// `--shadows`: the last light's transmittance grid (it depends on the light alone;
    /// one is built per light, not per view).
    shadow: Mutex<Option<(Vec3, Option<Arc<ShadowGrid>>)>>,
}

impl PreparedAsset {
    pub fn new(asset: &VolumeAsset) -> Result<Self, EvalError> {
        Ok(PreparedAsset {
            volume: DecodedVolume::decode(asset)?,
            dims0: asset.level_dims(0),
            cells: asset.cells.clone(),
            shadow: Mutex::new(None),
        })
    }

    /// The transmittance grid towards `light` ([`ShadowGrid::for_volume`]), built once per
    /// light.
    fn shadow_grid(&self, light: Vec3) -> Option<Arc<ShadowGrid>> {
        let mut cache = self.shadow.lock().unwrap_or_else(|e| e.into_inner());
        match &*cache {
            Some((l, grid)) if *l == light => grid.clone(),
            _ => {
                let grid = ShadowGrid::for_volume(&self.volume, &self.cells, light).map(Arc::new);
                *cache = Some((light, grid.clone()));
                grid
            }
        }
    }

    /// `--shadows`' transmittance grid for `params` ([`PreparedAsset::shadow_grid`]), only
    /// where the slicer uses it: a light, shadows asked for, and a volume that stores
    /// normals (one without keeps its baked colour, unshadowed).
    fn shadow_for(&self, params: &SlicerParams) -> Option<Arc<ShadowGrid>> {
        params
            .light
            .filter(|_| params.shadows && self.volume.has_normals())
            .and_then(|l| self.shadow_grid(l.dir))
    }

    /// World size of a level-0 voxel (see [`billow_core::slicing::voxel_size`]).
    pub fn voxel_size(&self) -> Option<f32> {
        billow_core::slicing::voxel_size(&self.cells, self.dims0)
    }
}

impl<'a> Evaluator<'a> {
    pub fn new(scene: &'a Scene, options: EvalOptions) -> Result<Self, EvalError> {
        if !(1..=16).contains(&options.reference_per_axis) {
            return Err(EvalError::InvalidParam(format!(
                "reference samples per axis {} is out of range (1 to 16)",
                options.reference_per_axis
            )));
        }
        let bounds = frame_bounds(scene)?;
        Ok(Evaluator {
            renderer: ReferenceRenderer::new(scene).with_lighting(options.lighting)?,
            bounds,
            options,
            light: None,
        })
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Everything lit by `light` from now on, as `billow view` lights each kind: the
    /// reference is the mesh under the viewer's mesh lighting ([`Lighting::Scene`], with
    /// ray-traced shadows when `shadows`), and the slicer shades volumes that carry
    /// normals with `light` (volumes without normals show their baked colour, as the
    /// viewer shows them), shadowed by their own transmittance when `shadows`
    /// ([`SlicerParams::shadows`]).
    pub fn set_light(&mut self, light: &EvalLight, shadows: bool) -> Result<(), EvalError> {
        let lighting = Lighting::Scene {
            light: light.dir,
            ambient: light.ambient,
            shadows,
        };
        self.renderer.set_lighting(lighting)?;
        self.options.lighting = lighting;
        self.options.slicer.light = Some(VolumeLight {
            dir: light.dir,
            ambient: light.ambient,
        });
        self.options.slicer.shadows = shadows;
        self.light = Some(light.name.clone());
        Ok(())
    }

    pub fn camera(&self, spec: &ViewSpec) -> Camera {
        let o = &self.options;
        spec.camera(&self.bounds, o.fov_y, o.width, o.height)
    }

    /// Renders the reference (and the 1-spp raster when enabled) of one view.
    pub fn reference(&self, spec: &ViewSpec) -> Result<ReferenceView, EvalError> {
        let camera = self.camera(spec);
        let t = Instant::now();
        let n = self.options.samples_per_axis(spec.distance_factor);
        let image = self
            .renderer
            .render(&camera, Sampling::Stratified { per_axis: n })?;
        let seconds = t.elapsed().as_secs_f64();
        let raster_1spp = if self.options.raster_1spp {
            let t = Instant::now();
            let img = self.renderer.render(&camera, Sampling::Centre)?;
            let s = t.elapsed().as_secs_f64();
            let err = compare(&image, &img)?;
            Some((img, err, s))
        } else {
            None
        };
        Ok(ReferenceView {
            spec: spec.clone(),
            camera,
            image,
            seconds,
            raster_1spp,
        })
    }

    /// Renders `asset` from `reference`'s view and compares; returns the result and the image.
    pub fn asset(
        &self,
        asset: &PreparedAsset,
        reference: &ReferenceView,
    ) -> Result<(ViewResult, ImageF32), EvalError> {
        // The reference's sample pattern, so the cells' edges are anti-aliased as the
        // mesh's are (the cloud renderer does the same).
        let params = SlicerParams {
            coverage_samples: self
                .options
                .samples_per_axis(reference.spec.distance_factor),
            ..self.options.slicer
        };
        let shadow = asset.shadow_for(&params);
        let r = render_decoded_with_shadow(
            &asset.volume,
            asset.dims0,
            &asset.cells,
            &reference.camera,
            &params,
            shadow.as_deref(),
        )?;
        let err = compare(&reference.image, &r.image)?;
        let cam = &reference.camera;
        let depth = (cam.target - cam.eye).length();
        let pixel_in_voxels = asset
            .voxel_size()
            .map_or(0.0, |v0| cam.pixel_size_at(depth) / v0);
        let spec = &reference.spec;
        let result = ViewResult {
            view: spec.name.clone(),
            light: self.light.clone(),
            dir: spec.dir.to_array(),
            distance_factor: spec.distance_factor,
            asset: err,
            raster_1spp: reference.raster_1spp.as_ref().map(|x| x.1),
            seconds: ViewSeconds {
                reference: reference.seconds,
                asset: r.stats.seconds,
                raster_1spp: reference.raster_1spp.as_ref().map_or(0.0, |x| x.2),
            },
            slices: r.stats.slices,
            polygons: r.stats.polygons,
            fragments: r.stats.fragments,
            pixel_in_voxels,
        };
        Ok((result, r.image))
    }
}

impl<'a> Evaluator<'a> {
    /// Renders LOD `lod` of a billboard cloud from `reference`'s view with the reference's
    /// sampling and compares. In the result, `slices` is 0, `polygons` the billboards hit,
    /// `fragments` the billboard samples shaded and `pixel_in_voxels` the pixel's size at
    /// the target's depth in the level's texels.
    pub fn cloud(
        &self,
        renderer: &CloudRenderer,
        cloud: &PreparedCloud,
        lod: usize,
        reference: &ReferenceView,
    ) -> Result<(ViewResult, ImageF32), EvalError> {
        let n = self
            .options
            .samples_per_axis(reference.spec.distance_factor);
        let r = renderer.render(lod, &reference.camera, Sampling::Stratified { per_axis: n })?;
        let err = compare(&reference.image, &r.image)?;
        let cam = &reference.camera;
        let depth = (cam.target - cam.eye).length();
        let spec = &reference.spec;
        let result = ViewResult {
            view: spec.name.clone(),
            light: self.light.clone(),
            dir: spec.dir.to_array(),
            distance_factor: spec.distance_factor,
            asset: err,
            raster_1spp: reference.raster_1spp.as_ref().map(|x| x.1),
            seconds: ViewSeconds {
                reference: reference.seconds,
                asset: r.stats.seconds,
                raster_1spp: reference.raster_1spp.as_ref().map_or(0.0, |x| x.2),
            },
            slices: 0,
            polygons: r.stats.visible_billboards,
            fragments: r.stats.fragments,
            pixel_in_voxels: cam.pixel_size_at(depth) * cloud.texel_density(lod),
        };
        Ok((result, r.image))
    }
}

/// A file-name-safe form of a view name: `+` → `p`, `-` → `n`, `@` → `_`
/// (`"+x-y+z@4x"` → `"pxnypz_4x"`).
pub fn view_file_stem(name: &str) -> String {
    name.chars()
        .map(|c| match c {
            '+' => 'p',
            '-' => 'n',
            '@' => '_',
            c if c.is_ascii_alphanumeric() || c == '.' => c,
            _ => '_',
        })
        .collect()
}

/// Direction helper for callers that build their own [`ViewSpec`]s.
pub fn spec(name: &str, dir: Vec3, distance_factor: f32) -> ViewSpec {
    ViewSpec {
        name: format!("{name}@{distance_factor}x"),
        dir: dir.normalize(),
        distance_factor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(rmse: f64, cov: f64) -> ImageError {
        ImageError {
            rmse_rgba: [rmse; 4],
            rmse,
            rmse_covered: 2.0 * rmse,
            covered_fraction: 0.25,
            psnr_rgba: [0.0; 4],
            psnr: 0.0,
            mean_abs_alpha: rmse,
            coverage_reference: 0.5,
            coverage_test: 0.5,
            coverage_rel_diff: cov,
            ssim_luma: 1.0,
            ssim_alpha: 0.5,
            flip: 0.1,
            luminance_reference: 0.5,
            luminance_test: 0.5,
            luminance_rel_diff: 0.0,
        }
    }

    #[test]
    fn means_use_the_mean_mse_for_psnr() {
        let m = mean_errors(&[err(0.1, -0.2), err(0.3, 0.0)]);
        assert_eq!(m.views, 2);
        assert!((m.rmse - 0.2).abs() < 1e-12);
        let mse = (0.01 + 0.09) / 2.0;
        assert!((m.psnr - (-10.0 * f64::log10(mse))).abs() < 1e-9);
        assert!((m.coverage_rel_diff + 0.1).abs() < 1e-12);
        assert_eq!(mean_errors(&[]).views, 0);
    }

    #[test]
    fn baked_lighting_selects_the_reference_lighting() {
        use billow_format::{ColourSpace, Header};
        let mut asset = VolumeAsset {
            header: Header::volume("test", ColourSpace::SrgbPremultiplied, [1, 1, 1], 1, false),
            levels: vec![vec![0; 4]],
            normals: None,
            bands: Vec::new(),
            cells: vec![],
        };
        assert_eq!(reference_lighting(&asset).unwrap(), (Lighting::Unlit, None));
        asset.header.params.insert("bake".into(), "none".into());
        assert_eq!(reference_lighting(&asset).unwrap(), (Lighting::Unlit, None));
        asset.header.params.insert("bake".into(), "ao".into());
        let (l, note) = reference_lighting(&asset).unwrap();
        assert!(matches!(l, Lighting::Ao { .. }) && note.is_none(), "{l:?}");
        asset.header.params.insert("bake".into(), "gi".into());
        let (l, note) = reference_lighting(&asset).unwrap();
        assert_eq!(l, Lighting::Unlit);
        assert!(note.unwrap().contains("bake=gi"));
    }

    /// A volume without normals is drawn unshadowed, so no grid is built for it (one 64³
    /// march per light, thrown away, before).
    #[test]
    fn no_shadow_grid_for_a_volume_without_normals() {
        use billow_format::{ColourSpace, Header};
        let asset = VolumeAsset {
            header: Header::volume("test", ColourSpace::SrgbPremultiplied, [2, 2, 2], 1, false),
            levels: vec![vec![255; 32]],
            normals: None,
            bands: Vec::new(),
            cells: crate::test_support::box_prisms_z([0.0; 3], [1.0; 3], |p| p),
        };
        let prepared = PreparedAsset::new(&asset).unwrap();
        let params = SlicerParams {
            shadows: true,
            ..SlicerParams::default()
        };
        assert!(prepared.shadow_for(&params).is_none());
        let cache = prepared.shadow.lock().unwrap();
        assert!(
            cache.is_none(),
            "a grid was built for a volume without normals"
        );
    }

    #[test]
    fn file_stems_are_plain() {
        assert_eq!(view_file_stem("+x-y+z@4x"), "pxnypz_4x");
        assert_eq!(view_file_stem("-z@2.5x"), "nz_2.5x");
    }
}
