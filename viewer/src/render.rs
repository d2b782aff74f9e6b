//! The frame. Passes, each built only when the content needs it:
//! 1. `shadow` — the light's depth map in cascades fitted to the view, one submission
//!    per cascade (meshes, clouds, volumes cast), only with shadows on and something to
//!    cast ([`crate::shadow`]);
//! 2. `mesh` — opaque meshes (and kept cloud trunks, the ground), depth write;
//! 3. `cloud` — billboard clouds: foliage meshes and billboards alpha-tested, depth
//!    write, one instanced draw per (cloud, level, atlas) ([`crate::cloud_pass`]);
//! 4. `volume` — volumetric-billboard slices, back to front, blended into Rgba16Float,
//!    each faded where the opaque depth (read-only from here) cuts its slab
//!    ([`crate::volume_pass`], [`crate::volume_plan`]);
//! 5. `resolve` — the read-back (headless) or the blit to the window.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::cell::{OnceCell, RefCell};

use billow_format::VolumeAsset;
use glam::{Mat4, Vec3};

use crate::cloud_pass::{CloudPass, GpuCloud};
use crate::frame_stats::FrameStats;
use crate::mesh_pass::{GpuMesh, MeshData, MeshPass};
use crate::particle_pass::{LayerTargets, ParticleLayerDesc, ParticlePass};
use crate::particles::ParticleSystemDesc;
use crate::shadow::{self, ShadowMap};
use crate::target::{RgbaImage, Target};
use crate::volume_pass::{VolumePass, VolumeStorage};
use crate::volume_plan::{self, PlanBuffers, VolumeBand, VolumeEntry};
use crate::{Gpu, SliceParams, ViewCamera, ViewError};

mod clouds;
mod frame;

struct CloudEntry {
    gpu: GpuCloud,
    instances: Vec<Mat4>,
    /// Transition distances (one per level change) and the transition fraction.
    distances: Vec<f32>,
    transition: f32,
    /// Dissolve half-width around each switch, in octaves of distance.
    dissolve: f32,
}

/// Owns the device, the passes the content needs, and the uploaded content.
pub struct Renderer {
    pub gpu: Gpu,
    pub params: SliceParams,
    volumes: Volumes,
    mesh_pass: Option<MeshPass>,
    meshes: Vec<GpuMesh>,
    cloud_pass: Option<CloudPass>,
    clouds: Vec<CloudEntry>,
    shadows: Shadows,
    /// Light direction (towards the light) and ambient term.
    pub light_dir: Vec3,
    pub ambient: f32,
    /// Force a camera distance for LOD selection (tests); `None`: the eye's distance.
    pub lod_distance_override: Option<f32>,
    /// Force every cloud's dissolve half-width (`Some(0.0)`: levels shown alone, as the
    /// LOD sweep's coverage frames need); `None`: each cloud's own.
    pub dissolve_override: Option<f32>,
    /// Sample meshes' base-colour textures at MIP level 0 only (`false`: the MIP chain, as
    /// a viewer draws them). The chain with the hashed alpha test draws an alpha-masked
    /// mesh's coverage in expectation (docs/viewer.md, "Alpha-tested meshes at a
    /// distance"); level 0 draws it at the distances the LOD sweep's coverage reference
    /// frames use (the oak within 2 % at 1×–4×) without the hash's noise.
    pub mesh_texture_level0: bool,
    /// Leave out of each shadow cascade the casters outside its window, and flat meshes
    /// with nothing behind them from the light (a ground under the sun): on by default;
    /// off only to check that it changes nothing.
    pub shadow_culling: bool,
    /// While the camera moves, keep the tile of shadow cascade `k ≥ 1` for up to
    /// `2^k − 1` frames while its window still holds the receivers its cascade is
    /// fitted to (`shadow::window_holds`: the same texels), so the far cascades are
    /// drawn less often than the near one; what lags is the clouds' levels in the kept
    /// tiles (docs/viewer.md, "Shadows"). On by default; off (or
    /// `BILLOW_VIEW_SHADOW_KEEP=off`): a tile is kept only while nothing it depends on
    /// changed, and every frame's picture is a fresh renderer's.
    pub shadow_keep_far: bool,
    /// The cell wireframe, when on ([`Renderer::set_wireframe`]).
    lines: Option<crate::lines::LinePass>,
    /// Scene time in seconds (animated cells, particles).
    pub time: f32,
    /// Volume textures bound at once (clamped to the device's limit when the volume
    /// pass is built, on the first volume added): [`crate::volume_pass::preferred_batch`]
    /// to start with (1 on software adapters); tests set it to exercise batches.
    pub texture_batch: usize,
    particles: Particles,
    /// Textures uploaded as BC7 blocks so far (volumes, atlases, normal maps); the others
    /// of compressed assets were decoded on load ([`Gpu::block_upload`]).
    pub block_textures: u32,
}

