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

use billow_format::{Prism, VolumeAsset};
use glam::{Mat4, Vec3};

use crate::cloud_pass::{CloudFrame, CloudPass, GpuCloud, View};
use crate::mesh_pass::{GpuMesh, MeshData, MeshFrame, MeshPass};
use crate::shadow::{self, ShadowMap, SHADOW_MAP_SIZE};
use crate::target::{RgbaImage, Target};
use crate::volume_pass::{GpuVolume, VolumePass};
use crate::volume_plan::{self, PlanBuffers, VolumePlan};
use crate::{Gpu, SliceParams, ViewCamera, ViewError};

mod clouds;

/// Vertices per cell × slice instance: a fan of 3 triangles covers the ≤ 5-gon.
pub const VERTICES_PER_INSTANCE: u32 = 9;

/// What a frame drew.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub slices: usize,
    /// Slabs drawn, and slabs skipped because no cell meets them.
    pub slabs: usize,
    pub empty_slabs: usize,
    /// Cells of all volume instances.
    pub cells: usize,
    /// Cell × slice instances drawn (each up to a pentagon).
    pub instances: u64,
    pub draw_calls: usize,
    pub mesh_triangles: usize,
    /// World size of a level-0 voxel `v₀` (the finest over the volumes).
    pub voxel_size: f32,
    pub min_spacing: f32,
    pub max_spacing: f32,
    /// Per cloud instance: its level (0 = foliage mesh) and morph factor.
    pub cloud_lods: Vec<(usize, f32)>,
    /// Per cloud instance: how far it has dissolved into the next level (0: not
    /// dissolving; `cloud_pass` module docs).
    pub cloud_dissolves: Vec<f32>,
    /// Slices of the volumes' shadow pass (0 without shadows).
    pub shadow_slices: usize,
    /// Billboard quads (sides) drawn.
    pub cloud_quads: usize,
    /// Bytes written to the GPU per frame for the clouds (instance data and frame
    /// uniforms; the per-asset buffers are uploaded once).
    pub cloud_bytes_uploaded: usize,
    /// Particles drawn (at the frame's time).
    pub particles: usize,
}

/// One texture of a volume asset and the cells that sample it: band 0 is the base, the
/// others are its LOD bands (SPEC §8.6).
pub struct VolumeBand {
    /// Object space.
    pub cells: Vec<Prism>,
    pub gpu: GpuVolume,
    /// The slice LOD from which this band is drawn.
    pub first_level: u32,
    /// Index among all volume textures (batch `texture / 8`, slot `texture % 8`).
    pub texture: usize,
}

/// A volume asset on the GPU with its instance transforms.
pub struct VolumeEntry {
    pub bands: Vec<VolumeBand>,
    pub instances: Vec<Mat4>,
    /// The asset's largest LOD `L` (the last band's `first_level + mip_count − 1`).
    pub max_lod: u32,
    /// Object-space bounds (the asset header's).
    pub bounds: (Vec3, Vec3),
    pub animation: Option<crate::animate::Sway>,
}

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
    volume_pass: Option<VolumePass>,
    volumes: Vec<VolumeEntry>,
    batches: Vec<wgpu::BindGroup>,
    mesh_pass: Option<MeshPass>,
    meshes: Vec<GpuMesh>,
    cloud_pass: Option<CloudPass>,
    clouds: Vec<CloudEntry>,
    receiver_layout: wgpu::BindGroupLayout,
    /// 1×1 stand-in bound where no shadow map is read.
    no_shadow: ShadowMap,
    /// Shadows on ([`Renderer::set_shadows`]); the map is made by the first frame that
    /// has something to cast (a scene with shadows on and nothing to cast never makes
    /// its 2048² atlas).
    shadows_on: bool,
    shadow_map: std::cell::OnceCell<ShadowMap>,
    /// Light direction (towards the light) and ambient term.
    pub light_dir: Vec3,
    pub ambient: f32,
    /// Force a camera distance for LOD selection (tests); `None`: the eye's distance.
    pub lod_distance_override: Option<f32>,
    /// Force every cloud's dissolve half-width (`Some(0.0)`: levels shown alone, as the
    /// LOD sweep's coverage frames need); `None`: each cloud's own.
    pub dissolve_override: Option<f32>,
    /// The cell wireframe, when on ([`Renderer::set_wireframe`]).
    lines: Option<crate::lines::LinePass>,
    /// Scene time in seconds (animated cells, particles).
    pub time: f32,
    /// Volume textures bound at once (clamped to the device's limit when the volume
    /// pass is built, on the first volume added); tests lower it to exercise batches.
    pub texture_batch: usize,
    particle_pass: Option<crate::particle_pass::ParticlePass>,
    particles: Vec<crate::particles::ParticleSystemDesc>,
    particle_layer: crate::particle_pass::ParticleLayerDesc,
    /// The particle layer's targets, for the last frame size (made on first use).
    layer_targets: std::cell::RefCell<Option<crate::particle_pass::LayerTargets>>,
    /// Textures uploaded as BC7 blocks so far (volumes, atlases, normal maps); the others
    /// of compressed assets were decoded on load ([`Gpu::block_upload`]).
    pub block_textures: u32,
    /// The volume plans' buffers, kept from frame to frame: the camera's, the light's
    /// (made on first use).
    plan_buffers: [std::cell::RefCell<Option<PlanBuffers>>; 2],
}

