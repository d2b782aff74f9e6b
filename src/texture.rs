//! Texture sampling for [`Texture`]s of the imported [`Scene`](crate::scene::Scene).
//!
//! Texels are stored as authored (RGB sRGB-encoded, alpha linear, straight alpha);
//! the samplers return **linear, straight** RGBA. Conventions:
//! - UV origin at the top-left of the image (glTF), texel `i` has its centre at `(i + 0.5) / w`;
//! - wrap modes per axis (repeat, clamp-to-edge, mirrored repeat);
//! - bilinear filtering weights colour by alpha (i.e. it filters premultiplied colour
//!   and divides back), so fully transparent texels never bleed their colour into
//!   the visible edge of a cut-out.

use std::sync::OnceLock;

use glam::{Vec2, Vec4};

use crate::scene::{Texture, Wrap};

/// Where a renderer's bilinear filter reads a row of `n` texels at `per_texel` regularly
/// spaced points per texel (point `q` at `(q + ½) / per_texel` texels): per point, its
/// two taps `(i0, i1)` clamped to the edge and the weight `t` of `i1`, texel centres at
/// `i + ½`. The coverage models of the bakers (`bbcloud::atlas`, `voxelize::coverage`)
/// sample this way; with a power-of-two `per_texel` every `t` is exact.
pub fn clamp_edge_taps(n: usize, per_texel: usize) -> Vec<(usize, usize, f64)> {
    let last = n as i64 - 1;
    (0..n * per_texel)
        .map(|q| {
            let x = (q as f64 + 0.5) / per_texel as f64 - 0.5;
            let x0 = x.floor();
            let i0 = (x0 as i64).clamp(0, last) as usize;
            let i1 = (x0 as i64 + 1).clamp(0, last) as usize;
            (i0, i1, x - x0)
        })
        .collect()
}

/// sRGB-encoded byte → linear value, a 256-entry table built once.
pub fn srgb_to_linear_lut() -> &'static [f32; 256] {
    static LUT: OnceLock<[f32; 256]> = OnceLock::new();
    LUT.get_or_init(|| {
        let mut t = [0.0; 256];
        for (i, v) in t.iter_mut().enumerate() {
            let c = i as f64 / 255.0;
            *v = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            } as f32;
        }
        t
    })
}

/// Maps an integer texel coordinate into `0..n` according to `wrap`. The in-range case
/// and power-of-two repeat (a mask) are answered first; the value is the same either way.
/// Shared by the generic sampler and the fast ones of the bakers.
#[inline(always)]
pub(crate) fn wrap_index(i: i64, n: u32, wrap: Wrap) -> usize {
    let n = i64::from(n);
    if (0..n).contains(&i) {
        return i as usize;
    }
    if wrap == Wrap::Repeat && (n as u64).is_power_of_two() {
        return (i & (n - 1)) as usize;
    }
    let j = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let k = i.rem_euclid(2 * n);
            if k >= n {
                2 * n - 1 - k
            } else {
                k
            }
        }
    };
    j as usize
}

/// `x.floor()` without a libm call (x86-64's baseline has no rounding instruction): the
/// truncation corrected downwards, exact for |x| < 2⁵²; larger values are integers already.
#[inline(always)]
pub(crate) fn floor_fast(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t > x {
            t - 1.0
        } else {
            t
        }
    } else {
        x.floor()
    }
}

/// Finite or zero: a NaN/Inf coordinate samples texel (0, 0) instead of misbehaving.
#[inline(always)]
pub(crate) fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

impl Texture {
    /// The texel at integer coordinates (wrapped per this texture's wrap modes),
    /// decoded to linear straight RGBA.
    pub fn texel_linear(&self, x: i64, y: i64) -> Vec4 {
        let lut = srgb_to_linear_lut();
        let xi = wrap_index(x, self.width, self.wrap_u);
        let yi = wrap_index(y, self.height, self.wrap_v);
        let p = self.texels[yi * self.width as usize + xi];
        Vec4::new(
            lut[p[0] as usize],
            lut[p[1] as usize],
            lut[p[2] as usize],
            p[3] as f32 / 255.0,
        )
    }

    /// Nearest-texel sample at `uv`, linear straight RGBA.
    pub fn sample_nearest(&self, uv: Vec2) -> Vec4 {
        let x = (finite_or_zero(uv.x) as f64 * self.width as f64).floor() as i64;
        let y = (finite_or_zero(uv.y) as f64 * self.height as f64).floor() as i64;
        self.texel_linear(x, y)
    }

