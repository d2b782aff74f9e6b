//! Watertight ray/triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013) with a tie rule on shared edges.
//!
//! The ray is sheared so that it points along +z of a permuted frame; the three 2D edge
//! functions `U, V, W` of the projected triangle are then computed from the *same*
//! vertex differences for every triangle sharing an edge, so a ray can never slip
//! between two triangles (no cracks). When an edge function is exactly zero in `f32`,
//! all three are recomputed in `f64` (as the paper recommends). A ray exactly on an edge
//! would hit both triangles sharing it; for alpha-blended surfaces that double-composites,
//! so an edge function of exactly zero is accepted only on edges that are "top-left" in
//! the sheared frame (an antisymmetric rule: of two triangles traversing the shared edge
//! in opposite directions, exactly one owns it — the rasterizer's fill rule).
//!
//! Near-degenerate (sliver, zero-area, edge-on) triangles give either a miss or a hit
//! with finite `t` and barycentrics in `[0,1]` summing to 1; never NaN.

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec3;

/// A ray prepared for repeated watertight tests.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub origin: Vec3,
    pub dir: Vec3,
    k: [usize; 3],
    shear: [f32; 3],
}

/// A hit: `t` along the ray's (unnormalised) direction, barycentric weights of v0, v1, v2,
/// and whether the triangle's counter-clockwise side faces the ray origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub bary: [f32; 3],
    pub front: bool,
}

impl WatertightRay {
    /// `dir` need not be normalised but must be finite and non-zero.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = dir[kz];
        WatertightRay {
            origin,
            dir,
            k: [kx, ky, kz],
            shear: [dir[kx] / dz, dir[ky] / dz, 1.0 / dz],
        }
    }

    /// Intersects the triangle; hits with `t ∉ [t_min, t_max]` are misses.
    pub fn intersect(
        &self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let a = v0 - self.origin;
        let b = v1 - self.origin;
        let c = v2 - self.origin;
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // Edge vectors in the sheared frame, for the tie rule (edge of U is b→c, etc.).
        let mut edges = [(cx - bx, cy - by), (ax - cx, ay - cy), (bx - ax, by - ay)];
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (sx, sy) = (f64::from(sx), f64::from(sy));
            let p = |q: Vec3| {
                let q = q.as_dvec3();
                (q[kx] - sx * q[kz], q[ky] - sy * q[kz])
            };
            let (ax, ay) = p(a);
            let (bx, by) = p(b);
            let (cx, cy) = p(c);
            let (ud, vd, wd) = (cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
            // Keep the exact-zero information of the f64 result.
            u = if ud == 0.0 { 0.0 } else { ud as f32 };
            v = if vd == 0.0 { 0.0 } else { vd as f32 };
            w = if wd == 0.0 { 0.0 } else { wd as f32 };
            if u == 0.0 && ud != 0.0 {
                u = (ud.signum() * f64::from(f32::MIN_POSITIVE)) as f32;
            }
            if v == 0.0 && vd != 0.0 {
                v = (vd.signum() * f64::from(f32::MIN_POSITIVE)) as f32;
            }
            if w == 0.0 && wd != 0.0 {
                w = (wd.signum() * f64::from(f32::MIN_POSITIVE)) as f32;
            }
            edges = [
                ((cx - bx) as f32, (cy - by) as f32),
                ((ax - cx) as f32, (ay - cy) as f32),
                ((bx - ax) as f32, (by - ay) as f32),
            ];
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // Orient so that the edge functions are non-negative inside.
        let flip = det < 0.0;
        for (e, val) in edges.iter().zip([u, v, w]) {
            if val == 0.0 {
                let (ex, ey) = if flip { (-e.0, -e.1) } else { *e };
                let owned = ey < 0.0 || (ey == 0.0 && ex > 0.0);
                if !owned {
                    return None;
                }
            }
        }
        let (az, bz, cz) = (sz * a[kz], sz * b[kz], sz * c[kz]);
        let t_scaled = u * az + v * bz + w * cz;
        let t = t_scaled / det;
        if !(t >= t_min && t <= t_max) {
            return None;
        }
        let inv = 1.0 / det;
        let mut bary = [u * inv, v * inv, w * inv];
        for x in &mut bary {
            *x = x.clamp(0.0, 1.0);
        }
        // Geometric orientation, robustly in f64.
        let n = (v1 - v0).as_dvec3().cross((v2 - v0).as_dvec3());
        let front = n.dot(self.dir.as_dvec3()) < 0.0;
        Some(TriangleHit { t, bary, front })
    }
}
