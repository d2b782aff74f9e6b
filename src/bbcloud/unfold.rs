//! Flattening a billboard's triangles onto its plane without losing their area.
//!
//! Lacewell et al. texture a billboard by projecting its triangles orthographically onto
//! its plane. A leaf tilted by θ from the plane then keeps `cos θ` of its area, and so of
//! the coverage it has on average over the directions it is seen from (`E|n·v| = ½` for
//! any orientation `n`, so a flat element covers in proportion to its area alone). The
//! oak's level-0 billboards keep 78 % of their leaves' area at ε = 0.04 and 59 % at
//! ε = 0.08 (the draft and balanced presets), which is most of why those clouds draw
//! thinner than the mesh (docs/bbcloud.md, "Coverage at a distance").
//!
//! Here each connected piece of the billboard's triangles (a leaf card: triangles sharing
//! vertex positions) is turned as a rigid body into the plane instead: about its
//! area-weighted centroid, by the shortest rotation from its mean normal to the plane's
//! (or its opposite, whichever is nearer). Its shape and area are kept; a point moves in
//! the plane by at most its distance from the centroid times `1 − cos θ` more than the
//! projection moves it. The height above the plane is left as it was, so that which
//! fragment is nearest to each side (`bake.rs`) does not change, and trimming (which looks
//! at positions in the plane only) sees the turned pieces.

use std::collections::HashMap;
use std::fmt;
use std::str::FromStr;

use glam::{Quat, Vec3};

use crate::scene::Scene;

/// How a billboard's triangles are laid onto its plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Flatten {
    /// Each connected piece turned into the plane about its centroid ([`unfold`]): its
    /// area, and so the mesh's coverage, is kept.
    #[default]
    Unfold,
    /// Projected orthographically onto the plane (Lacewell et al.): a piece tilted by θ
    /// keeps `cos θ` of its area.
    Project,
}

impl Flatten {
    pub fn name(self) -> &'static str {
        match self {
            Flatten::Unfold => "unfold",
            Flatten::Project => "project",
        }
    }
}

impl fmt::Display for Flatten {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A `--flatten` value that is neither `unfold` nor `project`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{0}': expected unfold or project")]
pub struct FlattenParseError(pub String);

impl FromStr for Flatten {
    type Err = FlattenParseError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "unfold" => Ok(Flatten::Unfold),
            "project" => Ok(Flatten::Project),
            _ => Err(FlattenParseError(s.to_string())),
        }
    }
}

/// The positions to texture `tris` (scene triangle indices) from on a plane of unit normal
/// `normal`: each connected piece turned into the plane about its centroid, each vertex
/// keeping its height along `normal`. One entry per triangle, in the order of `tris`.
pub fn unfold(scene: &Scene, tris: &[u32], normal: Vec3) -> Vec<[Vec3; 3]> {
    let verts = |i: usize| scene.triangles[tris[i] as usize].v.map(|v| v.position);
    // Pieces: union-find over the triangles, joined where they share a vertex position.
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first: HashMap<[u32; 3], usize> = HashMap::with_capacity(tris.len() * 2);
    for i in 0..tris.len() {
        for p in verts(i) {
            let key = p.to_array().map(f32::to_bits);
            let j = *first.entry(key).or_insert(i);
            let (a, b) = (root(&mut parent, i), root(&mut parent, j));
            // The smaller index is the root, so pieces do not depend on hashing order.
            if a != b {
                let (lo, hi) = (a.min(b), a.max(b));
                parent[hi] = lo;
            }
        }
    }
    // Per piece (indexed by its root): Σ twice-area vectors (each oriented to the plane's
    // side) and the area-weighted sum of centroids.
    let mut cross: Vec<Vec3> = vec![Vec3::ZERO; tris.len()];
    let mut moment: Vec<Vec3> = vec![Vec3::ZERO; tris.len()];
    let mut area: Vec<f32> = vec![0.0; tris.len()];
    for i in 0..tris.len() {
        let r = root(&mut parent, i);
        let [a, b, c] = verts(i);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if !len.is_finite() {
            continue;
        }
        cross[r] += if n.dot(normal) < 0.0 { -n } else { n };
        moment[r] += len * (a + b + c) / 3.0;
        area[r] += len;
    }
    (0..tris.len())
        .map(|i| {
            let r = root(&mut parent, i);
            let p = verts(i);
            let n = cross[r].normalize_or_zero();
            if area[r] <= 0.0 || n == Vec3::ZERO {
                return p; // degenerate piece: projected as before
            }
            let centre = moment[r] / area[r];
            let turn = Quat::from_rotation_arc(n, normal);
            p.map(|x| {
                let y = centre + turn * (x - centre);
                // Back to the vertex's own height above the plane.
                y + normal * (normal.dot(x) - normal.dot(y))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, SceneBuilder};
    use glam::Vec4;

    #[test]
    fn a_tilted_quad_keeps_its_area_and_shape_in_the_plane() {
        // A unit square tilted 60° about the x axis: projected, it keeps half its area.
        let (s, c) = (60f32.to_radians().sin(), 60f32.to_radians().cos());
        let p = |x: f32, y: f32| Vec3::new(x, y * c, y * s);
        let mut b = SceneBuilder::new();
        let (m, mesh) = (b.material(Material::default()), b.mesh("leaf"));
        b.quad(
            [p(0., 0.), p(1., 0.), p(1., 1.), p(0., 1.)],
            Vec4::ONE,
            m,
            mesh,
        );
        let scene = b.finish();
        let tris: Vec<[Vec3; 3]> = scene
            .triangles
            .iter()
            .map(|t| t.v.map(|v| v.position))
            .collect();
        let out = unfold(&scene, &[0, 1], Vec3::Z);
        let in_plane = |t: &[Vec3; 3]| {
            let q = t.map(|v| v.truncate());
            0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]).abs()
        };
        let total: f32 = out.iter().map(in_plane).sum();
        assert!(
            (total - 1.0).abs() < 1e-5,
            "area in the plane {total}, want 1"
        );
        let projected: f32 = tris.iter().map(in_plane).sum();
        assert!(
            (projected - 0.5).abs() < 1e-5,
            "projection keeps {projected}"
        );
        // The two triangles still share their diagonal (a–c): one rigid piece.
        assert!(out[0][0].distance(out[1][0]) < 1e-5);
        assert!(out[0][2].distance(out[1][1]) < 1e-5);
        // Heights along the normal are kept.
        for (o, t) in out.iter().zip(&tris) {
            for (a, b) in o.iter().zip(t) {
                assert!((a.z - b.z).abs() < 1e-6);
            }
        }
    }
}
