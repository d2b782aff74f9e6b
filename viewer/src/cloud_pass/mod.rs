//! Billboard clouds (Lacewell et al. 2006, §3): LOD chosen per instance by distance,
//! smooth transitions by sliding vertices toward their orthogonal projections on the
//! parent billboard, the kept (trunk) mesh drawn with them by the mesh pass.
//!
//! Levels of a cloud, finest first: `0` = the foliage base mesh (the source leaves,
//! textured and alpha-masked), `1..=L` = the asset's billboard levels. With transition
//! distances `D₀ < D₁ < … < D_{L−1}` and a transition fraction `w`, an instance at
//! distance `z` from the eye (to its bounds' centre) shows level `k` = the number of
//! `D` below `z`; within `[D_k (1 − w), D_k)` level `k` morphs toward level `k + 1`:
//! `a = (z − D_k (1 − w)) / (D_k w)`, each vertex at `mix(own, projection on parent, a)`.
//! At `a = 1` every vertex lies in its parent billboard's plane, so the silhouette does
//! not pop when the parent replaces it (only the texture changes).
//!
//! **Dissolve.** The texture change is not made in one frame either: around each switch
//! `D_k`, over `log₂(z/D_k) ∈ (−h, h)` (`h` octaves, [`DEFAULT_DISSOLVE`]; a scene's
//! `dissolve`), both levels are drawn with complementary screen-space dither masks: with
//! `t = (log₂(z/D_k) + h)/(2h)` a pixel whose threshold (interleaved gradient noise,
//! fixed per pixel) is below `t` shows level `k + 1`, the others level `k`, so each pixel
//! changes once, at its own distance, and the two levels never z-fight. The morph then
//! ends where the dissolve begins (`D_k·2^(−h)` in place of `D_k` above): by the time the
//! parent starts to show, every vertex lies on its plane. Bands never overlap (`h` is
//! capped at half the octave gap to the neighbouring switches); `h = 0` is the abrupt
//! switch of before. A dissolving instance costs both levels' draws.
//!
//! The foliage mesh and the billboards are alpha-tested and write depth, so nothing is
//! sorted and nothing is blended (the paper alpha-tests its billboards, §6). The foliage
//! mesh uses its materials' cut-off and is lit like meshes. A billboard texel passes
//! when its (premultiplied, SPEC §9) alpha reaches [`BILLBOARD_CUTOFF`] and is drawn
//! opaque in its straight colour `rgb / a`: lighting baked into the atlases (the
//! default) is scaled only by the shadow, `ambient + (1 − ambient)·visibility`; an asset
//! baked unlit with normal maps (`--normal-map --unlit`) is lit here with the mesh
//! pass's model, `ambient + (1 − ambient)·|N·L|·visibility`, N decoded from the
//! tangent-space normal map (T = U, B = −V, N = ± the plane normal, SPEC §9.4). Each
//! billboard is two one-sided quads: the front texture seen from `+normal`, the back from
//! `−normal` (back faces culled).
//!
//! Buffers: an asset's vertices and indices (per (level, atlas) group, fixed quad order)
//! are uploaded once ([`CloudPass::upload`]); the morph runs in the vertex shader
//! (`mix(pos, target, morph)`). Per frame only the instance data changes: one persistent
//! instance buffer, written with `queue.write_buffer` (re-created only when the instance
//! count outgrows it), instances grouped by (cloud, level) so that each (cloud, level,
//! atlas group) is one instanced draw. The frame uniforms (camera and light, one buffer
//! each so the shadow pass does not overwrite what the main pass reads in the same
//! submission) and their bind groups are made once with the pass.

use std::cell::{Cell, OnceCell, RefCell};

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::layout::{entry, frame_layout, sampler, shader, texture, uniform, Pipeline};
use crate::mesh_pass::{MeshFrame, View};
use crate::target::COLOR_FORMAT;
use crate::texture::{repeat_sampler, upload_rgba8_mips, TextureData};
use crate::Gpu;

mod upload;
pub use upload::GpuCloud;

