//! Uploading a cloud asset for [`super::CloudPass`], once: atlases (and their normal
//! maps) and mesh textures, one vertex buffer (the foliage mesh grouped by material, the
//! billboard quads by (level, atlas)) and one index buffer (the quads of each (level,
//! atlas) group in a fixed order), and the kept (trunk) mesh handed to the mesh pass.

use billow_format::{CloudAsset, CloudBlocks, NO_INDEX};
use glam::Vec3;

use super::{CloudPass, CloudVertex, DrawUniform, BILLBOARD_CUTOFF};
use crate::mesh_pass::{MeshData, MeshMaterial, MeshVertex};
use crate::texture::{upload_rgba8_mips, write_level, TextureData};
use crate::texture_bc::upload_bc7;
use crate::{Gpu, ViewError};

/// A foliage-mesh material's vertex range.
pub(super) struct MeshRange {
    pub(super) vertices: std::ops::Range<u32>,
    pub(super) bind: wgpu::BindGroup,
}

/// The quads of one billboard level that use one atlas: their range of the asset's
/// index buffer (6 indices per quad side).
pub(super) struct QuadGroup {
    pub(super) bind: wgpu::BindGroup,
    pub(super) indices: std::ops::Range<u32>,
    /// Lit at runtime from a normal map (else baked lighting).
    pub(super) lit: bool,
}

/// A cloud asset on the GPU.
pub struct GpuCloud {
    pub(super) vertices: wgpu::Buffer,
    pub(super) indices: wgpu::Buffer,
    /// Level 0: the foliage mesh, by material.
    pub(super) foliage: Vec<MeshRange>,
    /// Levels 1..: per billboard level, its quads by atlas.
    pub(super) billboard_levels: Vec<Vec<QuadGroup>>,
    /// Billboards per billboard level (for the stats).
    pub billboards: Vec<u32>,
    /// Per level (0: the foliage mesh's triangles, then one per billboard): the area
    /// vectors (normal × area, object space) of what it draws, for the shadow pass's
    /// counts ([`super::CloudFrame::shadow_work`]).
    pub(super) areas: Vec<Vec<Vec3>>,
    pub foliage_triangles: u32,
    /// Billboards lit at runtime from their normal maps (baked unlit, with `ANRM`).
    pub runtime_lit: bool,
    /// Object-space bounds centre and radius.
    pub centre: Vec3,
    pub radius: f32,
    /// Radius about `centre` of a sphere holding every vertex of every level at either
    /// end of its morph (and the bounds): what a shadow cascade culls instances by.
    pub caster_radius: f32,
    /// Object-space box holding the bounds and every vertex of every level at either end
    /// of its morph: what a flat caster is tested against (does a cloud lie behind it?).
    pub caster_box: (Vec3, Vec3),
    /// The kept mesh, for the mesh pass (object space); its `textures` are left empty: the
    /// mesh pass draws it with [`GpuCloud::mesh_textures`], uploaded once for the cloud
    /// and all its instances.
    pub trunk: MeshData,
    /// The asset's mesh textures (`MTEX`), as the foliage mesh and the kept mesh sample them.
    pub mesh_textures: Vec<wgpu::TextureView>,
    /// Atlases and normal maps uploaded as BC7 blocks (format 1.2, [`Gpu::block_upload`]).
    pub block_textures: u32,
}

impl GpuCloud {
    /// Levels including the foliage mesh.
    pub fn level_count(&self) -> usize {
        1 + self.billboard_levels.len()
    }

    /// Quad sides drawn per instance of billboard level `level` (≥ 1).
    pub fn quads(&self, level: usize) -> usize {
        self.billboard_levels
            .get(level.wrapping_sub(1))
            .map_or(0, |g| g.iter().map(|q| q.indices.len() / 6).sum())
    }
}

