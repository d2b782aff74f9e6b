//! The scan at the heart of Algorithm 1: the projected area of the remaining elements that lie
//! inside a candidate's slab, with an optional acceleration structure that gives the same
//! bits.
//!
//! The remaining elements are kept structure-of-arrays in a fixed **spatial order** (Morton
//! code of the centroid on a 2¹⁰ grid over the input's bounding box, ties by input index), so
//! consecutive elements are close together. The plain scan visits every element in that
//! order and adds its contribution (0 when outside the slab) to lane `j % 8`, `j` its
//! position; the lanes are combined in a fixed order at the end.
//!
//! Acceleration ([`Soa::score`] with `cull = true`): the elements are grouped into runs of
//! [`CHUNK`] consecutive positions, each with the bounding box of its vertices (rebuilt after
//! every removal). A run whose box lies entirely outside the slab (or, with the extent
//! limit, entirely outside the sphere) holds no element that contributes, so it is skipped.
//! Skipping only ever omits additions of `+0.0` to a lane (contributions are ≥ +0, and
//! `x + 0.0 = x` for every `x ≥ +0`), and every other element is added to the same lane in
//! the same order: the sum is bit for bit that of the plain scan. The box test is
//! conservative: a run is only skipped when it is outside by more than a margin (10⁻⁵ of the
//! magnitudes involved) that bounds the rounding of both the box test and the per-vertex
//! distances, so no element that the plain scan would count is ever skipped.

use glam::Vec3;

use super::element::{Element, Plane};

/// Elements per culling run.
pub const CHUNK: usize = 32;

/// The remaining elements, structure-of-arrays, in spatial order.
pub struct Soa {
    x: [Vec<f32>; 4],
    y: [Vec<f32>; 4],
    z: [Vec<f32>; 4],
    n: [Vec<f32>; 3],
    area: Vec<f32>,
    /// Index of each element in the input.
    pub id: Vec<u32>,
    /// Per run of `CHUNK` positions: min and max corner of its vertices.
    boxes: Vec<(Vec3, Vec3)>,
}

/// Morton code of a point on a 2¹⁰ grid over `[lo, hi]`.
fn morton(p: Vec3, lo: Vec3, hi: Vec3) -> u32 {
    let q = |v: f32, a: f32, b: f32| {
        let t = if b > a { (v - a) / (b - a) } else { 0.0 };
        ((t * 1023.0).clamp(0.0, 1023.0) as u32) & 1023
    };
    let spread = |mut v: u32| {
        v = (v | (v << 16)) & 0x0300_00FF;
        v = (v | (v << 8)) & 0x0300_F00F;
        v = (v | (v << 4)) & 0x030C_30C3;
        (v | (v << 2)) & 0x0924_9249
    };
    spread(q(p.x, lo.x, hi.x))
        | (spread(q(p.y, lo.y, hi.y)) << 1)
        | (spread(q(p.z, lo.z, hi.z)) << 2)
}

impl Soa {
    pub fn new(elems: &[Element]) -> Soa {
        let (lo, hi) = elems
            .iter()
            .flat_map(|e| e.verts[..e.count].iter())
            .filter(|v| v.is_finite())
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let mut order: Vec<(u32, u32)> = elems
            .iter()
            .enumerate()
            .map(|(i, e)| (morton(e.centroid(), lo, hi), i as u32))
            .collect();
        order.sort_unstable();
        let mut s = Soa {
            x: Default::default(),
            y: Default::default(),
            z: Default::default(),
            n: Default::default(),
            area: Vec::with_capacity(elems.len()),
            id: order.iter().map(|&(_, i)| i).collect(),
            boxes: Vec::new(),
        };
        for &(_, i) in &order {
            let e = &elems[i as usize];
            for k in 0..4 {
                s.x[k].push(e.verts[k].x);
                s.y[k].push(e.verts[k].y);
                s.z[k].push(e.verts[k].z);
            }
            let c = e.cross();
            let l = c.length();
            let n = if l.is_finite() && l > 0.0 {
                c / l
            } else {
                Vec3::ZERO
            };
            s.n[0].push(n.x);
            s.n[1].push(n.y);
            s.n[2].push(n.z);
            s.area.push(if l.is_finite() { 0.5 * l } else { 0.0 });
        }
        s.rebuild_boxes();
        s
    }

    pub fn len(&self) -> usize {
        self.id.len()
    }

    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    fn vertex(&self, k: usize, j: usize) -> Vec3 {
        Vec3::new(self.x[k][j], self.y[k][j], self.z[k][j])
    }

    fn rebuild_boxes(&mut self) {
        self.boxes = (0..self.len())
            .step_by(CHUNK)
            .map(|start| {
                let end = (start + CHUNK).min(self.len());
                let mut b = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for j in start..end {
                    for k in 0..4 {
                        let v = self.vertex(k, j);
                        b = (b.0.min(v), b.1.max(v));
                    }
                }
                b
            })
            .collect();
    }

    /// Keep the elements whose `keep` flag is set, in order.
    pub fn retain(&mut self, keep: &[bool]) {
        fn r<T>(v: &mut Vec<T>, keep: &[bool]) {
            let mut i = 0;
            v.retain(|_| (keep[i], i += 1).0);
        }
        for k in 0..4 {
            r(&mut self.x[k], keep);
            r(&mut self.y[k], keep);
            r(&mut self.z[k], keep);
        }
        self.n.iter_mut().for_each(|v| r(v, keep));
        r(&mut self.area, keep);
        r(&mut self.id, keep);
        self.rebuild_boxes();
    }

