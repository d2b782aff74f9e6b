//! Algorithm 1 of Lacewell et al. 2006: random search for billboard planes.
//!
//! ```text
//! repeat
//!   for i in 1..=N:                        (N = samples)
//!     T_s <- random seed element among the remaining ones
//!     p_j <- v_j + d_j n_Ts, d_j uniform in [-eps, eps)   (j = 0, 1, 2)
//!     B   <- plane through p_0, p_1, p_2
//!     area(B) = sum over remaining T with every vertex within eps of B of area(T) |n_B . n_T|
//!   keep the candidate with the largest area (ties: the lowest i), remove its elements
//! until nothing remains
//! ```
//!
//! (The paper's listing resets `maxarea` inside the loop; its text says to keep the best of the
//! N, which is what this does.) Elements are triangles (level 0) or the previous level's
//! billboard quads (LOD levels: the seed triangle is corners 0, 1, 2, as the paper says).
//!
//! Determinism: all random draws for one round come first, sequentially, from one PCG32
//! stream; the N candidates are then scored in parallel (rayon), each scan summing in a fixed
//! order (8 interleaved lanes, combined in a fixed order), and the best is picked sequentially.
//! The result is the same for any thread count. There is no acceleration structure: the
//! plain scan over the remaining elements (structure-of-arrays, branch-free) is fast enough.
//!
//! Extent limit (§5, optional): with `max_extent = Some(r)` a candidate only counts (and
//! only takes) elements whose vertices all lie within `r` of its seed element's centroid,
//! which bounds a billboard's size (and so its texture) around its seed.
//!
//! Degenerate seeds: an element whose seed triangle is (near) collinear — `|e1 x e2|` below
//! `1e-6 |longest edge|^2` — defines no normal, so a draw that lands on one is redrawn
//! (counted); after [`MAX_REDRAWS`] failures the candidate is skipped (counted). If a whole
//! round yields no candidate, the first remaining element gets a fallback plane through its
//! centroid (counted), so the search always terminates and never produces a NaN plane.

use glam::Vec3;
use rayon::prelude::*;

use crate::rng::Pcg32;

/// Redraws of a degenerate seed before a candidate is given up.
pub const MAX_REDRAWS: u32 = 64;

/// A planar polygon with 3 (triangle) or 4 (quad, corners in order) vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    pub verts: [Vec3; 4],
    pub count: usize,
}

impl Element {
    pub fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Element {
            verts: [a, b, c, c],
            count: 3,
        }
    }
    pub fn quad(c: [Vec3; 4]) -> Self {
        Element { verts: c, count: 4 }
    }
    /// Twice-area vector (triangle: e1 × e2; quad: diagonal cross product).
    fn cross(&self) -> Vec3 {
        let v = &self.verts;
        if self.count == 4 {
            (v[2] - v[0]).cross(v[3] - v[1])
        } else {
            (v[1] - v[0]).cross(v[2] - v[0])
        }
    }
    /// Unit normal of the seed triangle (vertices 0, 1, 2) if it is not degenerate.
    pub fn seed_normal(&self) -> Option<Vec3> {
        let v = &self.verts;
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let e = (v[1] - v[0])
            .length_squared()
            .max((v[2] - v[1]).length_squared());
        let e = e.max((v[0] - v[2]).length_squared());
        let l = c.length();
        (l.is_finite() && l > 1e-6 * e && l > 0.0).then(|| c / l)
    }
}

/// The plane `normal · x = offset`, `|normal| = 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f32,
}

impl Plane {
    pub fn distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }
    pub fn project(&self, p: Vec3) -> Vec3 {
        p - self.distance(p) * self.normal
    }
}

/// One billboard plane found by the search and the input elements it took (ascending).
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub plane: Plane,
    pub members: Vec<u32>,
    /// Summed projected area of the members.
    pub area: f32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SearchStats {
    pub planes: usize,
    pub candidates: u64,
    pub degenerate_redraws: u64,
    pub skipped_candidates: u64,
    pub fallback_planes: u64,
}