/// Which view a volume plan is for (its [`PlanBuffers`]).
#[derive(Clone, Copy)]
enum PlanView {
    Camera = 0,
    Light = 1,
}

impl Renderer {
    pub fn new(gpu: Gpu) -> Renderer {
        let receiver_layout = shadow::receiver_layout(&gpu.device);
        let no_shadow = ShadowMap::new(&gpu, &receiver_layout, 1);
        Renderer {
            gpu,
            params: SliceParams::default(),
            volume_pass: None,
            volumes: Vec::new(),
            batches: Vec::new(),
            mesh_pass: None,
            meshes: Vec::new(),
            cloud_pass: None,
            clouds: Vec::new(),
            receiver_layout,
            no_shadow,
            shadows_on: false,
            shadow_map: std::cell::OnceCell::new(),
            light_dir: Vec3::new(0.3, 1.0, 0.5).normalize(),
            ambient: 0.3,
            lod_distance_override: None,
            dissolve_override: None,
            lines: None,
            time: 0.0,
            texture_batch: crate::volume_pass::MAX_TEXTURES_PER_BATCH,
            particle_pass: None,
            particles: Vec::new(),
            particle_layer: Default::default(),
            layer_targets: std::cell::RefCell::new(None),
            block_textures: 0,
            plan_buffers: Default::default(),
        }
    }

    /// Sets the particle systems (spherical billboards) and how their layer is made; the
    /// LUTs, noise, targets and passes they need are built now, and only those.
    pub fn set_particles(
        &mut self,
        systems: Vec<crate::particles::ParticleSystemDesc>,
        layer: crate::particle_pass::ParticleLayerDesc,
    ) -> Result<(), ViewError> {
        for (i, s) in systems.iter().enumerate() {
            s.validate()
                .map_err(|e| ViewError::InvalidParam(format!("particles[{i}].{e}")))?;
        }
        layer
            .validate()
            .map_err(|e| ViewError::InvalidParam(format!("particle_layer.{e}")))?;
        let needs = crate::particle_pass::ParticleNeeds::of(&systems, &layer);
        self.particle_pass = needs
            .any
            .then(|| crate::particle_pass::ParticlePass::new(&self.gpu, needs));
        self.particles = systems;
        self.particle_layer = layer;
        *self.layer_targets.borrow_mut() = None;
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
        self.shadows_on
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
        self.particle_pass.is_some() || self.volumes.iter().any(|v| v.animation.is_some())
    }

