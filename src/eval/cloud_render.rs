//! CPU renderer for billboard-cloud assets (Lacewell et al. 2006; formats/SPEC.md §9): the
//! textured quads of one LOD level plus the kept (trunk) mesh, the reference a GPU
//! renderer of clouds is measured against.
//!
//! - **Billboards** of level `K` are intersected exactly by every sample ray (plane hit,
//!   then the quad's `[0,1)²` parameter range). The side is the one the ray comes from:
//!   the **front** texture when the ray travels against the plane normal (the viewer is on
//!   the +n side), the **back** one otherwise, both with the spec's corner → uv mapping.
//! - **Textures**: atlas texels are decoded once to linear premultiplied RGBA f32 (the sRGB
//!   EOTF on the stored premultiplied rgb, alpha / 255 — what an `*_SRGB` GPU format does),
//!   then filtered: bilinear within a level (texel centres at `(i + ½)/w`, clamp-to-edge),
//!   linear between the two nearest levels (GPU `LINEAR_MIPMAP_LINEAR`).
//! - **MIP selection by screen footprint**, as a GPU does it: the uv derivatives (in texels
//!   of level 0) towards the next pixel in x and in y are taken from the rays through
//!   `(px + 1, py)` and `(px, py + 1)` hitting the same (unbounded) plane, and
//!   `lod = log2(max(|∂uv/∂x|, |∂uv/∂y|))`, clamped to the atlas's levels; a derivative ray
//!   that misses the plane (grazing view) selects the coarsest level.
//! - **Trunk**: the kept mesh is ray-traced by [`ReferenceRenderer`] with the reference's
//!   shading and lighting (so it matches the reference wherever it is visible).
//! - **Runtime lighting**: a cloud baked unlit with normal maps (`bbcloud --normal-map
//!   --unlit`) is lit under a scene light ([`Lighting::Scene`], `billow eval --light`) as
//!   the viewer lights it (`cloud.wgsl`, `fs_billboard`): its straight albedo times
//!   `ambient + (1 − ambient)·|N·L|` (the shared core's two-sided Lambert), N the normal
//!   map's texel in the side's tangent frame (SPEC §9.4), filtered like the colour. Clouds
//!   with baked lighting show their texels as they are.
//! - **Alpha test**: billboards are alpha-tested like the viewer draws them (and Lacewell
//!   §6): a filtered texel with alpha at least [`ALPHA_CUTOFF`] (0.5) is an opaque hit of
//!   its straight colour (`rgb / α`), any other is a miss. The atlases' MIPs keep each
//!   level's tested coverage ([`crate::bbcloud::atlas::coverage_chain`]). Anti-aliasing
//!   comes from the `n × n` samples per pixel.
//! - **Compositing**: per sample ray, billboard hits and the trunk's blended layers are
//!   sorted by depth (ties: trunk first, then billboard index) and composited front to back
//!   (premultiplied "under", f32), stopping at the first opaque hit.
//! - **Sampling**: the same `n × n` pattern as the reference ([`super::reference`]), so
//!   quad and trunk edges are anti-aliased like the reference's; the texture filtering
//!   uses the pixel footprint, not the sample's.
//! - Rows are rendered in parallel; each pixel's result depends only on its own rays, so
//!   the image is the same for any thread count.

use std::time::Instant;

use billow_format::{CloudAsset, ColourSpace};
use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::lighting::Lighting;
use super::reference::{
    in_rect, per_axis, sample_offset, validate_camera, ReferenceRenderer, Sampling,
};
use super::{EvalError, ImageF32};
use crate::bbcloud::atlas::ALPHA_CUTOFF;
use crate::scene::{AlphaMode, Material, Scene, Texture, Triangle, Vertex, Wrap};
use crate::texture::srgb_to_linear_lut;
use billow_core::camera::Camera;
use billow_core::compositing::under;

