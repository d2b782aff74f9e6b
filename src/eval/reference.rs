//! Reference renderer: the source [`Scene`] ray-traced on the CPU (obvhs BVH2), the
//! ground truth every asset is measured against.
//!
//! - Colour = `base_color_factor × texture(uv) × vertex colour` (all linear, straight
//!   alpha; texture sampled bilinearly with [`crate::scene::Texture::sample_bilinear`]),
//!   unlit by default;
//!   [`ReferenceRenderer::with_lighting`] multiplies it by the lighting an asset was baked
//!   with (baked AO at the hit point, or ambient + diffuse; [`super::lighting`]).
//! - Alpha modes: `Opaque` stops the ray (alpha forced to 1); `Mask` stops it where
//!   alpha ≥ cutoff and is invisible elsewhere (the ray continues); `Blend` is composited
//!   front to back and the ray continues. Hits at the same `t` are ordered by triangle
//!   index, so the result does not depend on BVH traversal order.
//! - Single-sided triangles are visible only from their counter-clockwise side;
//!   double-sided ones from both.
//! - Rays start at the camera's near plane and end at its far plane (`t` = view depth,
//!   see [`billow_core::camera`]), like a rasterizer's clipping.
//! - Pixels average `n × n` stratified jittered samples (default 4 × 4 = 16 spp), the
//!   jitter a fixed hash of (pixel, sample): deterministic. [`Sampling::Centre`] is one
//!   sample at the pixel centre: what a renderer without anti-aliasing shows.
//! - Output: premultiplied linear RGBA f32 over a transparent background. Rows are
//!   rendered in parallel (rayon); results are identical for any thread count.
//! - **Lighting is stated here, not borrowed**: the lighting models the viewer and the
//!   bakers use (`billow_core::shading`, `mesh.wgsl`, `volume.wgsl`) are written out again
//!   in this file ([`two_sided`], [`one_sided`]) instead of called, so that a mistake in
//!   the asset path's formula shows up as an error against the reference instead of being
//!   shared by both (tests/eval_lighting.rs compares the two statements, and
//!   tests/view_lighting.rs the reference with the viewer's mesh pass).

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec2, Vec3, Vec3A, Vec4};
use obvhs::bvh2::Bvh2;
use obvhs::ray::{Ray, RayHit};
use rayon::prelude::*;

use super::lighting::{voxel_stream, Lighting};
use super::{EvalError, ImageF32};
use crate::bvh::scene_bvh;
use crate::material::{validate_scene, Shader};
use crate::scene::{AlphaMode, Scene};
use billow_core::camera::Camera;
use billow_core::compositing::under;
use billow_core::ray_triangle::{TriangleHit, WatertightRay};

/// Pixel sampling pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// One sample at the pixel centre.
    Centre,
    /// `n × n` stratified samples, each jittered inside its stratum.
    Stratified { per_axis: u32 },
}

impl Default for Sampling {
    /// 4 × 4 = 16 samples per pixel.
    fn default() -> Self {
        Sampling::Stratified { per_axis: 4 }
    }
}

/// A scene prepared for tracing (BVH built once, reusable for many views).
pub struct ReferenceRenderer<'a> {
    scene: &'a Scene,
    bvh: Option<Bvh2>,
    has_blend: bool,
    lighting: Lighting,
    /// The voxelizer's view of the materials, for AO occlusion tests (same alpha as the bake).
    shader: Option<Shader<'a>>,
}

/// A surface a ray meets: its view depth `t` and its premultiplied (lit) colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    pub t: f32,
    pub colour: Vec4,
}

/// Renders `scene` from `camera` with `sampling`. Convenience for
/// [`ReferenceRenderer::new`] + [`ReferenceRenderer::render`].
pub fn render_reference(
    scene: &Scene,
    camera: &Camera,
    sampling: Sampling,
) -> Result<ImageF32, EvalError> {
    ReferenceRenderer::new(scene).render(camera, sampling)
}

/// The scene with exactly one sample per pixel, at the pixel centre.
pub fn raster_1spp(scene: &Scene, camera: &Camera) -> Result<ImageF32, EvalError> {
    render_reference(scene, camera, Sampling::Centre)
}