/// The volume assets and what drawing them keeps: the pass (built with the first
/// volume), the texture batches' bind groups and the plans' buffers.
#[derive(Default)]
struct Volumes {
    pass: Option<VolumePass>,
    entries: Vec<VolumeEntry>,
    /// The volume textures' bind groups, [`Renderer::texture_batch`] textures each.
    batches: Vec<wgpu::BindGroup>,
    /// The volume plans' buffers, kept from frame to frame: the camera's, the light's
    /// (made on first use).
    plan_buffers: [RefCell<Option<PlanBuffers>>; 2],
}

/// The shadow state: what receivers bind, and the map when shadows are on.
struct Shadows {
    receiver_layout: wgpu::BindGroupLayout,
    /// 1×1 stand-in bound where no shadow map is read.
    none: ShadowMap,
    /// Shadows on ([`Renderer::set_shadows`]); the map is made by the first frame that
    /// has something to cast (a scene with shadows on and nothing to cast never makes
    /// its 2048² atlas).
    on: bool,
    map: OnceCell<ShadowMap>,
    /// What the atlas holds: what every tile depends on and, per cascade, what its tile
    /// was drawn for and counted (`frame::Atlas`); `None` after anything that changes
    /// the casters.
    drawn: RefCell<Option<frame::Atlas>>,
    /// Reuse the atlas's tiles (on by default; `BILLOW_VIEW_SHADOW_CACHE=off` turns it
    /// off to measure the cascades' cost).
    pub(crate) reuse: bool,
    /// Drawn when a frame keeps some tiles ([`shadow::tile_clear_pipeline`]).
    tile_clear: OnceCell<wgpu::RenderPipeline>,
}

impl Shadows {
    /// The casters changed (content added, a cloud's dissolve set, shadows toggled):
    /// the next frame draws the atlas again.
    fn forget(&mut self) {
        *self.drawn.get_mut() = None;
    }
}

/// The particle systems (spherical billboards), how their layer is made, its pass (only
/// when a system needs one) and its targets.
#[derive(Default)]
struct Particles {
    pass: Option<ParticlePass>,
    systems: Vec<ParticleSystemDesc>,
    layer: ParticleLayerDesc,
    /// The layer's targets, for the last frame size (made on first use).
    targets: RefCell<Option<LayerTargets>>,
}

impl Renderer {
    pub fn new(gpu: Gpu) -> Renderer {
        let receiver_layout = shadow::receiver_layout(&gpu.device);
        let none = ShadowMap::new(&gpu, &receiver_layout, 1);
        let texture_batch = crate::volume_pass::preferred_batch(&gpu);
        Renderer {
            gpu,
            params: SliceParams::default(),
            volumes: Volumes::default(),
            mesh_pass: None,
            meshes: Vec::new(),
            cloud_pass: None,
            clouds: Vec::new(),
            shadows: Shadows {
                receiver_layout,
                none,
                on: false,
                map: OnceCell::new(),
                drawn: RefCell::new(None),
                reuse: std::env::var("BILLOW_VIEW_SHADOW_CACHE").map_or(true, |v| v != "off"),
                tile_clear: OnceCell::new(),
            },
            light_dir: billow_core::shading::DEFAULT_LIGHT.normalize(),
            ambient: billow_core::shading::DEFAULT_AMBIENT,
            lod_distance_override: None,
            dissolve_override: None,
            mesh_texture_level0: false,
            shadow_culling: true,
            shadow_keep_far: std::env::var("BILLOW_VIEW_SHADOW_KEEP").map_or(true, |v| v != "off"),
            lines: None,
            time: 0.0,
            texture_batch,
            particles: Particles::default(),
            block_textures: 0,
        }
    }

