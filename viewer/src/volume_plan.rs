//! A frame's volume work, planned on the CPU: every cell of every instance in camera
//! space, the slices ([`crate::slice_plan`], back to front), the slabs
//! ([`crate::slab`]) and the draws, written into the volume pass's buffers
//! ([`PlanBuffers`], kept from frame to frame).
//!
//! Draws: a slab whose cells all use textures of one batch is **one draw** (its slices ×
//! its cells). A slab that mixes batches (more textures than
//! [`batch_size`](crate::volume_pass::batch_size)) is drawn slice by slice, one draw per
//! batch, so back-to-front order holds across batches.

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Mat3, Mat4, Vec3};

use crate::gpu::GrowBuffer;
use billow_format::Prism;

use crate::frame_stats::FrameStats;
use crate::slab::partition;
use crate::volume_pass::{
    FrameUniform, GpuCell, GpuDraw, GpuSlice, GpuVolume, GpuVolumeParams, VolumePass, VolumeStorage,
};
use crate::{Gpu, SliceParams, ViewCamera, ViewError};
use billow_core::slicing::{band_lod_range, far_slab, slice_lod};
use billow_core::slicing::{normal_matrix, slice_depths, voxel_size};

/// Vertices per cell × slice instance: a fan of 3 triangles covers the ≤ 5-gon.
pub const VERTICES_PER_INSTANCE: u32 = 9;

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

/// One planned draw: its batch, the dynamic offset of its [`GpuDraw`], its instances.
struct Draw {
    batch: usize,
    offset: u32,
    instances: u32,
}

/// The buffers and draws of one frame's volumes.
pub struct VolumePlan {
    frame_bind: wgpu::BindGroup,
    draws: Vec<Draw>,
    slices: usize,
    slabs: usize,
    empty_slabs: usize,
    cells: usize,
    instances: u64,
    v0: f32,
    spacing: (f32, f32),
}

impl VolumePlan {
    pub fn slice_count(&self) -> usize {
        self.slices
    }

    pub fn fill_stats(&self, s: &mut FrameStats) {
        s.slices = self.slices;
        s.slabs = self.slabs;
        s.empty_slabs = self.empty_slabs;
        s.cells = self.cells;
        s.instances = self.instances;
        s.voxel_size = self.v0;
        s.min_spacing = self.spacing.0;
        s.max_spacing = self.spacing.1;
    }

    /// Records the draws with `pipeline` (colour or shadow); returns the draw calls.
    pub fn draw(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        pipeline: &wgpu::RenderPipeline,
        batches: &[wgpu::BindGroup],
        receiver: &wgpu::BindGroup,
    ) -> usize {
        rp.set_pipeline(pipeline);
        rp.set_bind_group(2, receiver, &[]);
        let mut bound = usize::MAX;
        for d in &self.draws {
            rp.set_bind_group(0, &self.frame_bind, &[d.offset]);
            if bound != d.batch {
                rp.set_bind_group(1, &batches[d.batch], &[]);
                bound = d.batch;
            }
            rp.draw(0..VERTICES_PER_INSTANCE, 0..d.instances);
        }
        self.draws.len()
    }
}

/// The texture batches of `volumes`: texture `t` (volumes' bands in order) is slot
/// `t % N` of batch `t / N`.
pub fn batch_bind_groups(
    pass: &VolumePass,
    gpu: &Gpu,
    volumes: &[VolumeEntry],
) -> Vec<wgpu::BindGroup> {
    let views: Vec<(&wgpu::TextureView, Option<&wgpu::TextureView>)> = volumes
        .iter()
        .flat_map(|v| {
            v.bands
                .iter()
                .map(|b| (&b.gpu.view, b.gpu.normals.as_ref().map(|n| &n.1)))
        })
        .collect();
    views
        .chunks(pass.batch)
        .map(|c| pass.batch_bind_group(gpu, c))
        .collect()
}

/// The bytes of `data`, or of one default element when it is empty (a storage binding
/// is never empty).
fn nonempty<T: bytemuck::Pod + Default>(data: &[T]) -> Vec<u8> {
    if data.is_empty() {
        bytemuck::bytes_of(&T::default()).to_vec()
    } else {
        bytemuck::cast_slice(data).to_vec()
    }
}

/// The buffers of one view's volume plan, kept from frame to frame: the frame uniform,
/// the draws (dynamic-offset uniform) and the cells, slices, cell lists and volume
/// params (storage), each grown only when a frame needs more, and their bind group,
/// made again only when one of them grows. The camera's plan and the light's have one
/// each: both are written before the submission that reads them.
pub struct PlanBuffers {
    frame: wgpu::Buffer,
    draws: GrowBuffer,
    storage: [GrowBuffer; 4],
    bind: Option<wgpu::BindGroup>,
}