/// One decoded atlas: per MIP level `(width, height, texels)`, linear premultiplied.
struct DecodedAtlas {
    levels: Vec<(u32, u32, Vec<Vec4>)>,
}

impl DecodedAtlas {
    fn texel(&self, level: usize, x: i64, y: i64) -> Vec4 {
        let (w, h, t) = &self.levels[level];
        let x = x.clamp(0, i64::from(*w) - 1) as usize;
        let y = y.clamp(0, i64::from(*h) - 1) as usize;
        t[y * *w as usize + x]
    }

    fn bilinear(&self, level: usize, uv: Vec2) -> Vec4 {
        let (w, h, _) = &self.levels[level];
        let x = uv.x * *w as f32 - 0.5;
        let y = uv.y * *h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(level, x0, y0) * (1.0 - fx) + self.texel(level, x0 + 1, y0) * fx;
        let b = self.texel(level, x0, y0 + 1) * (1.0 - fx) + self.texel(level, x0 + 1, y0 + 1) * fx;
        a * (1.0 - fy) + b * fy
    }

    /// Trilinear sample at `lod` (level-0 texels per pixel, log2).
    fn sample(&self, uv: Vec2, lod: f32) -> Vec4 {
        let max = (self.levels.len() - 1) as f32;
        let lod = if lod.is_nan() {
            max
        } else {
            lod.clamp(0.0, max)
        };
        let l0 = lod.floor();
        let f = lod - l0;
        let c0 = self.bilinear(l0 as usize, uv);
        if f <= 0.0 {
            return c0;
        }
        c0 * (1.0 - f) + self.bilinear((l0 as usize + 1).min(max as usize), uv) * f
    }
}

/// One billboard side ready for ray casting.
#[derive(Clone, Copy, Debug)]
struct Quad {
    normal: Vec3,
    r: f32,
    c0: Vec3,
    /// Edge vectors c0→c1 and c0→c3 divided by their squared lengths (parameter = dot).
    du: Vec3,
    dv: Vec3,
    /// (atlas, [u0, v0, u1, v1]) of the front and the back.
    sides: [(usize, [f32; 4]); 2],
    /// Unit directions of increasing u and v (the normal maps' tangent frame, SPEC §9.4).
    u_dir: Vec3,
    v_dir: Vec3,
}

/// What a cloud render did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CloudStats {
    /// Billboards of the level.
    pub billboards: usize,
    /// Billboards that at least one sample ray hit with non-zero alpha.
    pub visible_billboards: usize,
    /// Billboard samples shaded (ray × billboard hits).
    pub fragments: u64,
    pub seconds: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct CloudRender {
    pub image: ImageF32,
    pub stats: CloudStats,
}

/// A cloud asset decoded for rendering (atlases decoded once; reusable for every view and
/// level).
pub struct PreparedCloud {
    levels: Vec<(std::ops::Range<usize>, f32)>,
    quads: Vec<Quad>,
    atlases: Vec<DecodedAtlas>,
    /// The atlases' normal maps (tangent-space unit normals, linear), when the cloud was
    /// baked unlit with them: the viewer then lights its billboards like meshes
    /// (`cloud.wgsl`, `fs_billboard`), and so does this renderer under a scene light.
    normal_maps: Option<Vec<DecodedAtlas>>,
    atlas_bytes: Vec<u64>,
    /// The kept mesh as a scene.
    pub trunk: Scene,
}

fn wrap_of(code: u32) -> Wrap {
    match code {
        1 => Wrap::ClampToEdge,
        2 => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    }
}