/// Search parameters. `epsilon` is in world units here (the caller scales by the radius).
#[derive(Clone, Copy, Debug)]
pub struct SearchParams {
    pub epsilon: f32,
    pub samples: u32,
    pub seed: u64,
    /// PCG32 stream, so that each LOD level draws independent numbers from one seed.
    pub stream: u64,
    /// Lacewell §5's optional extent limit, world units: a candidate only takes elements
    /// whose vertices all lie within this distance of its seed's centroid.
    pub max_extent: Option<f32>,
}

/// The remaining elements, structure-of-arrays, in input order.
struct Soa {
    x: [Vec<f32>; 4],
    y: [Vec<f32>; 4],
    z: [Vec<f32>; 4],
    n: [Vec<f32>; 3],
    area: Vec<f32>,
    id: Vec<u32>,
}

impl Soa {
    fn new(elems: &[Element]) -> Soa {
        let mut s = Soa {
            x: Default::default(),
            y: Default::default(),
            z: Default::default(),
            n: Default::default(),
            area: Vec::with_capacity(elems.len()),
            id: (0..elems.len() as u32).collect(),
        };
        for e in elems {
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
        s
    }

    fn len(&self) -> usize {
        self.id.len()
    }

    /// Keep the elements whose `keep` flag is set, in order.
    fn retain(&mut self, keep: &[bool]) {
        fn r(v: &mut Vec<f32>, keep: &[bool]) {
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
        let mut i = 0;
        self.id.retain(|_| (keep[i], i += 1).0);
    }

    /// Projected area of element `j` if all its vertices are within `eps` of the plane (and,
    /// with `LIMIT`, within `lim.1` of the point `lim.0`), else 0.
    #[inline(always)]
    fn contrib<const LIMIT: bool>(&self, j: usize, p: &Plane, eps: f32, lim: (Vec3, f32)) -> f32 {
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

    /// Summed projected area: element j goes to lane j % 8, lanes are added in a fixed order.
    fn score<const LIMIT: bool>(&self, p: &Plane, eps: f32, lim: (Vec3, f32)) -> f32 {
        let n = self.len();
        let mut acc = [0.0f32; 8];
        let full = n / 8 * 8;
        for base in (0..full).step_by(8) {
            for (l, a) in acc.iter_mut().enumerate() {
                *a += self.contrib::<LIMIT>(base + l, p, eps, lim);
            }
        }
        for j in full..n {
            acc[j % 8] += self.contrib::<LIMIT>(j, p, eps, lim);
        }
        ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
    }

    fn inside(&self, j: usize, p: &Plane, eps: f32, lim: Option<(Vec3, f32)>) -> bool {
        (0..4).all(|k| {
            let v = Vec3::new(self.x[k][j], self.y[k][j], self.z[k][j]);
            let d = p.normal.dot(v) - p.offset;
            let near = lim.is_none_or(|(c, r)| {
                let q = v - c;
                q.x * q.x + q.y * q.y + q.z * q.z <= r * r
            });
            d.abs() < eps && near
        })
    }
}

/// A drawn candidate: its plane and the SoA position of its seed.
#[derive(Clone, Copy)]
struct Candidate {
    plane: Plane,
    seed: usize,
    /// Centroid of the seed element (centre of the extent limit).
    centre: Vec3,
}

fn draw(
    rng: &mut Pcg32,
    elems: &[Element],
    soa: &Soa,
    eps: f32,
    stats: &mut SearchStats,
) -> Option<Candidate> {
    for _ in 0..MAX_REDRAWS {
        let s = rng.below(soa.len() as u32) as usize;
        let e = &elems[soa.id[s] as usize];
        let d = [0, 1, 2].map(|_| rng.range_f32(-eps, eps));
        let Some(n) = e.seed_normal() else {
            stats.degenerate_redraws += 1;
            continue;
        };
        let p = [0, 1, 2].map(|j| e.verts[j] + d[j] * n);
        let c = (p[1] - p[0]).cross(p[2] - p[0]);
        let nb = c.normalize_or_zero();
        let offset = nb.dot((p[0] + p[1] + p[2]) / 3.0);
        if nb == Vec3::ZERO || !nb.is_finite() || !offset.is_finite() {
            stats.degenerate_redraws += 1;
            continue;
        }
        let centre = e.verts[..e.count].iter().copied().sum::<Vec3>() / e.count as f32;
        return Some(Candidate {
            plane: Plane { normal: nb, offset },
            seed: s,
            centre,
        });
    }
    stats.skipped_candidates += 1;
    None
}

/// A plane through a degenerate element: its own normal if it has one, else one containing
/// its longest edge (or any plane through a point), through its centroid.
pub fn fallback_plane(e: &Element) -> Plane {
    let v = &e.verts[..e.count];
    let centroid = v.iter().copied().sum::<Vec3>() / e.count as f32;
    let normal = e.seed_normal().unwrap_or_else(|| {
        let mut edge = Vec3::ZERO;
        for i in 0..e.count {
            let d = v[(i + 1) % e.count] - v[i];
            if d.length_squared() > edge.length_squared() {
                edge = d;
            }
        }
        let edge = edge.normalize_or_zero();
        if edge == Vec3::ZERO {
            return Vec3::Y;
        }
        let a = edge.abs();
        let axis = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        edge.cross(axis).normalize()
    });
    Plane {
        normal,
        offset: normal.dot(centroid),
    }
}

/// Run Algorithm 1 until every element is on some plane. `progress(assigned, total)`.
pub fn search(
    elems: &[Element],
    params: &SearchParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Vec<Found>, SearchStats) {
    let eps = params.epsilon;
    let mut rng = Pcg32::seeded(params.seed, params.stream);
    let mut soa = Soa::new(elems);
    let mut stats = SearchStats::default();
    let mut found = Vec::new();
    let total = elems.len();
    while soa.len() > 0 {
        let mut cands = Vec::with_capacity(params.samples as usize);
        for _ in 0..params.samples.max(1) {
            stats.candidates += 1;
            if let Some(c) = draw(&mut rng, elems, &soa, eps, &mut stats) {
                cands.push(c);
            }
        }
        let best = if cands.is_empty() {
            stats.fallback_planes += 1;
            let e = &elems[soa.id[0] as usize];
            Candidate {
                plane: fallback_plane(e),
                seed: 0,
                centre: e.verts[..e.count].iter().copied().sum::<Vec3>() / e.count as f32,
            }
        } else {
            let scores: Vec<f32> = cands
                .par_iter()
                .map(|c| match params.max_extent {
                    None => soa.score::<false>(&c.plane, eps, (c.centre, 0.0)),
                    Some(r) => soa.score::<true>(&c.plane, eps, (c.centre, r)),
                })
                .collect();
            let mut bi = 0;
            for (i, &s) in scores.iter().enumerate() {
                if s > scores[bi] {
                    bi = i;
                }
            }
            cands[bi]
        };
        let mut keep = vec![true; soa.len()];
        let mut members = Vec::new();
        let mut area = 0.0;
        for (j, k) in keep.iter_mut().enumerate() {
            // The seed is inside by construction (|d_j| < eps); including it explicitly only
            // guards against rounding, so every round removes at least one element.
            let lim = params.max_extent.map(|r| (best.centre, r));
            if j == best.seed || soa.inside(j, &best.plane, eps, lim) {
                *k = false;
                members.push(soa.id[j]);
                area += soa.contrib::<false>(j, &best.plane, f32::INFINITY, (Vec3::ZERO, 0.0));
            }
        }
        soa.retain(&keep);
        found.push(Found {
            plane: best.plane,
            members,
            area,
        });
        progress(total - soa.len(), total);
    }
    stats.planes = found.len();
    (found, stats)
}