impl PlanBuffers {
    pub fn new(gpu: &Gpu) -> PlanBuffers {
        let st = wgpu::BufferUsages::STORAGE;
        PlanBuffers {
            frame: gpu.empty_buffer(
                "volume frame",
                std::mem::size_of::<FrameUniform>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            draws: GrowBuffer::new(gpu, "volume draws", wgpu::BufferUsages::UNIFORM),
            storage: [
                GrowBuffer::new(gpu, "cells", st),
                GrowBuffer::new(gpu, "slices", st),
                GrowBuffer::new(gpu, "cell lists", st),
                GrowBuffer::new(gpu, "volume params", st),
            ],
            bind: None,
        }
    }

    /// Writes a frame's data (`storage`: cells, slices, cell lists, volume params) and
    /// returns the bind group that reads it.
    fn write(
        &mut self,
        gpu: &Gpu,
        pass: &VolumePass,
        frame: &FrameUniform,
        draws: &[GpuDraw],
        storage: [Vec<u8>; 4],
    ) -> wgpu::BindGroup {
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
        let mut grown = self.draws.write(gpu, bytemuck::cast_slice(draws));
        for (b, data) in self.storage.iter_mut().zip(&storage) {
            grown |= b.write(gpu, data);
        }
        if grown || self.bind.is_none() {
            let [cb, sb, lb, vb] = self.storage.each_ref().map(|b| &b.buffer);
            self.bind = Some(gpu.bind_group(&wgpu::BindGroupDescriptor {
                label: Some("volume frame"),
                layout: &pass.frame_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.frame.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: cb.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: sb.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: lb.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: vb.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &self.draws.buffer,
                            offset: 0,
                            size: wgpu::BufferSize::new(16),
                        }),
                    },
                ],
            }));
        }
        self.bind.clone().expect("made above")
    }
}