/// The kept (trunk) mesh of `asset` as a [`Scene`] (vertex colour 1).
pub fn trunk_scene(asset: &CloudAsset) -> Scene {
    let materials = asset
        .materials
        .iter()
        .enumerate()
        .map(|(i, m)| Material {
            name: format!("material {i}"),
            base_color_factor: Vec4::from_array(m.base_color_factor),
            base_color_texture: m.texture,
            alpha_mode: match m.alpha_mode {
                1 => AlphaMode::Mask {
                    cutoff: m.alpha_cutoff,
                },
                2 => AlphaMode::Blend,
                _ => AlphaMode::Opaque,
            },
            double_sided: m.double_sided,
            unlit: false,
        })
        .collect();
    let textures = asset
        .textures
        .iter()
        .enumerate()
        .map(|(i, t)| Texture {
            name: format!("texture {i}"),
            width: t.width,
            height: t.height,
            texels: t
                .texels
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            wrap_u: wrap_of(t.wrap[0]),
            wrap_v: wrap_of(t.wrap[1]),
            encoded: None,
        })
        .collect();
    let m = &asset.trunk;
    let mut bounds = billow_core::Aabb::EMPTY;
    let triangles = m
        .triangles
        .iter()
        .zip(&m.materials)
        .map(|(t, &material)| {
            let v = t.map(|i| {
                let v = &m.vertices[i as usize];
                bounds.grow(Vec3::from(v.position));
                Vertex {
                    position: Vec3::from(v.position),
                    normal: Vec3::from(v.normal),
                    uv: Vec2::from(v.uv),
                    color: Vec4::ONE,
                }
            });
            Triangle {
                v,
                material,
                mesh: 0,
            }
        })
        .collect();
    Scene {
        triangles,
        materials,
        textures,
        meshes: Vec::new(),
        bounds,
    }
}

impl PreparedCloud {
    /// Validates and decodes `asset`.
    pub fn new(asset: &CloudAsset) -> Result<Self, EvalError> {
        asset
            .validate()
            .map_err(|e| EvalError::InvalidAsset(e.to_string()))?;
        let lut = srgb_to_linear_lut();
        let srgb = asset.header.colour_space == ColourSpace::SrgbPremultiplied;
        let atlases = asset
            .atlases
            .iter()
            .map(|a| DecodedAtlas {
                levels: a
                    .mips
                    .iter()
                    .enumerate()
                    .map(|(k, bytes)| {
                        let w = (a.width >> k).max(1);
                        let h = (a.height >> k).max(1);
                        let c = |b: u8| {
                            if srgb {
                                lut[b as usize]
                            } else {
                                f32::from(b) / 255.0
                            }
                        };
                        let t = bytes
                            .chunks_exact(4)
                            .map(|p| Vec4::new(c(p[0]), c(p[1]), c(p[2]), f32::from(p[3]) / 255.0))
                            .collect();
                        (w, h, t)
                    })
                    .collect(),
            })
            .collect();
        let atlas_bytes = asset
            .atlases
            .iter()
            .map(|a| a.mips.iter().map(|m| m.len() as u64).sum())
            .collect();
        let unlit = asset.header.baked_light().is_ok_and(|l| l.is_unlit());
        let normal_maps = asset
            .atlases
            .iter()
            .map(|a| {
                let normals = a.normals.as_ref()?;
                Some(DecodedAtlas {
                    levels: normals
                        .iter()
                        .enumerate()
                        .map(|(k, bytes)| {
                            let w = (a.width >> k).max(1);
                            let h = (a.height >> k).max(1);
                            let n = |b: u8| f32::from(b) / 255.0 * 2.0 - 1.0;
                            let t = bytes
                                .chunks_exact(4)
                                .map(|p| Vec4::new(n(p[0]), n(p[1]), n(p[2]), 0.0))
                                .collect();
                            (w, h, t)
                        })
                        .collect(),
                })
            })
            .collect::<Option<Vec<_>>>()
            .filter(|m| unlit && !m.is_empty());
        let quads = asset
            .billboards
            .iter()
            .map(|b| {
                let c = b.corners.map(Vec3::from);
                let (e1, e3) = (c[1] - c[0], c[3] - c[0]);
                let inv = |e: Vec3| {
                    let l2 = e.length_squared();
                    if l2 > 0.0 && l2.is_finite() {
                        e / l2
                    } else {
                        Vec3::ZERO
                    }
                };
                let n = Vec3::new(b.plane[0], b.plane[1], b.plane[2]);
                Quad {
                    normal: n,
                    r: n.dot(c[0]),
                    c0: c[0],
                    du: inv(e1),
                    dv: inv(e3),
                    u_dir: e1.normalize_or_zero(),
                    v_dir: e3.normalize_or_zero(),
                    sides: [
                        (b.front.atlas as usize, b.front.uv),
                        (b.back.atlas as usize, b.back.uv),
                    ],
                }
            })
            .collect();
        let levels = asset
            .levels
            .iter()
            .map(|l| {
                let first = l.first_billboard as usize;
                (first..first + l.billboard_count as usize, l.texel_density)
            })
            .collect();
        Ok(PreparedCloud {
            levels,
            quads,
            atlases,
            normal_maps,
            atlas_bytes,
            trunk: trunk_scene(asset),
        })
    }

    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Billboards of level `lod`.
    pub fn billboards(&self, lod: usize) -> usize {
        self.levels.get(lod).map_or(0, |l| l.0.len())
    }

