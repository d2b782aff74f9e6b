//! Trimming a billboard: the minimal-area rectangle around its projected elements.
//!
//! Points are projected into an orthonormal basis of the plane, their 2D convex hull is
//! computed (Andrew's monotone chain, in f64), and the minimum-area enclosing rectangle is
//! found by rotating calipers: the optimum has a side collinear with a hull edge
//! (Freeman & Shapira 1975), so every hull edge direction is tried with the extreme points
//! along it and across it tracked by three calipers that only ever advance.

use glam::{DVec2, Vec3};

use super::element::Plane;

/// A rectangle in a plane: `origin + s·u + t·v` for `s in [0, width]`, `t in [0, height]`,
/// with `u × v = normal` (right-handed) and `width >= height` is not required.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneRect {
    pub origin: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub width: f32,
    pub height: f32,
}

impl PlaneRect {
    pub fn corners(&self) -> [Vec3; 4] {
        let (a, b) = (self.u * self.width, self.v * self.height);
        [
            self.origin,
            self.origin + a,
            self.origin + a + b,
            self.origin + b,
        ]
    }
}

/// An orthonormal basis `(e1, e2)` of the plane with `e1 × e2 = n`.
pub fn plane_basis(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let e1 = a.cross(n).normalize();
    let e2 = n.cross(e1);
    (e1, e2)
}

fn cross(o: DVec2, a: DVec2, b: DVec2) -> f64 {
    (a - o).perp_dot(b - o)
}

/// Convex hull, counter-clockwise, no collinear points. Fewer than 3 points for degenerate input.
pub fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], q) <= 0.0 {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// Minimum-area rectangle around a convex CCW polygon: (origin, unit edge direction, width,
/// height) in 2D. Handles 0, 1 and 2 points (zero-size extents).
pub fn min_area_rect(hull: &[DVec2]) -> (DVec2, DVec2, f64, f64) {
    let n = hull.len();
    if n == 0 {
        return (DVec2::ZERO, DVec2::X, 0.0, 0.0);
    }
    if n < 3 {
        let d = hull[n - 1] - hull[0];
        let dir = if d.length() > 0.0 {
            d.normalize()
        } else {
            DVec2::X
        };
        return (hull[0], dir, d.length(), 0.0);
    }
    let at = |i: usize| hull[i % n];
    let dirs = |i: usize| {
        let u = (at(i + 1) - at(i)).normalize_or_zero();
        (at(i), u, u.perp()) // perp: the inward normal of a CCW polygon
    };
    let argbest = |f: &dyn Fn(DVec2) -> f64| {
        (0..n)
            .max_by(|&x, &y| f(at(x)).total_cmp(&f(at(y))).then(y.cmp(&x)))
            .unwrap_or(0)
    };
    // Calipers, as indices into the hull: max along the edge, max across it, min along it.
    let (a0, u0, w0) = dirs(0);
    let mut right = argbest(&|p| (p - a0).dot(u0));
    let mut far = argbest(&|p| (p - a0).dot(w0));
    let mut left = argbest(&|p| -(p - a0).dot(u0));
    let mut best = (f64::INFINITY, DVec2::ZERO, DVec2::X, 0.0, 0.0);
    for i in 0..n {
        let (a, u, w) = dirs(i);
        if u == DVec2::ZERO {
            continue;
        }
        let along = |p: DVec2| (p - a).dot(u);
        let across = |p: DVec2| (p - a).dot(w);
        while along(at(right + 1)) > along(at(right)) {
            right = (right + 1) % n;
        }
        while across(at(far + 1)) > across(at(far)) {
            far = (far + 1) % n;
        }
        while along(at(left + 1)) < along(at(left)) {
            left = (left + 1) % n;
        }
        let (s0, s1) = (along(at(left)), along(at(right)));
        let h = across(at(far));
        let area = (s1 - s0) * h;
        if area < best.0 {
            best = (area, a + u * s0, u, s1 - s0, h);
        }
    }
    (best.1, best.2, best.3, best.4)
}

/// The minimal rectangle in `plane` around the projections of `points`.
pub fn trim(plane: &Plane, points: &[Vec3]) -> PlaneRect {
    let (e1, e2) = plane_basis(plane.normal);
    let o = plane.normal * plane.offset;
    let p2: Vec<DVec2> = points
        .iter()
        .map(|&p| {
            let d = p - o;
            DVec2::new(f64::from(d.dot(e1)), f64::from(d.dot(e2)))
        })
        .collect();
    let (origin, dir, w, h) = min_area_rect(&convex_hull(&p2));
    let to3 = |q: DVec2| o + e1 * q.x as f32 + e2 * q.y as f32;
    let u = (e1 * dir.x as f32 + e2 * dir.y as f32).normalize_or(e1);
    let v = plane.normal.cross(u);
    PlaneRect {
        origin: to3(origin),
        u,
        v,
        width: w as f32,
        height: h as f32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(hull: &[DVec2]) -> f64 {
        let n = hull.len();
        (0..n)
            .map(|i| {
                let u = (hull[(i + 1) % n] - hull[i]).normalize();
                let w = u.perp();
                let s: Vec<f64> = hull.iter().map(|p| p.dot(u)).collect();
                let t: Vec<f64> = hull.iter().map(|p| p.dot(w)).collect();
                let r = |v: &[f64]| {
                    v.iter().cloned().fold(f64::MIN, f64::max)
                        - v.iter().cloned().fold(f64::MAX, f64::min)
                };
                r(&s) * r(&t)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn calipers_match_brute_force() {
        let mut rng = crate::rng::Pcg32::seeded(3, 0);
        for case in 0..300 {
            let k = 3 + case % 40;
            let pts: Vec<DVec2> = (0..k)
                .map(|_| DVec2::new(rng.next_f32() as f64 * 3.0, rng.next_f32() as f64))
                .collect();
            let hull = convex_hull(&pts);
            if hull.len() < 3 {
                continue;
            }
            let (o, u, w, h) = min_area_rect(&hull);
            assert!((w * h - brute(&hull)).abs() < 1e-9, "case {case}");
            for p in &pts {
                let (s, t) = ((*p - o).dot(u), (*p - o).dot(u.perp()));
                assert!(s > -1e-9 && s < w + 1e-9 && t > -1e-9 && t < h + 1e-9);
            }
        }
    }

    #[test]
    fn rotated_square_is_tight() {
        let a = 0.3f64;
        let (c, s) = (a.cos(), a.sin());
        let pts: Vec<DVec2> = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (0.0, 1.0), (1.0, 0.5)]
            .iter()
            .map(|&(x, y)| DVec2::new(c * x - s * y, s * x + c * y))
            .collect();
        let (_, _, w, h) = min_area_rect(&convex_hull(&pts));
        assert!((w * h - 2.0).abs() < 1e-9);
    }
}
