//! The opaque mesh pass: drawn first, writes depth, so the volume slices that follow
//! are cut by it (the paper's z-buffer compliance). Materials: base colour × vertex
//! colour × base-colour texture (sRGB, MIP-mapped, repeat), alpha-masked materials
//! discard below their cut-off. Blended materials are drawn as masked at 0.5 (the
//! viewer sorts no mesh triangles). One directional light (two-sided Lambert) plus
//! ambient, shadowed when the scene has a shadow map. Vertices with a zero normal are
//! unlit: base colour × texture as it is, neither Lambert nor shadow (how glTF
//! `KHR_materials_unlit` materials, whose lighting is baked in, are drawn).

use std::cell::OnceCell;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::layout::{color_target, frame_layout, material_layout, shader, Pipeline};
use crate::target::COLOR_FORMAT;
use crate::texture::{repeat_sampler, upload_rgba8_mips, TextureData};
use crate::{Gpu, ViewError};

/// A vertex: world position, normal (any length; zero = unlit: no Lambert, no shadow), uv,
/// linear RGBA colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MeshVertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    pub color: [f32; 4],
}

/// How a material is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeshMaterial {
    /// Index into [`MeshData::textures`].
    pub texture: Option<u32>,
    /// Discard fragments whose alpha is below this (`None`: opaque).
    pub alpha_cutoff: Option<f32>,
}

/// A triangle list (3 vertices a triangle), world space, one material per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    pub vertices: Vec<MeshVertex>,
    /// Per triangle, an index into `materials`; empty: every triangle uses material 0.
    pub triangle_materials: Vec<u32>,
    /// Empty: one untextured opaque material.
    pub materials: Vec<MeshMaterial>,
    pub textures: Vec<TextureData>,
}

impl MeshData {
    /// A flat quad `corner + s·u + t·v`, `s, t ∈ [0,1]`, of one colour.
    pub fn quad(corner: Vec3, u: Vec3, v: Vec3, color: [f32; 4]) -> MeshData {
        let n = u.cross(v).normalize_or_zero().to_array();
        let p = |s: f32, t: f32| MeshVertex {
            pos: (corner + u * s + v * t).to_array(),
            normal: n,
            uv: [s, t],
            color,
        };
        MeshData {
            vertices: vec![
                p(0., 0.),
                p(1., 0.),
                p(1., 1.),
                p(0., 0.),
                p(1., 1.),
                p(0., 1.),
            ],
            ..Default::default()
        }
    }
}

/// A mesh on the GPU: its vertices sorted by material, one draw range per material.
pub struct GpuMesh {
    pub buffer: wgpu::Buffer,
    pub vertices: u32,
    pub triangles: u32,
    /// (vertex range, material bind group).
    pub ranges: Vec<(std::ops::Range<u32>, wgpu::BindGroup)>,
    /// World-space bounds (min, max).
    pub bounds: (Vec3, Vec3),
    /// The plane every vertex lies in, `(n, d)` with `n·p = d` (`n` unit), if there is
    /// one (a ground): a shadow cascade leaves it out when nothing lies behind it
    /// ([`crate::Renderer::shadow_culling`]).
    pub plane: Option<(Vec3, f32)>,
}

/// The plane all of `vertices` lie in (within 1e-5 of the extent of their bounds
/// `(lo, hi)`), from the triangle of largest area; `None` for a mesh that is not flat or
/// has no triangle of non-zero area.
pub fn plane_of(vertices: &[MeshVertex], (lo, hi): (Vec3, Vec3)) -> Option<(Vec3, f32)> {
    let p = |v: &MeshVertex| Vec3::from(v.pos);
    let n = vertices
        .chunks_exact(3)
        .map(|t| (p(&t[1]) - p(&t[0])).cross(p(&t[2]) - p(&t[0])))
        .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))?
        .try_normalize()?;
    let d = n.dot(p(&vertices[0]));
    let tol = 1e-5 * (hi - lo).length().max(d.abs());
    vertices
        .iter()
        .all(|v| (n.dot(p(v)) - d).abs() <= tol)
        .then_some((n, d))
}

/// A mesh's materials, or one default material when it has none.
fn mesh_materials(mesh: &MeshData) -> Vec<MeshMaterial> {
    if mesh.materials.is_empty() {
        vec![MeshMaterial::default()]
    } else {
        mesh.materials.clone()
    }
}

/// Which persistent frame uniform a pass uses (the mesh and the cloud passes keep one
/// per view, written before each submission).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Camera,
    Light,
}

