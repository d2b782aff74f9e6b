//! Thin layers in the CPU slicer (issue 22, "see-through stripes"): a one-voxel-thick
//! opaque plane seen at 30°, 45° and 60° above it must stay opaque.
//!
//! Setup: a 64³ volume in `[0,1]³` whose only non-empty voxels are the layer `y = 32`
//! (α = 1 at every MIP level, the chain the `opaque`/`max` combine bakes for a plane:
//! composited along y, one voxel thick at every level). The camera looks at the layer's
//! centre from azimuth 30° at a near distance (pixels smaller than a voxel: slices at
//! `v₀`, MIP level 0) and a far one (MIP level ≈ 1). "Covered" is measured over the
//! pixels whose centre ray meets the layer at least two voxels inside its edges: the mean
//! alpha there (the area) must be ≥ 0.98 and the mean alpha of every pixel row with at
//! least 8 such pixels ≥ 0.95 (stripes run along rows: a slice plane meets the layer in a
//! line of constant depth).
//!
//! `thin_layer_measurements` (ignored; `cargo test --test eval_thin_layer -- --ignored
//! --nocapture`) prints the table of docs/eval.md "Thin layers".

use billow::eval::image::linear_to_srgb;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow::eval::volume_sampler::MipFilter;
use billow::eval::ImageF32;
use billow_core::camera::Camera;
use billow_core::slicing::Spacing;
use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, Prism, VolumeAsset};
use glam::Vec3;

const N: u32 = 64;
const LAYER: u32 = 32;
const SIZE: u32 = 128;
const COLOR: [f32; 3] = [0.3, 0.6, 0.2];
const AREA_TOL: f64 = 0.98;
const ROW_TOL: f64 = 0.95;
const NEAR: f32 = 1.8;
const FAR: f32 = 4.5;

fn box_prisms() -> Vec<Prism> {
    let (a, b) = ([0.0f32; 3], [1.0f32; 3]);
    let corner = |i: usize| {
        let c = [[0, 0], [1, 0], [1, 1], [0, 1]][i];
        [c[0] as f32, c[1] as f32]
    };
    let mut out = Vec::new();
    for tri in [[0, 1, 2], [0, 2, 3]] {
        let mut pos = [[0.0f32; 3]; 6];
        let mut uvw = [[0.0f32; 3]; 6];
        for (k, &i) in tri.iter().enumerate() {
            let [u, w] = corner(i);
            for (h, y) in [(0, a[1]), (3, b[1])] {
                pos[k + h] = [a[0] + u * (b[0] - a[0]), y, a[2] + w * (b[2] - a[2])];
                uvw[k + h] = [u, if h == 0 { 0.0 } else { 1.0 }, w];
            }
        }
        out.push(Prism { pos, uvw });
    }
    out
}

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

fn plane_asset(chain: Chain) -> VolumeAsset {
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
        cells: box_prisms(),
    }
}

/// The layer's mid-plane.
fn layer_y() -> f32 {
    (LAYER as f32 + 0.5) / N as f32
}

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

/// (mean alpha over the layer's pixels, worst row mean, rows measured).
fn coverage(img: &ImageF32, cam: &Camera) -> (f64, f64, usize) {
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

fn render(asset: &VolumeAsset, cam: &Camera, params: &SlicerParams) -> ImageF32 {
    render_volume(asset, cam, params).expect("render").image
}

#[test]
fn one_voxel_opaque_plane_is_covered_at_30_45_60_degrees() {
    let asset = plane_asset(Chain::Opaque);
    let mut failures = Vec::new();
    for distance in [NEAR, FAR] {
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let img = render(&asset, &cam, &SlicerParams::default());
            let (area, row, rows) = coverage(&img, &cam);
            println!(
                "distance {distance} elevation {elevation}°: area {area:.4}, worst row {row:.4} ({rows} rows)"
            );
            assert!(rows >= 12, "the layer must cover rows ({rows})");
            if !(area >= AREA_TOL && row >= ROW_TOL) {
                let p = std::env::temp_dir()
                    .join(format!("eval_thin_layer_{distance}_{elevation}.png"));
                img.write_png(&p).expect("png");
                failures.push(format!(
                    "distance {distance}, {elevation}°: area {area:.4} (≥ {AREA_TOL}), worst row {row:.4} (≥ {ROW_TOL}); image {}",
                    p.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The measurements of docs/eval.md "Thin layers": which of slice spacing, adaptive vs
/// uniform spacing, opacity correction and MIP choice makes the stripes.
#[test]
#[ignore]
fn thin_layer_measurements() {
    let v0 = 1.0 / N as f32;
    let opaque = plane_asset(Chain::Opaque);
    let mean = plane_asset(Chain::Mean);
    let cases: Vec<(&str, &VolumeAsset, SlicerParams, f32)> = vec![
        (
            "adaptive ×1 (default), near",
            &opaque,
            SlicerParams::default(),
            NEAR,
        ),
        (
            "adaptive ×½, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.5 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "adaptive ×¼, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.25 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "uniform v₀, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Uniform { spacing: v0 },
                ..Default::default()
            },
            NEAR,
        ),
        (
            "uniform v₀/4, near",
            &opaque,
            SlicerParams {
                spacing: Spacing::Uniform { spacing: v0 / 4.0 },
                ..Default::default()
            },
            NEAR,
        ),
        ("adaptive ×1, far", &opaque, SlicerParams::default(), FAR),
        (
            "adaptive ×1, far, nearest MIP",
            &opaque,
            SlicerParams {
                mip_filter: MipFilter::Nearest,
                ..Default::default()
            },
            FAR,
        ),
        (
            "adaptive ×¼, far",
            &opaque,
            SlicerParams {
                spacing: Spacing::Adaptive { bias: 0.25 },
                ..Default::default()
            },
            FAR,
        ),
        (
            "mean-combine MIPs, near",
            &mean,
            SlicerParams::default(),
            NEAR,
        ),
        (
            "mean-combine MIPs, far",
            &mean,
            SlicerParams::default(),
            FAR,
        ),
    ];
    println!("| case | 30° area / worst row | 45° | 60° |\n|---|---|---|---|");
    for (name, asset, params, distance) in cases {
        let mut line = format!("| {name} |");
        for elevation in [30.0f32, 45.0, 60.0] {
            let cam = camera(elevation, distance);
            let (area, row, _) = coverage(&render(asset, &cam, &params), &cam);
            line += &format!(" {area:.3} / {row:.3} |");
        }
        println!("{line}");
    }
}
