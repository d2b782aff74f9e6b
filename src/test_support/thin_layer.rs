//! The thin layer of issue 22 ("see-through stripes"), drawn by the CPU slicer's test
//! (tests/eval_thin_layer.rs), the GPU slicer's (viewer/tests/thin_layer.rs) and the
//! measurements of docs/eval.md "Thin layers" (examples/thin_layer_measurements.rs): a
//! 64³ volume in `[0,1]³` whose only non-empty voxels are the layer `y = 32`, cameras at
//! azimuth 30° looking at its centre, and the measure of how much of it is covered.

use glam::Vec3;

use crate::eval::image::linear_to_srgb;
use crate::eval::ImageF32;
use billow_core::camera::Camera;
use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, VolumeAsset};

/// Voxels per side.
pub const N: u32 = 64;
/// The layer's voxel row (y).
pub const LAYER: u32 = 32;
/// Image side, pixels.
pub const SIZE: u32 = 128;
/// The layer's linear colour.
pub const COLOR: [f32; 3] = [0.3, 0.6, 0.2];
/// Least mean alpha over the layer's pixels.
pub const AREA_TOL: f64 = 0.98;
/// Least mean alpha of any row with 8 or more of the layer's pixels.
pub const ROW_TOL: f64 = 0.95;
/// Camera distances: pixels smaller than a voxel (slices at `v₀`, MIP level 0), and MIP
/// level ≈ 1.
pub const NEAR: f32 = 1.8;
pub const FAR: f32 = 4.5;

/// How the MIP levels of the layer are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chain {
    /// α = 1 at every level (`opaque`/`max` combine).
    Opaque,
    /// The `mean` combine of six directions when all six see the layer opaque at level 0:
    /// composited along y (α 1), averaged across it by the four side directions
    /// (α 2^−l), `α_l = (2 + 4·2^−l)/6`.
    Mean,
}

/// The layer volume with its MIP chain made as `chain` says (sRGB premultiplied, one box
/// of two prisms over `[0,1]³`).
pub fn plane_asset(chain: Chain) -> VolumeAsset {
    let dims = [N; 3];
    let mips = full_mip_count(dims);
    let q = |v: f32| (v * 255.0).round() as u8;
    let levels = (0..mips)
        .map(|l| {
            let d = mip_dims(dims, l);
            let a = match chain {
                Chain::Opaque => 1.0,
                Chain::Mean => (2.0 + 4.0 * 0.5f32.powi(l as i32)) / 6.0,
            };
            let texel = [
                q(linear_to_srgb(COLOR[0] * a)),
                q(linear_to_srgb(COLOR[1] * a)),
                q(linear_to_srgb(COLOR[2] * a)),
                q(a),
            ];
            let layer = LAYER >> l;
            let mut v = vec![0u8; (d[0] * d[1] * d[2] * 4) as usize];
            for z in 0..d[2] {
                for x in 0..d[0] {
                    let i = 4 * (x + d[0] * (layer + d[1] * z)) as usize;
                    v[i..i + 4].copy_from_slice(&texel);
                }
            }
            v
        })
        .collect();
    VolumeAsset {
        header: Header::volume(
            "thin layer",
            ColourSpace::SrgbPremultiplied,
            dims,
            mips,
            false,
        ),
        levels,
        normals: None,
        bands: Vec::new(),
        cells: billow_core::cells::box_prisms(Vec3::ZERO, Vec3::ONE).to_vec(),
    }
}

/// The layer's mid-plane.
pub fn layer_y() -> f32 {
    (LAYER as f32 + 0.5) / N as f32
}

/// A [`SIZE`]² camera at azimuth 30°, `elevation_deg` above the layer, `distance` from its
/// centre.
pub fn camera(elevation_deg: f32, distance: f32) -> Camera {
    let (e, az) = (elevation_deg.to_radians(), 30f32.to_radians());
    let target = Vec3::new(0.5, layer_y(), 0.5);
    let dir = Vec3::new(e.cos() * az.sin(), e.sin(), e.cos() * az.cos());
    Camera {
        eye: target + dir * distance,
        target,
        up: Vec3::Y,
        fov_y: std::f32::consts::FRAC_PI_4,
        width: SIZE,
        height: SIZE,
        near: 0.05,
        far: distance + 3.0,
    }
}

/// (mean alpha over the layer's pixels, worst row mean, rows measured), over the pixels
/// whose centre ray meets the layer at least two voxels inside its edges; a row counts
/// with 8 or more such pixels (stripes run along rows: a slice plane meets the layer in a
/// line of constant depth).
pub fn coverage(img: &ImageF32, cam: &Camera) -> (f64, f64, usize) {
    let m = 2.0 / N as f32;
    let (mut sum, mut n) = (0.0f64, 0usize);
    let mut worst = f64::INFINITY;
    let mut rows = 0;
    for y in 0..cam.height {
        let (mut rs, mut rn) = (0.0f64, 0usize);
        for x in 0..cam.width {
            let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            if r.dir.y.abs() < 1e-9 {
                continue;
            }
            let t = (layer_y() - r.origin.y) / r.dir.y;
            let p = r.origin + r.dir * t;
            if t > 0.0 && p.x > m && p.x < 1.0 - m && p.z > m && p.z < 1.0 - m {
                rs += f64::from(img.get(x, y).w);
                rn += 1;
            }
        }
        sum += rs;
        n += rn;
        if rn >= 8 {
            rows += 1;
            worst = worst.min(rs / rn as f64);
        }
    }
    (sum / n.max(1) as f64, worst, rows)
}