    /// Sets the particle systems (spherical billboards) and how their layer is made; the
    /// LUTs, noise, targets and passes they need are built now, and only those.
    pub fn set_particles(
        &mut self,
        systems: Vec<ParticleSystemDesc>,
        layer: ParticleLayerDesc,
    ) -> Result<(), ViewError> {
        for (i, s) in systems.iter().enumerate() {
            s.validate()
                .map_err(|e| ViewError::InvalidParam(format!("particles[{i}].{e}")))?;
        }
        layer
            .validate()
            .map_err(|e| ViewError::InvalidParam(format!("particle_layer.{e}")))?;
        let needs = crate::particle_pass::ParticleNeeds::of(&systems, &layer);
        self.particles = Particles {
            pass: needs.any.then(|| ParticlePass::new(&self.gpu, needs)),
            systems,
            layer,
            targets: RefCell::new(None),
        };
        Ok(())
    }

    /// Draws the edges of every volume cell over the frame (on) or not (off).
    pub fn set_wireframe(&mut self, on: bool) {
        self.lines = on.then(|| crate::lines::LinePass::new(&self.gpu));
    }

    pub fn wireframe(&self) -> bool {
        self.lines.is_some()
    }

    pub fn shadows(&self) -> bool {
        self.shadows.on
    }

    /// What this renderer built (pipelines, bakes, the shadow map) and which passes its
    /// last frame encoded ([`crate::gpu::RenderRecord`]); tests compare it with
    /// [`Renderer::passes`] and `--print-passes`.
    pub fn record(&self) -> crate::gpu::RenderRecord {
        self.gpu.record()
    }

    /// Reads `target` back (the headless `resolve`, recorded as such).
    pub fn read(&self, target: &Target) -> Result<RgbaImage, ViewError> {
        let img = target.read(&self.gpu)?;
        self.gpu.note_pass("resolve");
        Ok(img)
    }

    /// Whether frames change with [`Renderer::time`] (particles, animated volume cells):
    /// a window showing nothing else redraws only on input.
    pub fn animated(&self) -> bool {
        self.particles.pass.is_some() || self.volumes.entries.iter().any(|v| v.animation.is_some())
    }

    /// World-space end points of every cell edge of every volume instance.
    fn cell_edges(&self) -> Vec<Vec3> {
        let mut pts = Vec::new();
        for v in &self.volumes.entries {
            for m in &v.instances {
                for c in v.bands.iter().flat_map(|b| &b.cells) {
                    for (a, b) in crate::lines::PRISM_EDGES {
                        pts.push(m.transform_point3(Vec3::from(c.pos[a])));
                        pts.push(m.transform_point3(Vec3::from(c.pos[b])));
                    }
                }
            }
        }
        pts
    }

    /// Turns shadows on (the map is made by the first frame with something to cast) or
    /// off (the map dropped).
    pub fn set_shadows(&mut self, on: bool) {
        self.shadows.forget();
        self.shadows.on = on;
        if !on {
            self.shadows.map = OnceCell::new();
        }
    }

    /// Adds a volume asset drawn once per transform in `instances` (they share its
    /// textures: the base and any LOD bands).
    pub fn add_volume(
        &mut self,
        asset: &VolumeAsset,
        instances: Vec<Mat4>,
    ) -> Result<(), ViewError> {
        self.add_animated_volume(asset, instances, None)
    }

    /// [`Renderer::add_volume`] with cells deformed over time by `animation`.
    pub fn add_animated_volume(
        &mut self,
        asset: &VolumeAsset,
        instances: Vec<Mat4>,
        animation: Option<crate::animate::Sway>,
    ) -> Result<(), ViewError> {
        self.add_volume_blocks(asset, None, instances, animation)
    }

