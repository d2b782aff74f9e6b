//! Billboard textures: the billboard's triangles projected orthographically onto its plane,
//! front (seen from +normal) and back (seen from −normal), K×K coverage samples per texel,
//! baked ambient + diffuse lighting, premultiplied linear RGBA.
//!
//! Per sample the nearest surviving fragment wins on each side (nearest = largest height
//! above the plane for the front, smallest for the back). A fragment survives the material's
//! alpha mode: MASK keeps it (alpha 1) where alpha ≥ cutoff, BLEND keeps it with its alpha
//! (no blending of several layers), OPAQUE with alpha 1. Every triangle is treated as
//! double-sided for visibility (leaf cards are); lighting is the viewer's mesh-pass model,
//! `albedo · (ambient + (1 − ambient) · |N·L|)` with the interpolated shading normal
//! ([`billow_core::shading::diffuse_factor`]), so a leaf seen from either side is lit alike
//! and a billboard looks like the mesh it replaces under the same light.
//! A texel's colour is the mean of its samples' premultiplied colours, its alpha their mean
//! coverage. Work is done in bands of rows so memory stays small for large billboards.
//!
//! Normal maps (optional): each sample also keeps the shading normal of its nearest fragment,
//! turned towards that side's viewer, expressed in the side's tangent frame
//! `(T, B, N) = (U, −V, ±n)` — U and −V are the directions of increasing u and of
//! decreasing v (image up) in the atlas, N the side's outward normal (+n front, −n back).
//! A texel holds the coverage-weighted mean of its samples' tangent-space normals,
//! premultiplied like colour: `(x·α, y·α, z·α, α)`; empty texels hold 0 (SPEC §9.4 says how
//! they are encoded).

use glam::{Vec2, Vec3, Vec4};

use super::rect::PlaneRect;
use super::sampler::Decoded;
use crate::scene::{AlphaMode, Scene};
use billow_core::shading::diffuse_factor;

/// Lighting of the bake. `light: None` bakes unlit albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Unit direction towards the light.
    pub light: Option<Vec3>,
    pub ambient: f32,
}

/// Premultiplied linear RGBA image, rows top (t = 0) to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec4>,
}

/// The textures of one billboard: front, back, and (with normal maps) the front and back
/// tangent-space normals, premultiplied by coverage.
pub struct Baked {
    pub front: Image,
    pub back: Image,
    pub normals: Option<[Image; 2]>,
}

/// What to render for one billboard.
pub struct Job<'a> {
    pub rect: PlaneRect,
    /// Plane normal (= rect.u × rect.v).
    pub normal: Vec3,
    pub density: f32,
    pub width: u32,
    pub height: u32,
    pub triangles: &'a [u32],
    /// Where each of `triangles` is drawn from (its vertices turned into the plane,
    /// [`super::unfold`]).
    pub positions: &'a [[Vec3; 3]],
    /// The scene's textures decoded for sampling (`None`: not used by the foliage).
    pub textures: &'a [Option<Decoded<'a>>],
}

const BAND: u32 = 16;

struct Prepared {
    p: [Vec2; 3],
    z: [f32; 3],
    inv_area: f32,
    tmin: f32,
    tmax: f32,
    tri: u32,
}

#[derive(Clone, Copy)]
struct Sample {
    fz: f32,
    f: Vec4,
    bz: f32,
    b: Vec4,
}

const EMPTY: Sample = Sample {
    fz: f32::NEG_INFINITY,
    f: Vec4::ZERO,
    bz: f32::INFINITY,
    b: Vec4::ZERO,
};

/// The samples of one band of rows: K² per texel, the normals of the winning fragments
/// (with normal maps), and which texels any fragment reached — the others are left empty
/// and skipped (a billboard's rectangle is mostly gaps between leaves).
struct Band {
    samples: Vec<Sample>,
    nrm: Vec<[Vec3; 2]>,
    touched: Vec<bool>,
}