/// Billboard texels at least this opaque (premultiplied alpha) are drawn, write depth
/// and cast shadows; the others are discarded.
pub const BILLBOARD_CUTOFF: f32 = 0.5;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CloudVertex {
    pub pos: [f32; 3],
    /// Where the vertex goes at the end of its level's transition.
    pub target: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// Billboards: `xyz` = T (the billboard's U), `w` = the sign `s` with
    /// B = `s`·(N × T) = −V (−1 on the front side, +1 on the back; SPEC §9.4).
    pub tangent: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CloudInstance {
    pub model: [[f32; 4]; 4],
    /// x: morph factor a, y: dissolve `t` (0: not dissolving), z: 0 = the outgoing level
    /// (drawn where the pixel's threshold is ≥ `t`), 1 = the incoming one (< `t`).
    pub morph: [f32; 4],
}

/// Half-width of the dithered dissolve around each switch, in octaves of distance (module
/// docs): the sweep of docs/bbcloud.md ("LOD switches") takes 8 frames per octave, so the
/// change is spread over 6 of them.
pub const DEFAULT_DISSOLVE: f32 = 0.375;

/// What an instance shows at a distance: `level`, its morph factor, and while
/// dissolving into `level + 1` the dissolve fraction `dissolve ∈ (0, 1)` and the next
/// level's own morph factor (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LodChoice {
    pub level: usize,
    pub morph: f32,
    pub dissolve: f32,
    pub next_morph: f32,
}

/// The dissolve half-width at switch `i`: `h`, capped at half the octave gap to the
/// neighbouring switches so bands never overlap.
fn half_band(distances: &[f32], i: usize, h: f32) -> f32 {
    let mut h = if h.is_finite() { h.max(0.0) } else { 0.0 };
    let d = distances[i];
    if i > 0 && distances[i - 1] > 0.0 {
        h = h.min(0.5 * (d / distances[i - 1]).log2());
    }
    if let Some(&next) = distances.get(i + 1) {
        if d > 0.0 {
            h = h.min(0.5 * (next / d).log2());
        }
    }
    h.max(0.0)
}

/// Morph factor of a level whose morph ends at `end`, over the fraction `w` before it.
fn morph_toward(z: f32, end: f32, w: f32) -> f32 {
    if w <= 0.0 || end <= 0.0 {
        return 0.0;
    }
    let start = end * (1.0 - w);
    if z < start {
        return 0.0;
    }
    ((z - start) / (end * w)).clamp(0.0, 1.0)
}