    /// World-space end points of every cell edge of every volume instance.
    fn cell_edges(&self) -> Vec<Vec3> {
        let mut pts = Vec::new();
        for v in &self.volumes {
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
        self.shadows_on = on;
        if !on {
            self.shadow_map = std::cell::OnceCell::new();
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
        if let Some(a) = &animation {
            a.validate().map_err(ViewError::InvalidParam)?;
        }
        let pass = self.volume_pass.get_or_insert_with(|| {
            VolumePass::new(&self.gpu, &self.receiver_layout, self.texture_batch)
        });
        let textures = pass.upload_with(&self.gpu, asset, blocks)?;
        self.block_textures += textures.iter().filter(|t| t.blocks).count() as u32;
        let first_texture: usize = self.volumes.iter().map(|v| v.bands.len()).sum();
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
        self.volumes.push(VolumeEntry {
            bands,
            instances,
            max_lod,
            bounds,
            animation,
        });
        self.batches = volume_plan::batch_bind_groups(pass, &self.gpu, &self.volumes);
        Ok(())
    }

    /// Adds an opaque triangle mesh (world space).
    pub fn add_mesh(&mut self, mesh: &MeshData) -> Result<(), ViewError> {
        let pass = self
            .mesh_pass
            .get_or_insert_with(|| MeshPass::new(&self.gpu, &self.receiver_layout));
        let m = pass.upload(&self.gpu, mesh)?;
        self.meshes.push(m);
        Ok(())
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
            volumes: !self.volumes.is_empty(),
            shadows: self.shadows_on,
            animated: self.volumes.iter().any(|v| v.animation.is_some()),
            particles: self
                .particle_pass
                .as_ref()
                .map_or(Default::default(), |p| p.needs),
        })
    }