/// Render the front and back textures of one billboard (and its normal maps when `normals`).
pub fn render(scene: &Scene, job: &Job<'_>, k: u32, shading: &Shading, normals: bool) -> Baked {
    let (w, h) = (job.width, job.height);
    let r = &job.rect;
    let to2 = |p: Vec3| {
        let d = p - r.origin;
        (
            Vec2::new(d.dot(r.u), d.dot(r.v)) * job.density,
            d.dot(job.normal),
        )
    };
    let mut prep: Vec<Prepared> = Vec::with_capacity(job.triangles.len());
    for (&ti, pos) in job.triangles.iter().zip(job.positions) {
        let (mut p, mut z) = ([Vec2::ZERO; 3], [0.0; 3]);
        for j in 0..3 {
            (p[j], z[j]) = to2(pos[j]);
        }
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area.is_nan() || area.abs() <= 1e-12 {
            continue; // edge-on: covers no sample
        }
        let tmin = p[0].y.min(p[1].y).min(p[2].y);
        let tmax = p[0].y.max(p[1].y).max(p[2].y);
        prep.push(Prepared {
            p,
            z,
            inv_area: 1.0 / area,
            tmin,
            tmax,
            tri: ti,
        });
    }
    let mut front = vec![Vec4::ZERO; (w * h) as usize];
    let mut back = vec![Vec4::ZERO; (w * h) as usize];
    let kk = (k * k) as usize;
    let texels = if normals { (w * h) as usize } else { 0 };
    let (mut front_n, mut back_n) = (vec![Vec4::ZERO; texels], vec![Vec4::ZERO; texels]);
    let n_samples = (w * BAND) as usize * kk;
    let mut band = Band {
        samples: vec![EMPTY; n_samples],
        nrm: vec![[Vec3::ZERO; 2]; if normals { n_samples } else { 0 }],
        touched: vec![false; (w * BAND) as usize],
    };
    let tangent_front = |n: Vec3| Vec3::new(n.dot(r.u), -n.dot(r.v), n.dot(job.normal));
    let inv_k = 1.0 / k as f32;
    for y0 in (0..h).step_by(BAND as usize) {
        let y1 = (y0 + BAND).min(h);
        for t in prep
            .iter()
            .filter(|t| t.tmax >= y0 as f32 && t.tmin <= y1 as f32)
        {
            if normals {
                raster::<true>(scene, t, job, y0, y1, k, shading, &mut band);
            } else {
                raster::<false>(scene, t, job, y0, y1, k, shading, &mut band);
            }
        }
        let Band {
            samples,
            nrm,
            touched,
        } = &mut band;
        for y in y0..y1 {
            for x in 0..w {
                let ti = ((y - y0) * w + x) as usize;
                if !std::mem::take(&mut touched[ti]) {
                    continue; // no fragment: stays empty, its samples are still EMPTY
                }
                let base = ti * kk;
                let (mut f, mut b) = (Vec4::ZERO, Vec4::ZERO);
                for s in &samples[base..base + kk] {
                    f += s.f;
                    b += s.b;
                }
                let i = (y * w + x) as usize;
                front[i] = f * inv_k * inv_k;
                back[i] = b * inv_k * inv_k;
                if normals {
                    let (mut nf, mut nb) = (Vec4::ZERO, Vec4::ZERO);
                    for (s, n) in samples[base..base + kk].iter().zip(&nrm[base..base + kk]) {
                        // Front frame (U, −V, n); back frame (U, −V, −n).
                        nf += (tangent_front(n[0]) * s.f.w).extend(s.f.w);
                        let t = tangent_front(n[1]);
                        nb += (Vec3::new(t.x, t.y, -t.z) * s.b.w).extend(s.b.w);
                    }
                    front_n[i] = nf * inv_k * inv_k;
                    back_n[i] = nb * inv_k * inv_k;
                }
                samples[base..base + kk].fill(EMPTY);
            }
        }
    }
    let img = |texels| Image {
        width: w,
        height: h,
        texels,
    };
    Baked {
        front: img(front),
        back: img(back),
        normals: normals.then(|| [img(front_n), img(back_n)]),
    }
}

