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
//! The foliage mesh is alpha-tested (its materials' cut-off), writes depth and is lit
//! like meshes. Billboards are semi-transparent: per frame and instance their quads are
//! sorted back to front (by the depth of their morphed centres) and blended
//! (premultiplied "over", atlases are premultiplied, SPEC §9) without writing depth,
//! after a depth-only pre-pass of the texels with alpha ≥ [`BILLBOARD_CUTOFF`], so the
//! dense parts occlude what lies behind them (meshes, other clouds and volume slices
//! drawn later test against them) while thin leaves keep their partial coverage at a
//! distance — an alpha test alone would erase leaves whose coverage in a texel is below
//! the cut-off. Each billboard is two one-sided quads: the front texture seen from
//! `+normal`, the back from `−normal`. Lighting is baked into the atlases.

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use crate::layout::{frame_layout, material_layout, shader, Pipeline};
use crate::mesh_pass::MeshFrame;
use crate::target::COLOR_FORMAT;
use crate::texture::{repeat_sampler, upload_rgba8_mips, TextureData};
use crate::Gpu;

mod upload;
pub use upload::GpuCloud;
use upload::MeshRange;

/// Texels at least this opaque write depth (the pre-pass) and cast shadows.
pub const BILLBOARD_CUTOFF: f32 = 0.5;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CloudVertex {
    pub pos: [f32; 3],
    /// Where the vertex goes at the end of its level's transition.
    pub target: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CloudInstance {
    pub model: [[f32; 4]; 4],
    /// x: morph factor a.
    pub morph: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct DrawUniform {
    /// x: alpha cut-off, y: 1 = premultiplied texels, z: 1 = lit (Lambert), w: 1 = textured.
    params: [f32; 4],
    /// Linear base colour factor.
    color: [f32; 4],
}

/// Which level an instance at distance `z` shows, and its morph factor (module docs).
pub fn select_level(z: f32, distances: &[f32], transition: f32) -> (usize, f32) {
    let k = distances.iter().take_while(|&&d| z >= d).count();
    let Some(&d) = distances.get(k) else {
        return (k, 0.0);
    };
    let w = transition.clamp(0.0, 1.0);
    let start = d * (1.0 - w);
    if w <= 0.0 || z < start {
        return (k, 0.0);
    }
    (k, ((z - start) / (d * w)).clamp(0.0, 1.0))
}

/// One cloud instance to draw this frame.
pub struct CloudDraw<'a> {
    pub cloud: &'a GpuCloud,
    /// Index into the frame's instance buffer.
    pub instance: u32,
    pub model: Mat4,
    pub level: usize,
    pub morph: f32,
}

/// A frame's cloud work: the instance and index buffers and the draws.
pub struct CloudFrame<'a> {
    instances: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// (vertex buffer, material range, instance).
    mesh_draws: Vec<(&'a wgpu::Buffer, &'a MeshRange, u32)>,
    /// (vertex buffer, atlas bind group, index range, instance).
    quad_draws: Vec<(
        &'a wgpu::Buffer,
        &'a wgpu::BindGroup,
        std::ops::Range<u32>,
        u32,
    )>,
    /// Billboard quads drawn.
    pub quads: usize,
}

pub struct CloudPass {
    foliage: wgpu::RenderPipeline,
    depth: wgpu::RenderPipeline,
    blend: wgpu::RenderPipeline,
    shadow: wgpu::RenderPipeline,
    pub frame_layout: wgpu::BindGroupLayout,
    draw_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    white: wgpu::TextureView,
}

#[derive(Clone, Copy)]
enum Kind {
    Foliage,
    Depth,
    Blend,
    Shadow,
}

