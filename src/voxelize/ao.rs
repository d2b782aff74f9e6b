//! Baked lighting: ambient occlusion (`--bake ao`), multiplied into the colour of the
//! level-0 voxels before the MIP pyramids are built (so every level filters lit colour).
//!
//! # Definition
//! For every level-0 voxel that is non-empty (alpha > 0) in at least one direction volume:
//! - `rays` rays start at the **voxel centre** and go in directions uniformly distributed
//!   over the **full sphere** (foliage has no single normal), stratified in `z`: ray `r`
//!   has `z = 1 − 2 (r + ξ₀) / rays` and an azimuth from a point drawn uniformly in the
//!   unit disc (rejection sampling), so only `+ − × / sqrt` are used and the directions are
//!   the same on every platform.
//! - The random numbers come from [`Pcg32`]`::seeded(AO_SEED, voxel index)` (index =
//!   `x + dx (y + dy z)`): a voxel's AO depends on nothing else, so the result does not
//!   depend on the thread count or on which direction found the voxel first.
//! - A ray counts hits with `t` in `[t_min, distance]`, where `t_min` is **half the voxel's
//!   diagonal** (the surface inside the voxel itself does not occlude it: a lone flat leaf
//!   stays lit) and `distance` is [`Bake::Ao`]'s (default [`DEFAULT_DISTANCE_FRACTION`] of
//!   the voxel grid's diagonal).
//! - Every triangle occludes from both sides (a closed mesh's inside is dark whatever its
//!   winding). By alpha mode, at the hit point (`factor × vertex colour × texture` alpha,
//!   bilinear, as the rasterizer shades it): `Opaque` blocks the ray; `Mask` blocks it
//!   where alpha ≥ cutoff and lets it through elsewhere (cut-out leaves occlude only where
//!   they are visible); `Blend` is a partial occluder, transmitting `1 − alpha`.
//! - Ray visibility = 0 if blocked, else `Π (1 − alpha)` over the blended hits (multiplied
//!   in triangle-index order, independent of BVH traversal). **AO = mean visibility of the
//!   rays** (the unoccluded fraction), in [0, 1].
//! - The colour of the voxel (premultiplied rgb, in every direction volume) is multiplied
//!   by AO; alpha and normals are unchanged.
//!
//! AO values are cached per level-0 voxel (2 bytes each, 16-bit fixed point), so each is
//! traced once even when six directions see the voxel.

use glam::{Vec3, Vec3A};
use obvhs::bvh2::Bvh2;
use obvhs::ray::Ray;
use rayon::prelude::*;

use super::grid::GridSpec;
use super::limits::{check_ao_distance, check_ao_rays, OptionError};
use super::slices::DirSlices;
use crate::bvh::scene_bvh;
use crate::material::Shader;
use crate::rng::Pcg32;
use crate::scene::{AlphaMode, Scene};
use billow_core::ray_triangle::WatertightRay;

/// Baked lighting (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Bake {
    /// Colour as captured (the default).
    #[default]
    None,
    /// Ambient occlusion: `rays` rays per voxel up to `distance` (scene units; `None` =
    /// [`DEFAULT_DISTANCE_FRACTION`] of the grid's diagonal).
    Ao { rays: u32, distance: Option<f32> },
}

/// Default number of AO rays per voxel.
pub const DEFAULT_AO_RAYS: u32 = 32;
/// Default AO distance, as a fraction of the voxel grid's diagonal.
pub const DEFAULT_DISTANCE_FRACTION: f32 = 0.2;
/// PCG32 seed of the AO directions (the stream is the voxel index).
pub const AO_SEED: u64 = 0x0A0B_A4E5;

impl Bake {
    /// AO with the default rays and distance.
    pub fn ao() -> Self {
        Bake::Ao {
            rays: DEFAULT_AO_RAYS,
            distance: None,
        }
    }

    /// The AO distance used for `grid` (`None` without AO).
    pub fn ao_distance(&self, grid: &GridSpec) -> Option<f32> {
        match *self {
            Bake::None => None,
            Bake::Ao {
                distance: Some(d), ..
            } => Some(d),
            Bake::Ao { distance: None, .. } => {
                Some(DEFAULT_DISTANCE_FRACTION * (grid.max() - grid.min).length())
            }
        }
    }