/// Rasterize one triangle into the band's samples; with `NORMALS`, also record each winning
/// fragment's shading normal turned towards that side (`nrm[i] = [front, back]`).
#[allow(clippy::too_many_arguments)]
fn raster<const NORMALS: bool>(
    scene: &Scene,
    t: &Prepared,
    job: &Job<'_>,
    y0: u32,
    y1: u32,
    k: u32,
    sh: &Shading,
    band: &mut Band,
) {
    let w = job.width;
    let kf = k as f32;
    let (smin, smax) = (
        t.p[0].x.min(t.p[1].x).min(t.p[2].x),
        t.p[0].x.max(t.p[1].x).max(t.p[2].x),
    );
    // Sample (x, i) sits at x + (i + 0.5) / k; cover the sample-index range of the bbox.
    let si0 = ((smin * kf - 0.5).ceil().max(0.0)) as i64;
    let si1 = ((smax * kf - 0.5).floor() as i64).min((w * k) as i64 - 1);
    let ti0 = ((t.tmin * kf - 0.5).ceil() as i64).max((y0 * k) as i64);
    let ti1 = ((t.tmax * kf - 0.5).floor() as i64).min((y1 * k) as i64 - 1);
    if si0 > si1 || ti0 > ti1 {
        return;
    }
    let tri = &scene.triangles[t.tri as usize];
    let mat = scene.material(tri);
    let tex = mat
        .base_color_texture
        .and_then(|i| job.textures.get(i as usize))
        .and_then(Option::as_ref);
    let face = tri.cross().normalize_or(job.normal);
    let kk = (k * k) as usize;
    for ty in ti0..=ti1 {
        let py = (ty as f32 + 0.5) / kf;
        for sx in si0..=si1 {
            let p = Vec2::new((sx as f32 + 0.5) / kf, py);
            let w0 = (t.p[2] - t.p[1]).perp_dot(p - t.p[1]) * t.inv_area;
            let w1 = (t.p[0] - t.p[2]).perp_dot(p - t.p[2]) * t.inv_area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * t.z[0] + w1 * t.z[1] + w2 * t.z[2];
            let (x, i) = ((sx / k as i64) as u32, (sx % k as i64) as usize);
            let (yy, j) = ((ty / k as i64) as u32 - y0, (ty % k as i64) as usize);
            let si = ((yy * w + x) as usize) * kk + j * k as usize + i;
            let s = &mut band.samples[si];
            if !(z > s.fz || z < s.bz) {
                continue;
            }
            let bw = [w0, w1, w2];
            let lerp4 = |f: &dyn Fn(usize) -> Vec4| bw[0] * f(0) + bw[1] * f(1) + bw[2] * f(2);
            let uv = lerp4(&|q| tri.v[q].uv.extend(0.0).extend(0.0))
                .truncate()
                .truncate();
            let mut albedo = mat.base_color_factor * lerp4(&|q| tri.v[q].color);
            if let Some(tx) = tex {
                albedo *= tx.sample_bilinear(uv);
            }
            let alpha = match mat.alpha_mode {
                AlphaMode::Mask { cutoff } if albedo.w < cutoff => continue,
                AlphaMode::Blend if albedo.w <= 0.0 => continue,
                AlphaMode::Blend => albedo.w.min(1.0),
                _ => 1.0,
            };
            let nf = if NORMALS || sh.light.is_some() {
                let n = lerp4(&|q| tri.v[q].normal.extend(0.0))
                    .truncate()
                    .normalize_or(face);
                if n.dot(job.normal) >= 0.0 {
                    n
                } else {
                    -n
                }
            } else {
                Vec3::Z
            };
            let (cf, cb) = match sh.light {
                None => (albedo.truncate(), albedo.truncate()),
                Some(l) => {
                    // The viewer's mesh-pass model: two-sided, so both sides alike.
                    let c = albedo.truncate() * diffuse_factor(nf, l, sh.ambient);
                    (c, c)
                }
            };
            if z > s.fz {
                s.fz = z;
                s.f = (cf * alpha).extend(alpha);
                if NORMALS {
                    band.nrm[si][0] = nf;
                }
            }
            if z < s.bz {
                s.bz = z;
                s.b = (cb * alpha).extend(alpha);
                if NORMALS {
                    band.nrm[si][1] = -nf;
                }
            }
            band.touched[(yy * w + x) as usize] = true;
        }
    }
}
