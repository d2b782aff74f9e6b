//! What a scene holds, on the CPU: loaded assets, meshes, light, options. The passes a
//! frame needs follow from it alone ([`Content::passes`], `--print-passes`, no GPU
//! needed), and [`Content::build`] uploads it into a [`Renderer`] that builds exactly
//! those passes.

use std::time::{Duration, Instant};

use billow_format::{CloudAsset, CloudBlocks, VolumeAsset, VolumeBlocks};
use glam::{Mat4, Vec3};

use crate::animate::Sway;
use crate::mesh_pass::MeshData;
use crate::particle_pass::{ParticleLayerDesc, ParticleNeeds};
use crate::particles::ParticleSystemDesc;
use crate::{Gpu, Renderer, SliceParams, ViewError};

/// A cloud asset and how it is placed.
#[derive(Clone, Debug)]
pub struct CloudContent {
    pub asset: CloudAsset,
    /// The BC7 blocks of a compressed asset (format 1.2), uploaded as they are where the
    /// device allows it; `asset` holds their decoded texels either way.
    pub blocks: Option<std::sync::Arc<CloudBlocks>>,
    pub instances: Vec<Mat4>,
    pub lod_distances: Option<Vec<f32>>,
    pub transition: f32,
    /// Dissolve half-width around each switch, in octaves (`cloud_pass` module docs).
    pub dissolve: f32,
}

/// Which kinds of content a frame draws (what decides its passes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Needs {
    pub meshes: bool,
    pub clouds: bool,
    pub volumes: bool,
    pub shadows: bool,
    /// Some volume deforms its cells over time.
    pub animated: bool,
    pub particles: ParticleNeeds,
}

/// The work of a frame with `n`, in order. First what is computed once at load, prefixed
/// `bake:` (the detail noise only with particle `detail > 0` or shimmer, the phase LUT only with dust or smoke,
/// the black-body LUT only with fire), then per frame: `animate:cells` only with animated
/// volumes, `shadow` only with shadows on and something to cast, `mesh` only with meshes
/// (a ground, cloud trunks), `cloud` only with clouds, `volume` only with volumes,
/// `particles` (+ `motion-blur`, `shimmer` when asked for) and `composite` only with
/// particles, then `resolve`.
pub fn pass_list(n: Needs) -> Vec<&'static str> {
    let pn = n.particles;
    [
        (pn.detail, "bake:detail-noise"),
        (pn.scattering, "bake:phase-lut"),
        (pn.fire, "bake:blackbody-lut"),
        (n.animated, "animate:cells"),
        (n.shadows && (n.meshes || n.clouds || n.volumes), "shadow"),
        (n.meshes, "mesh"),
        (n.clouds, "cloud"),
        (n.volumes, "volume"),
        (pn.any, "particles"),
        (pn.any && pn.motion_blur, "motion-blur"),
        (pn.any && pn.shimmer, "shimmer"),
        (pn.any, "composite"),
        (true, "resolve"),
    ]
    .into_iter()
    .filter_map(|(on, pass)| on.then_some(pass))
    .collect()
}

/// A volume asset, its instances and its cell animation.
#[derive(Clone, Debug)]
pub struct VolumeContent {
    pub asset: VolumeAsset,
    /// The BC7 blocks of a compressed asset (format 1.2), as for [`CloudContent::blocks`].
    pub blocks: Option<std::sync::Arc<VolumeBlocks>>,
    pub instances: Vec<Mat4>,
    pub animation: Option<Sway>,
}

#[derive(Clone, Debug)]
pub struct Content {
    pub volumes: Vec<VolumeContent>,
    pub clouds: Vec<CloudContent>,
    /// World-space opaque meshes (the ground included).
    pub meshes: Vec<MeshData>,
    /// Direction towards the light, ambient fraction.
    pub light_dir: Vec3,
    pub ambient: f32,
    pub shadows: bool,
    pub particles: Vec<ParticleSystemDesc>,
    pub particle_layer: ParticleLayerDesc,
}

impl Default for Content {
    fn default() -> Self {
        Content {
            volumes: Vec::new(),
            clouds: Vec::new(),
            meshes: Vec::new(),
            light_dir: billow_core::shading::DEFAULT_LIGHT,
            ambient: billow_core::shading::DEFAULT_AMBIENT,
            shadows: false,
            particles: Vec::new(),
            particle_layer: ParticleLayerDesc::default(),
        }
    }
}

impl Content {
    pub fn needs(&self) -> Needs {
        Needs {
            meshes: !self.meshes.is_empty()
                || self
                    .clouds
                    .iter()
                    .any(|c| !c.asset.trunk.triangles.is_empty()),
            clouds: !self.clouds.is_empty(),
            volumes: !self.volumes.is_empty(),
            shadows: self.shadows,
            animated: self.volumes.iter().any(|v| v.animation.is_some()),
            particles: ParticleNeeds::of(&self.particles, &self.particle_layer),
        }
    }

