//! One frame of the [`Renderer`], pass by pass (the order of the `render` module docs):
//! the clouds' instances, the `shadow` cascades, the frame uniforms, the opaque pass
//! (`mesh`, `cloud`), the `volume` pass (and the wireframe), the particle layer and its
//! composite. Each pass is a method; [`Renderer::render`] calls them in order.

use std::cell::Ref;

use glam::{Mat4, Vec3};

use super::{FrameStats, Renderer};
use crate::cloud_pass::{CloudFrame, LodChoice};
use crate::frame_stats::CascadeStats;
use crate::mesh_pass::{MeshFrame, View};
use crate::particle_pass::LayerTargets;
use crate::shadow::{self, ShadowMap, SHADOW_MAP_SIZE};
use crate::target::Target;
use crate::volume_plan::{self, PlanBuffers, VolumePlan};
use crate::{SliceParams, ViewCamera, ViewError};

/// Which view a volume plan is for (its [`PlanBuffers`]).
#[derive(Clone, Copy)]
enum PlanView {
    Camera = 0,
    Light = 1,
}

/// The shadow a frame's colour passes receive: the map and the light camera of its
/// cascades.
type Shadow<'a> = Option<(&'a ShadowMap, ViewCamera)>;

/// The camera's shadow lookup: world to shadow clip space, the depth bias and view to
/// shadow clip space.
type ShadowLookup = Option<(Mat4, f32, Mat4)>;

/// What the colour passes of one frame share.
struct ColourPass<'a> {
    target: &'a Target,
    camera: &'a ViewCamera,
    /// Where the opaque and volume passes draw: the target, or with particles the
    /// layer's scene image (the composite then writes the target).
    scene_view: &'a wgpu::TextureView,
    /// The shadow map's bind group, or the 1×1 stand-in.
    receiver: &'a wgpu::BindGroup,
}

/// What every tile of the shadow atlas depends on that may change from frame to frame
/// (the content itself only changes through `&mut` methods, which forget the atlas):
/// the light, the slicing parameters, the culling switch, the batch size, the scene
/// time where cells are animated, and the number of cascades.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct ShadowKey {
    light_dir: Vec3,
    params: SliceParams,
    culling: bool,
    texture_batch: usize,
    time: Option<f32>,
    cascades: usize,
}

/// One cascade's tile as drawn: its light camera (texel-snapped, so a camera that moves
/// a little may keep the far ones), every cloud instance's level, morph and dissolve,
/// and what it counted (reported again by the frames that keep it).
#[derive(Clone, Debug)]
pub(super) struct Tile {
    camera: ViewCamera,
    levels: Vec<LodChoice>,
    stats: CascadeStats,
}

/// What the atlas holds: the key its tiles share, and each cascade's tile.
#[derive(Clone, Debug)]
pub(super) struct Atlas {
    key: ShadowKey,
    tiles: Vec<Tile>,
}

impl Renderer {
    /// Renders one frame into `target` (submitted, not waited for).
    pub fn render(&self, target: &Target, camera: &ViewCamera) -> Result<FrameStats, ViewError> {
        self.check_frame(target, camera)?;
        let mut stats = FrameStats::default();
        self.gpu.note_frame_start();
        let (cloud_frame, levels) = self.cloud_frame(camera, &mut stats);
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());