    /// Projected area of element `j` if all its vertices are within `eps` of the plane (and,
    /// with `LIMIT`, within `lim.1` of the point `lim.0`), else +0.
    #[inline(always)]
    pub fn contrib<const LIMIT: bool>(
        &self,
        j: usize,
        p: &Plane,
        eps: f32,
        lim: (Vec3, f32),
    ) -> f32 {
        let (nx, ny, nz, r) = (p.normal.x, p.normal.y, p.normal.z, p.offset);
        let mut inside = true;
        for k in 0..4 {
            let d = (nx * self.x[k][j] + ny * self.y[k][j] + nz * self.z[k][j]) - r;
            inside &= d.abs() < eps;
            if LIMIT {
                let (dx, dy, dz) = (
                    self.x[k][j] - lim.0.x,
                    self.y[k][j] - lim.0.y,
                    self.z[k][j] - lim.0.z,
                );
                inside &= dx * dx + dy * dy + dz * dz <= lim.1 * lim.1;
            }
        }
        let w = self.area[j] * (nx * self.n[0][j] + ny * self.n[1][j] + nz * self.n[2][j]).abs();
        if inside {
            w
        } else {
            0.0
        }
    }

    /// Whether run `c` certainly holds no element inside the slab (and sphere).
    fn culled<const LIMIT: bool>(&self, c: usize, p: &Plane, eps: f32, lim: (Vec3, f32)) -> bool {
        let (lo, hi) = self.boxes[c];
        let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        let n = p.normal;
        let d = n.dot(mid) - p.offset;
        let e = n.abs().dot(half);
        let scale = n.abs().dot(lo.abs().max(hi.abs())) + p.offset.abs() + eps;
        let margin = 1e-5 * scale + 1e-30;
        if d - e - margin >= eps || d + e + margin <= -eps {
            return true;
        }
        if LIMIT {
            // Distance from the sphere's centre to the box.
            let q = (lo - lim.0).max(lim.0 - hi).max(Vec3::ZERO);
            let r = lim.1;
            let scale = lim.0.abs().max(lo.abs().max(hi.abs())).max_element() + r;
            let m = 1e-5 * scale * scale + 1e-30;
            if q.length_squared() > r * r + m {
                return true;
            }
        }
        false
    }

    /// Summed projected area over the remaining elements: element at position j goes to lane
    /// j % 8, lanes are added in a fixed order. `cull` skips runs outside the slab; the
    /// result is the same bits either way (see the module docs).
    pub fn score<const LIMIT: bool>(
        &self,
        p: &Plane,
        eps: f32,
        lim: (Vec3, f32),
        cull: bool,
    ) -> f32 {
        let n = self.len();
        let mut acc = [0.0f32; 8];
        for c in 0..n.div_ceil(CHUNK) {
            if cull && self.culled::<LIMIT>(c, p, eps, lim) {
                continue;
            }
            let start = c * CHUNK;
            let end = (start + CHUNK).min(n);
            let mut base = start;
            while base + 8 <= end {
                self.add8::<LIMIT>(base, p, eps, lim, &mut acc);
                base += 8;
            }
            for j in base..end {
                acc[j % 8] += self.contrib::<LIMIT>(j, p, eps, lim);
            }
        }
        ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
    }

    /// `acc[l] += contrib(base + l)` for l in 0..8 (`base` a multiple of 8), on fixed-size
    /// slices so the loop has no bounds checks and vectorises.
    #[inline(always)]
    fn add8<const LIMIT: bool>(
        &self,
        base: usize,
        p: &Plane,
        eps: f32,
        lim: (Vec3, f32),
        acc: &mut [f32; 8],
    ) {
        fn g8(v: &[f32], base: usize) -> &[f32; 8] {
            v[base..base + 8].try_into().expect("8 elements")
        }
        let g = |v| g8(v, base);
        let (nx, ny, nz, r) = (p.normal.x, p.normal.y, p.normal.z, p.offset);
        let mut inside = [true; 8];
        for k in 0..4 {
            let (x, y, z) = (g(&self.x[k]), g(&self.y[k]), g(&self.z[k]));
            for l in 0..8 {
                let d = (nx * x[l] + ny * y[l] + nz * z[l]) - r;
                inside[l] &= d.abs() < eps;
                if LIMIT {
                    let (dx, dy, dz) = (x[l] - lim.0.x, y[l] - lim.0.y, z[l] - lim.0.z);
                    inside[l] &= dx * dx + dy * dy + dz * dz <= lim.1 * lim.1;
                }
            }
        }
        let (a, n0, n1, n2) = (g(&self.area), g(&self.n[0]), g(&self.n[1]), g(&self.n[2]));
        for l in 0..8 {
            let w = a[l] * (nx * n0[l] + ny * n1[l] + nz * n2[l]).abs();
            acc[l] += if inside[l] { w } else { 0.0 };
        }
    }

    /// Whether element `j` lies inside the slab (and the sphere, if any).
    pub fn inside(&self, j: usize, p: &Plane, eps: f32, lim: Option<(Vec3, f32)>) -> bool {
        (0..4).all(|k| {
            let v = self.vertex(k, j);
            let d = p.normal.dot(v) - p.offset;
            let near = lim.is_none_or(|(c, r)| {
                let q = v - c;
                q.x * q.x + q.y * q.y + q.z * q.z <= r * r
            });
            d.abs() < eps && near
        })
    }
}

const _: () = assert!(CHUNK.is_multiple_of(8));
