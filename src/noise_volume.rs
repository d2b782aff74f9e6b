//! Procedural volumes from Perlin noise, for the paper's "asteroid belt" (VB §4,
//! Figure 10: 1200 billboards sharing 40 asteroid and 20 dust-cloud volumes generated
//! with Perlin noise).
//!
//! - Gradient noise: Perlin's improved noise (2002) — a seeded permutation of 256
//!   (PCG32, [`crate::rng`]), 12 gradient directions, quintic fade — summed in octaves
//!   (fBm, lacunarity 2, gain ½).
//! - [`asteroid`]: a rock — a sphere of radius 0.55 (in a `[-1, 1]³` box) whose surface
//!   is displaced by fBm, opaque inside with a one-voxel soft edge, grey-brown albedo
//!   varied by a second noise (craters darker).
//! - [`dust`]: a dust cloud — density `max(0, fBm − threshold)` under a spherical
//!   fall-off, low opacity per voxel, a pale warm tint.
//!
//! Both give level 0 as premultiplied linear RGBA and go through the same per-direction
//! MIP and combine as baked volumes ([`crate::voxelize::dense`], `mean` combine), so the
//! asset is an ordinary volume with one box cell.

use std::collections::BTreeMap;

use billow_format::{Bounds, ColourSpace, Header, VolumeAsset};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::rng::Pcg32;
use crate::voxelize::dense::pyramid_from_dense;
use crate::voxelize::mip::Grid3;
use crate::voxelize::{box_prisms, CombineFn, Preset};

/// Seeded 3D gradient noise in about `[-1, 1]`.
pub struct Perlin {
    perm: [u8; 512],
}

impl Perlin {
    pub fn new(seed: u64) -> Perlin {
        let mut p: Vec<u8> = (0..=255).collect();
        let mut rng = Pcg32::seeded(seed, 0x5eed);
        for i in (1..256).rev() {
            let j = rng.below(i as u32 + 1) as usize;
            p.swap(i, j);
        }
        let mut perm = [0u8; 512];
        for i in 0..512 {
            perm[i] = p[i & 255];
        }
        Perlin { perm }
    }

    fn grad(hash: u8, x: f32, y: f32, z: f32) -> f32 {
        let h = hash & 15;
        let u = if h < 8 { x } else { y };
        let v = if h < 4 {
            y
        } else if h == 12 || h == 14 {
            x
        } else {
            z
        };
        (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
    }

    /// Noise at `p` (period 256).
    pub fn noise(&self, p: Vec3) -> f32 {
        let f = p.floor();
        let (xi, yi, zi) = (
            (f.x as i32 & 255) as usize,
            (f.y as i32 & 255) as usize,
            (f.z as i32 & 255) as usize,
        );
        let (x, y, z) = (p.x - f.x, p.y - f.y, p.z - f.z);
        let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (u, v, w) = (fade(x), fade(y), fade(z));
        let pm = &self.perm;
        let a = pm[xi] as usize + yi;
        let (aa, ab) = (pm[a] as usize + zi, pm[a + 1] as usize + zi);
        let b = pm[xi + 1] as usize + yi;
        let (ba, bb) = (pm[b] as usize + zi, pm[b + 1] as usize + zi);
        let lerp = |t: f32, a: f32, b: f32| a + t * (b - a);
        let g = Self::grad;
        lerp(
            w,
            lerp(
                v,
                lerp(u, g(pm[aa], x, y, z), g(pm[ba], x - 1.0, y, z)),
                lerp(u, g(pm[ab], x, y - 1.0, z), g(pm[bb], x - 1.0, y - 1.0, z)),
            ),
            lerp(
                v,
                lerp(
                    u,
                    g(pm[aa + 1], x, y, z - 1.0),
                    g(pm[ba + 1], x - 1.0, y, z - 1.0),
                ),
                lerp(
                    u,
                    g(pm[ab + 1], x, y - 1.0, z - 1.0),
                    g(pm[bb + 1], x - 1.0, y - 1.0, z - 1.0),
                ),
            ),
        )
    }

    /// Fractal sum of `octaves` octaves starting at frequency `freq`.
    pub fn fbm(&self, p: Vec3, freq: f32, octaves: u32) -> f32 {
        let (mut s, mut amp, mut f) = (0.0, 1.0, freq);
        for _ in 0..octaves {
            s += amp * self.noise(p * f);
            amp *= 0.5;
            f *= 2.0;
        }
        s
    }
}

fn dense(res: u32, voxel: impl Fn(Vec3) -> Vec4 + Sync) -> Grid3<[f32; 4]> {
    let n = res.max(1) as usize;
    let mut g = Grid3::<[f32; 4]>::new([n; 3]);
    g.data
        .par_chunks_mut(n * n)
        .enumerate()
        .for_each(|(z, plane)| {
            for y in 0..n {
                for x in 0..n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                    let c = (p / n as f32) * 2.0 - 1.0;
                    plane[x + n * y] = voxel(c).to_array();
                }
            }
        });
    g
}

