//! The frame: opaque meshes first (depth write), then the volume slices (depth test only),
//! into an Rgba16Float target. See [`crate::volume_pass`] for the slicing.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use billow_format::{Prism, VolumeAsset};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::mesh_pass::{GpuMesh, MeshData, MeshPass};
use crate::slice_plan::{slice_depths, voxel_size};
use crate::target::{RgbaImage, Target};
use crate::volume_pass::{FrameUniform, GpuCell, GpuSlice, GpuVolume, VolumePass};
use crate::{Gpu, SliceParams, ViewCamera, ViewError};

/// Vertices per cell × slice instance: a fan of 3 triangles covers the ≤ 5-gon.
pub const VERTICES_PER_INSTANCE: u32 = 9;

/// What a frame drew.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    pub slices: usize,
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
}

struct VolumeEntry {
    cells: Vec<Prism>,
    instances: Vec<Mat4>,
    gpu: GpuVolume,
}

/// Owns the device, the passes the content needs, and the uploaded content.
pub struct Renderer {
    pub gpu: Gpu,
    pub params: SliceParams,
    volume_pass: Option<VolumePass>,
    volumes: Vec<VolumeEntry>,
    mesh_pass: Option<MeshPass>,
    meshes: Vec<GpuMesh>,
    /// Light direction (towards the light) and ambient term for meshes.
    pub light_dir: Vec3,
    pub ambient: f32,
}

impl Renderer {
    pub fn new(gpu: Gpu) -> Renderer {
        Renderer {
            gpu,
            params: SliceParams::default(),
            volume_pass: None,
            volumes: Vec::new(),
            mesh_pass: None,
            meshes: Vec::new(),
            light_dir: Vec3::new(0.3, 1.0, 0.5).normalize(),
            ambient: 0.3,
        }
    }

    /// Adds a volume asset drawn once per transform in `instances` (they share its texture).
    pub fn add_volume(
        &mut self,
        asset: &VolumeAsset,
        instances: Vec<Mat4>,
    ) -> Result<(), ViewError> {
        if !instances.iter().all(|m| m.is_finite()) {
            return Err(ViewError::InvalidParam(
                "instance transform is not finite".into(),
            ));
        }
        let pass = self
            .volume_pass
            .get_or_insert_with(|| VolumePass::new(&self.gpu));
        let gpu = pass.upload(&self.gpu, asset)?;
        self.volumes.push(VolumeEntry {
            cells: asset.cells.clone(),
            instances,
            gpu,
        });
        Ok(())
    }

    /// Adds an opaque triangle mesh (world space).
    pub fn add_mesh(&mut self, mesh: &MeshData) -> Result<(), ViewError> {
        let pass = self
            .mesh_pass
            .get_or_insert_with(|| MeshPass::new(&self.gpu));
        let m = pass.upload(&self.gpu, mesh)?;
        self.meshes.push(m);
        Ok(())
    }