    /// [`Renderer::add_animated_volume`] of a compressed asset with its BC7 `blocks`
    /// (format 1.2): uploaded as blocks where the device allows it, else decoded.
    pub fn add_volume_blocks(
        &mut self,
        asset: &VolumeAsset,
        blocks: Option<&billow_format::VolumeBlocks>,
        instances: Vec<Mat4>,
        animation: Option<crate::animate::Sway>,
    ) -> Result<(), ViewError> {
        check_transforms(&instances)?;
        self.shadows.forget();
        if let Some(a) = &animation {
            a.validate().map_err(ViewError::InvalidParam)?;
        }
        let pass = self.volumes.pass.get_or_insert_with(|| {
            VolumePass::new(&self.gpu, &self.shadows.receiver_layout, self.texture_batch)
        });
        let textures = pass.upload_with(&self.gpu, asset, blocks)?;
        for t in &textures {
            pass.note_storage(t.storage);
        }
        // Colour textures, and normal moments, uploaded as their BC7 blocks.
        let block_textures = textures
            .iter()
            .map(|t| usize::from(t.storage == VolumeStorage::Blocks) + usize::from(t.moments_bc))
            .sum::<usize>();
        self.block_textures += block_textures as u32;
        let first_texture: usize = self.volumes.entries.iter().map(|v| v.bands.len()).sum();
        let b = &asset.header.bounds;
        let bounds = (Vec3::from(b.min), Vec3::from(b.max));
        let mut bands = Vec::new();
        for (i, gpu) in textures.into_iter().enumerate() {
            let (cells, first_level) = match i {
                0 => (asset.cells.clone(), 0),
                _ => (
                    asset.bands[i - 1].cells.clone(),
                    asset.bands[i - 1].first_level,
                ),
            };
            // An animated single box bends only once it is cut into layers.
            let cells = match (&animation, asset.bands.is_empty()) {
                (Some(a), true) => {
                    crate::animate::layered_box(&cells, bounds, a.layers).unwrap_or(cells)
                }
                _ => cells,
            };
            bands.push(VolumeBand {
                cells,
                gpu,
                first_level,
                texture: first_texture + i,
            });
        }
        let last = bands.last().expect("a base texture");
        let max_lod = last.first_level + last.gpu.levels - 1;
        self.volumes.entries.push(VolumeEntry {
            bands,
            instances,
            max_lod,
            bounds,
            animation,
        });
        self.volumes.batches =
            volume_plan::batch_bind_groups(pass, &self.gpu, &self.volumes.entries);
        Ok(())
    }

    /// Adds an opaque triangle mesh (world space).
    pub fn add_mesh(&mut self, mesh: &MeshData) -> Result<(), ViewError> {
        let pass = self
            .mesh_pass
            .get_or_insert_with(|| MeshPass::new(&self.gpu, &self.shadows.receiver_layout));
        let m = pass.upload(&self.gpu, mesh)?;
        self.meshes.push(m);
        self.shadows.forget();
        Ok(())
    }

    /// Builds now the pipelines the next frame's passes need ([`Renderer::passes`]), which
    /// the frame would otherwise build on first use: the volume slices' with volumes, and
    /// the shadow pipelines of the meshes, clouds and volumes only when the frame has a
    /// `shadow` pass (shadows on, something to cast). Drivers that compile shaders when a
    /// pipeline is made do it here; lavapipe compiles a fragment shader at its first draw,
    /// so there the first frame still pays for it.
    pub fn prepare(&self) {
        let shadow = self.has_casters();
        if let Some(v) = &self.volumes.pass {
            if !self.volumes.entries.is_empty() {
                v.pipeline(&self.gpu);
                if shadow {
                    v.shadow_pipeline(&self.gpu);
                }
            }
        }
        if shadow {
            if let Some(m) = &self.mesh_pass {
                m.shadow_pipeline(&self.gpu);
            }
            if let Some(c) = &self.cloud_pass {
                c.shadow_pipelines(&self.gpu);
            }
        }
    }

    /// Whether anything casts into a shadow map.
    fn has_casters(&self) -> bool {
        self.passes().contains(&"shadow")
    }