        // 1. Shadow map.
        let clouds = (cloud_frame.as_ref(), levels);
        let shadow = self.shadow_cascades(camera, clouds, &mut stats)?;
        let receiver = shadow.map_or(&self.shadows.none.bind_group, |(m, _)| &m.bind_group);
        let lookup: ShadowLookup = shadow.map(|(_, l)| {
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
            lookup.map(|w| (w.2, w.1)),
            None,
        )?;
        if let Some(p) = &plan {
            p.fill_stats(&mut stats);
        }
        let frame = self.frame_uniforms(camera, shadow.is_some(), lookup);
        let mesh_bind = self
            .mesh_pass
            .as_ref()
            .map(|p| p.frame_bind_group(&self.gpu, View::Camera, &frame));
        let cloud_bind = self.cloud_pass.as_ref().map(|p| {
            stats.cloud_bytes_uploaded += std::mem::size_of::<MeshFrame>();
            p.frame_bind_group(&self.gpu, View::Camera, &frame)
        });
        let layer_targets = self.layer_targets(target);
        let scene_view = match (&self.particles.pass, layer_targets.as_ref()) {
            (Some(_), Some(t)) => &t.scene,
            _ => &target.color_view,
        };
        let pass = ColourPass {
            target,
            camera,
            scene_view,
            receiver,
        };
        let opaque = (mesh_bind, cloud_bind, cloud_frame.as_ref());
        self.opaque_pass(&mut enc, &pass, opaque, &mut stats);
        self.volume_pass(&mut enc, &pass, plan.as_ref(), &mut stats);
        if let Some(t) = layer_targets.as_ref() {
            self.particle_pass(&mut enc, &pass, t, &mut stats);
        }
        self.gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    /// The camera, the slicing parameters and the target's size agree.
    fn check_frame(&self, target: &Target, camera: &ViewCamera) -> Result<(), ViewError> {
        camera.validate()?;
        self.params.validate()?;
        if camera.width != target.width || camera.height != target.height {
            return Err(ViewError::InvalidParam(format!(
                "camera is {}x{} but the target is {}x{}",
                camera.width, camera.height, target.width, target.height
            )));
        }
        Ok(())
    }

    /// The clouds' levels for `camera` (returned, and into `stats`) and their instance
    /// data, which serves the shadow and the main pass (it does not depend on the view):
    /// written once, before anything is encoded.
    fn cloud_frame(
        &self,
        camera: &ViewCamera,
        stats: &mut FrameStats,
    ) -> (Option<CloudFrame<'_>>, Vec<LodChoice>) {
        let levels = self.cloud_levels(camera);
        stats.cloud_lods = levels.iter().map(|l| (l.level, l.morph)).collect();
        stats.cloud_dissolves = levels.iter().map(|l| l.dissolve).collect();
        let cloud_draws = self.cloud_draws(&levels);
        let cloud_frame = self
            .cloud_pass
            .as_ref()
            .map(|p| p.frame(&self.gpu, &cloud_draws));
        if let Some(cf) = &cloud_frame {
            stats.cloud_quads = cf.quads;
            stats.cloud_bytes_uploaded = cf.bytes_uploaded;
        }
        (cloud_frame, levels)
    }

    /// With shadows on and something to cast: the cascades fitted to `camera`, one
    /// submission each (the light's uniforms and volume plan are written again for each;
    /// writes land before the next submission). Returns the map and the light camera.
    /// When nothing the atlas depends on changed since it was drawn ([`ShadowKey`]: a
    /// still camera and light, no animated cells, no cloud changing level), it is reused
    /// and only its counts are reported again.
    fn shadow_cascades(
        &self,
        camera: &ViewCamera,
        (clouds, levels): (Option<&CloudFrame<'_>>, Vec<LodChoice>),
        stats: &mut FrameStats,
    ) -> Result<Shadow<'_>, ViewError> {
        if !(self.shadows.on && self.has_casters()) {
            return Ok(None);
        }
        let map = self.shadows.map.get_or_init(|| {
            self.gpu.note_built("texture:shadow-map");
            ShadowMap::new(&self.gpu, &self.shadows.receiver_layout, SHADOW_MAP_SIZE)
        });
        let cs = shadow::cascades(self.light_dir, camera, self.content_bounds(), map.size);
        let key = ShadowKey {
            light_dir: self.light_dir,
            params: self.params,
            culling: self.shadow_culling,
            texture_batch: self.texture_batch,
            time: self
                .volumes
                .entries
                .iter()
                .any(|v| v.animation.is_some())
                .then_some(self.time),
            cascades: cs.cameras.len(),
        };
        let mut drawn = self.shadows.drawn.borrow_mut();
        let old = drawn
            .take()
            .filter(|a| self.shadows.reuse && a.key == key)
            .map_or_else(Vec::new, |a| a.tiles);
        // Per cascade: its tile kept from an earlier frame, or `None` (drawn now).
        let kept: Vec<Option<Tile>> = cs
            .cameras
            .iter()
            .enumerate()
            .map(|(k, fitted)| {
                let t = old.get(k)?;
                let mut t = t.clone();
                t.stats.drawn = false;
                if t.camera == *fitted && t.levels == levels {
                    // What this frame would draw.
                    t.stats.age = 0;
                    return Some(t);
                }
                let young = t.stats.age + 1 < 1 << k.min(16);
                (self.shadow_keep_far
                    && k > 0
                    && young
                    && shadow::window_holds(&t.camera, fitted, &cs.receivers[k]))
                .then(|| {
                    t.stats.age += 1;
                    t
                })
            })
            .collect();
        let all_drawn = kept.iter().all(Option::is_none);
        let cameras: Vec<ViewCamera> = kept
            .iter()
            .zip(&cs.cameras)
            .map(|(t, fitted)| t.as_ref().map_or(*fitted, |t| t.camera))
            .collect();
        // The receivers' map from the base camera (fitted to the whole view, not part of
        // the key) to each cascade: written every frame.
        let uniform = if kept.iter().any(Option::is_some) {
            shadow::cascade_uniform(&cs.base, &cameras)
        } else {
            cs.uniform
        };
        self.gpu
            .queue
            .write_buffer(&map.cascades, 0, bytemuck::bytes_of(&uniform));
        let mut tiles = Vec::with_capacity(kept.len());
        for (k, t) in kept.into_iter().enumerate() {
            let tile = match t {
                Some(t) => t,
                None => {
                    let light = &cameras[k];
                    let mut senc = self.gpu.device.create_command_encoder(&Default::default());
                    // With every tile drawn the first clears the atlas; else each clears
                    // its own.
                    let clear = if all_drawn && k == 0 {
                        Clear::Atlas
                    } else if all_drawn {
                        Clear::None
                    } else {
                        Clear::Tile
                    };
                    let cascade = (k, light, clear);
                    let counts = self.shadow_pass(&mut senc, map, cascade, clouds, stats)?;
                    self.gpu.queue.submit([senc.finish()]);
                    Tile {
                        camera: *light,
                        levels: levels.clone(),
                        stats: counts,
                    }
                }
            };
            stats.shadow_slices += tile.stats.slices;
            stats.shadow_casters += tile.stats.casters;
            stats.shadow_casters_culled += tile.stats.culled;
            stats.shadow_cascades.push(tile.stats.clone());
            tiles.push(tile);
        }
        stats.shadow_reused = !tiles.iter().any(|t| t.stats.drawn);
        *drawn = Some(Atlas { key, tiles });
        Ok(Some((map, cs.base)))
    }

    /// The camera's frame uniforms of the mesh and cloud passes (`shadowed`: a shadow map
    /// is bound, looked up with `lookup`).
    fn frame_uniforms(
        &self,
        camera: &ViewCamera,
        shadowed: bool,
        lookup: ShadowLookup,
    ) -> MeshFrame {
        MeshFrame {
            view_proj: (camera.projection() * camera.view).to_cols_array_2d(),
            world_to_shadow: lookup.map_or(Mat4::IDENTITY, |w| w.0).to_cols_array_2d(),
            light: {
                let l = self.light_dir.normalize_or(Vec3::Y);
                [l.x, l.y, l.z, self.ambient.clamp(0.0, 1.0)]
            },
            flags: [
                f32::from(u8::from(shadowed)),
                f32::from(u8::from(self.mesh_texture_level0)),
                lookup.map_or(0.0, |w| w.1),
                0.0,
            ],
        }
    }

    /// The particle layer's targets for `target`'s size (remade when it changed; none
    /// without particles).
    fn layer_targets(&self, target: &Target) -> Ref<'_, Option<LayerTargets>> {
        if let Some(pp) = &self.particles.pass {
            let mut lt = self.particles.targets.borrow_mut();
            let div = self.particles.layer.resolution.divisor();
            if lt
                .as_ref()
                .is_none_or(|t| t.size != (target.width, target.height))
            {
                *lt = Some(pp.targets(&self.gpu, target.width, target.height, div));
            }
        }
        self.particles.targets.borrow()
    }

