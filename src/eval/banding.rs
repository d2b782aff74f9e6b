//! Banding: the high-frequency energy an asset adds inside a surface.
//!
//! A closed surface drawn from a volume can show contour bands and herringbone patterns
//! that the mesh does not have (issue 38: block-compression error in the thin shell of
//! partly covered voxels). RMSE counts them with every other error; this measure keeps only
//! what varies over a few pixels. On the display's luma (sRGB-encoded Rec. 709 luma of the
//! premultiplied colour over black, as SSIM sees it), each image minus its Gaussian blur
//! (σ = [`SIGMA`] pixels, normalised over the reference's covered pixels only, so that the
//! background does not bleed in) is the high-pass; its RMS over the **interior** (pixels
//! whose reference is covered over a square of [`ERODE`] pixels each side, so silhouettes,
//! which are high-frequency by nature, are left out) is the image's high-frequency
//! energy. The asset's minus the reference's is what the asset adds: about 0 for an asset
//! that is only smoother than the mesh (it may be negative), 0.015 for the contour bands
//! of a 64-voxel torus compressed in sRGB.

use super::image::linear_to_srgb;
use super::ImageF32;

/// The blur of the high-pass, in pixels.
pub const SIGMA: f32 = 2.0;
/// Pixels of coverage required around an interior pixel (each side).
pub const ERODE: usize = 3;

/// [`banding`]'s result.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Banding {
    /// High-frequency RMS of the reference's and of the asset's luma over the interior.
    pub reference: f64,
    pub asset: f64,
    /// `asset − reference`.
    pub excess: f64,
    /// Interior pixels (0: no interior, and every value 0).
    pub pixels: usize,
}

/// The banding `asset` adds to `reference` (same size; see the module docs).
pub fn banding(reference: &ImageF32, asset: &ImageF32) -> Banding {
    let (w, h) = (reference.width as usize, reference.height as usize);
    let none = Banding {
        reference: 0.0,
        asset: 0.0,
        excess: 0.0,
        pixels: 0,
    };
    if w == 0 || h == 0 || asset.width as usize != w || asset.height as usize != h {
        return none;
    }
    let covered: Vec<bool> = reference.data.iter().map(|p| p.w > 0.5).collect();
    let interior: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            x >= ERODE
                && y >= ERODE
                && x + ERODE < w
                && y + ERODE < h
                && (y - ERODE..=y + ERODE)
                    .all(|yy| (x - ERODE..=x + ERODE).all(|xx| covered[yy * w + xx]))
        })
        .collect();
    let pixels = interior.iter().filter(|&&b| b).count();
    let mask: Vec<f32> = covered.iter().map(|&c| f32::from(u8::from(c))).collect();
    if pixels == 0 {
        return none;
    }
    let rms = |img: &ImageF32| -> f64 {
        let luma: Vec<f32> = img
            .data
            .iter()
            .map(|p| linear_to_srgb((0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z).clamp(0.0, 1.0)))
            .collect();
        let masked: Vec<f32> = (0..w * h)
            .map(|i| if covered[i] { luma[i] } else { 0.0 })
            .collect();
        let (low, weight) = (blur(&masked, w, h), blur(&mask, w, h));
        let sum: f64 = (0..w * h)
            .filter(|&i| interior[i])
            .map(|i| f64::from(luma[i] - low[i] / weight[i]).powi(2))
            .sum();
        (sum / pixels as f64).sqrt()
    };
    let (r, a) = (rms(reference), rms(asset));
    Banding {
        reference: r,
        asset: a,
        excess: a - r,
        pixels,
    }
}

/// A separable Gaussian blur of σ = [`SIGMA`] (radius 3σ), clamped at the edges.
fn blur(v: &[f32], w: usize, h: usize) -> Vec<f32> {
    let r = (3.0 * SIGMA).ceil() as isize;
    let k: Vec<f32> = (-r..=r)
        .map(|d| (-(d * d) as f32 / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    let norm: f32 = k.iter().sum();
    let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                let mut s = 0.0;
                for (j, kw) in k.iter().enumerate() {
                    let d = j as isize - r;
                    let (xx, yy) = if horizontal {
                        ((x + d).clamp(0, w as isize - 1), y)
                    } else {
                        (x, (y + d).clamp(0, h as isize - 1))
                    };
                    s += kw * src[yy as usize * w + xx as usize];
                }
                s / norm
            })
            .collect()
    };
    pass(&pass(v, true), false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> ImageF32 {
        let mut img = ImageF32::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let v = f(x, y);
                img.data[(y * w + x) as usize] = Vec4::new(v, v, v, 1.0);
            }
        }
        img
    }

    #[test]
    fn stripes_add_banding_a_smooth_ramp_does_not() {
        let ramp = image(48, 48, |x, _| 0.2 + 0.5 * x as f32 / 47.0);
        let stripes = image(48, 48, |x, y| {
            0.2 + 0.5 * x as f32 / 47.0 + if (x + y) % 4 < 2 { 0.03 } else { 0.0 }
        });
        let same = banding(&ramp, &ramp);
        assert_eq!(same.excess, 0.0);
        assert!(same.pixels == 42 * 42, "{same:?}");
        let b = banding(&ramp, &stripes);
        assert!(b.excess > 0.01, "{b:?}");
        // The ramp alone has (almost) no high frequencies.
        assert!(b.reference < 1e-3, "{b:?}");
    }

    #[test]
    fn silhouettes_are_not_interior() {
        // A disc over black: all its energy is at the edge, which the erosion leaves out.
        let disc = |r: f32| {
            let mut img = ImageF32::new(40, 40);
            for y in 0..40 {
                for x in 0..40 {
                    let d = ((x as f32 - 19.5).powi(2) + (y as f32 - 19.5).powi(2)).sqrt();
                    if d < r {
                        img.data[y * 40 + x] = Vec4::splat(1.0);
                    }
                }
            }
            img
        };
        let b = banding(&disc(15.0), &disc(15.7));
        assert!(b.pixels > 300 && b.excess.abs() < 1e-3, "{b:?}");
    }
}