    /// The passes a frame runs, in order (only those the content needs).
    pub fn passes(&self) -> Vec<&'static str> {
        let mut p = Vec::new();
        if !self.meshes.is_empty() {
            p.push("mesh");
        }
        if !self.volumes.is_empty() {
            p.push("volume");
        }
        p.push("resolve");
        p
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
        let device = &self.gpu.device;
        let plan = self.plan_volumes(camera, &mut stats)?;
        let mesh_bind = self
            .mesh_pass
            .as_ref()
            .map(|p| p.frame_bind_group(&self.gpu, camera, self.light_dir, self.ambient));
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("frame"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target.color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(pass), Some(bind)) = (&self.mesh_pass, &mesh_bind) {
                for m in &self.meshes {
                    stats.mesh_triangles += m.triangles as usize;
                    stats.draw_calls += pass.draw(&mut rp, bind, m);
                }
            }
            if let (Some(pass), Some(plan)) = (&self.volume_pass, &plan) {
                rp.set_pipeline(&pass.pipeline);
                rp.set_bind_group(0, &plan.frame_bind, &[]);
                let n = plan.total_cells;
                if plan.groups.len() == 1 {
                    let g = &plan.groups[0];
                    rp.set_bind_group(1, &self.volumes[g.volume].gpu.bind_group, &[]);
                    let (s0, s1) = g.slices;
                    if s0 < s1 {
                        rp.draw(0..VERTICES_PER_INSTANCE, s0 * n..s1 * n);
                        stats.draw_calls += 1;
                        stats.instances += u64::from((s1 - s0) * n);
                    }
                } else {
                    let mut bound = usize::MAX;
                    for s in 0..plan.slices {
                        for g in &plan.groups {
                            if !(g.slices.0 <= s && s < g.slices.1) {
                                continue;
                            }
                            if bound != g.volume {
                                rp.set_bind_group(1, &self.volumes[g.volume].gpu.bind_group, &[]);
                                bound = g.volume;
                            }
                            let b = s * n + g.offset;
                            rp.draw(0..VERTICES_PER_INSTANCE, b..b + g.count);
                            stats.draw_calls += 1;
                            stats.instances += u64::from(g.count);
                        }
                    }
                }
            }
        }
        self.gpu.queue.submit([enc.finish()]);
        Ok(stats)
    }

    /// Renders into a new target and reads it back.
    pub fn render_image(&self, camera: &ViewCamera) -> Result<(RgbaImage, FrameStats), ViewError> {
        camera.validate()?;
        let target = Target::new(&self.gpu, camera.width, camera.height);
        let stats = self.render(&target, camera)?;
        Ok((target.read(&self.gpu)?, stats))
    }

    /// Cells to camera space, slice placement, per-volume slice ranges, GPU buffers.
    fn plan_volumes(
        &self,
        camera: &ViewCamera,
        stats: &mut FrameStats,
    ) -> Result<Option<VolumePlan>, ViewError> {
        let Some(pass) = &self.volume_pass else {
            return Ok(None);
        };
        let mut cells: Vec<GpuCell> = Vec::new();
        let mut groups = Vec::new();
        let (mut z_min, mut z_max) = (f32::INFINITY, f32::NEG_INFINITY);
        let mut v0_all: Option<f32> = None;
        for (vi, v) in self.volumes.iter().enumerate() {
            let offset = cells.len();
            let (mut gz0, mut gz1) = (f32::INFINITY, f32::NEG_INFINITY);
            let mut v0g: Option<f32> = None;
            for m in &v.instances {
                let world: Vec<Prism> = if *m == Mat4::IDENTITY {
                    v.cells.clone()
                } else {
                    v.cells
                        .iter()
                        .map(|c| Prism {
                            pos: c.pos.map(|p| m.transform_point3(Vec3::from(p)).to_array()),
                            uvw: c.uvw,
                        })
                        .collect()
                };
                if let Some(s) = voxel_size(&world, v.gpu.dims0) {
                    v0g = Some(v0g.map_or(s, |b| b.min(s)));
                }
                for c in &world {
                    let pos = c.pos.map(|p| camera.to_view(Vec3::from(p)).to_array());
                    for p in &pos {
                        gz0 = gz0.min(-p[2]);
                        gz1 = gz1.max(-p[2]);
                    }
                    cells.push(GpuCell::new(&pos, &c.uvw));
                }
            }
            let Some(v0g) = v0g else {
                cells.truncate(offset); // no cell with a usable uvw mapping: nothing to draw
                continue;
            };
            v0_all = Some(v0_all.map_or(v0g, |b| b.min(v0g)));
            z_min = z_min.min(gz0);
            z_max = z_max.max(gz1);
            let max_lod = (v.gpu.levels - 1) as f32;
            self.gpu.queue.write_buffer(
                &v.gpu.params,
                0,
                bytemuck::cast_slice(&[v0g, max_lod, 0.0, 0.0]),
            );
            groups.push(Group {
                volume: vi,
                offset: offset as u32,
                count: (cells.len() - offset) as u32,
                z: (gz0, gz1),
                slices: (0, 0),
            });
        }
        stats.cells = cells.len();
        let Some(v0) = v0_all else {
            return Ok(None);
        };
        stats.voxel_size = v0;
        let z_min = z_min.max(camera.near);
        let z_max = z_max.min(camera.far);
        if !(z_min < z_max) {
            return Ok(None);
        }
        let mut slices = slice_depths(
            camera,
            self.params.spacing,
            v0,
            z_min,
            z_max,
            self.params.max_slices,
        )?;
        slices.reverse(); // back to front
        stats.slices = slices.len();
        stats.min_spacing = slices.iter().map(|s| s.1).fold(f32::INFINITY, f32::min);
        stats.max_spacing = slices.iter().map(|s| s.1).fold(0.0, f32::max);
        if slices.is_empty() {
            return Ok(None);
        }
        let n = cells.len() as u64;
        if n * slices.len() as u64 > u64::from(u32::MAX) {
            return Err(ViewError::InvalidParam(format!(
                "{} cells × {} slices exceed the instance limit of 2^32",
                n,
                slices.len()
            )));
        }
        // Slices are sorted by decreasing depth: those within [gz0, gz1] form a run.
        for g in &mut groups {
            let first = slices.partition_point(|s| s.0 > g.z.1);
            let last = slices.partition_point(|s| s.0 >= g.z.0);
            g.slices = (first as u32, last.max(first) as u32);
        }
        let gpu_slices: Vec<GpuSlice> = slices
            .iter()
            .map(|&(depth, d)| GpuSlice {
                zd: [-depth, d, 0.0, 0.0],
            })
            .collect();
        let device = &self.gpu.device;
        let frame = FrameUniform {
            proj: camera.projection().to_cols_array_2d(),
            counts: [cells.len() as u32, 0, 0, 0],
        };
        let mk = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let fb = mk(
            "frame",
            bytemuck::bytes_of(&frame),
            wgpu::BufferUsages::UNIFORM,
        );
        let cb = mk(
            "cells",
            bytemuck::cast_slice(&cells),
            wgpu::BufferUsages::STORAGE,
        );
        let sb = mk(
            "slices",
            bytemuck::cast_slice(&gpu_slices),
            wgpu::BufferUsages::STORAGE,
        );
        let frame_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("volume frame"),
            layout: &pass.frame_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: fb.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: cb.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: sb.as_entire_binding(),
                },
            ],
        });
        Ok(Some(VolumePlan {
            frame_bind,
            total_cells: cells.len() as u32,
            slices: slices.len() as u32,
            groups,
        }))
    }
}

struct Group {
    volume: usize,
    offset: u32,
    count: u32,
    /// Depth range of its cells.
    z: (f32, f32),
    /// Run of back-to-front slice indices that can cut its cells.
    slices: (u32, u32),
}

struct VolumePlan {
    frame_bind: wgpu::BindGroup,
    total_cells: u32,
    slices: u32,
    groups: Vec<Group>,
}