/// What an instance at distance `z` shows (module docs): `distances` the switches,
/// `transition` the morph fraction, `dissolve` the dissolve half-width in octaves.
pub fn choose_lod(z: f32, distances: &[f32], transition: f32, dissolve: f32) -> LodChoice {
    let w = transition.clamp(0.0, 1.0);
    // No allocation: this runs per instance per frame.
    let h = |i: usize| half_band(distances, i, dissolve);
    // Where each level's morph ends: where the dissolve into its parent begins.
    let end = |i: usize| distances[i] * (-h(i)).exp2();
    for (i, &d) in distances.iter().enumerate() {
        let hi = h(i);
        if hi > 0.0 && d > 0.0 && z > 0.0 {
            let u = (z / d).log2();
            if u > -hi && u < hi {
                return LodChoice {
                    level: i,
                    morph: morph_toward(z, end(i), w),
                    dissolve: ((u + hi) / (2.0 * hi)).clamp(0.0, 1.0),
                    next_morph: if i + 1 < distances.len() {
                        morph_toward(z, end(i + 1), w)
                    } else {
                        0.0
                    },
                };
            }
        }
    }
    let k = distances.iter().take_while(|&&d| z >= d).count();
    LodChoice {
        level: k,
        morph: if k < distances.len() {
            morph_toward(z, end(k), w)
        } else {
            0.0
        },
        dissolve: 0.0,
        next_morph: 0.0,
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct DrawUniform {
    /// x: alpha cut-off, y: 1 = premultiplied texels, z: 1 = billboards lit at runtime
    /// from the normal map, w: 1 = textured.
    params: [f32; 4],
    /// Linear base colour factor.
    color: [f32; 4],
}

/// Which level an instance at distance `z` shows, and its morph factor, without a
/// dissolve (module docs; [`choose_lod`] with `dissolve` 0).
pub fn select_level(z: f32, distances: &[f32], transition: f32) -> (usize, f32) {
    let c = choose_lod(z, distances, transition, 0.0);
    (c.level, c.morph)
}

/// One cloud instance to draw this frame.
pub struct CloudDraw<'a> {
    pub cloud: &'a GpuCloud,
    pub model: Mat4,
    pub level: usize,
    pub morph: f32,
    /// Dissolve fraction into `level + 1` (0: none) and that level's morph factor.
    pub dissolve: f32,
    pub next_morph: f32,
}

/// A frame's cloud work: the instance ranges of each (cloud, level) in the persistent
/// instance buffer, written by [`CloudPass::frame`].
#[derive(Clone)]
pub struct CloudFrame<'a> {
    instances: wgpu::Buffer,
    /// (cloud, level, instance range).
    groups: Vec<(&'a GpuCloud, usize, std::ops::Range<u32>)>,
    /// Per instance (buffer order): a world-space sphere holding everything it draws,
    /// and its model transform.
    spheres: Vec<(Vec3, f32)>,
    models: Vec<Mat4>,
    /// Billboard quads (sides) drawn.
    pub quads: usize,
    /// Bytes written to the GPU for this frame's clouds (instances and frame uniforms).
    pub bytes_uploaded: usize,
}

impl<'a> CloudFrame<'a> {
    /// The frame with only the instances whose sphere `keep` accepts (the same
    /// instance buffer; each group split into its runs of kept instances), and how
    /// many instances were left out.
    pub fn culled(&self, keep: impl Fn(Vec3, f32) -> bool) -> (CloudFrame<'a>, usize) {
        let mut groups = Vec::with_capacity(self.groups.len());
        let mut dropped = 0;
        for &(cloud, level, ref range) in &self.groups {
            let mut run: Option<u32> = None;
            for i in range.clone() {
                let (c, r) = self.spheres[i as usize];
                let kept = keep(c, r);
                dropped += usize::from(!kept);
                match (kept, run) {
                    (true, None) => run = Some(i),
                    (false, Some(s)) => {
                        groups.push((cloud, level, s..i));
                        run = None;
                    }
                    _ => {}
                }
            }
            if let Some(s) = run {
                groups.push((cloud, level, s..range.end));
            }
        }
        let frame = CloudFrame {
            groups,
            ..self.clone()
        };
        (frame, dropped)
    }

    /// Instances drawn (a dissolving instance counts in both its levels).
    pub fn instance_count(&self) -> usize {
        self.groups.iter().map(|g| g.2.len()).sum()
    }

    /// What the frame draws into a depth map seen along `-towards` with texels of side
    /// `texel`: billboard quads (the side facing the light), foliage triangles, and their
    /// area across the light in texels — the fragments the alpha test runs on (overlaps
    /// counted, the window not clipped), load-independent.
    pub fn shadow_work(&self, towards: Vec3, texel: f32) -> (usize, usize, f64) {
        let l = towards.normalize_or(Vec3::Y);
        let (mut quads, mut triangles, mut area) = (0, 0, 0.0f64);
        for &(cloud, level, ref range) in &self.groups {
            let Some(areas) = cloud.areas.get(level) else {
                continue;
            };
            if level == 0 {
                triangles += cloud.foliage_triangles as usize * range.len();
            } else {
                quads += cloud.quads(level) / 2 * range.len();
            }
            for i in range.clone() {
                // A patch of area vector `a` covers |l · cof(M)·a| across the light.
                let m = glam::Mat3::from_mat4(self.models[i as usize]);
                let v = m.determinant() * (m.inverse() * l);
                area += areas
                    .iter()
                    .map(|a| f64::from(v.dot(*a).abs()))
                    .sum::<f64>();
            }
        }
        (quads, triangles, area / f64::from(texel * texel).max(1e-30))
    }
}

/// The world-space sphere holding everything `cloud` draws under `model` (its
/// [`GpuCloud::caster_radius`] scaled by the model's largest axis scale).
fn instance_sphere(cloud: &GpuCloud, model: Mat4) -> (Vec3, f32) {
    let scale = [model.x_axis, model.y_axis, model.z_axis]
        .iter()
        .map(|a| a.truncate().length())
        .fold(0.0f32, f32::max);
    (
        model.transform_point3(cloud.centre),
        cloud.caster_radius * scale,
    )
}

pub struct CloudPass {
    foliage: wgpu::RenderPipeline,
    /// Billboards with baked lighting (the default bake): their colour scaled by the
    /// shadow only.
    billboard: wgpu::RenderPipeline,
    /// Billboards lit at runtime from their normal maps, made on first use.
    billboard_lit: OnceCell<wgpu::RenderPipeline>,
    /// Alpha-tested depth only, (foliage mesh, billboards), made by the first shadow
    /// pass ([`CloudPass::shadow_pipelines`]).
    shadow: OnceCell<(wgpu::RenderPipeline, wgpu::RenderPipeline)>,
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    draw_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    /// The shadow pass's alpha test: bilinear within the nearest MIP level.
    shadow_sampler: wgpu::Sampler,
    white: wgpu::TextureView,
    /// The flat normal (128, 128, 255), bound where an asset has no normal map.
    flat_normal: wgpu::TextureView,
    /// Frame uniforms and their bind groups: the camera's, the light's.
    frames: [(wgpu::Buffer, wgpu::BindGroup); 2],
    /// The persistent instance buffer and its capacity in instances.
    instances: RefCell<(wgpu::Buffer, u64)>,
    /// Buffers and bind groups made after [`CloudPass::new`] outside uploads (instance
    /// buffer growth).
    created: Cell<u64>,
}

const INSTANCE_SIZE: u64 = std::mem::size_of::<CloudInstance>() as u64;

fn instance_buffer(gpu: &Gpu, capacity: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("cloud instances"),
        size: capacity.max(1) * INSTANCE_SIZE,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

#[derive(Clone, Copy)]
enum Kind {
    Foliage,
    Billboard,
    BillboardLit,
    FoliageShadow,
    BillboardShadow,
}

impl CloudPass {
    pub fn new(gpu: &Gpu, shadow_layout: &wgpu::BindGroupLayout) -> CloudPass {
        let device = &gpu.device;
        let module = shader(
            device,
            "cloud.wgsl",
            &[
                include_str!("../shaders/shadow_lookup.wgsl"),
                include_str!("../shaders/shading.wgsl"),
                include_str!("../shaders/alpha_hash.wgsl"),
                include_str!("../shaders/cloud.wgsl"),
            ],
        );
        let frame_layout = frame_layout(device, "cloud frame");
        let fs = wgpu::ShaderStages::FRAGMENT;
        let d2 = wgpu::TextureViewDimension::D2;
        let draw_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cloud draw"),
            entries: &[
                entry(0, fs, uniform(false)),
                entry(1, fs, texture(d2)),
                entry(2, fs, sampler()),
                entry(3, fs, texture(d2)),
                entry(4, fs, sampler()),
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cloud"),
            bind_group_layouts: &[Some(&frame_layout), Some(&draw_layout), Some(shadow_layout)],
            immediate_size: 0,
        });
        let foliage = build_pipeline(device, &pl, &module, Kind::Foliage);
        let billboard = build_pipeline(device, &pl, &module, Kind::Billboard);
        gpu.note_built("pipeline:cloud");
        let sampler = repeat_sampler(device, "cloud texture");
        let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("cloud shadow alpha"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Nearest,
            ..Default::default()
        });
        let white =
            upload_rgba8_mips(gpu, &TextureData::white(), "white").create_view(&Default::default());
        let flat_normal = upload::linear_texture(gpu, 1, 1, &[vec![128, 128, 255, 255]])
            .create_view(&Default::default());
        let frames = [View::Camera, View::Light].map(|v| {
            let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(match v {
                    View::Camera => "cloud frame (camera)",
                    View::Light => "cloud frame (light)",
                }),
                size: std::mem::size_of::<MeshFrame>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cloud frame"),
                layout: &frame_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                }],
            });
            (buf, bind)
        });
        CloudPass {
            foliage,
            billboard,
            billboard_lit: OnceCell::new(),
            shadow: OnceCell::new(),
            layout: pl,
            module,
            draw_layout,
            sampler,
            shadow_sampler,
            white,
            flat_normal,
            frames,
            instances: RefCell::new((instance_buffer(gpu, 1), 1)),
            created: Cell::new(0),
        }
    }

    /// Buffers and bind groups the pass has made for frames since it was built (the
    /// instance buffer's growth): constant once the instance count stops growing.
    pub fn resources_created(&self) -> u64 {
        self.created.get()
    }

    /// Plans a frame's clouds: instances grouped by (cloud, level) — in the order of
    /// each cloud's first draw, levels ascending, draw order within a group — and
    /// written to the persistent instance buffer (grown when too small). The same frame
    /// serves the shadow pass and the main pass: instance data does not depend on the
    /// view.
    pub fn frame<'a>(&self, gpu: &Gpu, draws: &[CloudDraw<'a>]) -> CloudFrame<'a> {
        // (cloud, per level: its instances, their spheres and models).
        type Level = Vec<(CloudInstance, (Vec3, f32), Mat4)>;
        let mut clouds: Vec<(&'a GpuCloud, Vec<Level>)> = Vec::new();
        for d in draws {
            let i = match clouds.iter().position(|(c, _)| std::ptr::eq(*c, d.cloud)) {
                Some(i) => i,
                None => {
                    clouds.push((d.cloud, vec![Vec::new(); d.cloud.level_count()]));
                    clouds.len() - 1
                }
            };
            let dissolving = d.dissolve > 0.0 && d.level + 1 < d.cloud.level_count();
            let t = if dissolving { d.dissolve } else { 0.0 };
            let sphere = instance_sphere(d.cloud, d.model);
            if let Some(level) = clouds[i].1.get_mut(d.level) {
                level.push((
                    instance_dissolving(d.model, d.morph, t, false),
                    sphere,
                    d.model,
                ));
            }
            if dissolving {
                if let Some(next) = clouds[i].1.get_mut(d.level + 1) {
                    let inst = instance_dissolving(d.model, d.next_morph, t, true);
                    next.push((inst, sphere, d.model));
                }
            }
        }
        let mut data: Vec<CloudInstance> = Vec::with_capacity(draws.len());
        let mut spheres = Vec::with_capacity(draws.len());
        let mut models = Vec::with_capacity(draws.len());
        let mut groups = Vec::new();
        let mut quads = 0;
        for (cloud, levels) in clouds {
            for (level, inst) in levels.into_iter().enumerate() {
                if inst.is_empty() {
                    continue;
                }
                let start = data.len() as u32;
                data.extend(inst.iter().map(|i| i.0));
                spheres.extend(inst.iter().map(|i| i.1));
                models.extend(inst.iter().map(|i| i.2));
                if level > 0 {
                    quads += cloud.quads(level) * inst.len();
                }
                groups.push((cloud, level, start..data.len() as u32));
            }
        }
        let mut held = self.instances.borrow_mut();
        let n = data.len() as u64;
        if n > held.1 {
            let cap = n.next_power_of_two();
            *held = (instance_buffer(gpu, cap), cap);
            self.created.set(self.created.get() + 1);
        }
        if !data.is_empty() {
            gpu.queue
                .write_buffer(&held.0, 0, bytemuck::cast_slice(&data));
        }
        CloudFrame {
            instances: held.0.clone(),
            groups,
            spheres,
            models,
            quads,
            bytes_uploaded: std::mem::size_of_val(data.as_slice()),
        }
    }

    /// Writes the frame uniform of `view` (written, not re-created) and returns its
    /// bind group. The camera and the light have their own buffers: writes are applied
    /// before the submission, so one shared buffer would give both passes the last one.
    pub fn frame_bind_group(&self, gpu: &Gpu, view: View, frame: &MeshFrame) -> &wgpu::BindGroup {
        let (buf, bind) = &self.frames[view as usize];
        gpu.queue.write_buffer(buf, 0, bytemuck::bytes_of(frame));
        bind
    }

    /// The alpha-tested depth-only pipeline of the shadow pass, made on first use
    /// (recorded as `pipeline:cloud-shadow`; only scenes with shadows make it).
    /// The foliage mesh's is drawn two-sided, the billboards' from the side facing the
    /// light only: each billboard is two quads on one plane (SPEC §9.4), and the
    /// light's depth needs one of them.
    pub fn shadow_pipelines(&self, gpu: &Gpu) -> &(wgpu::RenderPipeline, wgpu::RenderPipeline) {
        self.shadow.get_or_init(|| {
            let f = build_pipeline(&gpu.device, &self.layout, &self.module, Kind::FoliageShadow);
            let b = build_pipeline(
                &gpu.device,
                &self.layout,
                &self.module,
                Kind::BillboardShadow,
            );
            gpu.note_built("pipeline:cloud-shadow");
            (f, b)
        })
    }

    /// Records the frame's clouds: per (cloud, level) the foliage mesh's materials or
    /// the billboards' atlas groups, each one instanced draw (`shadow`: everything
    /// alpha-tested into the shadow map). Returns the draw calls.
    pub fn draw(
        &self,
        gpu: &Gpu,
        rp: &mut wgpu::RenderPass<'_>,
        frame_bind: &wgpu::BindGroup,
        receiver: &wgpu::BindGroup,
        f: &CloudFrame<'_>,
        shadow: bool,
    ) -> usize {
        let mut n = 0;
        let shadow_pipelines = shadow.then(|| self.shadow_pipelines(gpu));
        rp.set_bind_group(0, frame_bind, &[]);
        rp.set_bind_group(2, receiver, &[]);
        rp.set_vertex_buffer(1, f.instances.slice(..));
        for &(cloud, level, ref range) in &f.groups {
            rp.set_vertex_buffer(0, cloud.vertices.slice(..));
            if level == 0 {
                rp.set_pipeline(shadow_pipelines.map_or(&self.foliage, |p| &p.0));
                for r in &cloud.foliage {
                    rp.set_bind_group(1, &r.bind, &[]);
                    rp.draw(r.vertices.clone(), range.clone());
                    n += 1;
                }
                continue;
            }
            let Some(atlas_groups) = cloud.billboard_levels.get(level - 1) else {
                continue;
            };
            rp.set_index_buffer(cloud.indices.slice(..), wgpu::IndexFormat::Uint32);
            for g in atlas_groups {
                rp.set_pipeline(match shadow_pipelines {
                    Some(p) => &p.1,
                    None if g.lit => self.billboard_lit.get_or_init(|| {
                        build_pipeline(&gpu.device, &self.layout, &self.module, Kind::BillboardLit)
                    }),
                    None => &self.billboard,
                });
                rp.set_bind_group(1, &g.bind, &[]);
                rp.draw_indexed(g.indices.clone(), 0, range.clone());
                n += 1;
            }
        }
        n
    }
}

