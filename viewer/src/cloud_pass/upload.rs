//! Uploading a cloud asset for [`super::CloudPass`]: atlases and mesh textures, the
//! billboard quads grouped by (level, atlas), the foliage mesh grouped by material, and
//! the kept (trunk) mesh handed to the mesh pass.

use billow_format::{CloudAsset, NO_INDEX};
use glam::Vec3;

use super::{CloudPass, CloudVertex, DrawUniform, BILLBOARD_CUTOFF};
use crate::mesh_pass::{MeshData, MeshMaterial, MeshVertex};
use crate::texture::{upload_rgba8_mips, TextureData};
use crate::{Gpu, ViewError};

/// A foliage-mesh material's vertex range.
pub(super) struct MeshRange {
    pub(super) vertices: std::ops::Range<u32>,
    pub(super) bind: wgpu::BindGroup,
}

/// The quads of one billboard level that use one atlas: 4 vertices each from
/// `first_vertex`, with their own and target (parent) centres for sorting.
pub(super) struct QuadGroup {
    pub(super) bind: wgpu::BindGroup,
    pub(super) first_vertex: u32,
    pub(super) centres: Vec<(Vec3, Vec3)>,
}

/// A cloud asset on the GPU.
pub struct GpuCloud {
    pub(super) buffer: wgpu::Buffer,
    /// Level 0: the foliage mesh, by material.
    pub(super) foliage: Vec<MeshRange>,
    /// Levels 1..: per billboard level, its quads by atlas.
    pub(super) billboard_levels: Vec<Vec<QuadGroup>>,
    /// Billboards per billboard level (for the stats).
    pub billboards: Vec<u32>,
    pub foliage_triangles: u32,
    /// Object-space bounds centre and radius.
    pub centre: Vec3,
    pub radius: f32,
    /// The kept mesh, for the mesh pass (object space).
    pub trunk: MeshData,
}

impl GpuCloud {
    /// Levels including the foliage mesh.
    pub fn level_count(&self) -> usize {
        1 + self.billboard_levels.len()
    }
}

impl CloudPass {
    fn bind(
        &self,
        gpu: &Gpu,
        params: [f32; 4],
        color: [f32; 4],
        view: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        gpu.uniform_texture_bind_group(
            "cloud draw",
            &self.draw_layout,
            bytemuck::bytes_of(&DrawUniform { params, color }),
            view,
            &self.sampler,
        )
    }