    /// Texels per world unit of level `lod`'s textures.
    pub fn texel_density(&self, lod: usize) -> f32 {
        self.levels.get(lod).map_or(0.0, |l| l.1)
    }

    /// Bytes of the atlases (all MIP levels) that level `lod` uses.
    pub fn texture_bytes(&self, asset: &CloudAsset, lod: usize) -> u64 {
        asset.levels.get(lod).map_or(0, |l| {
            let first = l.first_atlas as usize;
            self.atlas_bytes[first..first + l.atlas_count as usize]
                .iter()
                .sum()
        })
    }
}

/// Renders a [`PreparedCloud`]; the trunk is traced with the given lighting.
pub struct CloudRenderer<'a> {
    cloud: &'a PreparedCloud,
    trunk: ReferenceRenderer<'a>,
    /// Under a scene light ([`Lighting::Scene`]), a cloud with normal maps is lit by it:
    /// unit direction towards the light, ambient.
    light: Option<(Vec3, f32)>,
}

/// A billboard hit: depth, billboard index, premultiplied colour.
type Hit = (f32, usize, Vec4);

/// Primary rays of a camera with the inverse view matrix computed once
/// (same directions as [`Camera::ray`]).
struct Rays<'c> {
    camera: &'c Camera,
    inv: glam::Mat4,
}

impl Rays<'_> {
    fn dir(&self, px: f32, py: f32) -> Vec3 {
        self.inv
            .transform_vector3(self.camera.view_dir_of_pixel(px, py))
    }
}

impl<'a> CloudRenderer<'a> {
    pub fn new(cloud: &'a PreparedCloud, lighting: Lighting) -> Result<Self, EvalError> {
        let light = match lighting {
            Lighting::Scene { light, ambient, .. } if cloud.normal_maps.is_some() => {
                Some((light, ambient))
            }
            _ => None,
        };
        Ok(CloudRenderer {
            cloud,
            trunk: ReferenceRenderer::new(&cloud.trunk).with_lighting(lighting)?,
            light,
        })
    }

    /// The parameters `(s, t)` of the quad point hit by `origin + t·dir`, and `t`.
    fn plane_hit(q: &Quad, origin: Vec3, dir: Vec3) -> Option<(Vec2, f32)> {
        let denom = q.normal.dot(dir);
        if denom == 0.0 || !denom.is_finite() {
            return None;
        }
        let t = (q.r - q.normal.dot(origin)) / denom;
        if !t.is_finite() {
            return None;
        }
        let p = origin + dir * t - q.c0;
        Some((Vec2::new(p.dot(q.du), p.dot(q.dv)), t))
    }