fn asset(res: u32, level0: &Grid3<[f32; 4]>, kind: &str, seed: u64) -> VolumeAsset {
    let levels = pyramid_from_dense(level0, &CombineFn::Preset(Preset::Mean));
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let mut params = BTreeMap::new();
    params.insert(
        "procedural".to_string(),
        format!("{kind} res={res} seed={seed}"),
    );
    VolumeAsset {
        header: Header {
            bounds: Bounds {
                min: lo.to_array(),
                max: hi.to_array(),
            },
            seed: Some(seed),
            params,
            ..Header::volume(
                format!("billow {}", env!("CARGO_PKG_VERSION")),
                ColourSpace::SrgbPremultiplied,
                [res; 3],
                levels.len() as u32,
                false,
            )
        },
        levels,
        normals: None,
        cells: box_prisms(lo, hi).to_vec(),
        bands: Vec::new(),
    }
}

/// A rock of `res`³ voxels (module docs).
pub fn asteroid(res: u32, seed: u64) -> VolumeAsset {
    let shape = Perlin::new(seed);
    let tone = Perlin::new(seed ^ 0x9e37_79b9);
    let edge = 2.0 / res.max(1) as f32; // one voxel, in box units
    let g = dense(res, |c| {
        let r = c.length();
        let surface = 0.55 * (1.0 + 0.35 * shape.fbm(c, 1.6, 4));
        let a = ((surface - r) / edge + 0.5).clamp(0.0, 1.0);
        if a <= 0.0 {
            return Vec4::ZERO;
        }
        let t = 0.5 + 0.5 * tone.fbm(c, 3.0, 3);
        let crater = (shape.noise(c * 7.0) * 2.0).clamp(0.0, 1.0);
        let albedo = Vec3::new(0.34, 0.30, 0.27) * (0.6 + 0.6 * t) * (1.0 - 0.4 * crater);
        (albedo * a).extend(a)
    });
    asset(res, &g, "asteroid", seed)
}

/// A dust cloud of `res`³ voxels (module docs).
pub fn dust(res: u32, seed: u64) -> VolumeAsset {
    let noise = Perlin::new(seed);
    let per_voxel = 2.5 / res.max(1) as f32; // opacity scale: thin per voxel
    let g = dense(res, |c| {
        let fall = (1.0 - c.length()).clamp(0.0, 1.0);
        let d = (noise.fbm(c, 1.3, 5) + 0.25).max(0.0) * fall * fall;
        let a = (d * per_voxel).clamp(0.0, 1.0);
        (Vec3::new(0.75, 0.68, 0.58) * a).extend(a)
    });
    asset(res, &g, "dust", seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_deterministic_bounded_and_zero_on_the_lattice() {
        let a = Perlin::new(7);
        let b = Perlin::new(7);
        let c = Perlin::new(8);
        let mut differs = false;
        for i in 0..500 {
            let p = Vec3::new(i as f32 * 0.37, i as f32 * 0.11 - 3.0, i as f32 * 0.73);
            let v = a.noise(p);
            assert_eq!(v, b.noise(p));
            assert!(v.abs() <= 1.5, "{v}");
            differs |= v != c.noise(p);
        }
        assert!(differs, "another seed gives other noise");
        assert_eq!(a.noise(Vec3::new(3.0, 5.0, 7.0)), 0.0);
    }

    #[test]
    fn asteroid_is_opaque_inside_and_empty_at_the_corners() {
        let v = asteroid(16, 3);
        v.validate().expect("valid asset");
        let l0 = &v.levels[0];
        let at = |x: usize, y: usize, z: usize| l0[4 * (x + 16 * (y + 16 * z)) + 3];
        assert_eq!(at(8, 8, 8), 255, "the centre is solid rock");
        assert_eq!(at(0, 0, 0), 0, "the corners are empty");
        assert_eq!(v.levels.len(), 5);
        let d = dust(16, 3);
        d.validate().expect("valid asset");
        let max_a = d.levels[0].chunks_exact(4).map(|p| p[3]).max().unwrap();
        assert!(max_a > 0 && max_a < 200, "dust is thin: {max_a}");
    }
}
