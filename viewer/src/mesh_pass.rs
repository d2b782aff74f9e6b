//! The opaque mesh pass: drawn first, writes depth, so the volume slices that follow
//! are cut by it (the paper's z-buffer compliance).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::target::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::{Gpu, ViewCamera, ViewError};

/// A vertex: world position, normal (any length; zero = unlit), linear RGBA colour.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MeshVertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    pub color: [f32; 4],
}

/// A triangle list (3 vertices a triangle), world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    pub vertices: Vec<MeshVertex>,
}

impl MeshData {
    /// A flat quad `corner + s·u + t·v`, `s, t ∈ [0,1]`, of one colour.
    pub fn quad(corner: Vec3, u: Vec3, v: Vec3, color: [f32; 4]) -> MeshData {
        let n = u.cross(v).normalize_or_zero().to_array();
        let p = |s: f32, t: f32| MeshVertex {
            pos: (corner + u * s + v * t).to_array(),
            normal: n,
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
        }
    }
}

pub struct GpuMesh {
    pub buffer: wgpu::Buffer,
    pub vertices: u32,
    pub triangles: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct MeshFrame {
    view_proj: [[f32; 4]; 4],
    light: [f32; 4],
}

pub struct MeshPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl MeshPass {
    pub fn new(gpu: &Gpu) -> MeshPass {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/mesh.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mesh frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mesh"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mesh"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<MeshVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attrs,
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        MeshPass { pipeline, layout }
    }

    pub fn upload(&self, gpu: &Gpu, mesh: &MeshData) -> Result<GpuMesh, ViewError> {
        if !mesh.vertices.len().is_multiple_of(3) {
            return Err(ViewError::InvalidParam(format!(
                "mesh has {} vertices, not a multiple of 3",
                mesh.vertices.len()
            )));
        }
        if mesh
            .vertices
            .iter()
            .any(|v| !v.pos.iter().all(|c| c.is_finite()))
        {
            return Err(ViewError::InvalidParam(
                "mesh has a non-finite vertex".into(),
            ));
        }
        let n = mesh.vertices.len().max(3);
        let mut data = mesh.vertices.clone();
        data.resize(n, MeshVertex::default());
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh"),
                contents: bytemuck::cast_slice(&data),
                usage: wgpu::BufferUsages::VERTEX,
            });
        Ok(GpuMesh {
            buffer,
            vertices: mesh.vertices.len() as u32,
            triangles: (mesh.vertices.len() / 3) as u32,
        })
    }

    pub fn frame_bind_group(
        &self,
        gpu: &Gpu,
        camera: &ViewCamera,
        light: Vec3,
        ambient: f32,
    ) -> wgpu::BindGroup {
        let l = light.normalize_or(Vec3::Y);
        let u = MeshFrame {
            view_proj: (camera.projection() * camera.view).to_cols_array_2d(),
            light: [l.x, l.y, l.z, ambient.clamp(0.0, 1.0)],
        };
        let buf = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("mesh frame"),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mesh frame"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buf.as_entire_binding(),
            }],
        })
    }

    /// Draws `mesh`; returns the number of draw calls.
    pub fn draw(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        bind: &wgpu::BindGroup,
        mesh: &GpuMesh,
    ) -> usize {
        if mesh.vertices == 0 {
            return 0;
        }
        rp.set_pipeline(&self.pipeline);
        rp.set_bind_group(0, bind, &[]);
        rp.set_vertex_buffer(0, mesh.buffer.slice(..));
        rp.draw(0..mesh.vertices, 0..1);
        1
    }
}
