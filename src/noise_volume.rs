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
//! - [`sphere`]: a plain opaque ball of one albedo, the runtime-shading test subject.
//!
//! Both give level 0 as premultiplied linear RGBA and go through the same per-direction
//! MIP and combine as baked volumes ([`crate::voxelize::dense`], `mean` combine), so the
//! asset is an ordinary volume with one box cell.
//!
//! The rock and the sphere are closed surfaces and carry **normals** (SPEC §8.4): the
//! outward unit normal of their implicit surface (the gradient of `surface − r`, by
//! central differences for the rock) in every non-empty voxel, MIP-mapped with Toksvig's
//! filter as the voxelizer does (`src/voxelize/toksvig.rs`: the alpha-weighted mean of
//! the children's normals, not renormalised), so viewers shade them at runtime with the
//! scene light and their colour is albedo. The dust stays unshaded (fuzzy: the VB paper,
//! §3.2, keeps such objects' lighting precomputed).

use std::collections::BTreeMap;

use billow_format::{Bounds, ColourSpace, Header, VolumeAsset};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::rng::Pcg32;
use crate::voxelize::dense::pyramid_from_dense;
use crate::voxelize::grid3::Grid3;
use crate::voxelize::{CombineFn, Preset};
use billow_core::cells::box_prisms;

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

/// Level 0 of a normal field: `normal(c)` (unit) where `level0` has alpha, else zero,
/// as `(α·n, α)`.
fn dense_normals(
    res: u32,
    level0: &Grid3<[f32; 4]>,
    normal: impl Fn(Vec3) -> Vec3 + Sync,
) -> Vec<Vec4> {
    let n = res.max(1) as usize;
    let mut out = vec![Vec4::ZERO; n * n * n];
    out.par_chunks_mut(n * n)
        .enumerate()
        .for_each(|(z, plane)| {
            for y in 0..n {
                for x in 0..n {
                    let a = level0.data[x + n * (y + n * z)][3];
                    if a > 0.0 {
                        let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                        let c = (p / n as f32) * 2.0 - 1.0;
                        plane[x + n * y] = (normal(c).normalize_or_zero() * a).extend(a);
                    }
                }
            }
        });
    out
}

/// Toksvig MIP levels of `(α·n, α)` texels of a `res`³ level 0 (`levels` in all): each
/// parent is the mean of its (up to 8) children, then `n̄ = α·n / α` (not renormalised)
/// is encoded as snorm8 (SPEC §8.4).
fn normal_levels(res: u32, level0: Vec<Vec4>, levels: usize) -> Vec<Vec<u8>> {
    use crate::voxelize::quantize::encode_normal;
    use crate::voxelize::toksvig::average_normal;
    let encode = |l: &[Vec4]| -> Vec<u8> {
        l.iter()
            .flat_map(|t| encode_normal(average_normal(t.truncate(), t.w)))
            .collect()
    };
    let mut out = vec![encode(&level0)];
    let mut cur = level0;
    let mut dims = [res.max(1); 3];
    for l in 1..levels {
        let nd = billow_format::mip_dims([res.max(1); 3], l as u32);
        let (w, h) = (dims[0] as usize, dims[1] as usize);
        let (nw, nh, nz) = (nd[0] as usize, nd[1] as usize, nd[2] as usize);
        let mut next = vec![Vec4::ZERO; nw * nh * nz];
        for z in 0..nz {
            for y in 0..nh {
                for x in 0..nw {
                    let mut acc = Vec4::ZERO;
                    let mut k = 0.0;
                    for dz in 0..2 {
                        for dy in 0..2 {
                            for dx in 0..2 {
                                let (cx, cy, cz) = (2 * x + dx, 2 * y + dy, 2 * z + dz);
                                if cx < w && cy < h && cz < dims[2] as usize {
                                    acc += cur[cx + w * (cy + h * cz)];
                                    k += 1.0;
                                }
                            }
                        }
                    }
                    next[x + nw * (y + nh * z)] = acc / f32::max(k, 1.0);
                }
            }
        }
        out.push(encode(&next));
        cur = next;
        dims = nd;
    }
    out
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

fn asset(
    res: u32,
    level0: &Grid3<[f32; 4]>,
    normals0: Option<Vec<Vec4>>,
    kind: &str,
    seed: u64,
) -> VolumeAsset {
    let levels = pyramid_from_dense(level0, &CombineFn::Preset(Preset::Mean));
    let normals = normals0.map(|n| normal_levels(res, n, levels.len()));
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
                normals.is_some(),
            )
        },
        levels,
        normals,
        cells: box_prisms(lo, hi).to_vec(),
        bands: Vec::new(),
    }
}

/// A rock of `res`³ voxels (module docs).
pub fn asteroid(res: u32, seed: u64) -> VolumeAsset {
    let shape = Perlin::new(seed);
    let tone = Perlin::new(seed ^ 0x9e37_79b9);
    let edge = 2.0 / res.max(1) as f32; // one voxel, in box units
    let surface = |c: Vec3| 0.55 * (1.0 + 0.35 * shape.fbm(c, 1.6, 4));
    let g = dense(res, |c| {
        let r = c.length();
        let surface = surface(c);
        let a = ((surface - r) / edge + 0.5).clamp(0.0, 1.0);
        if a <= 0.0 {
            return Vec4::ZERO;
        }
        let t = 0.5 + 0.5 * tone.fbm(c, 3.0, 3);
        let crater = (shape.noise(c * 7.0) * 2.0).clamp(0.0, 1.0);
        let albedo = Vec3::new(0.34, 0.30, 0.27) * (0.6 + 0.6 * t) * (1.0 - 0.4 * crater);
        (albedo * a).extend(a)
    });
    // Outward normal: −∇(surface − r), central differences of a tenth of a voxel.
    let h = 0.1 * edge;
    let f = |c: Vec3| surface(c) - c.length();
    let n = dense_normals(res, &g, |c| {
        -Vec3::new(
            f(c + Vec3::X * h) - f(c - Vec3::X * h),
            f(c + Vec3::Y * h) - f(c - Vec3::Y * h),
            f(c + Vec3::Z * h) - f(c - Vec3::Z * h),
        )
    });
    asset(res, &g, Some(n), "asteroid", seed)
}

/// An opaque ball of radius 0.8 in the `[-1, 1]³` box, `res`³ voxels, one linear
/// `albedo`, a one-voxel soft edge, radial normals: the subject of the shading tests
/// (a ball lit from +x is brighter on its +x side by the Lambert ratio).
pub fn sphere(res: u32, albedo: Vec3) -> VolumeAsset {
    let edge = 2.0 / res.max(1) as f32;
    let g = dense(res, |c| {
        let a = ((0.8 - c.length()) / edge + 0.5).clamp(0.0, 1.0);
        (albedo * a).extend(a)
    });
    let n = dense_normals(res, &g, |c| c);
    asset(res, &g, Some(n), "sphere", 0)
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
    asset(res, &g, None, "dust", seed)
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