    pub fn passes(&self) -> Vec<&'static str> {
        pass_list(self.needs())
    }

    /// World-space bounds (min, max) of everything; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut grow_box = |min: [f32; 3], max: [f32; 3], m: &Mat4| {
            for i in 0..8 {
                let c = Vec3::new(
                    if i & 1 == 0 { min[0] } else { max[0] },
                    if i & 2 == 0 { min[1] } else { max[1] },
                    if i & 4 == 0 { min[2] } else { max[2] },
                );
                let p = m.transform_point3(c);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        };
        for v in &self.volumes {
            for m in &v.instances {
                grow_box(v.asset.header.bounds.min, v.asset.header.bounds.max, m);
            }
        }
        for c in &self.clouds {
            for m in &c.instances {
                grow_box(c.asset.header.bounds.min, c.asset.header.bounds.max, m);
            }
        }
        for m in &self.meshes {
            for v in &m.vertices {
                lo = lo.min(Vec3::from(v.pos));
                hi = hi.max(Vec3::from(v.pos));
            }
        }
        for s in &self.particles {
            let e = &s.emitter;
            let reach = e.spread + e.radius.1 + e.rise.abs();
            let c = Vec3::from(e.position);
            lo = lo.min(c - Vec3::splat(reach));
            hi = hi.max(c + Vec3::splat(reach));
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    /// A renderer on `gpu` holding this content (`fov_y` sets default LOD distances), its
    /// pipelines built ([`Content::build_with`] without progress).
    pub fn build(&self, gpu: Gpu, params: SliceParams, fov_y: f32) -> Result<Renderer, ViewError> {
        self.build_with(gpu, params, fov_y, &mut |_| {})
    }

    /// Volume textures of this content: each volume's base and LOD bands.
    pub fn volume_textures(&self) -> usize {
        self.volumes.iter().map(|v| 1 + v.asset.bands.len()).sum()
    }

    /// [`Content::build`], telling `progress` when each [`BuildStep`] starts and ends: the
    /// uploads (meshes, clouds, volumes, particle tables; timed until the GPU has them),
    /// then the pipelines the passes need ([`Renderer::prepare`]). The volume pass binds
    /// at most as many textures at once as the content has (and the renderer's
    /// [`Renderer::texture_batch`] allows), so its shader switches over no texture slot it
    /// does not use.
    pub fn build_with(
        &self,
        gpu: Gpu,
        params: SliceParams,
        fov_y: f32,
        progress: &mut dyn FnMut(BuildProgress),
    ) -> Result<Renderer, ViewError> {
        progress(BuildProgress::Started(BuildStep::Upload));
        let t = Instant::now();
        let mut r = Renderer::new(gpu);
        r.params = params;
        r.light_dir = self.light_dir;
        r.ambient = self.ambient;
        r.texture_batch = r.texture_batch.min(self.volume_textures().max(1));
        r.set_shadows(self.shadows);
        for m in &self.meshes {
            r.add_mesh(m)?;
        }
        for c in &self.clouds {
            r.add_cloud_blocks(
                &c.asset,
                c.blocks.as_deref(),
                c.instances.clone(),
                c.lod_distances.clone(),
                c.transition,
                fov_y,
            )?;
            r.set_cloud_dissolve(r.cloud_count() - 1, c.dissolve)?;
        }
        for v in &self.volumes {
            r.add_volume_blocks(
                &v.asset,
                v.blocks.as_deref(),
                v.instances.clone(),
                v.animation,
            )?;
        }
        if !self.particles.is_empty() {
            r.set_particles(self.particles.clone(), self.particle_layer)?;
        }
        // The writes land with the next submission: submit one and wait, so the step's
        // time includes them.
        r.gpu.queue.submit([]);
        r.gpu.wait()?;
        progress(BuildProgress::Finished(BuildStep::Upload, t.elapsed()));
        progress(BuildProgress::Started(BuildStep::Pipelines));
        let t = Instant::now();
        r.prepare();
        progress(BuildProgress::Finished(BuildStep::Pipelines, t.elapsed()));
        Ok(r)
    }
}

/// A step of [`Content::build_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildStep {
    /// Textures, buffers and tables to the GPU.
    Upload,
    /// The pipelines the passes need ([`Renderer::prepare`]).
    Pipelines,
}

impl BuildStep {
    /// What the step does, for a progress line ("uploading the content").
    pub fn describe(self) -> &'static str {
        match self {
            BuildStep::Upload => "uploading the content",
            BuildStep::Pipelines => "building the pipelines",
        }
    }
}

/// What [`Content::build_with`] tells its caller: a step started, or ended after a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BuildProgress {
    Started(BuildStep),
    Finished(BuildStep, Duration),
}
