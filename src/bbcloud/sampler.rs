//! A faster bilinear sampler for the billboard bake, bit for bit the same as
//! [`Texture::sample_bilinear`] (tested).
//!
//! The bake samples leaf textures K² times per texel, so the generic sampler's per-tap work
//! (an integer division for the wrap of each of the four taps, a libm `floor`) dominates.
//! Here each axis is wrapped once per sample (two indices per axis, not eight),
//! repeat-wrapped power-of-two sizes wrap with a mask, and `floor` is computed inline. The
//! texels stay 8-bit (a quarter of the memory traffic of decoded floats) and are decoded
//! with the same table; the arithmetic is the generic sampler's, in the same order, so the
//! results are identical.

use glam::{Vec2, Vec4};

use crate::scene::{Texture, Wrap};
use crate::texture::{
    filter_taps, finite_or_zero, floor_fast as floor, srgb_to_linear_lut, wrap_index as wrap,
};

/// A texture prepared for sampling.
pub struct Decoded<'a> {
    width: u32,
    height: u32,
    wrap: [Wrap; 2],
    texels: &'a [[u8; 4]],
    lut: &'static [f32; 256],
}

impl<'a> Decoded<'a> {
    pub fn new(t: &'a Texture) -> Decoded<'a> {
        Decoded {
            width: t.width,
            height: t.height,
            wrap: [t.wrap_u, t.wrap_v],
            texels: &t.texels,
            lut: srgb_to_linear_lut(),
        }
    }

    #[inline(always)]
    fn texel(&self, i: usize) -> Vec4 {
        let p = self.texels[i];
        let l = self.lut;
        Vec4::new(
            l[p[0] as usize],
            l[p[1] as usize],
            l[p[2] as usize],
            p[3] as f32 / 255.0,
        )
    }

    /// Bilinear sample at `uv`, linear straight RGBA (alpha-weighted colour).
    #[inline]
    pub fn sample_bilinear(&self, uv: Vec2) -> Vec4 {
        let x = finite_or_zero(uv.x) as f64 * self.width as f64 - 0.5;
        let y = finite_or_zero(uv.y) as f64 * self.height as f64 - 0.5;
        let (x0, y0) = (floor(x), floor(y));
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let xs = [
            wrap(x0, self.width, self.wrap[0]),
            wrap(x0.saturating_add(1), self.width, self.wrap[0]),
        ];
        let ys = [
            wrap(y0, self.height, self.wrap[1]) * self.width as usize,
            wrap(y0.saturating_add(1), self.height, self.wrap[1]) * self.width as usize,
        ];
        let t = |i: usize, j: usize| self.texel(ys[j] + xs[i]);
        let taps = [
            (t(0, 0), (1.0 - fx) * (1.0 - fy)),
            (t(1, 0), fx * (1.0 - fy)),
            (t(0, 1), (1.0 - fx) * fy),
            (t(1, 1), fx * fy),
        ];
        filter_taps(taps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn same_bits_as_the_generic_sampler() {
        let mut rng = Pcg32::seeded(5, 0);
        for (w, h) in [(8u32, 8u32), (5, 3), (16, 7)] {
            for wrap_u in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
                let texels = (0..w * h)
                    .map(|_| [0; 4].map(|_: u8| (rng.next_u32() & 255) as u8))
                    .collect();
                let t = Texture {
                    name: "t".into(),
                    width: w,
                    height: h,
                    texels,
                    wrap_u,
                    wrap_v: Wrap::Repeat,
                    encoded: None,
                };
                let d = Decoded::new(&t);
                for _ in 0..500 {
                    let uv = Vec2::new(rng.range_f32(-3.0, 3.0), rng.range_f32(-3.0, 3.0));
                    assert_eq!(d.sample_bilinear(uv), t.sample_bilinear(uv), "{uv}");
                }
            }
        }
    }
}