/// An `Rgba8Unorm` (linear) texture with exactly the given levels (level `i` is
/// `max(1, w >> i)` × `max(1, h >> i)`): normal maps.
pub(super) fn linear_texture(
    gpu: &Gpu,
    width: u32,
    height: u32,
    levels: &[Vec<u8>],
) -> wgpu::Texture {
    let tex = gpu.asset_texture(&wgpu::TextureDescriptor {
        label: Some("cloud normal map"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels.len().max(1) as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (l, texels) in levels.iter().enumerate() {
        let (w, h) = ((width >> l).max(1), (height >> l).max(1));
        write_level(gpu, &tex, l as u32, texels, (w, h));
    }
    tex
}

/// Fraction of the texels whose alpha, scaled by `scale`, reaches `cutoff`.
fn coverage(texels: &[u8], cutoff: f32, scale: f32) -> f64 {
    let pass = texels
        .chunks_exact(4)
        .filter(|p| f32::from(p[3]) / 255.0 * scale >= cutoff)
        .count();
    pass as f64 / (texels.len() / 4).max(1) as f64
}

/// Scales a premultiplied sRGB level's alpha so that the fraction of texels passing the
/// alpha test at `cutoff` is `target` (level 0's; Castaño, "Computing alpha mipmaps",
/// 2010), keeping each texel's straight colour (premultiplied colour scaled with alpha).
/// Averaged alpha MIPs thin an alpha-tested canopy with distance; assets whose MIPs
/// already preserve coverage come out (almost) unchanged.
fn preserve_coverage(level: &mut [u8], cutoff: f32, target: f64) {
    let (mut lo, mut hi) = (0.0f32, 8.0f32);
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if coverage(level, cutoff, mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // Only ever scale up (a level never loses coverage to this), and leave a level that
    // already has its share as it is.
    let s = hi.max(1.0);
    if s == 1.0 || coverage(level, cutoff, 1.0) >= target {
        return;
    }
    let decode = |v: u8| {
        let v = f32::from(v) / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let encode = |v: f32| {
        let v = v.clamp(0.0, 1.0);
        let e = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (e * 255.0).round() as u8
    };
    for p in level.chunks_exact_mut(4) {
        if p[3] == 0 {
            continue;
        }
        let a = f32::from(p[3]) / 255.0;
        let a2 = (a * s).min(1.0);
        let k = a2 / a;
        for c in &mut p[..3] {
            *c = encode(decode(*c) * k);
        }
        p[3] = (a2 * 255.0).round() as u8;
    }
}

impl CloudPass {
    fn bind(
        &self,
        gpu: &Gpu,
        params: [f32; 4],
        color: [f32; 4],
        view: &wgpu::TextureView,
        normals: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let buf = gpu.buffer(
            "cloud draw",
            bytemuck::bytes_of(&DrawUniform { params, color }),
            wgpu::BufferUsages::UNIFORM,
        );
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cloud draw"),
            layout: &self.draw_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(normals),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&self.shadow_sampler),
                },
            ],
        })
    }

    /// Uploads a cloud asset: atlases (with their normal maps), billboard quads grouped
    /// by (level, atlas), the foliage mesh grouped by material; the trunk is returned as
    /// [`GpuCloud::trunk`]. Nothing of it changes afterwards.
    pub fn upload(&self, gpu: &Gpu, asset: &CloudAsset) -> Result<GpuCloud, ViewError> {
        self.upload_with(gpu, asset, None)
    }

    /// [`CloudPass::upload`] of a compressed asset: atlases and normal maps are uploaded as
    /// their BC7 `blocks` where the device allows it ([`Gpu::block_upload`]; the blocks
    /// are drawn as the baker stored them, its MIP alpha already keeps the alpha-tested
    /// coverage), else as the decoded texels in `asset` (what the reader decoded on load).
    /// Mesh textures are always uploaded decoded: the viewer builds their MIP chains.
    pub fn upload_with(
        &self,
        gpu: &Gpu,
        asset: &CloudAsset,
        blocks: Option<&CloudBlocks>,
    ) -> Result<GpuCloud, ViewError> {
        asset
            .validate()
            .map_err(|e| ViewError::InvalidAsset(e.to_string()))?;
        let blocks = blocks.filter(|b| b.atlases.len() == asset.atlases.len());
        let mut block_textures = 0u32;
        let atlas_views: Vec<wgpu::TextureView> = asset
            .atlases
            .iter()
            .enumerate()
            .map(|(i, a)| {
                if let Some(b) = blocks.filter(|_| gpu.block_upload([a.width, a.height, 1], false))
                {
                    block_textures += 1;
                    return upload_bc7(
                        gpu,
                        "cloud atlas (BC7)",
                        [a.width, a.height, 1],
                        wgpu::TextureDimension::D2,
                        &b.atlases[i],
                        true,
                    )
                    .create_view(&Default::default());
                }
                let mut mips = a.mips[1..].to_vec();
                let target = coverage(&a.mips[0], BILLBOARD_CUTOFF, 1.0);
                for m in &mut mips {
                    preserve_coverage(m, BILLBOARD_CUTOFF, target);
                }
                let t = TextureData {
                    width: a.width,
                    height: a.height,
                    texels: a.mips[0].clone(),
                    premultiplied: true,
                    mips,
                };
                upload_rgba8_mips(gpu, &t, "cloud atlas").create_view(&Default::default())
            })
            .collect();
        // Runtime lighting: every atlas has a normal map and the bake left lighting out.
        let unlit = asset.header.baked_light().is_ok_and(|l| l.is_unlit());
        let has_normals =
            !asset.atlases.is_empty() && asset.atlases.iter().all(|a| a.normals.is_some());
        let runtime_lit = unlit && has_normals;
        let normal_blocks = blocks.and_then(|b| b.atlas_normals.as_ref());
        let normal_views: Vec<Option<wgpu::TextureView>> = asset
            .atlases
            .iter()
            .enumerate()
            .map(|(i, a)| match (&a.normals, runtime_lit) {
                (Some(n), true) => Some(
                    match normal_blocks.filter(|_| gpu.block_upload([a.width, a.height, 1], false))
                    {
                        Some(nb) => {
                            block_textures += 1;
                            upload_bc7(
                                gpu,
                                "cloud normal map (BC7)",
                                [a.width, a.height, 1],
                                wgpu::TextureDimension::D2,
                                &nb[i],
                                false,
                            )
                        }
                        None => linear_texture(gpu, a.width, a.height, n),
                    }
                    .create_view(&Default::default()),
                ),
                _ => None,
            })
            .collect();
        let mesh_textures: Vec<wgpu::TextureView> = asset
            .textures
            .iter()
            .map(|t| {
                // Plain MIPs: the foliage mesh's alpha test is hashed where they are used.
                let d = TextureData::straight(t.width, t.height, t.texels.clone());
                upload_rgba8_mips(gpu, &d, "cloud mesh texture").create_view(&Default::default())
            })
            .collect();
        let mut verts: Vec<CloudVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
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
                        tangent: [0.0; 4],
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
                    bind: self.bind(
                        gpu,
                        [cutoff, 0.0, 1.0, textured],
                        m.base_color_factor,
                        view,
                        &self.flat_normal,
                    ),
                });
            }
        }
        let pos = |i: u32| Vec3::from(f.vertices[i as usize].position);
        let mut areas = vec![f
            .triangles
            .iter()
            .map(|t| 0.5 * (pos(t[1]) - pos(t[0])).cross(pos(t[2]) - pos(t[0])))
            .collect::<Vec<Vec3>>()];
        // Billboard levels, by atlas: 4 vertices and 6 indices per quad side.
        let mut billboards = Vec::new();
        let mut billboard_levels = Vec::new();
        for l in &asset.levels {
            let bbs = &asset.billboards
                [l.first_billboard as usize..(l.first_billboard + l.billboard_count) as usize];
            billboards.push(l.billboard_count);
            areas.push(
                bbs.iter()
                    .map(|b| {
                        let c = b.corners.map(Vec3::from);
                        (c[1] - c[0]).cross(c[3] - c[0])
                    })
                    .collect(),
            );
            let mut groups = Vec::new();
            for a in l.first_atlas..l.first_atlas + l.atlas_count {
                let first_index = indices.len() as u32;
                for b in bbs {
                    let n = Vec3::new(b.plane[0], b.plane[1], b.plane[2]);
                    let u = (Vec3::from(b.corners[1]) - Vec3::from(b.corners[0]))
                        .normalize_or(n.any_orthonormal_vector());
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
                    // Tangent frame (SPEC §9.4): T = U, B = −V = s·(N × T), s = −1 on the
                    // front (N = n, n × U = V), +1 on the back (N = −n).
                    for (rect, order, nn, s) in [
                        (&b.front, [0usize, 1, 2, 3], n, -1.0),
                        (&b.back, [0, 3, 2, 1], -n, 1.0),
                    ] {
                        if rect.atlas != a {
                            continue;
                        }
                        let [u0, v0, u1, v1] = rect.uv;
                        let uv = [[u0, v0], [u1, v0], [u1, v1], [u0, v1]];
                        let base = verts.len() as u32;
                        for c in order {
                            verts.push(CloudVertex {
                                pos: b.corners[c],
                                target: target(c),
                                normal: nn.to_array(),
                                uv: uv[c],
                                tangent: [u.x, u.y, u.z, s],
                            });
                        }
                        indices.extend_from_slice(&[
                            base,
                            base + 1,
                            base + 2,
                            base,
                            base + 2,
                            base + 3,
                        ]);
                    }
                }
                let end = indices.len() as u32;
                if end > first_index {
                    let normals = normal_views[a as usize].as_ref();
                    groups.push(QuadGroup {
                        bind: self.bind(
                            gpu,
                            [
                                BILLBOARD_CUTOFF,
                                1.0,
                                f32::from(u8::from(normals.is_some())),
                                1.0,
                            ],
                            [1.0; 4],
                            &atlas_views[a as usize],
                            normals.unwrap_or(&self.flat_normal),
                        ),
                        indices: first_index..end,
                        lit: normals.is_some(),
                    });
                }
            }
            billboard_levels.push(groups);
        }
        let b = &asset.header.bounds;
        let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
        let centre = 0.5 * (lo + hi);
        let radius = 0.5 * (hi - lo).length();
        let caster_radius = verts.iter().fold(radius, |r, v| {
            let d = (Vec3::from(v.pos) - centre).length();
            r.max(d).max((Vec3::from(v.target) - centre).length())
        });
        let caster_box = verts.iter().fold((lo, hi), |(a, b), v| {
            let (p, t) = (Vec3::from(v.pos), Vec3::from(v.target));
            (a.min(p).min(t), b.max(p).max(t))
        });
        let n = verts.len();
        verts.resize(n.max(1), CloudVertex::default());
        let n = indices.len();
        indices.resize(n.max(3), 0);
        let vertices = gpu.buffer(
            "cloud vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        );
        let indices = gpu.buffer(
            "cloud indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        Ok(GpuCloud {
            vertices,
            indices,
            foliage,
            billboard_levels,
            billboards,
            areas,
            foliage_triangles: f.triangles.len() as u32,
            runtime_lit,
            centre,
            radius,
            caster_radius,
            caster_box,
            trunk: trunk_mesh(asset),
            mesh_textures,
            block_textures,
        })
    }
}