    /// The rays within `1..=`[`MAX_AO_RAYS`](super::MAX_AO_RAYS) and the distance, when
    /// given, a positive number (checked in that order).
    pub fn validate(&self) -> Result<(), OptionError> {
        match *self {
            Bake::None => Ok(()),
            Bake::Ao { rays, distance } => {
                check_ao_rays(rays)?;
                distance.map_or(Ok(()), check_ao_distance)
            }
        }
    }
}

const NOT_YET: u16 = u16::MAX;
const SCALE: f32 = (u16::MAX - 1) as f32;

/// The AO estimator of the module docs, at any point: `rays` directions over the full
/// sphere drawn from [`Pcg32`]`::seeded(seed, stream)`, hits counted for `t` in
/// `[t_min, t_max]`. The bake evaluates it at voxel centres ([`AoRays::for_grid`], stream =
/// voxel index); the evaluation's lit reference (`crate::eval::lighting`) at surface points,
/// with the stream of the voxel containing the point ([`voxel_stream`]), so both draw the
/// same directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoRays {
    pub rays: u32,
    pub t_min: f32,
    pub t_max: f32,
    pub seed: u64,
}

impl AoRays {
    /// The bake's estimator on `grid`: `t_min` = half the voxel diagonal, seed [`AO_SEED`].
    pub fn for_grid(grid: &GridSpec, rays: u32, distance: f32) -> Self {
        AoRays {
            rays,
            t_min: 0.5 * grid.voxel.length(),
            t_max: distance,
            seed: AO_SEED,
        }
    }

    /// Visibility along one ray (1 = unoccluded).
    fn visibility(
        &self,
        scene: &Scene,
        shader: &Shader,
        bvh: &Bvh2,
        origin: Vec3,
        dir: Vec3,
    ) -> f32 {
        let wr = WatertightRay::new(origin, dir);
        let ray = Ray::new(
            Vec3A::from(origin),
            Vec3A::from(dir),
            self.t_min,
            self.t_max,
        );
        let mut blended: Vec<(u32, f32)> = Vec::new();
        let missed = bvh.ray_traverse_miss(ray, |r, id| {
            let tri_i = bvh.primitive_indices[id];
            let tri = &scene.triangles[tri_i as usize];
            let Some(h) = wr.intersect(
                tri.v[0].position,
                tri.v[1].position,
                tri.v[2].position,
                r.tmin,
                r.tmax,
            ) else {
                return f32::INFINITY;
            };
            let m = shader.material(tri.material);
            let alpha = || {
                let b = h.bary;
                let uv = tri.v[0].uv * b[0] + tri.v[1].uv * b[1] + tri.v[2].uv * b[2];
                let vc = tri.v[0].color * b[0] + tri.v[1].color * b[1] + tri.v[2].color * b[2];
                shader.alpha(m, uv, vc)
            };
            match m.alpha_mode {
                AlphaMode::Opaque => h.t,
                AlphaMode::Mask { cutoff } => {
                    if alpha() >= cutoff {
                        h.t
                    } else {
                        f32::INFINITY
                    }
                }
                AlphaMode::Blend => {
                    let a = alpha();
                    if a.is_finite() && a > 0.0 {
                        blended.push((tri_i, a.min(1.0)));
                    }
                    f32::INFINITY
                }
            }
        });
        if !missed {
            return 0.0;
        }
        blended.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
        blended.iter().fold(1.0, |v, &(_, a)| v * (1.0 - a))
    }

    /// AO at `origin` (mean visibility of the rays, in [0, 1]) with the directions of
    /// stream `stream`. The scene must have passed `material::validate_scene`; `bvh` is
    /// [`scene_bvh`] of it.
    pub(crate) fn ambient_occlusion(
        &self,
        scene: &Scene,
        shader: &Shader,
        bvh: &Bvh2,
        origin: Vec3,
        stream: u64,
    ) -> f32 {
        if self.t_max <= self.t_min || self.rays == 0 {
            return 1.0;
        }
        let mut rng = Pcg32::seeded(self.seed, stream);
        let n = self.rays;
        let mut sum = 0.0f64;
        for r in 0..n {
            let z = 1.0 - 2.0 * (r as f32 + rng.next_f32()) / n as f32;
            let (a, b, l2) = loop {
                let a = rng.range_f32(-1.0, 1.0);
                let b = rng.range_f32(-1.0, 1.0);
                let l2 = a * a + b * b;
                if l2 > 1e-6 && l2 <= 1.0 {
                    break (a, b, l2);
                }
            };
            let s = (1.0 - z * z).max(0.0).sqrt() / l2.sqrt();
            let dir = Vec3::new(a * s, b * s, z);
            sum += self.visibility(scene, shader, bvh, origin, dir) as f64;
        }
        (sum / n as f64) as f32
    }
}