    /// Uploads a cloud asset: atlases, billboard quads grouped by (level, atlas), the
    /// foliage mesh grouped by material; the trunk is returned as [`GpuCloud::trunk`].
    pub fn upload(&self, gpu: &Gpu, asset: &CloudAsset) -> Result<GpuCloud, ViewError> {
        asset
            .validate()
            .map_err(|e| ViewError::InvalidAsset(e.to_string()))?;
        let atlas_views: Vec<wgpu::TextureView> = asset
            .atlases
            .iter()
            .map(|a| {
                let t = TextureData {
                    width: a.width,
                    height: a.height,
                    texels: a.mips[0].clone(),
                    premultiplied: true,
                    mips: a.mips[1..].to_vec(),
                    coverage_cutoff: None,
                };
                upload_rgba8_mips(gpu, &t, "cloud atlas").create_view(&Default::default())
            })
            .collect();
        let mesh_textures: Vec<wgpu::TextureView> = asset
            .textures
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut d = TextureData::straight(t.width, t.height, t.texels.clone());
                d.coverage_cutoff = asset
                    .materials
                    .iter()
                    .find(|m| m.texture == Some(i as u32) && m.alpha_mode != 0)
                    .map(|m| {
                        if m.alpha_mode == 1 {
                            m.alpha_cutoff
                        } else {
                            0.5
                        }
                    });
                upload_rgba8_mips(gpu, &d, "cloud mesh texture").create_view(&Default::default())
            })
            .collect();
        let mut verts: Vec<CloudVertex> = Vec::new();
        // Level 0: the foliage mesh, by material.
        let f = &asset.foliage;
        let mut foliage = Vec::new();
        for (mi, m) in asset.materials.iter().enumerate() {
            let start = verts.len() as u32;
            for (t, tri) in f.triangles.iter().enumerate() {
                if f.materials[t] as usize != mi {
                    continue;
                }
                for &i in tri {
                    let v = &f.vertices[i as usize];
                    verts.push(CloudVertex {
                        pos: v.position,
                        target: f.morph[i as usize],
                        normal: v.normal,
                        uv: v.uv,
                    });
                }
            }
            let end = verts.len() as u32;
            if end > start {
                let cutoff = if m.alpha_mode == 1 {
                    m.alpha_cutoff
                } else {
                    0.5
                };
                let view = m
                    .texture
                    .map_or(&self.white, |t| &mesh_textures[t as usize]);
                let textured = f32::from(u8::from(m.texture.is_some()));
                foliage.push(MeshRange {
                    vertices: start..end,
                    bind: self.bind(gpu, [cutoff, 0.0, 1.0, textured], m.base_color_factor, view),
                });
            }
        }
        // Billboard levels, by atlas: 4 vertices per quad side.
        let mut billboards = Vec::new();
        let mut billboard_levels = Vec::new();
        for l in &asset.levels {
            let bbs = &asset.billboards
                [l.first_billboard as usize..(l.first_billboard + l.billboard_count) as usize];
            billboards.push(l.billboard_count);
            let mut groups = Vec::new();
            for a in l.first_atlas..l.first_atlas + l.atlas_count {
                let first_vertex = verts.len() as u32;
                let mut centres = Vec::new();
                for b in bbs {
                    let n = Vec3::new(b.plane[0], b.plane[1], b.plane[2]);
                    let has_parent = b.parent.is_some_and(|p| p != NO_INDEX);
                    let target = |c: usize| {
                        if has_parent {
                            b.parent_corners[c]
                        } else {
                            b.corners[c]
                        }
                    };
                    // Front: corners 0,1,2,3 (counter-clockwise from +normal); back: the
                    // reverse order, so both sides are front faces where they are seen.
                    for (rect, order, nn) in [
                        (&b.front, [0usize, 1, 2, 3], n),
                        (&b.back, [0, 3, 2, 1], -n),
                    ] {
                        if rect.atlas != a {
                            continue;
                        }
                        let [u0, v0, u1, v1] = rect.uv;
                        let uv = [[u0, v0], [u1, v0], [u1, v1], [u0, v1]];
                        for c in order {
                            verts.push(CloudVertex {
                                pos: b.corners[c],
                                target: target(c),
                                normal: nn.to_array(),
                                uv: uv[c],
                            });
                        }
                        let mean = |p: [[f32; 3]; 4]| {
                            p.iter().map(|q| Vec3::from(*q)).sum::<Vec3>() * 0.25
                        };
                        centres.push((mean(b.corners), mean([0, 1, 2, 3].map(target))));
                    }
                }
                if !centres.is_empty() {
                    groups.push(QuadGroup {
                        bind: self.bind(
                            gpu,
                            [BILLBOARD_CUTOFF, 1.0, 0.0, 1.0],
                            [1.0; 4],
                            &atlas_views[a as usize],
                        ),
                        first_vertex,
                        centres,
                    });
                }
            }
            billboard_levels.push(groups);
        }
        let n = verts.len();
        verts.resize(n.max(1), CloudVertex::default());
        let buffer = gpu.buffer(
            "cloud vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        );
        let b = &asset.header.bounds;
        let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
        Ok(GpuCloud {
            buffer,
            foliage,
            billboard_levels,
            billboards,
            foliage_triangles: f.triangles.len() as u32,
            centre: 0.5 * (lo + hi),
            radius: 0.5 * (hi - lo).length(),
            trunk: trunk_mesh(asset),
        })
    }
}

/// The asset's kept (non-foliage) mesh as mesh-pass data, object space.
fn trunk_mesh(asset: &CloudAsset) -> MeshData {
    let t = &asset.trunk;
    let mut out = MeshData {
        textures: asset
            .textures
            .iter()
            .map(|x| TextureData::straight(x.width, x.height, x.texels.clone()))
            .collect(),
        materials: asset
            .materials
            .iter()
            .map(|m| MeshMaterial {
                texture: m.texture,
                alpha_cutoff: match m.alpha_mode {
                    1 => Some(m.alpha_cutoff),
                    2 => Some(0.5),
                    _ => None,
                },
            })
            .collect(),
        ..Default::default()
    };
    for (ti, tri) in t.triangles.iter().enumerate() {
        let m = &asset.materials[t.materials[ti] as usize];
        for &i in tri {
            let v = &t.vertices[i as usize];
            out.vertices.push(MeshVertex {
                pos: v.position,
                normal: v.normal,
                uv: v.uv,
                color: m.base_color_factor,
            });
        }
        out.triangle_materials.push(t.materials[ti]);
    }
    out
}