    /// Passes 2–3: opaque meshes and clouds with depth write (cleared first): `binds` are the
    /// mesh and cloud passes' frame bind groups and the clouds' instances.
    fn opaque_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        f: &ColourPass<'_>,
        binds: (
            Option<&wgpu::BindGroup>,
            Option<&wgpu::BindGroup>,
            Option<&CloudFrame<'_>>,
        ),
        stats: &mut FrameStats,
    ) {
        let (mesh_bind, cloud_bind, cloud_frame) = binds;
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("frame"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: f.scene_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(depth_attachment(&f.target.depth_view)),
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
                stats.draw_calls += pass.draw(&self.gpu, &mut rp, bind, f.receiver, m, false);
            }
        }
        if let (Some(pass), Some(bind), Some(cf)) = (&self.cloud_pass, cloud_bind, cloud_frame) {
            self.gpu.note_pass("cloud");
            stats.draw_calls += pass.draw(&self.gpu, &mut rp, bind, f.receiver, cf, false);
        }
    }

    /// Pass 4: the volumes' slices (`plan`) and the cell wireframe, over the opaque image.
    /// The slices read the opaque depth (they fade at it), so it is attached read-only
    /// from here on. No pass without either.
    fn volume_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        f: &ColourPass<'_>,
        plan: Option<&VolumePlan>,
        stats: &mut FrameStats,
    ) {
        if plan.is_none() && self.lines.is_none() {
            return;
        }
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("frame volumes"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: f.scene_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &f.target.depth_view,
                depth_ops: None,
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if let (Some(pass), Some(plan)) = (&self.volumes.pass, plan) {
            let depth = f
                .target
                .scene_depth
                .get_or_init(|| pass.depth_bind_group(&self.gpu, &f.target.depth_view));
            rp.set_bind_group(3, depth, &[]);
            self.gpu.note_pass("volume");
            stats.draw_calls += plan.draw(
                &mut rp,
                pass.pipeline(&self.gpu),
                &self.volumes.batches,
                f.receiver,
            );
        }
        if let Some(lines) = &self.lines {
            let vp = f.camera.projection() * f.camera.view;
            let pts = self.cell_edges();
            stats.draw_calls += lines.draw(&self.gpu, &mut rp, vp, &pts, [1.0, 0.85, 0.1, 1.0]);
        }
    }

    /// Pass 5: the particle layer over the scene image (`targets`), composited into the
    /// target.
    fn particle_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        f: &ColourPass<'_>,
        targets: &LayerTargets,
        stats: &mut FrameStats,
    ) {
        let Some(pp) = &self.particles.pass else {
            return;
        };
        let (n, draws) = pp.render(
            &self.gpu,
            enc,
            &self.particles.systems,
            &self.particles.layer,
            f.camera,
            (self.light_dir, self.ambient),
            self.time,
            &f.target.depth_view,
            targets,
            &f.target.color_view,
        );
        stats.particles = n;
        stats.draw_calls += draws;
    }

    /// Cascade `k` of the light's depth atlas (its tile; cascade 0 clears the atlas):
    /// meshes, clouds (at the levels the viewer shows), volumes sliced from the light with
    /// [`shadow::SHADOW_SPACING_BIAS`]× the spacing.
    fn shadow_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        map: &ShadowMap,
        (k, light, clear): (usize, &ViewCamera, Clear),
        clouds: Option<&CloudFrame<'_>>,
        stats: &mut FrameStats,
    ) -> Result<CascadeStats, ViewError> {
        let mut params = self.params;
        params.spacing = params.spacing.scaled(shadow::SHADOW_SPACING_BIAS);
        let plan = self.plan(
            PlanView::Light,
            light,
            params,
            None,
            Some(shadow::SHADOW_ALPHA_CUTOFF),
        )?;
        let mut cascade = CascadeStats {
            texel: light.pixel_size_at(1.0),
            drawn: true,
            slices: plan.as_ref().map_or(0, |p| p.slice_count()),
            ..Default::default()
        };
        let frame = MeshFrame {
            view_proj: (light.projection() * light.view).to_cols_array_2d(),
            world_to_shadow: Mat4::IDENTITY.to_cols_array_2d(),
            light: [0.0, 1.0, 0.0, 1.0],
            flags: [0.0; 4],
        };
        let none = &self.shadows.none.bind_group;
        let mut depth = depth_attachment(&map.view);
        if clear != Clear::Atlas {
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
        if clear == Clear::Tile {
            let p = self
                .shadows
                .tile_clear
                .get_or_init(|| shadow::tile_clear_pipeline(&self.gpu));
            rp.set_pipeline(p);
            rp.draw(0..3, 0..1);
        }
        // Casters outside the cascade's window are left out (each cascade's depth range
        // covers every caster, so only the window across the light decides).
        let seen = |c: Vec3, r: f32| !self.shadow_culling || shadow::sphere_in_window(light, c, r);
        if let Some(pass) = &self.mesh_pass {
            let bind = pass.frame_bind_group(&self.gpu, View::Light, &frame);
            for m in &self.meshes {
                let (lo, hi) = m.bounds;
                // A flat mesh (a ground) casts on nothing when nothing lies behind it
                // from the light: rays towards the light never cross it.
                let flat = self.shadow_culling
                    && m.plane
                        .is_some_and(|p| !self.behind_plane(p, self.light_dir));
                if !flat && seen(0.5 * (lo + hi), 0.5 * (hi - lo).length()) {
                    cascade.casters += pass.draw(&self.gpu, &mut rp, bind, none, m, true);
                } else {
                    cascade.culled += m.ranges.len();
                }
            }
        }
        if let (Some(pass), Some(cf)) = (&self.cloud_pass, clouds) {
            let (cf, culled) = cf.culled(seen);
            cascade.casters += cf.instance_count();
            cascade.culled += culled;
            let (quads, triangles, texels) = cf.shadow_work(self.light_dir, cascade.texel);
            (cascade.cloud_quads, cascade.foliage_triangles) = (quads, triangles);
            cascade.cloud_texels = texels;
            let bind = pass.frame_bind_group(&self.gpu, View::Light, &frame);
            stats.cloud_bytes_uploaded += std::mem::size_of::<MeshFrame>();
            pass.draw(&self.gpu, &mut rp, bind, none, &cf, true);
        }
        if let (Some(pass), Some(plan)) = (&self.volumes.pass, &plan) {
            plan.draw(
                &mut rp,
                pass.shadow_pipeline(&self.gpu),
                &self.volumes.batches,
                none,
            );
        }
        Ok(cascade)
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
        let Some(pass) = &self.volumes.pass else {
            return Ok(None);
        };
        let mut bufs = self.volumes.plan_buffers[view as usize].borrow_mut();
        let bufs = bufs.get_or_insert_with(|| PlanBuffers::new(&self.gpu));
        volume_plan::plan(
            &self.gpu,
            pass,
            bufs,
            &self.volumes.entries,
            camera,
            params,
            (self.light_dir, self.ambient),
            shadow,
            shadow_cutoff,
            self.time,
        )
    }
}

/// What a cascade's pass clears before drawing.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Clear {
    /// The whole atlas (the first cascade, when every tile is drawn).
    Atlas,
    /// Nothing (a later cascade of a frame that draws every tile).
    None,
    /// Its own tile (a frame that keeps some tiles).
    Tile,
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