/// The index `x + dx (y + dy z)` of the level-0 voxel of `grid` containing `p` (clamped to
/// the grid): the AO stream of that voxel.
pub fn voxel_stream(grid: &GridSpec, p: Vec3) -> u64 {
    let d = grid.dims;
    let c = |i: usize| {
        let f = ((p[i] - grid.min[i]) / grid.voxel[i]).floor();
        if f.is_finite() {
            (f.max(0.0) as u64).min(u64::from(d[i].max(1)) - 1)
        } else {
            0
        }
    };
    c(0) + u64::from(d[0]) * (c(1) + u64::from(d[1]) * c(2))
}

/// Traces and caches the AO of level-0 voxels.
pub(crate) struct AoBaker<'a> {
    scene: &'a Scene,
    shader: &'a Shader<'a>,
    bvh: Option<Bvh2>,
    grid: GridSpec,
    rays: AoRays,
    cache: Vec<u16>,
}

impl<'a> AoBaker<'a> {
    pub fn new(
        scene: &'a Scene,
        shader: &'a Shader<'a>,
        grid: GridSpec,
        rays: u32,
        distance: f32,
    ) -> Self {
        AoBaker {
            scene,
            shader,
            bvh: scene_bvh(scene),
            grid,
            rays: AoRays::for_grid(&grid, rays, distance),
            cache: vec![NOT_YET; grid.voxel_count() as usize],
        }
    }

    /// AO of level-0 voxel `index` (see the module docs).
    pub fn trace_voxel(&self, index: usize) -> f32 {
        let Some(bvh) = &self.bvh else {
            return 1.0;
        };
        let d = self.grid.dims.map(|x| x as usize);
        let p = [index % d[0], (index / d[0]) % d[1], index / (d[0] * d[1])];
        let centre = self.grid.min
            + self.grid.voxel * Vec3::new(p[0] as f32 + 0.5, p[1] as f32 + 0.5, p[2] as f32 + 0.5);
        self.rays
            .ambient_occlusion(self.scene, self.shader, bvh, centre, index as u64)
    }

    fn cached(&self, index: usize) -> f32 {
        self.cache[index] as f32 / SCALE
    }

    /// Traces the voxels non-empty in a direction's sparse level 0 not traced yet, then
    /// multiplies the colour of every non-empty voxel by its AO.
    pub(crate) fn apply_sparse(&mut self, s: &mut DirSlices) {
        let idx = s.indices();
        let pending: Vec<usize> = idx
            .par_iter()
            .zip(&s.vox)
            .filter(|(i, v)| v.rgba[3] != 0.0 && self.cache[**i] == NOT_YET)
            .map(|(i, _)| *i)
            .collect();
        let values: Vec<u16> = pending
            .par_iter()
            .with_min_len(16)
            .map(|&i| (self.trace_voxel(i).clamp(0.0, 1.0) * SCALE).round() as u16)
            .collect();
        for (i, v) in pending.into_iter().zip(values) {
            self.cache[i] = v;
        }
        let this = &*self;
        s.vox.par_iter_mut().zip(&idx).for_each(|(v, &i)| {
            if v.rgba[3] != 0.0 {
                let ao = this.cached(i);
                for c in 0..3 {
                    v.rgba[c] *= ao;
                }
            }
        });
    }

    /// Memory it needs for `dims` and `triangles` (cache + BVH), in bytes, roughly.
    pub fn estimate_bytes(dims: [u32; 3], triangles: usize) -> u64 {
        let n: u64 = dims.iter().map(|&d| d as u64).product();
        2 * n + 160 * triangles as u64
    }
}
