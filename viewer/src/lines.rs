//! The cell wireframe (a debugging view, `W` in the window, `--wireframe` headless):
//! the nine edges of every prism cell of every volume instance as lines, depth-tested
//! against the opaque scene, drawn over the slices.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::gpu::GrowBuffer;
use crate::layout::{color_target, frame_layout, shader, Pipeline};
use crate::target::COLOR_FORMAT;
use crate::Gpu;

/// Vertex index pairs of a prism's edges (0,1,2 bottom, 3,4,5 top).
pub const PRISM_EDGES: [(usize, usize); 9] = [
    (0, 1),
    (1, 2),
    (2, 0),
    (3, 4),
    (4, 5),
    (5, 3),
    (0, 3),
    (1, 4),
    (2, 5),
];

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LineFrame {
    view_proj: [[f32; 4]; 4],
    color: [f32; 4],
}

/// The wireframe pipeline, its frame uniform and bind group (made once) and its vertex
/// buffer (kept, grown when the edges outgrow it).
pub struct LinePass {
    pipeline: wgpu::RenderPipeline,
    frame: wgpu::Buffer,
    bind: wgpu::BindGroup,
    vertices: std::cell::RefCell<GrowBuffer>,
}

impl LinePass {
    pub fn new(gpu: &Gpu) -> LinePass {
        let device = &gpu.device;
        let module = shader(
            device,
            "lines.wgsl",
            &["struct F { view_proj: mat4x4<f32>, color: vec4<f32> }\n\
               @group(0) @binding(0) var<uniform> f: F;\n\
               @vertex fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {\n\
                   return f.view_proj * vec4<f32>(p, 1.0);\n}\n\
               @fragment fn fs() -> @location(0) vec4<f32> { return f.color; }\n"],
        );
        let layout = frame_layout(device, "lines");
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let attrs = wgpu::vertex_attr_array![0 => Float32x3];
        let buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attrs,
        })];
        let pipeline = Pipeline {
            vs: "vs",
            fs: "fs",
            buffers: &buffers,
            topology: wgpu::PrimitiveTopology::LineList,
            depth: Some((false, wgpu::CompareFunction::LessEqual)),
            target: color_target(COLOR_FORMAT, None),
            ..Pipeline::new("cell wireframe", &pl, &module)
        }
        .build(device);
        gpu.note_built("pipeline:lines");
        let frame = gpu.empty_buffer(
            "lines frame",
            std::mem::size_of::<LineFrame>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind = gpu.bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lines"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame.as_entire_binding(),
            }],
        });
        let vertices = GrowBuffer::new(gpu, "lines", wgpu::BufferUsages::VERTEX);
        LinePass {
            pipeline,
            frame,
            bind,
            vertices: std::cell::RefCell::new(vertices),
        }
    }

    /// Records `points` (pairs, world space) as lines of `color` seen by `view_proj`.
    pub fn draw(
        &self,
        gpu: &Gpu,
        rp: &mut wgpu::RenderPass<'_>,
        view_proj: Mat4,
        points: &[Vec3],
        color: [f32; 4],
    ) -> usize {
        if points.len() < 2 {
            return 0;
        }
        let frame = LineFrame {
            view_proj: view_proj.to_cols_array_2d(),
            color,
        };
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
        let flat: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
        let mut vb = self.vertices.borrow_mut();
        vb.write(gpu, bytemuck::cast_slice(&flat));
        rp.set_pipeline(&self.pipeline);
        rp.set_bind_group(0, &self.bind, &[]);
        rp.set_vertex_buffer(0, vb.buffer.slice(..));
        rp.draw(0..(points.len() as u32 / 2) * 2, 0..1);
        1
    }
}