    /// The passes a frame runs, in order (only those the content needs;
    /// [`crate::content::pass_list`]).
    pub fn passes(&self) -> Vec<&'static str> {
        crate::content::pass_list(crate::content::Needs {
            meshes: !self.meshes.is_empty(),
            clouds: !self.clouds.is_empty(),
            volumes: !self.volumes.entries.is_empty(),
            shadows: self.shadows.on,
            animated: self.volumes.entries.iter().any(|v| v.animation.is_some()),
            particles: self
                .particles
                .pass
                .as_ref()
                .map_or(Default::default(), |p| p.needs),
        })
    }

    /// Bounds of all content (world space, min and max), for the shadow camera; a unit
    /// box around the origin when there is none.
    pub fn content_bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in &self.volumes.entries {
            for m in &v.instances {
                for c in v.bands.iter().flat_map(|b| &b.cells) {
                    for p in &c.pos {
                        let q = m.transform_point3(Vec3::from(*p));
                        lo = lo.min(q);
                        hi = hi.max(q);
                    }
                }
            }
        }
        for c in &self.clouds {
            for m in &c.instances {
                let q = m.transform_point3(c.gpu.centre);
                let r = c.gpu.radius * m.x_axis.truncate().length();
                lo = lo.min(q - Vec3::splat(r));
                hi = hi.max(q + Vec3::splat(r));
            }
        }
        for m in &self.meshes {
            lo = lo.min(m.bounds.0);
            hi = hi.max(m.bounds.1);
        }
        if !(lo.x <= hi.x) {
            return (Vec3::splat(-1.0), Vec3::ONE);
        }
        (lo, hi)
    }

    /// Whether anything of the scene may lie on the far side of the plane `(n, d)` from
    /// the light (`towards` it), where a flat caster in that plane could shadow it: the
    /// corners of every mesh's bounds and of every cloud instance's caster box, and every
    /// volume cell's corners, within 1e-4 of the scene's extent. A plane the light grazes,
    /// or any animated volume, counts as something behind it.
    pub(crate) fn behind_plane(&self, (n, d): (Vec3, f32), towards: Vec3) -> bool {
        let side = n.dot(towards);
        // Animated cells move off the positions tested here.
        if side.abs() < 1e-6 || self.volumes.entries.iter().any(|v| v.animation.is_some()) {
            return true;
        }
        let (lo, hi) = self.content_bounds();
        let tol = 1e-4 * (hi - lo).length();
        let behind = |p: Vec3| side.signum() * (n.dot(p) - d) < -tol;
        let corners = |(a, b): (Vec3, Vec3)| {
            (0..8).map(move |i| {
                Vec3::new(
                    if i & 1 == 0 { a.x } else { b.x },
                    if i & 2 == 0 { a.y } else { b.y },
                    if i & 4 == 0 { a.z } else { b.z },
                )
            })
        };
        self.meshes.iter().any(|m| corners(m.bounds).any(behind))
            || self.clouds.iter().any(|c| {
                c.instances
                    .iter()
                    .any(|m| corners(c.gpu.caster_box).any(|p| behind(m.transform_point3(p))))
            })
            || self.volumes.entries.iter().any(|v| {
                v.instances.iter().any(|m| {
                    v.bands
                        .iter()
                        .flat_map(|b| &b.cells)
                        .flat_map(|c| &c.pos)
                        .any(|p| behind(m.transform_point3(Vec3::from(*p))))
                })
            })
    }

    /// Renders into a new target and reads it back.
    pub fn render_image(&self, camera: &ViewCamera) -> Result<(RgbaImage, FrameStats), ViewError> {
        camera.validate()?;
        let target = Target::new(&self.gpu, camera.width, camera.height);
        let stats = self.render(&target, camera)?;
        Ok((self.read(&target)?, stats))
    }
}

fn check_transforms(m: &[Mat4]) -> Result<(), ViewError> {
    if !m.iter().all(|m| m.is_finite()) {
        return Err(ViewError::InvalidParam(
            "instance transform is not finite".into(),
        ));
    }
    Ok(())
}

/// Level-change distances when a scene gives none: with `Z₀ = R / tan(fov/2)` (the
/// distance at which the cloud's bounding sphere fills the view, Lacewell §4), the
/// foliage mesh is shown up to `2 Z₀` and each billboard level to twice the distance
/// of the one before.
pub fn default_lod_distances(radius: f32, fov_y: f32, levels: usize) -> Vec<f32> {
    let z0 = radius.max(1e-6) / (0.5 * fov_y).tan().max(1e-6);
    (0..levels.saturating_sub(1))
        .map(|k| z0 * 2f32.powi(k as i32 + 1))
        .collect()
}
