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

/// Makes any value a valid premultiplied colour: NaN → 0, `0 ≤ a ≤ 1`, `0 ≤ rgb ≤ a`.
pub fn clamp_premultiplied(v: Vec4) -> Vec4 {
    let f = |x: f32| if x.is_nan() { 0.0 } else { x };
    let a = f(v.w).clamp(0.0, 1.0);
    Vec4::new(
        f(v.x).clamp(0.0, a),
        f(v.y).clamp(0.0, a),
        f(v.z).clamp(0.0, a),
        a,
    )
}

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

/// A table-driven [`encode_rgba8`] (same bytes, no `powf`): for every byte value the
/// smallest f32 that encodes to it (found once by bisection over the f32 bit patterns, the
/// encoding being monotonic), and a table indexed by the top 16 bits of the input that
/// gives where to start counting.
pub struct Encoder {
    /// `lower[b]`: the smallest x ≥ 0 with `unorm8(srgb_oetf(x)) ≥ b` (`lower[0] = 0`).
    lower: [f32; 256],
    /// Per `x.to_bits() >> 16` for x in [0, 1]: the byte of the smallest x with those bits.
    start: Vec<u8>,
}

impl Encoder {
    fn new() -> Self {
        let enc = |bits: u32| unorm8(srgb_oetf(f32::from_bits(bits)));
        let one = 1.0f32.to_bits();
        let mut lower = [0.0f32; 256];
        for (b, l) in lower.iter_mut().enumerate().skip(1) {
            // Smallest bit pattern in [0, one] whose encoding is ≥ b.
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if enc(mid) as usize >= b {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *l = f32::from_bits(lo);
        }
        let start = (0..=(one >> 16)).map(|hi| enc(hi << 16)).collect();
        Encoder { lower, start }
    }

    /// The process-wide table.
    pub fn get() -> &'static Encoder {
        static ENC: std::sync::OnceLock<Encoder> = std::sync::OnceLock::new();
        ENC.get_or_init(Encoder::new)
    }

    /// `unorm8(srgb_oetf(x))`.
    #[inline]
    pub fn channel(&self, x: f32) -> u8 {
        // `+ 0.0` turns −0 into +0 (whose bits index the table).
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) } + 0.0;
        let mut b = self.start[(x.to_bits() >> 16) as usize];
        while b < 255 && self.lower[b as usize + 1] <= x {
            b += 1;
        }
        b
    }

    /// Same as [`encode_rgba8`].
    #[inline]
    pub fn rgba8(&self, c: Vec4) -> [u8; 4] {
        [
            self.channel(c.x),
            self.channel(c.y),
            self.channel(c.z),
            unorm8(if c.w.is_nan() { 0.0 } else { c.w }),
        ]
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_encoder_matches_powf_on_every_byte_boundary_and_many_values() {
        let enc = Encoder::get();
        let direct = |x: f32| unorm8(srgb_oetf(x));
        for b in 1..256 {
            let l = enc.lower[b];
            assert_eq!(enc.channel(l), direct(l), "at {l}");
            let below = f32::from_bits(l.to_bits() - 1);
            assert_eq!(enc.channel(below), direct(below), "below {l}");
        }
        let mut x = 0x1234_5678u32;
        for i in 0..200_000u32 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let v = if i % 2 == 0 {
                (x >> 8) as f32 / (1u32 << 24) as f32
            } else {
                f32::from_bits(x)
            };
            assert_eq!(enc.channel(v), direct(v), "{v}");
        }
        for v in [0.0, -0.0, 1.0, 2.0, -1.0, f32::NAN, f32::INFINITY, 1e-30] {
            assert_eq!(enc.channel(v), direct(v), "{v}");
        }
    }
}
