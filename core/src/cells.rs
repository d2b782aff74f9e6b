//! The cells of a volumetric billboard (VB paper §3.1, Figure 2 left): a box as two
//! triangular prisms.
//!
//! Prism vertices: 0, 1, 2 the bottom triangle, 3, 4, 5 the top one, vertex `k + 3` above
//! vertex `k` (the "vertical" edges (0,3), (1,4), (2,5) of the paper's Figure 6). For a box,
//! the extrusion axis is +Y (billow's up): bottom triangles lie in the `y = min.y` face, top
//! ones in `y = max.y`, and both bottom triangles wind counter-clockwise seen from above
//! (`(p1 − p0) × (p2 − p0)` points +Y). They split the xz rectangle along its
//! `(min.x, min.z)`–`(max.x, max.z)` diagonal. `uvw = (p − min) / (max − min)`, so the
//! volume's texture coordinates span [0, 1]³ over the box.
//!
//! Used by the voxelizer, the empty-space pass and the procedural volumes.

use glam::Vec3;

/// One prism-shaped cell (the asset format's type): positions and 3D texture coordinates
/// of its six vertices.
pub use billow_format::Prism;

/// The box `[min, max]` as two prisms (see the module docs).
pub fn box_prisms(min: Vec3, max: Vec3) -> [Prism; 2] {
    // Corners of the bottom face in (x, z), as uvw on the unit square.
    let (a, b, c, d) = ([0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]);
    let prism = |tri: [[f32; 2]; 3]| {
        let mut uvw = [[0.0; 3]; 6];
        for k in 0..3 {
            uvw[k] = [tri[k][0], 0.0, tri[k][1]];
            uvw[k + 3] = [tri[k][0], 1.0, tri[k][1]];
        }
        let pos = uvw.map(|t| (min + (max - min) * Vec3::from_array(t)).to_array());
        Prism { pos, uvw }
    };
    // (x, z) counter-clockwise seen from +Y: a → c → b and a → d → c.
    [prism([a, c, b]), prism([a, d, c])]
}