/// Plans the volumes for `camera` at time `time` (animated cells), written into `bufs`. `light`: the world
/// direction towards the light and the ambient fraction, which shade the volumes that
/// store normals; `receive`: (camera view → shadow clip, depth bias) when the slices
/// receive shadows; `shadow_cutoff`: the alpha cut-off when this plan renders into the
/// shadow map.
#[allow(clippy::too_many_arguments)]
pub fn plan(
    gpu: &Gpu,
    pass: &VolumePass,
    bufs: &mut PlanBuffers,
    volumes: &[VolumeEntry],
    camera: &ViewCamera,
    params: SliceParams,
    light: (Vec3, f32),
    receive: Option<(Mat4, f32)>,
    shadow_cutoff: Option<f32>,
    time: f32,
) -> Result<Option<VolumePlan>, ViewError> {
    // A shadow map's (orthographic) cascade draws only the cells across its window: the
    // cascades of a view share the casters, each sees a part of them. The camera's plan
    // keeps every cell (its slices follow the cells' depth range).
    let window = match (shadow_cutoff, camera.ortho_half_height) {
        (Some(_), Some(hh)) => Some((hh * camera.aspect(), hh)),
        _ => None,
    };
    let mut cells: Vec<GpuCell> = Vec::new();
    let mut ranges: Vec<(f32, f32)> = Vec::new();
    let mut vparams: Vec<GpuVolumeParams> = Vec::new();
    let mut batch_of_cell: Vec<u32> = Vec::new();
    // Per cell: its params entry (for the band's LOD range).
    let mut entry_of_cell: Vec<u32> = Vec::new();
    let (mut z_min, mut z_max) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut v0_all: Option<f32> = None;
    for v in volumes {
        for (ii, m) in v.instances.iter().enumerate() {
            // Object-space cells of every band, deformed when animated (a per-instance
            // phase), then to world space.
            let world: Vec<Vec<billow_format::Prism>> = v
                .bands
                .iter()
                .map(|b| {
                    let local = match &v.animation {
                        Some(a) => {
                            gpu.note_pass("animate:cells");
                            a.deform(&b.cells, v.bounds, time, ii as f32 * 2.399_963)
                        }
                        None => b.cells.clone(),
                    };
                    local
                        .iter()
                        .map(|c| billow_format::Prism {
                            pos: c.pos.map(|p| m.transform_point3(Vec3::from(p)).to_array()),
                            uvw: c.uvw,
                        })
                        .collect()
                })
                .collect();
            // The instance's level-0 voxel size (SPEC §8.6: the finest over the bands,
            // each band's scaled back by 2^first_level); its MIP levels follow it
            // (instances of one asset may be scaled differently).
            let v0 = v
                .bands
                .iter()
                .zip(&world)
                .filter_map(|(b, w)| {
                    voxel_size(w, b.gpu.dims0).map(|s| s / (b.first_level as f32).exp2())
                })
                .reduce(f32::min);
            let Some(v0) = v0 else {
                continue; // no cell with a usable uvw mapping: nothing to draw
            };
            v0_all = Some(v0_all.map_or(v0, |b| b.min(v0)));
            // Stored normals → view space (src/eval/slicer.rs::normal_matrix): box assets
            // through the instance and the camera; shells per cell.
            let object_to_view = Mat3::from_mat4(camera.view * *m);
            let first_levels: Vec<u32> = v.bands.iter().map(|b| b.first_level).collect();
            for (bi, (b, w)) in v.bands.iter().zip(&world).enumerate() {
                let entry = vparams.len() as u32;
                let shaded = b.gpu.normals.is_some();
                let [lo, hi] = band_lod_range(&first_levels, bi);
                vparams.push(GpuVolumeParams {
                    p: [
                        v0 * (b.first_level as f32).exp2(),
                        (b.gpu.levels - 1) as f32,
                        (b.texture % pass.batch) as f32,
                        f32::from(
                            u8::from(b.gpu.repeat)
                                + 2 * u8::from(shaded)
                                + 4 * u8::from(b.gpu.storage == VolumeStorage::Blocks)
                                + 8 * u8::from(shaded && b.gpu.moments)
                                + 16 * u8::from(shaded && b.gpu.moments_bc),
                        ),
                    ],
                    q: [v0, v.max_lod as f32, lo, hi],
                    r: [
                        voxel_size(w, b.gpu.dims0).unwrap_or(v0 * (b.first_level as f32).exp2()),
                        0.0,
                        0.0,
                        0.0,
                    ],
                });
                for c in w {
                    let pos = c.pos.map(|p| camera.to_view(Vec3::from(p)).to_array());
                    if outside_window(&pos, window) {
                        continue;
                    }
                    let (mut a, mut z) = (f32::INFINITY, f32::NEG_INFINITY);
                    for p in &pos {
                        a = a.min(-p[2]);
                        z = z.max(-p[2]);
                    }
                    let mut cell = GpuCell::new(&pos, &c.uvw).with_volume(entry);
                    if shaded {
                        let shell = b.gpu.repeat;
                        cell = cell.with_normal_matrix(normal_matrix(
                            object_to_view,
                            shell,
                            &pos,
                            &c.uvw,
                        ));
                    }
                    cells.push(cell);
                    ranges.push((a, z));
                    batch_of_cell.push((b.texture / pass.batch) as u32);
                    entry_of_cell.push(entry);
                    z_min = z_min.min(a);
                    z_max = z_max.max(z);
                }
            }
        }
    }
    let Some(v0) = v0_all else {
        return Ok(None);
    };
    let z_lo = z_min.max(camera.near);
    let z_hi = z_max.min(camera.far);
    if !(z_lo < z_hi) {
        return Ok(None);
    }
    let mut slices = slice_depths(
        |z| camera.pixel_size_at(z),
        params.spacing,
        v0,
        z_lo,
        z_hi,
        params.max_slices,
    )?;
    slices.reverse(); // back to front
    if slices.is_empty() {
        return Ok(None);
    }
    let depths: Vec<f32> = slices.iter().map(|s| s.0).collect();
    restrict_to_bands(&mut ranges, &entry_of_cell, &vparams, &slices);
    let (slabs, empty_slabs) =
        partition(&depths, &ranges, params.partition, params.slab_min_slices);

    // Draws: per slab, batch runs of its (ascending) cell list.
    let mut list: Vec<u32> = Vec::new();
    let mut draw_data: Vec<GpuDraw> = Vec::new();
    let mut draws = Vec::new();
    let mut instances = 0u64;
    let stride = std::mem::size_of::<GpuDraw>() as u32;
    let mut push = |draws: &mut Vec<Draw>, batch, first, count: u32, off, n: u32| {
        let inst = u64::from(count) * u64::from(n);
        if inst > u64::from(u32::MAX) {
            return Err(ViewError::InvalidParam(format!(
                "{n} cells × {count} slices in one slab exceed the instance limit of 2^32"
            )));
        }
        draws.push(Draw {
            batch,
            offset: draw_data.len() as u32 * stride,
            instances: inst as u32,
        });
        draw_data.push(GpuDraw {
            first_slice: first,
            slice_count: count,
            list_offset: off,
            cell_count: n,
            pad: [0; 60],
        });
        instances += inst;
        Ok(())
    };
    for slab in &slabs {
        let mut runs: Vec<(usize, u32, u32)> = Vec::new(); // (batch, offset, count)
        for &c in &slab.cells {
            let b = batch_of_cell[c as usize] as usize;
            match runs.last_mut() {
                Some(r) if r.0 == b => r.2 += 1,
                _ => runs.push((b, list.len() as u32, 1)),
            }
            list.push(c);
        }
        let (s0, s1) = slab.slices;
        if runs.len() == 1 {
            let (b, off, n) = runs[0];
            push(&mut draws, b, s0, s1 - s0, off, n)?;
        } else {
            for s in s0..s1 {
                for &(b, off, n) in &runs {
                    push(&mut draws, b, s, 1, off, n)?;
                }
            }
        }
    }

    let (view_to_shadow, bias) = receive.unwrap_or((Mat4::IDENTITY, 0.0));
    let l = camera.view.transform_vector3(light.0).normalize_or(Vec3::Y);
    let ambient = light.1.clamp(0.0, 1.0);
    let frame = FrameUniform {
        proj: camera.projection().to_cols_array_2d(),
        view_to_shadow: view_to_shadow.to_cols_array_2d(),
        flags: [
            f32::from(u8::from(receive.is_some())),
            shadow_cutoff.unwrap_or(0.5),
            bias,
            0.0,
        ],
        light: [l.x, l.y, l.z, ambient],
    };
    // The farthest slice (the first, back to front) stands for the slab to the end of the
    // depth range (billow_core::slicing::far_slab), as the CPU slicer's does.
    let gpu_slices: Vec<GpuSlice> = slices
        .iter()
        .enumerate()
        .map(|(i, &(depth, d))| GpuSlice {
            zd: [
                -depth,
                d,
                if i == 0 { far_slab(depth, d, z_hi) } else { d },
                0.0,
            ],
        })
        .collect();
    draw_data.resize(draw_data.len().max(1), GpuDraw::default());
    let frame_bind = bufs.write(
        gpu,
        pass,
        &frame,
        &draw_data,
        [
            nonempty(&cells),
            nonempty(&gpu_slices),
            nonempty(&list),
            nonempty(&vparams),
        ],
    );
    let spacing = slices.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), s| {
        (lo.min(s.1), hi.max(s.1))
    });
    Ok(Some(VolumePlan {
        frame_bind,
        draws,
        slices: slices.len(),
        slabs: slabs.len(),
        empty_slabs,
        cells: cells.len(),
        instances,
        v0,
        spacing,
    }))
}