    /// Colour of quad `q` hit at `st` by a ray of direction `dir` through pixel
    /// `(px, py)`; `lod` from the rays through the neighbouring pixels. Also the side's
    /// world normal from its normal map, when it is lit at runtime.
    fn shade(
        &self,
        q: &Quad,
        st: Vec2,
        dir: Vec3,
        rays: &Rays,
        px: f32,
        py: f32,
    ) -> (Vec4, Option<Vec3>) {
        let side = usize::from(q.normal.dot(dir) > 0.0);
        let (atlas_index, r) = q.sides[side];
        let atlas = &self.cloud.atlases[atlas_index];
        let (w0, h0, _) = atlas.levels[0];
        let scale = Vec2::new((r[2] - r[0]) * w0 as f32, (r[3] - r[1]) * h0 as f32);
        let uv_of = |st: Vec2| Vec2::new(r[0], r[1]) + st * Vec2::new(r[2] - r[0], r[3] - r[1]);
        let deriv = |ox: f32, oy: f32| -> Option<f32> {
            let (s2, _) = Self::plane_hit(q, rays.camera.eye, rays.dir(px + ox, py + oy))?;
            Some(((s2 - st) * scale).length())
        };
        let lod = match (deriv(1.0, 0.0), deriv(0.0, 1.0)) {
            (Some(a), Some(b)) if a.max(b) > 0.0 => a.max(b).log2(),
            (Some(_), Some(_)) => 0.0,
            _ => f32::INFINITY,
        };
        let colour = atlas.sample(uv_of(st), lod);
        let normal = self.light.and(self.cloud.normal_maps.as_ref()).map(|maps| {
            // SPEC §9.4: T = U, B = −V, N = ±the plane normal (front +, back −).
            let t = maps[atlas_index].sample(uv_of(st), lod);
            let n_side = if side == 0 { q.normal } else { -q.normal };
            (t.x * q.u_dir - t.y * q.v_dir + t.z * n_side).normalize_or_zero()
        });
        (colour, normal)
    }

    /// The billboards among `candidates` hit by one ray within `[t_min, t_max]`, shaded
    /// (`pc`: the pixel centre, for the MIP footprint).
    fn hits(&self, candidates: &[usize], dir: Vec3, rays: &Rays, pc: (f32, f32)) -> Vec<Hit> {
        let cam = rays.camera;
        let (origin, t_min, t_max) = (cam.eye, cam.near, cam.far);
        let mut out = Vec::new();
        for &i in candidates {
            let q = &self.cloud.quads[i];
            let Some((st, t)) = Self::plane_hit(q, origin, dir) else {
                continue;
            };
            let inside = (t_min..=t_max).contains(&t)
                && (0.0..1.0).contains(&st.x)
                && (0.0..1.0).contains(&st.y);
            if !inside {
                continue;
            }
            // Alpha test, as the viewer draws billboards: a texel at or above the cut-off
            // is an opaque surface of its straight colour, anything else is a miss.
            let (c, normal) = self.shade(q, st, dir, rays, pc.0, pc.1);
            if c.w >= ALPHA_CUTOFF {
                // Lit at runtime like the viewer's `fs_billboard`: the mesh pass's model
                // (the shared core's, as the viewer's shader states it).
                let k = match (normal, self.light) {
                    (Some(n), Some((l, ambient))) if n != Vec3::ZERO => {
                        billow_core::shading::diffuse_factor(n, l, ambient)
                    }
                    _ => 1.0,
                };
                out.push((t, i, (c.truncate() / c.w * k).extend(1.0)));
            }
        }
        out
    }

