//! The particle layer (Umenhoffer et al. §2–4): spherical billboards rendered into their
//! own Rgba16Float target at a fraction of the resolution, optionally averaged over a
//! shutter interval (motion blur), a heat-shimmer offset target for fire, then composited
//! over the opaque + volume image.
//!
//! Only what the scene's particles need is built ([`ParticleNeeds`]): the phase LUT only
//! with dust or smoke, the black-body LUT only with fire, the shimmer pipeline and target
//! only with `shimmer`, the accumulation pipeline and target only with motion blur; the
//! detail noise only when a system has `detail > 0` or with shimmer — without it the
//! particle shader is built from `particle_no_detail.wgsl` (no noise binding, nothing
//! sampled) and the bind group has no binding 3. Missing LUTs are 1×1 stand-ins never
//! sampled.
//!
//! Order against the rest: the layer is composited after the volume slices, so particles
//! are drawn over volumetric billboards wherever they overlap on screen — a particle
//! behind a semi-transparent volume is not dimmed by it. Opaque meshes and clouds do hide
//! particles: the particle shader clips each ray at the scene depth.

use std::cell::RefCell;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::gpu::GrowBuffer;
use crate::layout::{
    color_target, depth_texture, entry, sampler, shader, storage, texture, uniform, Pipeline,
};
use crate::particle_layer::Bakes;
pub use crate::particle_layer::{LayerResolution, MotionBlur, ParticleLayerDesc, ParticleNeeds};
use crate::particles::{particles_at, BillboardMode, ParticleKind, ParticleSystemDesc};
use crate::target::COLOR_FORMAT;
use crate::texture::desc_2d;
use crate::{Gpu, ViewCamera};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct PFrame {
    proj: [[f32; 4]; 4],
    light: [f32; 4],
    light_colour: [f32; 4],
    screen: [f32; 4],
    clip: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuParticle {
    centre: [f32; 4],
    params: [f32; 4],
    fire: [f32; 4],
    detail: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Comp {
    flags: [f32; 4],
}

/// The layer's targets for one frame size.
pub struct LayerTargets {
    pub size: (u32, u32),
    pub layer_size: (u32, u32),
    /// The opaque + volume image the main passes render into.
    pub scene: wgpu::TextureView,
    pub layer: wgpu::TextureView,
    sub: Option<wgpu::TextureView>,
    shimmer: Option<wgpu::TextureView>,
    /// The composite's bind group (scene, layer, shimmer) and, with motion blur, the
    /// accumulation's (the time sample): made with the targets.
    composite_bind: wgpu::BindGroup,
    accumulate_bind: Option<wgpu::BindGroup>,
}

/// The buffers of one particle draw (one per shutter sample), kept from frame to frame:
/// the frame uniform, the particles (grown when they outgrow it) and their bind group,
/// made again when the particle buffer grows or the depth target changes.
struct ParticleSlot {
    frame: wgpu::Buffer,
    particles: GrowBuffer,
    bind: Option<(wgpu::TextureView, wgpu::BindGroup)>,
}

pub struct ParticlePass {
    pub needs: ParticleNeeds,
    draw: wgpu::RenderPipeline,
    shimmer: Option<wgpu::RenderPipeline>,
    accumulate: Option<wgpu::RenderPipeline>,
    composite: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    comp_layout: wgpu::BindGroupLayout,
    detail: Option<wgpu::TextureView>,
    phase: wgpu::TextureView,
    blackbody: wgpu::TextureView,
    dummy: wgpu::TextureView,
    smp_repeat: wgpu::Sampler,
    smp_clamp: wgpu::Sampler,
    slots: RefCell<Vec<ParticleSlot>>,
}

impl ParticlePass {
    pub fn new(gpu: &Gpu, needs: ParticleNeeds) -> ParticlePass {
        let device = &gpu.device;
        let module = shader(
            device,
            "particles.wgsl",
            &[
                include_str!("shaders/particles.wgsl"),
                if needs.detail {
                    include_str!("shaders/particle_detail.wgsl")
                } else {
                    include_str!("shaders/particle_no_detail.wgsl")
                },
            ],
        );
        let comp_module = shader(
            device,
            "composite.wgsl",
            &[
                include_str!("shaders/fullscreen.wgsl"),
                include_str!("shaders/composite.wgsl"),
            ],
        );
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let fs = wgpu::ShaderStages::FRAGMENT;
        let (d2, d3) = (
            wgpu::TextureViewDimension::D2,
            wgpu::TextureViewDimension::D3,
        );
        let entries: Vec<_> = [
            entry(0, vf, uniform(false)),
            entry(1, vf, storage()),
            entry(2, fs, depth_texture()),
            entry(3, fs, texture(d3)),
            entry(4, fs, texture(d2)),
            entry(5, fs, texture(d2)),
            entry(6, fs, sampler()),
            entry(7, fs, sampler()),
        ]
        .into_iter()
        .filter(|e| needs.detail || e.binding != 3)
        .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("particles"),
            entries: &entries,
        });
        let comp_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("composite"),
            entries: &[
                entry(0, fs, uniform(false)),
                entry(1, fs, texture(d2)),
                entry(2, fs, texture(d2)),
                entry(3, fs, texture(d2)),
                entry(4, fs, sampler()),
            ],
        });
        let pipeline = |module: &wgpu::ShaderModule,
                        layout: &wgpu::BindGroupLayout,
                        vs: &str,
                        fs_entry: &str,
                        format: wgpu::TextureFormat,
                        blend: wgpu::BlendState| {
            let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(fs_entry),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            Pipeline {
                vs,
                fs: fs_entry,
                target: color_target(format, Some(blend)),
                ..Pipeline::new(fs_entry, &pl, module)
            }
            .build(device)
        };
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let weighted = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Constant,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let draw = pipeline(
            &module,
            &layout,
            "vs_main",
            "fs_main",
            COLOR_FORMAT,
            wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING,
        );
        let shimmer = needs.shimmer.then(|| {
            pipeline(
                &module,
                &layout,
                "vs_main",
                "fs_shimmer",
                wgpu::TextureFormat::Rg16Float,
                wgpu::BlendState {
                    color: add,
                    alpha: add,
                },
            )
        });
        let accumulate = needs.motion_blur.then(|| {
            pipeline(
                &comp_module,
                &comp_layout,
                "vs_full",
                "fs_accumulate",
                COLOR_FORMAT,
                wgpu::BlendState {
                    color: weighted,
                    alpha: weighted,
                },
            )
        });
        let composite = pipeline(
            &comp_module,
            &comp_layout,
            "vs_full",
            "fs_composite",
            COLOR_FORMAT,
            wgpu::BlendState::REPLACE,
        );
        gpu.note_built(if needs.detail {
            "pipeline:particles"
        } else {
            "pipeline:particles-no-detail"
        });
        if needs.shimmer {
            gpu.note_built("pipeline:shimmer");
        }
        if needs.motion_blur {
            gpu.note_built("pipeline:motion-blur");
        }
        gpu.note_built("pipeline:composite");
        let Bakes {
            detail,
            phase,
            blackbody,
            dummy,
        } = Bakes::new(gpu, needs);
        let sampler = |mode| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("particles"),
                address_mode_u: mode,
                address_mode_v: mode,
                address_mode_w: mode,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            })
        };
        ParticlePass {
            needs,
            draw,
            shimmer,
            accumulate,
            composite,
            layout,
            comp_layout,
            detail,
            phase,
            blackbody,
            dummy,
            smp_repeat: sampler(wgpu::AddressMode::Repeat),
            smp_clamp: sampler(wgpu::AddressMode::ClampToEdge),
            slots: RefCell::new(Vec::new()),
        }
    }

    /// Targets for a `w`×`h` frame with the layer at `1/div` of it.
    pub fn targets(&self, gpu: &Gpu, w: u32, h: u32, div: u32) -> LayerTargets {
        let (lw, lh) = (w.div_ceil(div).max(1), h.div_ceil(div).max(1));
        let make = |w, h, format, label| {
            let usage =
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
            gpu.texture(&desc_2d(label, w, h, format, usage))
                .create_view(&Default::default())
        };
        let scene = make(w, h, COLOR_FORMAT, "scene (opaque + volumes)");
        let layer = make(lw, lh, COLOR_FORMAT, "particle layer");
        let sub = self
            .needs
            .motion_blur
            .then(|| make(lw, lh, COLOR_FORMAT, "particle time sample"));
        let shimmer = self
            .needs
            .shimmer
            .then(|| make(lw, lh, wgpu::TextureFormat::Rg16Float, "shimmer offsets"));
        // Add a time sample into the layer with weight 1/N (the blend constant).
        let accumulate_bind = sub
            .as_ref()
            .map(|s| self.comp_bind(gpu, &Comp { flags: [0.0; 4] }, s, s, &self.dummy));
        let u = Comp {
            flags: [
                f32::from(u8::from(shimmer.is_some())),
                1.0 / lw as f32,
                1.0 / lh as f32,
                0.0,
            ],
        };
        let composite_bind = self.comp_bind(
            gpu,
            &u,
            &scene,
            &layer,
            shimmer.as_ref().unwrap_or(&self.dummy),
        );
        LayerTargets {
            size: (w, h),
            layer_size: (lw, lh),
            scene,
            layer,
            sub,
            shimmer,
            composite_bind,
            accumulate_bind,
        }
    }

    /// The particles of `systems` at time `t`, view space, sorted back to front (systems
    /// by their mean depth, particles within a system by theirs).
    fn instances(systems: &[ParticleSystemDesc], camera: &ViewCamera, t: f32) -> Vec<GpuParticle> {
        let mut groups: Vec<(f32, Vec<(f32, GpuParticle)>)> = Vec::new();
        for s in systems {
            let kind = match s.kind {
                ParticleKind::Dust => 0.0,
                ParticleKind::Smoke => 1.0,
                ParticleKind::Fire => 2.0,
            };
            let planar = f32::from(u8::from(s.mode == BillboardMode::Planar));
            let mut v: Vec<(f32, GpuParticle)> = particles_at(s, t)
                .into_iter()
                .map(|p| {
                    let c = camera.to_view(p.centre);
                    (
                        c.z,
                        GpuParticle {
                            centre: [c.x, c.y, c.z, p.radius],
                            params: [p.density, s.albedo(), s.g(), kind],
                            fire: [p.t0, p.t1, s.emission, s.detail],
                            detail: [
                                p.detail_offset.x,
                                p.detail_offset.y,
                                p.detail_offset.z,
                                planar,
                            ],
                        },
                    )
                })
                .collect();
            if v.is_empty() {
                continue;
            }
            // Most negative view z (farthest) first; ties keep emission order.
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mean = v.iter().map(|x| x.0).sum::<f32>() / v.len() as f32;
            groups.push((mean, v));
        }
        groups.sort_by(|a, b| a.0.total_cmp(&b.0));
        groups.into_iter().flat_map(|g| g.1).map(|x| x.1).collect()
    }

    /// Renders the layer (and shimmer) for `camera` at time `t` and composites it over
    /// `targets.scene` into `out`. Returns (particles drawn at `t`, draw calls).
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        systems: &[ParticleSystemDesc],
        layer_desc: &ParticleLayerDesc,
        camera: &ViewCamera,
        light: (Vec3, f32),
        t: f32,
        depth: &wgpu::TextureView,
        targets: &LayerTargets,
        out: &wgpu::TextureView,
    ) -> (usize, usize) {
        let (lw, lh) = targets.layer_size;
        let l = camera.view.transform_vector3(light.0).normalize_or(Vec3::Y);
        let frame = PFrame {
            proj: camera.projection().to_cols_array_2d(),
            light: [l.x, l.y, l.z, light.1],
            light_colour: [1.0 - light.1, 1.0 - light.1, 1.0 - light.1, 0.0],
            screen: [
                lw as f32,
                lh as f32,
                targets.size.0 as f32,
                targets.size.1 as f32,
            ],
            clip: [
                camera.near,
                camera.far,
                t,
                layer_desc.shimmer.unwrap_or(0.0),
            ],
        };
        let times: Vec<f32> = match layer_desc.motion_blur {
            Some(m) if self.accumulate.is_some() => (0..m.samples)
                .map(|k| t - m.shutter * k as f32 / (m.samples - 1) as f32)
                .collect(),
            _ => vec![t],
        };
        let mut draws = 0;
        let mut drawn_now = 0;
        for (k, &tk) in times.iter().enumerate() {
            let parts = Self::instances(systems, camera, tk);
            if k == 0 {
                drawn_now = parts.len();
            }
            let bind = self.bind(
                gpu,
                k,
                &PFrame {
                    clip: [frame.clip[0], frame.clip[1], tk, frame.clip[3]],
                    ..frame
                },
                &parts,
                depth,
            );
            let into = if times.len() > 1 {
                targets.sub.as_ref().expect("motion blur target")
            } else {
                &targets.layer
            };
            draws += self.pass(enc, &self.draw, &bind, parts.len(), into);
            gpu.note_pass("particles");
            if times.len() > 1 {
                // Add this sample into the layer with weight 1/N.
                let cb = targets
                    .accumulate_bind
                    .as_ref()
                    .expect("motion blur bind group");
                let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("motion blur"),
                    color_attachments: &[Some(attachment(&targets.layer, k == 0))],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                rp.set_pipeline(self.accumulate.as_ref().expect("motion blur pipeline"));
                let w = 1.0 / times.len() as f64;
                rp.set_blend_constant(wgpu::Color {
                    r: w,
                    g: w,
                    b: w,
                    a: w,
                });
                rp.set_bind_group(0, cb, &[]);
                rp.draw(0..3, 0..1);
                draws += 1;
                gpu.note_pass("motion-blur");
            }
            if k == 0 {
                if let (Some(p), Some(target)) = (&self.shimmer, &targets.shimmer) {
                    draws += self.pass(enc, p, &bind, parts.len(), target);
                    gpu.note_pass("shimmer");
                }
            }
        }
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("composite"),
            color_attachments: &[Some(attachment(out, true))],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rp.set_pipeline(&self.composite);
        rp.set_bind_group(0, &targets.composite_bind, &[]);
        rp.draw(0..3, 0..1);
        gpu.note_pass("composite");
        (drawn_now, draws + 1)
    }

    /// One particle draw into `into` (cleared).
    fn pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        bind: &wgpu::BindGroup,
        count: usize,
        into: &wgpu::TextureView,
    ) -> usize {
        let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("particles"),
            color_attachments: &[Some(attachment(into, true))],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if count == 0 {
            return 0;
        }
        rp.set_pipeline(pipeline);
        rp.set_bind_group(0, bind, &[]);
        rp.draw(0..6, 0..count as u32);
        1
    }

    /// Writes draw `k`'s frame uniform and particles into its slot (made on first use)
    /// and returns its bind group.
    fn bind(
        &self,
        gpu: &Gpu,
        k: usize,
        frame: &PFrame,
        parts: &[GpuParticle],
        depth: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let mut slots = self.slots.borrow_mut();
        while slots.len() <= k {
            slots.push(ParticleSlot {
                frame: gpu.empty_buffer(
                    "particle frame",
                    std::mem::size_of::<PFrame>() as u64,
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                ),
                particles: GrowBuffer::new(gpu, "particles", wgpu::BufferUsages::STORAGE),
                bind: None,
            });
        }
        let slot = &mut slots[k];
        gpu.queue
            .write_buffer(&slot.frame, 0, bytemuck::bytes_of(frame));
        let one = [GpuParticle::default()];
        let data: &[GpuParticle] = if parts.is_empty() { &one } else { parts };
        let grown = slot.particles.write(gpu, bytemuck::cast_slice(data));
        if let Some((view, bind)) = &slot.bind {
            if !grown && view == depth {
                return bind.clone();
            }
        }
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: slot.frame.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: slot.particles.buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(depth),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::TextureView(&self.phase),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::TextureView(&self.blackbody),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: wgpu::BindingResource::Sampler(&self.smp_repeat),
            },
            wgpu::BindGroupEntry {
                binding: 7,
                resource: wgpu::BindingResource::Sampler(&self.smp_clamp),
            },
        ];
        if let Some(detail) = &self.detail {
            entries.push(wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(detail),
            });
        }
        let bind = gpu.bind_group(&wgpu::BindGroupDescriptor {
            label: Some("particles"),
            layout: &self.layout,
            entries: &entries,
        });
        slot.bind = Some((depth.clone(), bind.clone()));
        bind
    }

    fn comp_bind(
        &self,
        gpu: &Gpu,
        u: &Comp,
        scene: &wgpu::TextureView,
        layer: &wgpu::TextureView,
        shimmer: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let ub = gpu.buffer(
            "composite",
            bytemuck::bytes_of(u),
            wgpu::BufferUsages::UNIFORM,
        );
        let views = [scene, layer, shimmer];
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: ub.as_entire_binding(),
        }];
        for (i, v) in views.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: i as u32 + 1,
                resource: wgpu::BindingResource::TextureView(v),
            });
        }
        entries.push(wgpu::BindGroupEntry {
            binding: 4,
            resource: wgpu::BindingResource::Sampler(&self.smp_clamp),
        });
        gpu.bind_group(&wgpu::BindGroupDescriptor {
            label: Some("composite"),
            layout: &self.comp_layout,
            entries: &entries,
        })
    }
}

fn attachment(view: &wgpu::TextureView, clear: bool) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: if clear {
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
            } else {
                wgpu::LoadOp::Load
            },
            store: wgpu::StoreOp::Store,
        },
    }
}