/// Whether the cell with view-space corners `pos` lies wholly to one side of the
/// orthographic window `(half width, half height)` (never, without a window).
fn outside_window(pos: &[[f32; 3]; 6], window: Option<(f32, f32)>) -> bool {
    let Some((hw, hh)) = window else {
        return false;
    };
    pos.iter().all(|p| p[0] < -hw)
        || pos.iter().all(|p| p[0] > hw)
        || pos.iter().all(|p| p[1] < -hh)
        || pos.iter().all(|p| p[1] > hh)
}

/// A banded asset draws each slice with one band (SPEC §8.6): clip each cell's depth
/// range to the slices whose LOD `λ = clamp(log2(d/v₀), 0, L)` ([`slice_lod`]) its band's
/// range `[f_b, f_{b+1})` holds ([`band_lod_range`],
/// [`billow_core::slicing::band_holds`]: the band [`billow_core::slicing::slice_band`]
/// picks for the CPU slicer); a cell whose band no
/// slice uses gets an empty range (`lo > hi`) and
/// no slab lists it. `slices` are back to front (depth decreasing, λ non-increasing).
/// The vertex shader checks the band again, so this only saves work.
fn restrict_to_bands(
    ranges: &mut [(f32, f32)],
    entry_of_cell: &[u32],
    vparams: &[GpuVolumeParams],
    slices: &[(f32, f32)],
) {
    for (r, &e) in ranges.iter_mut().zip(entry_of_cell) {
        let q = vparams[e as usize].q;
        if q[2] < 0.0 && q[3] >= 1e29 {
            continue; // the only band
        }
        let lambda = |d: f32| slice_lod(d, q[0], q[1]);
        // Back-to-front indices: λ is non-increasing along the list, so the slices whose
        // λ the range holds (band_holds) follow every λ ≥ hi and precede every λ < lo.
        let first = slices.partition_point(|s| lambda(s.1) >= q[3]);
        let last = slices.partition_point(|s| lambda(s.1) >= q[2]);
        if first >= last {
            *r = (1.0, 0.0);
            continue;
        }
        let (far, near) = (slices[first].0, slices[last - 1].0);
        *r = (r.0.max(near), r.1.min(far));
    }
}