    /// Bilinear sample at `uv`, linear straight RGBA (alpha-weighted colour, see module docs).
    pub fn sample_bilinear(&self, uv: Vec2) -> Vec4 {
        let x = finite_or_zero(uv.x) as f64 * self.width as f64 - 0.5;
        let y = finite_or_zero(uv.y) as f64 * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let taps = [
            (self.texel_linear(x0, y0), (1.0 - fx) * (1.0 - fy)),
            (self.texel_linear(x0.saturating_add(1), y0), fx * (1.0 - fy)),
            (self.texel_linear(x0, y0.saturating_add(1)), (1.0 - fx) * fy),
            (
                self.texel_linear(x0.saturating_add(1), y0.saturating_add(1)),
                fx * fy,
            ),
        ];
        filter_taps(taps)
    }
}

/// The alpha-weighted bilinear filter of four decoded taps `(linear straight RGBA,
/// weight)`: colour weighted by alpha and divided back (plain weights where all is
/// transparent), alpha clamped to [0, 1]. In tap order, so every sampler that calls it
/// gives the same bits.
#[inline(always)]
pub(crate) fn filter_taps(taps: [(Vec4, f32); 4]) -> Vec4 {
    // Four lanes at once (the alpha lane of `premul` is unused; `plain.w` is the alpha);
    // lane by lane the same operations as three colour sums and one alpha sum.
    let mut premul = Vec4::ZERO;
    let mut plain = Vec4::ZERO;
    for (c, w) in taps {
        premul += c * (c.w * w);
        plain += c * w;
    }
    let alpha = plain.w;
    let rgb = if alpha > 1e-6 { premul / alpha } else { plain };
    rgb.truncate().extend(alpha.clamp(0.0, 1.0))
}

/// Linear → sRGB byte thresholds: byte b is the count of thresholds ≤ value, i.e.
/// `round(255 · oetf(c))`, computed exactly and without `powf` per texel.
fn srgb_thresholds() -> &'static [f32; 255] {
    static T: std::sync::OnceLock<[f32; 255]> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        std::array::from_fn(|b| {
            let c = (b as f64 + 0.5) / 255.0;
            (if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }) as f32
        })
    })
}

/// For bucket k of [0, 1] in steps of 1/4096: how many thresholds are ≤ k/4096.
fn srgb_buckets() -> &'static [u8; 4097] {
    static B: std::sync::OnceLock<[u8; 4097]> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        let t = srgb_thresholds();
        std::array::from_fn(|k| t.partition_point(|&x| x <= k as f32 / 4096.0) as u8)
    })
}

