//! Premultiplied linear RGBA f32 images and their PNG output.
//!
//! PNGs are written as 8-bit sRGB with straight alpha (un-premultiplied), over a
//! transparent background, so any viewer shows them correctly; atomically (a temporary
//! file in the destination folder, then a rename), so no partial image is ever left.

use std::path::Path;

use glam::Vec4;

use super::EvalError;

/// Premultiplied linear RGBA, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageF32 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<Vec4>,
}

impl ImageF32 {
    /// A transparent image.
    pub fn new(width: u32, height: u32) -> Self {
        ImageF32 {
            width,
            height,
            data: vec![Vec4::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec4 {
        self.data[y as usize * self.width as usize + x as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, v: Vec4) {
        let w = self.width as usize;
        self.data[y as usize * w + x as usize] = v;
    }

    /// A decoded image as premultiplied linear RGBA: 8- and 16-bit images are taken as
    /// sRGB with straight alpha (what [`ImageF32::write_png`] writes), float images as
    /// linear; alpha is clamped to [0, 1].
    pub fn from_image(img: &image::DynamicImage) -> ImageF32 {
        let float = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let px = img.to_rgba32f();
        let data = px
            .pixels()
            .map(|q| {
                let a = q[3].clamp(0.0, 1.0);
                let c = |v: f32| if float { v } else { srgb_to_linear(v) };
                Vec4::new(c(q[0]) * a, c(q[1]) * a, c(q[2]) * a, a)
            })
            .collect();
        ImageF32 {
            width: px.width(),
            height: px.height(),
            data,
        }
    }

    /// Mean alpha: the fraction of the image covered.
    pub fn coverage(&self) -> f64 {
        if self.data.is_empty() {
            return 0.0;
        }
        self.data.iter().map(|p| f64::from(p.w)).sum::<f64>() / self.data.len() as f64
    }

    /// 8-bit sRGB, straight alpha.
    pub fn to_srgb8(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.data.len() * 4);
        for p in &self.data {
            out.extend_from_slice(&premul_linear_to_srgb8(*p));
        }
        out
    }

    /// Writes the image as an sRGB PNG with straight alpha.
    pub fn write_png(&self, path: &Path) -> Result<(), EvalError> {
        write_png_bytes(path, &self.png_bytes(path)?)
    }

    /// The PNG [`ImageF32::write_png`] writes, in memory (`path` only names it in errors).
    pub fn png_bytes(&self, path: &Path) -> Result<Vec<u8>, EvalError> {
        encode_rgba8(path, self.width, self.height, self.to_srgb8())
    }
}

/// sRGB OETF of a linear value in `[0,1]`.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB EOTF of an encoded value in `[0,1]`.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// One premultiplied linear pixel → straight sRGB bytes.
pub fn premul_linear_to_srgb8(p: Vec4) -> [u8; 4] {
    let a = if p.w.is_finite() {
        p.w.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = |v: f32| (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
    if a <= 0.0 {
        return [0, 0, 0, 0];
    }
    let s = |c: f32| q(linear_to_srgb(if c.is_finite() { c / a } else { 0.0 }));
    [s(p.x), s(p.y), s(p.z), q(a)]
}

fn encode_rgba8(path: &Path, w: u32, h: u32, bytes: Vec<u8>) -> Result<Vec<u8>, EvalError> {
    let img = image::RgbaImage::from_raw(w, h, bytes).ok_or_else(|| EvalError::Encode {
        path: path.to_path_buf(),
        message: "buffer size does not match the image size".into(),
    })?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| EvalError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(png)
}

fn write_png_bytes(path: &Path, png: &[u8]) -> Result<(), EvalError> {
    // Atomic: a temporary file in the destination folder, then a rename.
    billow_format::write_atomic(path, png).map_err(|e| match e {
        billow_format::FormatError::Io { path, source } => EvalError::Io { path, source },
        other => EvalError::Encode {
            path: path.to_path_buf(),
            message: other.to_string(),
        },
    })
}

/// Heatmap colour for `v ∈ [0,1]` (black → blue → red → yellow → white).
fn heat(v: f32) -> [u8; 4] {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let stops = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0],
    ];
    let x = v * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f32;
    let c = |k: usize| ((stops[i][k] * (1.0 - f) + stops[i + 1][k] * f) * 255.0 + 0.5) as u8;
    [c(0), c(1), c(2), 255]
}

/// Writes `reference | test | heatmap(max_channel |test − reference| × gain)` side by
/// side (the first two panels straight-alpha sRGB over transparent, the heatmap opaque).
pub fn write_comparison_png(
    reference: &ImageF32,
    test: &ImageF32,
    gain: f32,
    path: &Path,
) -> Result<(), EvalError> {
    write_comparisons_png(reference, &[test], gain, path)
}

/// Writes `reference | test₁ | heatmap₁ | test₂ | heatmap₂ | …` side by side, each heatmap
/// showing `max_channel |testᵢ − reference| × gain` (black = equal, white ≥ 1/gain).
pub fn write_comparisons_png(
    reference: &ImageF32,
    tests: &[&ImageF32],
    gain: f32,
    path: &Path,
) -> Result<(), EvalError> {
    write_png_bytes(path, &comparisons_png_bytes(reference, tests, gain, path)?)
}

/// The PNG [`write_comparisons_png`] writes, in memory (`path` only names it in errors).
pub fn comparisons_png_bytes(
    reference: &ImageF32,
    tests: &[&ImageF32],
    gain: f32,
    path: &Path,
) -> Result<Vec<u8>, EvalError> {
    for t in tests {
        if reference.width != t.width || reference.height != t.height {
            return Err(EvalError::SizeMismatch {
                a_w: reference.width,
                a_h: reference.height,
                b_w: t.width,
                b_h: t.height,
            });
        }
    }
    let (w, h) = (reference.width as usize, reference.height as usize);
    let panels = 1 + 2 * tests.len();
    let mut out = vec![0u8; panels * w * h * 4];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let r = reference.data[i];
            let row = y * panels * w;
            let mut put = |panel: usize, px: [u8; 4]| {
                let o = (row + panel * w + x) * 4;
                out[o..o + 4].copy_from_slice(&px);
            };
            put(0, premul_linear_to_srgb8(r));
            for (k, t) in tests.iter().enumerate() {
                let t = t.data[i];
                put(1 + 2 * k, premul_linear_to_srgb8(t));
                put(2 + 2 * k, heat((t - r).abs().max_element() * gain));
            }
        }
    }
    encode_rgba8(path, (panels * w) as u32, reference.height, out)
}
