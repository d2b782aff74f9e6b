//! The measure: `billow eval`'s covered RMSE over the distances and lights of a target ([`Judge`]).

use billow_format::{CloudAsset, VolumeAsset};

use crate::eval::cloud_render::{CloudRenderer, PreparedCloud};
use crate::eval::lighting::{EvalLight, Lighting};
use crate::eval::metrics::{compare, ImageError};
use crate::eval::suite::{
    mean_errors, reference_lighting, EvalOptions, Evaluator, PreparedAsset, ReferenceView,
    EVAL_FOV_Y,
};
use crate::eval::EvalError;
use crate::scene::Scene;
use billow_core::camera::ViewSpec;

use super::types::*;
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