/// `round(255 · oetf(c))` for c in [0, 1] (NaN: 0): the number of thresholds ≤ c, found
/// from the bucket of c (which starts at or below c, so it never overcounts) and at most a
/// few steps up (thresholds are at least 1/3300 apart, buckets 1/4096 wide).
#[inline]
pub fn encode_srgb(c: f32) -> u8 {
    let t = srgb_thresholds();
    let mut b = srgb_buckets()[((c * 4095.0) as usize).min(4096)] as usize;
    while b < 255 && t[b] <= c {
        b += 1;
    }
    b as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bucketed_srgb_encoding_is_the_threshold_count() {
        let t = srgb_thresholds();
        let exact = |c: f32| t.partition_point(|&x| x <= c) as u8;
        let mut c = 0.0f32;
        while c <= 1.0 {
            assert_eq!(encode_srgb(c), exact(c), "{c}");
            c = if c < 1e-3 { c + 1e-7 } else { c + 3e-6 };
        }
        for &x in t.iter() {
            for v in [
                x,
                f32::from_bits(x.to_bits() - 1),
                f32::from_bits(x.to_bits() + 1),
            ] {
                assert_eq!(encode_srgb(v), exact(v), "{v}");
            }
        }
        assert_eq!(encode_srgb(1.0), 255);
        assert_eq!(encode_srgb(f32::NAN), 0);
    }

    fn tex(w: u32, h: u32, texels: Vec<[u8; 4]>, wrap: Wrap) -> Texture {
        Texture {
            name: "t".into(),
            width: w,
            height: h,
            texels,
            wrap_u: wrap,
            wrap_v: wrap,
            encoded: None,
        }
    }

    fn close(a: Vec4, b: Vec4) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    #[test]
    fn lut_endpoints_and_midpoint() {
        let lut = srgb_to_linear_lut();
        assert_eq!(lut[0], 0.0);
        assert!((lut[255] - 1.0).abs() < 1e-7);
        assert!((lut[188] - 0.5028865).abs() < 1e-4);
        assert!(lut.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn nearest_texel_centres_and_wrap() {
        // 2x1: black, white.
        let t = tex(
            2,
            1,
            vec![[0, 0, 0, 255], [255, 255, 255, 255]],
            Wrap::Repeat,
        );
        assert!(close(
            t.sample_nearest(Vec2::new(0.25, 0.5)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        ));
        assert!(close(t.sample_nearest(Vec2::new(0.75, 0.5)), Vec4::ONE));
        // Repeat: u = 1.25 → texel 0; -0.25 → texel 1.
        assert!(close(
            t.sample_nearest(Vec2::new(1.25, 0.5)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        ));
        assert!(close(t.sample_nearest(Vec2::new(-0.25, 0.5)), Vec4::ONE));
        let c = tex(2, 1, t.texels.clone(), Wrap::ClampToEdge);
        assert!(close(
            c.sample_nearest(Vec2::new(-3.0, 0.5)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        ));
        assert!(close(c.sample_nearest(Vec2::new(7.0, 0.5)), Vec4::ONE));
        let m = tex(2, 1, t.texels.clone(), Wrap::MirroredRepeat);
        // Mirrored: u in [1,2) maps back: 1.25 → texel 1, 1.75 → texel 0.
        assert!(close(m.sample_nearest(Vec2::new(1.25, 0.5)), Vec4::ONE));
        assert!(close(
            m.sample_nearest(Vec2::new(1.75, 0.5)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        ));
        // NaN does not panic.
        let _ = t.sample_nearest(Vec2::new(f32::NAN, f32::INFINITY));
    }

    #[test]
    fn nearest_decodes_srgb() {
        let t = tex(1, 1, vec![[188, 188, 188, 128]], Wrap::Repeat);
        let s = t.sample_nearest(Vec2::splat(0.5));
        assert!((s.x - 0.5028865).abs() < 1e-4);
        assert!((s.w - 128.0 / 255.0).abs() < 1e-6);
    }

    #[test]
    fn bilinear_interpolates_in_linear_space() {
        let t = tex(
            2,
            1,
            vec![[0, 0, 0, 255], [255, 255, 255, 255]],
            Wrap::ClampToEdge,
        );
        // At texel centres: exact texels.
        assert!(close(
            t.sample_bilinear(Vec2::new(0.25, 0.5)),
            Vec4::new(0.0, 0.0, 0.0, 1.0)
        ));
        assert!(close(t.sample_bilinear(Vec2::new(0.75, 0.5)), Vec4::ONE));
        // Halfway between the centres: linear 0.5 (not sRGB 0.5).
        assert!(close(
            t.sample_bilinear(Vec2::new(0.5, 0.5)),
            Vec4::new(0.5, 0.5, 0.5, 1.0)
        ));
        // Clamp: beyond the last centre stays at the edge texel.
        assert!(close(t.sample_bilinear(Vec2::new(0.95, 0.5)), Vec4::ONE));
        // Repeat: at u = 0 we are halfway between texel 1 (wrapped) and texel 0.
        let r = tex(2, 1, t.texels.clone(), Wrap::Repeat);
        assert!(close(
            r.sample_bilinear(Vec2::new(0.0, 0.5)),
            Vec4::new(0.5, 0.5, 0.5, 1.0)
        ));
    }

    #[test]
    fn bilinear_does_not_bleed_transparent_colour() {
        // Opaque red next to fully transparent green.
        let t = tex(
            2,
            1,
            vec![[255, 0, 0, 255], [0, 255, 0, 0]],
            Wrap::ClampToEdge,
        );
        let s = t.sample_bilinear(Vec2::new(0.5, 0.5));
        assert!(close(s, Vec4::new(1.0, 0.0, 0.0, 0.5)), "{s}");
        // All transparent: plain average colour, alpha 0.
        let z = tex(
            2,
            1,
            vec![[255, 0, 0, 0], [0, 0, 255, 0]],
            Wrap::ClampToEdge,
        );
        let s = z.sample_bilinear(Vec2::new(0.5, 0.5));
        assert!(close(s, Vec4::new(0.5, 0.0, 0.5, 0.0)), "{s}");
    }

    #[test]
    fn bilinear_2d_weights() {
        // 2x2 with alpha 1: values 0, 1 (top), 1, 0 (bottom) in the red channel.
        let t = tex(
            2,
            2,
            vec![
                [0, 0, 0, 255],
                [255, 0, 0, 255],
                [255, 0, 0, 255],
                [0, 0, 0, 255],
            ],
            Wrap::ClampToEdge,
        );
        let s = t.sample_bilinear(Vec2::new(0.5, 0.5));
        assert!((s.x - 0.5).abs() < 1e-6);
        // A quarter of the way from texel (0,0) centre toward (1,1).
        let s = t.sample_bilinear(Vec2::new(0.375, 0.375));
        let expect = 0.75 * 0.25 + 0.25 * 0.75; // (1-fx)fy*1 + fx(1-fy)*1 with fx=fy=0.25
        assert!((s.x - expect).abs() < 1e-6, "{s}");
    }
}