    /// Bounds of all content (world space, min and max), for the shadow camera; a unit
    /// box around the origin when there is none.
    pub fn content_bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in &self.volumes {
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

    /// Renders one frame into `target` (submitted, not waited for).
    pub fn render(&self, target: &Target, camera: &ViewCamera) -> Result<FrameStats, ViewError> {
        camera.validate()?;
        self.params.validate()?;
        if camera.width != target.width || camera.height != target.height {
            return Err(ViewError::InvalidParam(format!(
                "camera is {}x{} but the target is {}x{}",
                camera.width, camera.height, target.width, target.height
            )));
        }
        let mut stats = FrameStats::default();
        self.gpu.note_frame_start();
        let device = &self.gpu.device;
        let levels = self.cloud_levels(camera);
        stats.cloud_lods = levels.iter().map(|l| (l.level, l.morph)).collect();
        stats.cloud_dissolves = levels.iter().map(|l| l.dissolve).collect();
        let cloud_draws = self.cloud_draws(&levels);
        // The instance data serves the shadow and the main pass (it does not depend on
        // the view): written once, before anything is encoded.
        let cloud_frame = self
            .cloud_pass
            .as_ref()
            .map(|p| p.frame(&self.gpu, &cloud_draws));
        if let Some(cf) = &cloud_frame {
            stats.cloud_quads = cf.quads;
            stats.cloud_bytes_uploaded = cf.bytes_uploaded;
        }
        let mut enc = device.create_command_encoder(&Default::default());

        // 1. Shadow map.
        let shadow = match self.shadows_on && self.has_casters() {
            true => {
                let map = self.shadow_map.get_or_init(|| {
                    self.gpu.note_built("texture:shadow-map");
                    ShadowMap::new(&self.gpu, &self.receiver_layout, SHADOW_MAP_SIZE)
                });
                let cs = shadow::cascades(self.light_dir, camera, self.content_bounds(), map.size);
                self.gpu
                    .queue
                    .write_buffer(&map.cascades, 0, bytemuck::bytes_of(&cs.uniform));
                // One submission per cascade: the light's uniforms and volume plan are
                // written again for each (writes land before the next submission).
                for (k, light) in cs.cameras.iter().enumerate() {
                    let mut senc = device.create_command_encoder(&Default::default());
                    self.shadow_pass(&mut senc, map, k, light, cloud_frame.as_ref(), &mut stats)?;
                    self.gpu.queue.submit([senc.finish()]);
                }
                Some((map, cs.base))
            }
            false => None,
        };
        let receiver = shadow.map_or(&self.no_shadow.bind_group, |(m, _)| &m.bind_group);
        let world_to_shadow = shadow.map(|(_, l)| {
            (
                l.projection() * l.view,
                shadow::depth_bias(&l),
                shadow::view_to_shadow(camera, &l),
            )
        });

        // 2–4. Meshes, clouds, volumes.
        let plan = self.plan(
            PlanView::Camera,
            camera,
            self.params,
            world_to_shadow.map(|w| (w.2, w.1)),
            None,
        )?;
        if let Some(p) = &plan {
            p.fill_stats(&mut stats);
        }
        let mesh_frame = MeshFrame {
            view_proj: (camera.projection() * camera.view).to_cols_array_2d(),
            world_to_shadow: world_to_shadow
                .map_or(Mat4::IDENTITY, |w| w.0)
                .to_cols_array_2d(),
            light: {
                let l = self.light_dir.normalize_or(Vec3::Y);
                [l.x, l.y, l.z, self.ambient.clamp(0.0, 1.0)]
            },
            flags: [
                f32::from(u8::from(shadow.is_some())),
                0.0,
                world_to_shadow.map_or(0.0, |w| w.1),
                0.0,
            ],
        };
        let mesh_bind = self
            .mesh_pass
            .as_ref()
            .map(|p| p.frame_bind_group(&self.gpu, View::Camera, &mesh_frame));
        let cloud_bind = self.cloud_pass.as_ref().map(|p| {
            stats.cloud_bytes_uploaded += std::mem::size_of::<MeshFrame>();
            p.frame_bind_group(&self.gpu, View::Camera, &mesh_frame)
        });
        // With particles the opaque + volume image goes to the layer's scene target and
        // the composite writes the frame.
        if let Some(pp) = &self.particle_pass {
            let mut lt = self.layer_targets.borrow_mut();
            let div = self.particle_layer.resolution.divisor();
            if lt
                .as_ref()
                .is_none_or(|t| t.size != (target.width, target.height))
            {
                *lt = Some(pp.targets(&self.gpu, target.width, target.height, div));
            }
        }
        let layer_targets = self.layer_targets.borrow();
        let scene_view = match (&self.particle_pass, layer_targets.as_ref()) {
            (Some(_), Some(t)) => &t.scene,
            _ => &target.color_view,
        };
        {
            let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("frame"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: scene_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(depth_attachment(&target.depth_view)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(pass), Some(bind)) = (&self.mesh_pass, mesh_bind) {
                if !self.meshes.is_empty() {
                    self.gpu.note_pass("mesh");
                }
                for m in &self.meshes {
                    stats.mesh_triangles += m.triangles as usize;
                    stats.draw_calls += pass.draw(&mut rp, bind, receiver, m, false);
                }
            }
            if let (Some(pass), Some(bind), Some(cf)) = (&self.cloud_pass, cloud_bind, &cloud_frame)
            {
                self.gpu.note_pass("cloud");
                stats.draw_calls += pass.draw(&mut rp, bind, receiver, cf, false);
            }
        }
        if plan.is_some() || self.lines.is_some() {
            // The slices read the opaque depth (they fade at it), so it is attached
            // read-only from here on.
            let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("frame volumes"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: scene_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(pass), Some(plan)) = (&self.volume_pass, &plan) {
                let depth = target
                    .scene_depth
                    .get_or_init(|| pass.depth_bind_group(&self.gpu, &target.depth_view));
                rp.set_bind_group(3, depth, &[]);
                self.gpu.note_pass("volume");
                stats.draw_calls += plan.draw(&mut rp, &pass.pipeline, &self.batches, receiver);
            }
            if let Some(lines) = &self.lines {
                let vp = camera.projection() * camera.view;
                let pts = self.cell_edges();
                stats.draw_calls += lines.draw(&self.gpu, &mut rp, vp, &pts, [1.0, 0.85, 0.1, 1.0]);
            }
        }
        if let (Some(pp), Some(t)) = (&self.particle_pass, layer_targets.as_ref()) {
            let (n, draws) = pp.render(
                &self.gpu,
                &mut enc,
                &self.particles,
                &self.particle_layer,
                camera,
                (self.light_dir, self.ambient),
                self.time,
                &target.depth_view,
                t,
                &target.color_view,
            );
            stats.particles = n;
            stats.draw_calls += draws;
        }
        self.gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    /// Cascade `k` of the light's depth atlas (its tile; cascade 0 clears the atlas):
    /// meshes, clouds (at the levels the viewer shows), volumes sliced from the light with
    /// [`shadow::SHADOW_SPACING_BIAS`]× the spacing.
    fn shadow_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        map: &ShadowMap,
        k: usize,
        light: &ViewCamera,
        clouds: Option<&CloudFrame<'_>>,
        stats: &mut FrameStats,
    ) -> Result<(), ViewError> {
        let mut params = self.params;
        params.spacing = params.spacing.scaled(shadow::SHADOW_SPACING_BIAS);
        let plan = self.plan(
            PlanView::Light,
            light,
            params,
            None,
            Some(shadow::SHADOW_ALPHA_CUTOFF),
        )?;
        stats.shadow_slices += plan.as_ref().map_or(0, |p| p.slice_count());
        let frame = MeshFrame {
            view_proj: (light.projection() * light.view).to_cols_array_2d(),
            world_to_shadow: Mat4::IDENTITY.to_cols_array_2d(),
            light: [0.0, 1.0, 0.0, 1.0],
            flags: [0.0; 4],
        };
        let none = &self.no_shadow.bind_group;
        let mut depth = depth_attachment(&map.view);
        if k > 0 {
            depth.depth_ops = Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            });
        }
        self.gpu.note_pass("shadow");
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow"),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let (x, y, side) = shadow::tile_rect(k, map.size);
        rp.set_viewport(x as f32, y as f32, side as f32, side as f32, 0.0, 1.0);
        rp.set_scissor_rect(x, y, side, side);
        if let Some(pass) = &self.mesh_pass {
            let bind = pass.frame_bind_group(&self.gpu, View::Light, &frame);
            for m in &self.meshes {
                pass.draw(&mut rp, bind, none, m, true);
            }
        }
        if let (Some(pass), Some(cf)) = (&self.cloud_pass, clouds) {
            let bind = pass.frame_bind_group(&self.gpu, View::Light, &frame);
            stats.cloud_bytes_uploaded += std::mem::size_of::<MeshFrame>();
            pass.draw(&mut rp, bind, none, cf, true);
        }
        if let (Some(pass), Some(plan)) = (&self.volume_pass, &plan) {
            plan.draw(&mut rp, &pass.shadow_pipeline, &self.batches, none);
        }
        Ok(())
    }

    /// The volume plan for `camera` (cells in camera space, slices, slabs, draws),
    /// written into `view`'s buffers.
    fn plan(
        &self,
        view: PlanView,
        camera: &ViewCamera,
        params: SliceParams,
        shadow: Option<(Mat4, f32)>,
        shadow_cutoff: Option<f32>,
    ) -> Result<Option<VolumePlan>, ViewError> {
        let Some(pass) = &self.volume_pass else {
            return Ok(None);
        };
        let mut bufs = self.plan_buffers[view as usize].borrow_mut();
        let bufs = bufs.get_or_insert_with(|| PlanBuffers::new(&self.gpu));
        volume_plan::plan(
            &self.gpu,
            pass,
            bufs,
            &self.volumes,
            camera,
            params,
            (self.light_dir, self.ambient),
            shadow,
            shadow_cutoff,
            self.time,
        )
    }

    /// Renders into a new target and reads it back.
    pub fn render_image(&self, camera: &ViewCamera) -> Result<(RgbaImage, FrameStats), ViewError> {
        camera.validate()?;
        let target = Target::new(&self.gpu, camera.width, camera.height);
        let stats = self.render(&target, camera)?;
        Ok((self.read(&target)?, stats))
    }
}

fn depth_attachment(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
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