/// The instance data of a cloud instance (`model` transform, morph factor).
pub fn instance(model: Mat4, morph: f32) -> CloudInstance {
    instance_dissolving(model, morph, 0.0, false)
}

/// The instance data of a cloud instance dissolving at `t` (module docs): the outgoing
/// level, or the incoming one when `incoming`.
pub fn instance_dissolving(model: Mat4, morph: f32, t: f32, incoming: bool) -> CloudInstance {
    CloudInstance {
        model: model.to_cols_array_2d(),
        morph: [morph, t, if incoming { 1.0 } else { 0.0 }, 0.0],
    }
}

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x2, 4 => Float32x4
];
const INSTANCE_ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    5 => Float32x4, 6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4
];

/// One of the cloud pass's pipelines (vertex and instance buffers as [`CloudVertex`] and
/// [`CloudInstance`]).
fn build_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    kind: Kind,
) -> wgpu::RenderPipeline {
    let buffers = [
        Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<CloudVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &VERTEX_ATTRIBUTES,
        }),
        Some(wgpu::VertexBufferLayout {
            array_stride: INSTANCE_SIZE,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &INSTANCE_ATTRIBUTES,
        }),
    ];
    let (label, vs, fs, cull) = match kind {
        Kind::Foliage => ("cloud foliage", "vs_main", "fs_foliage", None),
        Kind::Billboard => (
            "cloud billboards",
            "vs_baked",
            "fs_baked",
            Some(wgpu::Face::Back),
        ),
        Kind::BillboardLit => (
            "cloud billboards lit",
            "vs_main",
            "fs_billboard",
            Some(wgpu::Face::Back),
        ),
        // The shadow pass's own entry points: what the alpha test reads and nothing more.
        Kind::FoliageShadow => (
            "cloud foliage shadow",
            "vs_foliage_shadow",
            "fs_shadow",
            None,
        ),
        Kind::BillboardShadow => (
            "cloud billboard shadow",
            "vs_billboard_shadow",
            "fs_billboard_shadow",
            Some(wgpu::Face::Back),
        ),
    };
    Pipeline {
        vs,
        fs,
        buffers: &buffers,
        cull,
        depth: Some((true, wgpu::CompareFunction::Less)),
        target: match kind {
            Kind::FoliageShadow | Kind::BillboardShadow => None,
            _ => Some(wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            }),
        },
        ..Pipeline::new(label, layout, module)
    }
    .build(device)
}