/// Deterministic hash → `[0,1)` (PCG-style output permutation of a mixed key).
fn hash01(x: u32, y: u32, s: u32, dim: u32) -> f32 {
    let mut h = x.wrapping_mul(0x9E37_79B1)
        ^ y.wrapping_mul(0x85EB_CA77)
        ^ s.wrapping_mul(0xC2B2_AE3D)
        ^ dim.wrapping_mul(0x27D4_EB2F);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846C_A68B);
    h ^= h >> 16;
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The position inside pixel `(x, y)` of sample `(sx, sy)` of an `n × n` pattern (in
/// `[0,1)²`): the pixel centre for [`Sampling::Centre`], a fixed hash-jittered point of
/// its stratum otherwise. Shared with the cloud renderer so both sample the same points.
pub(crate) fn sample_offset(
    sampling: Sampling,
    x: u32,
    y: u32,
    sx: u32,
    sy: u32,
    n: u32,
) -> (f32, f32) {
    match sampling {
        Sampling::Centre => (0.5, 0.5),
        Sampling::Stratified { .. } => {
            let s = sy * n + sx;
            (
                (sx as f32 + hash01(x, y, s, 0)) / n as f32,
                (sy as f32 + hash01(x, y, s, 1)) / n as f32,
            )
        }
    }
}

/// Whether pixel `(x, y)` lies in `[x0, y0, x1, y1)` (a [`ReferenceRenderer`]'s reach).
pub(crate) fn in_rect([x0, y0, x1, y1]: [u32; 4], x: u32, y: u32) -> bool {
    x >= x0 && x < x1 && y >= y0 && y < y1
}

/// Samples per axis of `sampling` (1 for the centre), checked to be 1..=64.
pub(crate) fn per_axis(sampling: Sampling) -> Result<u32, EvalError> {
    match sampling {
        Sampling::Centre => Ok(1),
        Sampling::Stratified { per_axis } if (1..=64).contains(&per_axis) => Ok(per_axis),
        Sampling::Stratified { per_axis } => Err(EvalError::InvalidParam(format!(
            "samples per axis {per_axis} is out of range (1 to 64)"
        ))),
    }
}

pub(crate) fn validate_camera(camera: &Camera) -> Result<(), EvalError> {
    let ok = camera.width > 0
        && camera.height > 0
        && camera.fov_y > 0.0
        && camera.fov_y < std::f32::consts::PI
        && camera.near > 0.0
        && camera.far > camera.near
        && camera.eye.is_finite()
        && camera.target.is_finite()
        && camera.eye != camera.target
        && camera.far.is_finite();
    if ok {
        Ok(())
    } else {
        Err(EvalError::InvalidCamera(format!("{camera:?}")))
    }
}

impl<'a> ReferenceRenderer<'a> {
    /// Builds the BVH over all triangles of `scene` ([`scene_bvh`]); unlit.
    pub fn new(scene: &'a Scene) -> Self {
        let has_blend = scene
            .materials
            .iter()
            .any(|m| m.alpha_mode == AlphaMode::Blend);
        ReferenceRenderer {
            scene,
            bvh: scene_bvh(scene),
            has_blend,
            lighting: Lighting::Unlit,
            shader: None,
        }
    }

    /// Shades with `lighting` ([`super::lighting`]). AO needs a scene whose material and
    /// texture indices are valid.
    pub fn with_lighting(mut self, lighting: Lighting) -> Result<Self, EvalError> {
        self.set_lighting(lighting)?;
        Ok(self)
    }

    /// [`ReferenceRenderer::with_lighting`] in place (the BVH is kept).
    pub fn set_lighting(&mut self, lighting: Lighting) -> Result<(), EvalError> {
        if let Lighting::Ao { .. } = lighting {
            validate_scene(self.scene).map_err(EvalError::InvalidParam)?;
            self.shader = Some(Shader::new(self.scene));
        }
        self.lighting = lighting;
        Ok(())
    }

    /// The pixels `[x0, y0, x1, y1)` that a ray can hit the scene's bounds through: the
    /// box's eight corners projected, a pixel of margin; `None` (every pixel) when a corner
    /// is not in front of the eye; none for a scene without triangles. No ray of a pixel
    /// outside meets a triangle, so skipping them changes no image.
    pub(crate) fn pixels_reached(&self, camera: &Camera) -> Option<[u32; 4]> {
        if self.scene.triangles.is_empty() {
            return Some([0; 4]);
        }
        let b = &self.scene.bounds;
        if !(b.min.cmple(b.max).all()) {
            return None;
        }
        let view = camera.view();
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let v = view.transform_point3(c);
            // Only corners well in front: the projection is then exact.
            if !(-v.z > camera.near) {
                return None;
            }
            let (px, py) = camera.view_to_pixel(v)?;
            lo = lo.min(Vec2::new(px, py));
            hi = hi.max(Vec2::new(px, py));
        }
        let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32) as u32;
        Some([
            clamp((lo.x - 1.0).floor(), camera.width),
            clamp((lo.y - 1.0).floor(), camera.height),
            clamp((hi.x + 1.0).ceil(), camera.width),
            clamp((hi.y + 1.0).ceil(), camera.height),
        ])
    }

    pub fn lighting(&self) -> &Lighting {
        &self.lighting
    }

    /// Renders one view.
    pub fn render(&self, camera: &Camera, sampling: Sampling) -> Result<ImageF32, EvalError> {
        validate_camera(camera)?;
        let n = per_axis(sampling)?;
        let mut img = ImageF32::new(camera.width, camera.height);
        let w = camera.width as usize;
        let inv = 1.0 / (n * n) as f32;
        let reach = self.pixels_reached(camera);
        img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            let y = y as u32;
            for (x, px) in row.iter_mut().enumerate() {
                let x = x as u32;
                if !reach.is_none_or(|r| in_rect(r, x, y)) {
                    continue;
                }
                let mut acc = Vec4::ZERO;
                for sy in 0..n {
                    for sx in 0..n {
                        let (jx, jy) = sample_offset(sampling, x, y, sx, sy, n);
                        let r = camera.ray(x as f32 + jx, y as f32 + jy);
                        acc += self.trace(r.origin, r.dir, r.t_min, r.t_max);
                    }
                }
                *px = acc * inv;
            }
        });
        Ok(img)
    }

    /// Straight linear RGBA of triangle `tri` at barycentrics `bary`.
    pub fn shade(&self, tri: usize, bary: [f32; 3]) -> Vec4 {
        let t = &self.scene.triangles[tri];
        let m = self.scene.material(t);
        let uv = t.v[0].uv * bary[0] + t.v[1].uv * bary[1] + t.v[2].uv * bary[2];
        let vc = t.v[0].color * bary[0] + t.v[1].color * bary[1] + t.v[2].color * bary[2];
        let tex = m
            .base_color_texture
            .and_then(|i| self.scene.textures.get(i as usize))
            .filter(|t| t.width > 0 && t.height > 0 && !t.texels.is_empty())
            .map_or(Vec4::ONE, |t| t.sample_bilinear(uv));
        m.base_color_factor * tex * vc
    }

    /// [`ReferenceRenderer::shade`] with the lighting applied: straight RGBA of the hit of
    /// the ray `origin + t·dir` on triangle `tri`.
    pub fn shade_lit(&self, tri: usize, bary: [f32; 3], origin: Vec3, dir: Vec3, t: f32) -> Vec4 {
        let c = self.shade(tri, bary);
        let f = match self.lighting {
            Lighting::Scene {
                light,
                ambient,
                shadows,
            } => {
                if self.scene.material(&self.scene.triangles[tri]).unlit {
                    return c;
                }
                let n = self.shading_normal(tri, bary);
                let visibility = if shadows {
                    self.transmittance(origin + dir * t, light, tri)
                } else {
                    1.0
                };
                two_sided(n, light, ambient, visibility)
            }
            Lighting::Unlit => return c,
            Lighting::Ao {
                rays,
                grid,
                shaded,
                two_sided: moments,
            } => {
                let (Some(bvh), Some(shader)) = (&self.bvh, &self.shader) else {
                    return c;
                };
                let p = origin + dir * t;
                let ao = rays.ambient_occlusion(self.scene, shader, bvh, p, voxel_stream(&grid, p));
                ao * shaded.map_or(1.0, |l| {
                    if moments {
                        two_sided(self.shading_normal(tri, bary), l.dir, l.ambient, 1.0)
                    } else {
                        one_sided(self.volume_normal(tri, bary, dir), l.dir, l.ambient)
                    }
                })
            }
            Lighting::Diffuse { light, ambient } => {
                two_sided(self.shading_normal(tri, bary), light, ambient, 1.0)
            }
            Lighting::Volume { light, ambient } => {
                one_sided(self.volume_normal(tri, bary, dir), light, ambient)
            }
        };
        (c.truncate() * f).extend(c.w)
    }

    /// The interpolated shading normal of `tri` at `bary`, unit (the face normal where the
    /// vertex normals cancel).
    fn shading_normal(&self, tri: usize, bary: [f32; 3]) -> Vec3 {
        let v = &self.scene.triangles[tri].v;
        let face = (v[1].position - v[0].position).cross(v[2].position - v[0].position);
        (v[0].normal * bary[0] + v[1].normal * bary[1] + v[2].normal * bary[2])
            .normalize_or(face.normalize_or_zero())
    }

    /// The fraction of the light towards unit `light` that reaches `p` (on triangle
    /// `from`): 0 behind an opaque or alpha-tested surface (whichever side faces the light,
    /// as a shadow map sees it), `Π (1 − α)` through blended ones. The ray starts a hair
    /// (10⁻⁴ of the scene's size) off the surface and ignores `from` itself.
    fn transmittance(&self, p: Vec3, light: Vec3, from: usize) -> f32 {
        let Some(bvh) = &self.bvh else {
            return 1.0;
        };
        let size = (self.scene.bounds.max - self.scene.bounds.min)
            .length()
            .max(1e-6);
        let origin = p + light * (1e-4 * size);
        let wr = WatertightRay::new(origin, light);
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(light), 0.0, f32::INFINITY);
        let mut through = 1.0f32;
        bvh.ray_traverse_anyhit(ray, |_, id| {
            let tri = bvh.primitive_indices[id] as usize;
            if tri == from || through == 0.0 {
                return;
            }
            let t = &self.scene.triangles[tri];
            let Some(h) = wr.intersect(
                t.v[0].position,
                t.v[1].position,
                t.v[2].position,
                0.0,
                f32::INFINITY,
            ) else {
                return;
            };
            through *= match self.scene.material(t).alpha_mode {
                AlphaMode::Opaque => 0.0,
                AlphaMode::Mask { cutoff } => {
                    if self.shade(tri, h.bary).w >= cutoff {
                        0.0
                    } else {
                        1.0
                    }
                }
                AlphaMode::Blend => 1.0 - self.shade(tri, h.bary).w.clamp(0.0, 1.0),
            };
        });
        through
    }

    /// The shading normal as the voxelizer captures it: interpolated (the face normal where
    /// it cancels), flipped on the back face of a double-sided triangle (a single-sided one
    /// is only hit from the front) — what a volume's runtime shading reads.
    fn volume_normal(&self, tri: usize, bary: [f32; 3], dir: Vec3) -> Vec3 {
        let v = &self.scene.triangles[tri].v;
        let face = (v[1].position - v[0].position).cross(v[2].position - v[0].position);
        let n = self.shading_normal(tri, bary);
        if face.dot(dir) > 0.0 {
            -n
        } else {
            n
        }
    }

    fn hit(&self, wr: &WatertightRay, tri: usize, t_min: f32, t_max: f32) -> Option<TriangleHit> {
        let t = &self.scene.triangles[tri];
        let h = wr.intersect(
            t.v[0].position,
            t.v[1].position,
            t.v[2].position,
            t_min,
            t_max,
        )?;
        (h.front || self.scene.material(t).double_sided).then_some(h)
    }

    /// Premultiplied linear RGBA seen along one ray (`t` in `[t_min, t_max]`).
    pub fn trace(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Vec4 {
        let (layers, stop) = self.trace_layers(origin, dir, t_min, t_max);
        let mut acc = Vec4::ZERO;
        for l in layers.iter().chain(&stop) {
            acc = under(acc, l.colour);
            if acc.w >= 1.0 {
                break;
            }
        }
        acc
    }

    /// What one ray meets: the blended surfaces in front of the stopping hit, front to back
    /// (ties by triangle index), and the stopping hit (opaque, or mask ≥ cutoff; alpha 1),
    /// all shaded and lit, premultiplied.
    pub fn trace_layers(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> (Vec<Layer>, Option<Layer>) {
        let Some(bvh) = &self.bvh else {
            return (Vec::new(), None);
        };
        let wr = WatertightRay::new(origin, dir);
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), t_min, t_max);
        // Pass 1: the closest hit that stops the ray (opaque, or mask ≥ cutoff).
        let mut best: Option<(f32, usize, [f32; 3])> = None;
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |r, id| {
            let tri = bvh.primitive_indices[id] as usize;
            let Some(h) = self.hit(&wr, tri, r.tmin, r.tmax) else {
                return f32::INFINITY;
            };
            let stops = match self.scene.material(&self.scene.triangles[tri]).alpha_mode {
                AlphaMode::Opaque => true,
                AlphaMode::Mask { cutoff } => self.shade(tri, h.bary).w >= cutoff,
                AlphaMode::Blend => false,
            };
            if !stops {
                return f32::INFINITY;
            }
            // Equal t: lower triangle index wins, independent of traversal order.
            let better = match best {
                None => true,
                Some((bt, bi, _)) => h.t < bt || (h.t == bt && tri < bi),
            };
            if better {
                best = Some((h.t, tri, h.bary));
            }
            h.t
        });
        let t_stop = best.map_or(t_max, |b| b.0);
        let mut out = Vec::new();
        // Pass 2: blended surfaces in front of the stopping hit, front to back.
        if self.has_blend {
            let mut layers: Vec<(f32, usize, [f32; 3])> = Vec::new();
            let ray2 = Ray::new(ray.origin, ray.direction, t_min, t_stop);
            bvh.ray_traverse_anyhit(ray2, |_, id| {
                let tri = bvh.primitive_indices[id] as usize;
                let t = &self.scene.triangles[tri];
                if self.scene.material(t).alpha_mode != AlphaMode::Blend {
                    return;
                }
                if let Some(h) = self.hit(&wr, tri, t_min, t_stop) {
                    if best.is_none() || h.t < t_stop {
                        layers.push((h.t, tri, h.bary));
                    }
                }
            });
            layers.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            layers.dedup_by_key(|l| l.1);
            let mut opacity = 0.0f32;
            for (t, tri, bary) in layers {
                let c = self.shade_lit(tri, bary, origin, dir, t);
                let a = c.w.clamp(0.0, 1.0);
                out.push(Layer {
                    t,
                    colour: (c.truncate() * a).extend(a),
                });
                opacity += (1.0 - opacity) * a;
                if opacity >= 1.0 {
                    return (out, None);
                }
            }
        }
        let stop = best.map(|(t, tri, bary)| Layer {
            t,
            colour: self
                .shade_lit(tri, bary, origin, dir, t)
                .truncate()
                .extend(1.0),
        });
        (out, stop)
    }
}

/// Two-sided Lambert with ambient, as the viewer's mesh pass (`mesh.wgsl`) and the billboard
/// bake light a surface: `ambient + (1 − ambient) · visibility · |n·light|`. Stated here on
/// purpose rather than taken from `billow_core::shading` (see the module docs).
pub fn two_sided(n: Vec3, light: Vec3, ambient: f32, visibility: f32) -> f32 {
    let cosine = n.dot(light).abs();
    ambient + (1.0 - ambient) * visibility * cosine
}

/// One-sided Lambert with ambient, as a volume's runtime shading (`volume.wgsl`) lights its
/// voxels: `ambient + (1 − ambient) · max(n·light, 0)`, `n` not renormalised. Stated here on
/// purpose (see the module docs).
pub fn one_sided(n: Vec3, light: Vec3, ambient: f32) -> f32 {
    let cosine = n.dot(light).max(0.0);
    ambient + (1.0 - ambient) * cosine
}