impl CloudPass {
    pub fn new(gpu: &Gpu, shadow_layout: &wgpu::BindGroupLayout) -> CloudPass {
        let device = &gpu.device;
        let module = shader(
            device,
            "cloud.wgsl",
            &[
                include_str!("../shaders/shadow_lookup.wgsl"),
                include_str!("../shaders/cloud.wgsl"),
            ],
        );
        let frame_layout = frame_layout(device, "cloud frame");
        let draw_layout = material_layout(device, "cloud draw");
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cloud"),
            bind_group_layouts: &[Some(&frame_layout), Some(&draw_layout), Some(shadow_layout)],
            immediate_size: 0,
        });
        let vattrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x2
        ];
        let iattrs = wgpu::vertex_attr_array![
            4 => Float32x4, 5 => Float32x4, 6 => Float32x4, 7 => Float32x4, 8 => Float32x4
        ];
        let buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<CloudVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &vattrs,
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<CloudInstance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &iattrs,
            }),
        ];
        let make = |kind: Kind| {
            let (label, fs, cull, blend, writes, depth_write, compare) = match kind {
                Kind::Foliage => (
                    "cloud foliage",
                    "fs_foliage",
                    None,
                    None,
                    wgpu::ColorWrites::ALL,
                    true,
                    wgpu::CompareFunction::Less,
                ),
                Kind::Depth => (
                    "cloud depth pre-pass",
                    "fs_depth",
                    Some(wgpu::Face::Back),
                    None,
                    wgpu::ColorWrites::empty(),
                    true,
                    wgpu::CompareFunction::Less,
                ),
                Kind::Blend => (
                    "cloud billboards",
                    "fs_blend",
                    Some(wgpu::Face::Back),
                    Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    wgpu::ColorWrites::ALL,
                    false,
                    wgpu::CompareFunction::LessEqual,
                ),
                Kind::Shadow => (
                    "cloud shadow",
                    "fs_shadow",
                    None,
                    None,
                    wgpu::ColorWrites::empty(),
                    true,
                    wgpu::CompareFunction::Less,
                ),
            };
            Pipeline {
                fs,
                buffers: &buffers,
                cull,
                depth: Some((depth_write, compare)),
                target: match kind {
                    Kind::Shadow => None,
                    _ => Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend,
                        write_mask: writes,
                    }),
                },
                ..Pipeline::new(label, &pl, &module)
            }
            .build(device)
        };
        let sampler = repeat_sampler(device, "cloud texture");
        let white =
            upload_rgba8_mips(gpu, &TextureData::white(), "white").create_view(&Default::default());
        CloudPass {
            foliage: make(Kind::Foliage),
            depth: make(Kind::Depth),
            blend: make(Kind::Blend),
            shadow: make(Kind::Shadow),
            frame_layout,
            draw_layout,
            sampler,
            white,
        }
    }

    /// Plans a frame's clouds for a camera with world → view `view`: the instance
    /// buffer, and per billboard instance its quads sorted back to front.
    pub fn frame<'a>(&self, gpu: &Gpu, draws: &[CloudDraw<'a>], view: Mat4) -> CloudFrame<'a> {
        let mut inst: Vec<CloudInstance> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut mesh_draws = Vec::new();
        let mut quad_draws = Vec::new();
        let mut quads = 0;
        for d in draws {
            let i = inst.len() as u32;
            inst.push(instance(d.model, d.morph));
            if d.level == 0 {
                for r in &d.cloud.foliage {
                    mesh_draws.push((&d.cloud.buffer, r, i));
                }
                continue;
            }
            let Some(groups) = d.cloud.billboard_levels.get(d.level - 1) else {
                continue;
            };
            let mv = view * d.model;
            for g in groups {
                let mut order: Vec<(f32, u32)> = g
                    .centres
                    .iter()
                    .enumerate()
                    .map(|(q, (own, target))| {
                        let p = mv.transform_point3(own.lerp(*target, d.morph));
                        (p.z, q as u32)
                    })
                    .collect();
                // Far first: most negative view z first; ties by quad index.
                order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let start = indices.len() as u32;
                for (_, q) in &order {
                    let b = g.first_vertex + 4 * q;
                    indices.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
                }
                quads += order.len();
                quad_draws.push((&d.cloud.buffer, &g.bind, start..indices.len() as u32, i));
            }
        }
        inst.resize(inst.len().max(1), CloudInstance::default());
        indices.resize(indices.len().max(3), 0);
        CloudFrame {
            instances: gpu.buffer(
                "cloud instances",
                bytemuck::cast_slice(&inst),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: gpu.buffer(
                "cloud indices",
                bytemuck::cast_slice(&indices),
                wgpu::BufferUsages::INDEX,
            ),
            mesh_draws,
            quad_draws,
            quads,
        }
    }

    /// Records the frame's clouds: the foliage meshes, then the billboards' depth
    /// pre-pass and their sorted blend (`shadow`: everything alpha-tested into the
    /// shadow map). Returns the draw calls.
    pub fn draw(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        frame_bind: &wgpu::BindGroup,
        receiver: &wgpu::BindGroup,
        f: &CloudFrame<'_>,
        shadow: bool,
    ) -> usize {
        let mut n = 0;
        rp.set_bind_group(0, frame_bind, &[]);
        rp.set_bind_group(2, receiver, &[]);
        rp.set_vertex_buffer(1, f.instances.slice(..));
        rp.set_index_buffer(f.indices.slice(..), wgpu::IndexFormat::Uint32);
        rp.set_pipeline(if shadow { &self.shadow } else { &self.foliage });
        for (b, r, i) in &f.mesh_draws {
            rp.set_vertex_buffer(0, b.slice(..));
            rp.set_bind_group(1, &r.bind, &[]);
            rp.draw(r.vertices.clone(), *i..*i + 1);
            n += 1;
        }
        let passes: &[&wgpu::RenderPipeline] = if shadow {
            &[&self.shadow]
        } else {
            &[&self.depth, &self.blend]
        };
        for p in passes {
            rp.set_pipeline(p);
            for (b, bind, range, i) in &f.quad_draws {
                rp.set_vertex_buffer(0, b.slice(..));
                rp.set_bind_group(1, *bind, &[]);
                rp.draw_indexed(range.clone(), 0, *i..*i + 1);
                n += 1;
            }
        }
        n
    }

    /// The frame bind group (the mesh pass's frame uniform layout).
    pub fn frame_bind_group(&self, gpu: &Gpu, frame: &MeshFrame) -> wgpu::BindGroup {
        let buf = gpu.buffer(
            "cloud frame",
            bytemuck::bytes_of(frame),
            wgpu::BufferUsages::UNIFORM,
        );
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cloud frame"),
            layout: &self.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buf.as_entire_binding(),
            }],
        })
    }
}

/// The instance data of a cloud instance (`model` transform, morph factor).
pub fn instance(model: Mat4, morph: f32) -> CloudInstance {
    CloudInstance {
        model: model.to_cols_array_2d(),
        morph: [morph, 0.0, 0.0, 0.0],
    }
}

#[cfg(test)]
mod tests {
    use super::select_level;

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
}