#[cfg(test)]
mod tests {
    use super::{choose_lod, select_level};

    #[test]
    fn levels_and_morph_factors() {
        let d = [10.0, 20.0, 40.0];
        assert_eq!(select_level(1.0, &d, 0.25), (0, 0.0));
        assert_eq!(select_level(7.5, &d, 0.25), (0, 0.0));
        let (k, a) = select_level(8.75, &d, 0.25);
        assert_eq!(k, 0);
        assert!((a - 0.5).abs() < 1e-6);
        assert_eq!(select_level(10.0, &d, 0.25), (1, 0.0));
        assert_eq!(select_level(100.0, &d, 0.25), (3, 0.0));
        // No transition band: a hard switch.
        assert_eq!(select_level(9.99, &d, 0.0), (0, 0.0));
        // Morph factor is continuous and reaches 1 at the switch.
        let (_, a) = select_level(19.9999, &d, 0.5);
        assert!(a > 0.999);
    }

    #[test]
    fn dissolve_bands_are_centred_on_the_switches() {
        let d = [10.0, 20.0, 40.0];
        let h = 0.375;
        // Outside every band: one level, as without a dissolve, except that the morph
        // ends where the band begins (10·2^−0.375 ≈ 7.71).
        let c = choose_lod(5.0, &d, 0.25, h);
        assert_eq!((c.level, c.dissolve), (0, 0.0));
        let end = 10.0 * (-h).exp2();
        let c = choose_lod(end * 0.999, &d, 0.25, h);
        assert!(c.morph > 0.99 && c.dissolve == 0.0, "{c:?}");
        // At the switch itself: half dissolved, the outgoing level on its parent's planes.
        let c = choose_lod(10.0, &d, 0.25, h);
        assert_eq!(c.level, 0);
        assert!((c.dissolve - 0.5).abs() < 1e-6 && c.morph == 1.0, "{c:?}");
        // Linear in log distance across the band.
        let c = choose_lod(10.0 * (0.5 * h).exp2(), &d, 0.25, h);
        assert!((c.dissolve - 0.75).abs() < 1e-5, "{c:?}");
        // Past the band: the next level alone.
        let c = choose_lod(10.0 * (h + 0.01).exp2(), &d, 0.25, h);
        assert_eq!((c.level, c.dissolve), (1, 0.0));
        // The last switch dissolves into the last level, which never morphs.
        let c = choose_lod(40.0, &d, 0.25, h);
        assert_eq!((c.level, c.next_morph), (2, 0.0));
        assert!(c.dissolve > 0.0);
        assert_eq!(choose_lod(1000.0, &d, 0.25, h).level, 3);
        // Bands are capped at half the gap to the neighbouring switch (here ±0.069 octave
        // around 10 and 11, meeting at 10.488): never two at once.
        let close = [10.0, 11.0];
        let c = choose_lod(10.48, &close, 0.25, 1.0);
        assert!(c.dissolve > 0.9 && c.level == 0, "{c:?}");
        assert_eq!(choose_lod(10.5, &close, 0.25, 1.0).level, 1);
        // dissolve 0 is the abrupt switch of select_level.
        for z in [1.0, 7.5, 8.75, 9.99, 10.0, 19.9999, 100.0] {
            let c = choose_lod(z, &d, 0.25, 0.0);
            assert_eq!((c.level, c.morph), select_level(z, &d, 0.25));
            assert_eq!(c.dissolve, 0.0);
        }
    }
}