/// The asset's kept (non-foliage) mesh as mesh-pass data, object space.
fn trunk_mesh(asset: &CloudAsset) -> MeshData {
    let t = &asset.trunk;
    let mut out = MeshData {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atlas_levels_keep_their_coverage_and_straight_colour() {
        // Level 0: one opaque texel in four (coverage 0.25 at the 0.5 cut-off); its
        // averaged MIP has alpha 0.25 everywhere (coverage 0). Scaled, the level passes
        // again, with the same straight colour.
        let level0 = [[188u8, 137, 99, 255], [0; 4], [0; 4], [0; 4]].concat();
        let mut mip = vec![99u8, 70, 50, 64];
        let target = coverage(&level0, 0.5, 1.0);
        assert_eq!(target, 0.25);
        assert_eq!(coverage(&mip, 0.5, 1.0), 0.0);
        let straight = |p: &[u8]| {
            let d = |v: u8| {
                let v = f32::from(v) / 255.0;
                if v <= 0.04045 {
                    v / 12.92
                } else {
                    ((v + 0.055) / 1.055).powf(2.4)
                }
            };
            let a = f32::from(p[3]) / 255.0;
            [d(p[0]) / a, d(p[1]) / a, d(p[2]) / a]
        };
        let before = straight(&mip);
        preserve_coverage(&mut mip, 0.5, target);
        assert!(mip[3] >= 128, "{mip:?}");
        let after = straight(&mip);
        for c in 0..3 {
            assert!(
                (before[c] - after[c]).abs() < 0.02,
                "{before:?} vs {after:?}"
            );
        }
        // A level that already has its coverage is left alone.
        let mut full = vec![200u8, 100, 50, 255];
        preserve_coverage(&mut full, 0.5, 1.0);
        assert_eq!(full, vec![200, 100, 50, 255]);
    }
}
