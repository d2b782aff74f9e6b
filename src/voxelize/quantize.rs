//! Final quantization of the combined levels.
//!
//! - Colour (`ColourSpace::SrgbPremultiplied`): `rgb8 = round(255 · srgb_oetf(c))` where `c`
//!   is the **linear premultiplied** rgb (clamped to [0, 1]), `a8 = round(255 · a)` (linear).
//!   A reader decodes rgb with the sRGB EOTF and gets linear premultiplied colour back
//!   (an sRGB 3D texture format does exactly that in hardware).
//! - Normals: snorm8 `round(127 · clamp(n, −1, 1))` per component, stored as
//!   two's-complement bytes `[x, y, z, 0]`; `n` is the shortened (Toksvig) average normal,
//!   so its length encodes the spread and an empty voxel is `[0, 0, 0, 0]`.

use glam::{Vec3, Vec4};

/// The sRGB opto-electronic transfer function (linear → encoded), input clamped to [0, 1].
pub fn srgb_oetf(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) } as f64;
    (if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }) as f32
}

/// The sRGB EOTF (encoded → linear).
pub fn srgb_eotf(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0) as f64;
    (if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }) as f32
}

fn unorm8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Premultiplied linear RGBA → RGBA8 in `SrgbPremultiplied`.
pub fn encode_rgba8(c: Vec4) -> [u8; 4] {
    [
        unorm8(srgb_oetf(c.x)),
        unorm8(srgb_oetf(c.y)),
        unorm8(srgb_oetf(c.z)),
        unorm8(if c.w.is_nan() { 0.0 } else { c.w }),
    ]
}

/// RGBA8 in `SrgbPremultiplied` → premultiplied linear RGBA.
pub fn decode_rgba8(p: [u8; 4]) -> Vec4 {
    let f = |b: u8| b as f32 / 255.0;
    Vec4::new(
        srgb_eotf(f(p[0])),
        srgb_eotf(f(p[1])),
        srgb_eotf(f(p[2])),
        f(p[3]),
    )
}

/// A (shortened) normal → snorm8 `[x, y, z, 0]`.
pub fn encode_normal(n: Vec3) -> [u8; 4] {
    let q =
        |x: f32| ((if x.is_nan() { 0.0 } else { x.clamp(-1.0, 1.0) }) * 127.0).round() as i8 as u8;
    [q(n.x), q(n.y), q(n.z), 0]
}

/// snorm8 bytes → normal (length ≤ ~1).
pub fn decode_normal(p: [u8; 4]) -> Vec3 {
    let f = |b: u8| (b as i8 as f32 / 127.0).max(-1.0);
    Vec3::new(f(p[0]), f(p[1]), f(p[2]))
}
