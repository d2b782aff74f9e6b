//! The geometry the plane search works on: the mesh's planar elements (triangles and
//! quads) and the planes it fits to them (`plane_search`, `slab`, `lod` and `rect` share
//! them).

use glam::Vec3;

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
    /// Mean of the vertices.
    pub fn centroid(&self) -> Vec3 {
        self.verts[..self.count].iter().copied().sum::<Vec3>() / self.count as f32
    }
    /// Twice-area vector (triangle: e1 × e2; quad: diagonal cross product).
    pub fn cross(&self) -> Vec3 {
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