    /// Renders level `lod` from `camera` with `sampling`.
    pub fn render(
        &self,
        lod: usize,
        camera: &Camera,
        sampling: Sampling,
    ) -> Result<CloudRender, EvalError> {
        let start = Instant::now();
        validate_camera(camera)?;
        let n = per_axis(sampling)?;
        let Some((range, _)) = self.cloud.levels.get(lod) else {
            return Err(EvalError::InvalidParam(format!(
                "LOD {lod} does not exist (the asset has {})",
                self.cloud.levels.len()
            )));
        };
        let range = range.clone();
        // Screen box each billboard can touch (everything when a corner is behind the eye).
        let view = camera.view();
        let rays = Rays {
            camera,
            inv: view.inverse(),
        };
        let boxes: Vec<(usize, [f32; 4])> = range
            .clone()
            .map(|i| {
                let q = &self.cloud.quads[i];
                let s = |v: Vec3| q.c0 + v;
                let e1 = q.du / q.du.length_squared().max(f32::MIN_POSITIVE);
                let e3 = q.dv / q.dv.length_squared().max(f32::MIN_POSITIVE);
                let corners = [q.c0, s(e1), s(e1 + e3), s(e3)];
                let mut b = [
                    f32::INFINITY,
                    f32::INFINITY,
                    f32::NEG_INFINITY,
                    f32::NEG_INFINITY,
                ];
                for c in corners {
                    match camera.view_to_pixel(billow_core::camera::to_view(&view, c)) {
                        Some((x, y)) if x.is_finite() && y.is_finite() => {
                            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
                        }
                        _ => {
                            return (
                                i,
                                [
                                    f32::NEG_INFINITY,
                                    f32::NEG_INFINITY,
                                    f32::INFINITY,
                                    f32::INFINITY,
                                ],
                            )
                        }
                    }
                }
                // One pixel of slack: samples anywhere in a pixel.
                (i, [b[0] - 1.0, b[1] - 1.0, b[2] + 1.0, b[3] + 1.0])
            })
            .collect();
        let mut image = ImageF32::new(camera.width, camera.height);
        let w = camera.width as usize;
        let inv = 1.0 / (n * n) as f32;
        // The pixels the kept mesh can be seen through (every pixel where that is unknown).
        let trunk_reach = self.trunk.pixels_reached(camera);
        let per_row: Vec<(u64, Vec<usize>)> = image
            .data
            .par_chunks_mut(w)
            .enumerate()
            .map(|(y, row)| {
                let yf = y as f32;
                let in_row: Vec<(usize, [f32; 4])> = boxes
                    .iter()
                    .filter(|b| b.1[1] <= yf + 1.0 && yf <= b.1[3])
                    .copied()
                    .collect();
                let mut candidates: Vec<usize> = Vec::with_capacity(in_row.len());
                let mut frags = 0u64;
                let mut visible = Vec::new();
                for (x, px) in row.iter_mut().enumerate() {
                    let (xu, yu) = (x as u32, y as u32);
                    let xf = x as f32;
                    candidates.clear();
                    candidates.extend(
                        in_row
                            .iter()
                            .filter(|b| b.1[0] <= xf + 1.0 && xf <= b.1[2])
                            .map(|b| b.0),
                    );
                    // Nothing to meet: no billboard's box and outside the kept mesh's.
                    if candidates.is_empty() && trunk_reach.is_some_and(|r| !in_rect(r, xu, yu)) {
                        continue;
                    }
                    let mut acc = Vec4::ZERO;
                    for sy in 0..n {
                        for sx in 0..n {
                            let (jx, jy) = sample_offset(sampling, xu, yu, sx, sy, n);
                            let dir = rays.dir(xf + jx, yf + jy);
                            let mut hits = self.hits(&candidates, dir, &rays, (xf + 0.5, yf + 0.5));
                            frags += hits.len() as u64;
                            visible.extend(hits.iter().map(|h| h.1));
                            let (layers, stop) =
                                self.trunk
                                    .trace_layers(camera.eye, dir, camera.near, camera.far);
                            if let Some(s) = stop {
                                hits.retain(|h| h.0 <= s.t);
                            }
                            // Trunk layers sort before billboards at equal depth.
                            let mut all: Vec<(f32, usize, Vec4)> = layers
                                .iter()
                                .chain(&stop)
                                .map(|l| (l.t, 0, l.colour))
                                .chain(hits.into_iter().map(|h| (h.0, h.1 + 1, h.2)))
                                .collect();
                            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                            let mut c = Vec4::ZERO;
                            for l in &all {
                                c = under(c, l.2);
                                if c.w >= 1.0 {
                                    break;
                                }
                            }
                            acc += c;
                        }
                    }
                    *px = acc * inv;
                }
                visible.sort_unstable();
                visible.dedup();
                (frags, visible)
            })
            .collect();
        let mut visible: Vec<usize> = per_row.iter().flat_map(|r| r.1.iter().copied()).collect();
        visible.sort_unstable();
        visible.dedup();
        Ok(CloudRender {
            image,
            stats: CloudStats {
                billboards: range.len(),
                visible_billboards: visible.len(),
                fragments: per_row.iter().map(|r| r.0).sum(),
                seconds: start.elapsed().as_secs_f64(),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square z = 0 (as `PreparedCloud::new` builds its quad).
    fn unit_square() -> Quad {
        Quad {
            normal: Vec3::Z,
            r: 0.0,
            c0: Vec3::ZERO,
            du: Vec3::X,
            dv: Vec3::Y,
            sides: [(0, [0.0, 0.0, 1.0, 1.0]); 2],
            u_dir: Vec3::X,
            v_dir: Vec3::Y,
        }
    }

    /// Issue 25, item 5, where the edge-on billboard is decided: a ray in the plane of
    /// the billboard (0/0), parallel beside it (x/0), at a subnormal or overflowing slope
    /// (t past f32::MAX), or with a NaN or ∞ component meets the quad nowhere: `None`,
    /// so the callers' range tests never see a NaN or ∞. A grazing ray still hits, at
    /// the right point. Seen failing with either guard removed: without `t.is_finite()` the
    /// subnormal slope gives t = ∞ and s = NaN; without the denominator's, the ray along −∞
    /// gives t = 0 and s = NaN.
    #[test]
    fn an_edge_on_or_non_finite_ray_misses_the_plane() {
        let q = unit_square();
        let cases = [
            // In the plane, through the square: 0/0.
            (Vec3::new(-3.0, 0.5, 0.0), Vec3::X),
            // Parallel, beside the plane: 1/0.
            (Vec3::new(-3.0, 0.5, 1.0), Vec3::X),
            // Slopes whose t overflows f32: subnormal and tiny normal denominators.
            (Vec3::new(-3.0, 0.5, 1.0), Vec3::new(1.0, 0.0, -1e-40)),
            (Vec3::new(-3.0, 0.5, 1e30), Vec3::new(1.0, 0.0, -1e-10)),
            // Non-finite directions and origins.
            (Vec3::new(-3.0, 0.5, 1.0), Vec3::new(f32::NAN, 0.0, -1.0)),
            (
                Vec3::new(-3.0, 0.5, 1.0),
                Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
            ),
            (
                Vec3::new(f32::INFINITY, 0.5, 1.0),
                Vec3::new(0.0, 0.0, -1.0),
            ),
        ];
        for (origin, dir) in cases {
            let hit = CloudRenderer::plane_hit(&q, origin, dir);
            assert!(
                hit.is_none(),
                "ray {origin} + t·{dir} meets the plane nowhere, got {hit:?}"
            );
        }
        // Grazing but not parallel: 1e-6 rad below the plane's horizon from 1e-6 above.
        let (st, t) =
            CloudRenderer::plane_hit(&q, Vec3::new(-0.5, 0.5, 1e-6), Vec3::new(1.0, 0.0, -1e-6))
                .expect("a grazing ray meets the plane");
        assert!((t - 1.0).abs() < 1e-5 && (st - Vec2::new(0.5, 0.5)).abs().max_element() < 1e-5);
    }
}