/// Per-frame uniform of the mesh pipelines.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MeshFrame {
    pub view_proj: [[f32; 4]; 4],
    pub world_to_shadow: [[f32; 4]; 4],
    /// xyz: direction towards the light (unit), w: ambient.
    pub light: [f32; 4],
    /// x: 1 = receive shadows, z: shadow depth bias.
    pub flags: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct MaterialUniform {
    /// x: alpha cut-off (0 = opaque), y: 1 = textured.
    params: [f32; 4],
}

pub struct MeshPass {
    pipeline: wgpu::RenderPipeline,
    /// Depth only, made by the first shadow pass ([`MeshPass::shadow_pipeline`]).
    shadow_pipeline: OnceCell<wgpu::RenderPipeline>,
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    /// Frame uniforms and their bind groups, made once: the camera's, the light's (both
    /// are written before the submission that reads them, so each has its own).
    frames: [(wgpu::Buffer, wgpu::BindGroup); 2],
    material_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    white: wgpu::TextureView,
}

impl MeshPass {
    pub fn new(gpu: &Gpu, shadow_layout: &wgpu::BindGroupLayout) -> MeshPass {
        let device = &gpu.device;
        let module = shader(
            device,
            "mesh.wgsl",
            &[
                include_str!("shaders/shadow_lookup.wgsl"),
                include_str!("shaders/shading.wgsl"),
                include_str!("shaders/alpha_hash.wgsl"),
                include_str!("shaders/mesh.wgsl"),
            ],
        );
        let frame_layout = frame_layout(device, "mesh frame");
        let material_layout = material_layout(device, "mesh material");
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&material_layout),
                Some(shadow_layout),
            ],
            immediate_size: 0,
        });
        let pipeline = build_pipeline(device, &pl, &module, false);
        gpu.note_built("pipeline:mesh");
        let sampler = repeat_sampler(device, "mesh texture");
        let white =
            upload_rgba8_mips(gpu, &TextureData::white(), "white").create_view(&Default::default());
        let frames = [View::Camera, View::Light].map(|_| {
            let buf = gpu.empty_buffer(
                "mesh frame",
                std::mem::size_of::<MeshFrame>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            );
            let bind = gpu.bind_group(&wgpu::BindGroupDescriptor {
                label: Some("mesh frame"),
                layout: &frame_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                }],
            });
            (buf, bind)
        });
        MeshPass {
            pipeline,
            shadow_pipeline: OnceCell::new(),
            layout: pl,
            module,
            frames,
            material_layout,
            sampler,
            white,
        }
    }

    pub fn upload(&self, gpu: &Gpu, mesh: &MeshData) -> Result<GpuMesh, ViewError> {
        let views: Vec<wgpu::TextureView> = mesh
            .textures
            .iter()
            // Plain MIPs: alpha-masked materials are tested hashed where they are used
            // (alpha_hash.wgsl).
            .map(|t| upload_rgba8_mips(gpu, t, "mesh texture").create_view(&Default::default()))
            .collect();
        self.upload_with_views(gpu, mesh, &views)
    }

    /// [`MeshPass::upload`] of a mesh whose textures are already on the GPU: `views[i]`
    /// stands for `mesh.textures[i]` (which may be left empty), e.g. a cloud's kept mesh
    /// drawn once per instance with the cloud's textures.
    pub fn upload_with_views(
        &self,
        gpu: &Gpu,
        mesh: &MeshData,
        views: &[wgpu::TextureView],
    ) -> Result<GpuMesh, ViewError> {
        let bad = |m: String| Err(ViewError::InvalidParam(m));
        if !mesh.vertices.len().is_multiple_of(3) {
            return bad(format!(
                "mesh has {} vertices, not a multiple of 3",
                mesh.vertices.len()
            ));
        }
        let tris = mesh.vertices.len() / 3;
        if !mesh.triangle_materials.is_empty() && mesh.triangle_materials.len() != tris {
            return bad("mesh: one material index per triangle is needed".into());
        }
        if mesh
            .vertices
            .iter()
            .any(|v| !v.pos.iter().all(|c| c.is_finite()))
        {
            return bad("mesh has a non-finite vertex".into());
        }
        let materials = mesh_materials(mesh);
        let mat_of = |t: usize| mesh.triangle_materials.get(t).copied().unwrap_or(0);
        if (0..tris).any(|t| mat_of(t) as usize >= materials.len())
            || materials
                .iter()
                .any(|m| m.texture.is_some_and(|i| i as usize >= views.len()))
        {
            return bad("mesh: material or texture index out of range".into());
        }
        // Vertices sorted by material (stable: triangle order within a material).
        let mut order: Vec<usize> = (0..tris).collect();
        order.sort_by_key(|&t| mat_of(t));
        let mut data = Vec::with_capacity(mesh.vertices.len().max(3));
        let mut ranges = Vec::new();
        let mut start = 0u32;
        for (i, &t) in order.iter().enumerate() {
            data.extend_from_slice(&mesh.vertices[3 * t..3 * t + 3]);
            let last = i + 1 == order.len() || mat_of(order[i + 1]) != mat_of(t);
            if last {
                let end = data.len() as u32;
                let m = &materials[mat_of(t) as usize];
                ranges.push((start..end, self.material_bind(gpu, m, views)));
                start = end;
            }
        }
        let n = data.len();
        data.resize(n.max(3), MeshVertex::default());
        let buffer = gpu.buffer(
            "mesh",
            bytemuck::cast_slice(&data),
            wgpu::BufferUsages::VERTEX,
        );
        let mut bounds = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for v in &mesh.vertices {
            bounds.0 = bounds.0.min(Vec3::from(v.pos));
            bounds.1 = bounds.1.max(Vec3::from(v.pos));
        }
        Ok(GpuMesh {
            bounds,
            plane: plane_of(&mesh.vertices[..3 * tris], bounds),
            buffer,
            vertices: n as u32,
            triangles: tris as u32,
            ranges,
        })
    }

    fn material_bind(
        &self,
        gpu: &Gpu,
        m: &MeshMaterial,
        views: &[wgpu::TextureView],
    ) -> wgpu::BindGroup {
        let u = MaterialUniform {
            params: [
                m.alpha_cutoff.unwrap_or(0.0),
                f32::from(u8::from(m.texture.is_some())),
                0.0,
                0.0,
            ],
        };
        let view = m.texture.map_or(&self.white, |i| &views[i as usize]);
        gpu.uniform_texture_bind_group(
            "mesh material",
            &self.material_layout,
            bytemuck::bytes_of(&u),
            view,
            &self.sampler,
        )
    }

    /// Writes `frame` into `view`'s uniform (the camera's, or the light's for the shadow
    /// map) and returns its bind group (both made once, with the pass).
    pub fn frame_bind_group(&self, gpu: &Gpu, view: View, frame: &MeshFrame) -> &wgpu::BindGroup {
        let (buf, bind) = &self.frames[view as usize];
        gpu.queue.write_buffer(buf, 0, bytemuck::bytes_of(frame));
        bind
    }

    /// The depth-only pipeline of the shadow pass, made on first use (recorded as
    /// `pipeline:mesh-shadow`; only scenes with shadows make it).
    pub fn shadow_pipeline(&self, gpu: &Gpu) -> &wgpu::RenderPipeline {
        self.shadow_pipeline.get_or_init(|| {
            let p = build_pipeline(&gpu.device, &self.layout, &self.module, true);
            gpu.note_built("pipeline:mesh-shadow");
            p
        })
    }

    /// Draws `mesh` (colour pass, or the depth-only shadow pass); returns the draw calls.
    pub fn draw(
        &self,
        gpu: &Gpu,
        rp: &mut wgpu::RenderPass<'_>,
        frame: &wgpu::BindGroup,
        shadow: &wgpu::BindGroup,
        mesh: &GpuMesh,
        depth_only: bool,
    ) -> usize {
        if mesh.vertices == 0 {
            return 0;
        }
        rp.set_pipeline(if depth_only {
            self.shadow_pipeline(gpu)
        } else {
            &self.pipeline
        });
        rp.set_bind_group(0, frame, &[]);
        rp.set_bind_group(2, shadow, &[]);
        rp.set_vertex_buffer(0, mesh.buffer.slice(..));
        for (range, bind) in &mesh.ranges {
            rp.set_bind_group(1, bind, &[]);
            rp.draw(range.clone(), 0..1);
        }
        mesh.ranges.len()
    }
}

/// The vertex attributes of [`MeshVertex`].
const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4
];

/// The colour pipeline, or (`depth_only`) the shadow pass's.
fn build_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    depth_only: bool,
) -> wgpu::RenderPipeline {
    let buffers = [Some(wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<MeshVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    })];
    let (label, fs) = if depth_only {
        ("mesh shadow", "fs_shadow")
    } else {
        ("mesh", "fs_main")
    };
    Pipeline {
        fs,
        buffers: &buffers,
        depth: Some((true, wgpu::CompareFunction::Less)),
        target: if depth_only {
            None
        } else {
            color_target(COLOR_FORMAT, None)
        },
        ..Pipeline::new(label, layout, module)
    }
    .build(device)
}
