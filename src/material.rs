//! What one fragment looks like: glTF metallic-roughness base colour and alpha mode.
//!
//! `colour = base_color_factor × texture(uv) × vertex colour` (linear, straight alpha), then
//! - `Opaque`: alpha = 1;
//! - `Mask { cutoff }`: alpha ≥ cutoff → alpha = 1, otherwise discarded (tested per
//!   coverage sample by the rasterizer, [`Shader::mask_pass`]);
//! - `Blend`: alpha as computed;
//!
//! and the result is premultiplied. Textures are sampled bilinearly with
//! [`Texture::sample_bilinear`] (glTF UVs, wrap modes, sRGB → linear, colour filtered
//! weighted by alpha so transparent texels do not bleed).

use glam::{Vec2, Vec3, Vec4};

use crate::scene::{AlphaMode, Material, Scene, Texture};
use crate::texture::{
    filter_taps, finite_or_zero, floor_fast as floor, srgb_to_linear_lut, wrap_index as wrap,
};

/// Validated view of a scene's materials and textures.
pub(crate) struct Shader<'a> {
    materials: &'a [Material],
    textures: &'a [Texture],
    /// Per texture, its alpha bytes alone when a `Mask` material uses it: the alpha test
    /// reads a quarter of the memory the RGBA texels take (the test is per coverage
    /// sample, and its texel fetches are what it waits on).
    alphas: Vec<Option<Vec<u8>>>,
    /// sRGB byte → linear ([`srgb_to_linear_lut`], fetched once).
    lut: &'static [f32; 256],
}

/// Checks every index and size the voxelizer relies on.
pub(crate) fn validate_scene(scene: &Scene) -> Result<(), String> {
    for (i, t) in scene.textures.iter().enumerate() {
        if t.width == 0 || t.height == 0 || t.texels.len() != t.width as usize * t.height as usize {
            return Err(format!(
                "texture {i} ('{}'): {}x{} but {} texels",
                t.name,
                t.width,
                t.height,
                t.texels.len()
            ));
        }
    }
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(t) = m.base_color_texture {
            if t as usize >= scene.textures.len() {
                return Err(format!(
                    "material {i} ('{}') refers to missing texture {t}",
                    m.name
                ));
            }
        }
    }
    for (i, t) in scene.triangles.iter().enumerate() {
        if t.material as usize >= scene.materials.len() {
            return Err(format!(
                "triangle {i} refers to missing material {}",
                t.material
            ));
        }
    }
    Ok(())
}

impl<'a> Shader<'a> {
    /// The scene must have passed [`validate_scene`].
    pub(crate) fn new(scene: &'a Scene) -> Self {
        let masked = |t: usize| {
            scene.materials.iter().any(|m| {
                matches!(m.alpha_mode, AlphaMode::Mask { .. })
                    && m.base_color_texture == Some(t as u32)
            })
        };
        let alphas = (0..scene.textures.len())
            .map(|t| masked(t).then(|| scene.textures[t].texels.iter().map(|p| p[3]).collect()))
            .collect();
        Shader {
            materials: &scene.materials,
            textures: &scene.textures,
            alphas,
            lut: srgb_to_linear_lut(),
        }
    }

    pub(crate) fn material(&self, i: u32) -> &Material {
        &self.materials[i as usize]
    }

    /// Premultiplied linear RGBA of a fragment whose `Mask` alpha test the caller has
    /// already passed ([`Shader::mask_pass`]; `Mask` gives alpha 1 without testing), or
    /// `None` when it is invisible (`Blend` alpha 0, non-finite colour).
    ///
    /// `c = factor × vertex_color × texture.sample_bilinear(uv)` (bit for bit), but
    /// faster: the four texels are fetched once (two wraps per axis instead of eight).
    #[inline(always)]
    pub(crate) fn shade_tested(&self, m: &Material, uv: Vec2, vertex_color: Vec4) -> Option<Vec4> {
        let mut c = m.base_color_factor * vertex_color;
        if let Some(t) = self.texel(m, uv) {
            c *= t;
        }
        Self::finish(m, c)
    }

    /// The base-colour texture of `m` sampled at `uv` (bilinear, linear RGB and straight
    /// alpha: the factor [`Shader::shade_tested`] multiplies in), or `None` without one.
    #[inline(always)]
    pub(crate) fn texel(&self, m: &Material, uv: Vec2) -> Option<Vec4> {
        let t = m.base_color_texture?;
        Some(Taps::new(&self.textures[t as usize], uv).filtered(self.lut))
    }

    /// [`Shader::shade_tested`] with the texture's term given: `texel` stands for the
    /// texture's colour over the fragment (the mean of its samples' [`Shader::texel`]s).
    #[inline(always)]
    pub(crate) fn shade_texel(
        &self,
        m: &Material,
        texel: Vec4,
        vertex_color: Vec4,
    ) -> Option<Vec4> {
        Self::finish(m, m.base_color_factor * vertex_color * texel)
    }

    /// Straight linear `c` (factor × vertex colour × texture) made premultiplied by the
    /// alpha mode, or `None` when invisible.
    #[inline(always)]
    fn finish(m: &Material, c: Vec4) -> Option<Vec4> {
        let rgb = c.truncate().clamp(Vec3::ZERO, Vec3::ONE);
        let a = match m.alpha_mode {
            AlphaMode::Opaque | AlphaMode::Mask { .. } => 1.0,
            AlphaMode::Blend => c.w.clamp(0.0, 1.0),
        };
        if a.is_nan() || a <= 0.0 || !rgb.is_finite() {
            return None;
        }
        Some((rgb * a).extend(a))
    }

    /// The `Mask` alpha test alone (only the texture's alpha channel is read): whether a
    /// point with this `uv` and vertex alpha has `factor.a × vertex alpha × texture alpha
    /// ≥ cutoff` (NaN fails).
    #[inline]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x >= cutoff)` also discards NaN.
    pub(crate) fn mask_pass(&self, m: &Material, cutoff: f32, uv: Vec2, vertex_alpha: f32) -> bool {
        let cw = m.base_color_factor.w * vertex_alpha;
        match m.base_color_texture {
            Some(t) => {
                let tex = &self.textures[t as usize];
                let alpha = match &self.alphas[t as usize] {
                    Some(a) => Taps::alpha_only(tex, |i| a[i], uv),
                    None => Taps::alpha_only(tex, |i| tex.texels[i][3], uv),
                };
                cw * alpha.clamp(0.0, 1.0) >= cutoff
            }
            None => cw >= cutoff,
        }
    }

    /// Straight alpha of a surface point (`factor × vertex colour × texture`, before the
    /// alpha mode), for occlusion tests.
    pub(crate) fn alpha(&self, m: &Material, uv: Vec2, vertex_color: Vec4) -> f32 {
        let c = m.base_color_factor.w * vertex_color.w;
        match m.base_color_texture {
            Some(t) => {
                c * Taps::new(&self.textures[t as usize], uv)
                    .alpha()
                    .clamp(0.0, 1.0)
            }
            None => c,
        }
    }
}

/// The four texels and weights of a bilinear sample, exactly as
/// [`Texture::sample_bilinear`] computes them (see `crate::texture`).
struct Taps {
    texels: [[u8; 4]; 4],
    weights: [f32; 4],
}

/// `a as f32 / 255.0` for every byte (the same values, without the division).
const ALPHA: [f32; 256] = {
    let mut t = [0.0f32; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = i as f32 / 255.0;
        i += 1;
    }
    t
};

impl Taps {
    #[inline(always)]
    fn new(t: &Texture, uv: Vec2) -> Self {
        let x = finite_or_zero(uv.x) as f64 * t.width as f64 - 0.5;
        let y = finite_or_zero(uv.y) as f64 * t.height as f64 - 0.5;
        if x.abs() < 4.0e15 && y.abs() < 4.0e15 {
            // `floor` of both, as integers and floats (exact in this range).
            let (mut xi, mut yi) = (x as i64, y as i64);
            let (mut x0, mut y0) = (xi as f64, yi as f64);
            if x0 > x {
                x0 -= 1.0;
                xi -= 1;
            }
            if y0 > y {
                y0 -= 1.0;
                yi -= 1;
            }
            let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
            let w = t.width as usize;
            // All four taps inside the texture: no wrapping.
            if (xi as u64) < t.width as u64 - 1 && (yi as u64) < t.height as u64 - 1 {
                let base = yi as usize * w + xi as usize;
                let r = &t.texels[base..base + w + 2];
                return Taps {
                    texels: [r[0], r[1], r[w], r[w + 1]],
                    weights: Self::weights(fx, fy),
                };
            }
            return Self::wrapped(t, xi, yi, fx, fy);
        }
        let (x0, y0) = (floor(x), floor(y));
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        Self::wrapped(t, x0 as i64, y0 as i64, fx, fy)
    }

    #[inline]
    fn weights(fx: f32, fy: f32) -> [f32; 4] {
        [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ]
    }

    /// The taps at texel `(x0, y0)` and the next ones, wrapped.
    #[inline(never)]
    fn wrapped(t: &Texture, x0: i64, y0: i64, fx: f32, fy: f32) -> Self {
        let (xa, xb) = (
            wrap(x0, t.width, t.wrap_u),
            wrap(x0.saturating_add(1), t.width, t.wrap_u),
        );
        let (ya, yb) = (
            wrap(y0, t.height, t.wrap_v),
            wrap(y0.saturating_add(1), t.height, t.wrap_v),
        );
        let w = t.width as usize;
        let at = |x: usize, y: usize| t.texels[y * w + x];
        Taps {
            texels: [at(xa, ya), at(xb, ya), at(xa, yb), at(xb, yb)],
            weights: Self::weights(fx, fy),
        }
    }

    /// [`Taps::new`] followed by [`Taps::alpha`] (same value), reading only the alpha bytes
    /// (`alpha(i)` is texel `i`'s).
    #[inline]
    fn alpha_only(t: &Texture, alpha: impl Fn(usize) -> u8, uv: Vec2) -> f32 {
        let x = finite_or_zero(uv.x) as f64 * t.width as f64 - 0.5;
        let y = finite_or_zero(uv.y) as f64 * t.height as f64 - 0.5;
        let (x0, y0) = (floor(x), floor(y));
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let (xa, xb) = (
            wrap(x0, t.width, t.wrap_u),
            wrap(x0.saturating_add(1), t.width, t.wrap_u),
        );
        let (ya, yb) = (
            wrap(y0, t.height, t.wrap_v),
            wrap(y0.saturating_add(1), t.height, t.wrap_v),
        );
        let w = t.width as usize;
        let at = |x: usize, y: usize| ALPHA[alpha(y * w + x) as usize];
        let mut alpha = 0.0f32;
        alpha += at(xa, ya) * ((1.0 - fx) * (1.0 - fy));
        alpha += at(xb, ya) * (fx * (1.0 - fy));
        alpha += at(xa, yb) * ((1.0 - fx) * fy);
        alpha += at(xb, yb) * (fx * fy);
        alpha
    }

    /// Σ alpha·weight (unclamped), in tap order.
    #[inline]
    fn alpha(&self) -> f32 {
        let mut alpha = 0.0f32;
        for (p, w) in self.texels.iter().zip(self.weights) {
            alpha += ALPHA[p[3] as usize] * w;
        }
        alpha
    }

    /// The filtered linear straight RGBA: [`Texture::sample_bilinear`] bit for bit (every
    /// lane of the two sums is the scalar sum of the same terms in the same order, with
    /// alpha in the last lane of the plain sum).
    #[inline(always)]
    fn filtered(&self, lut: &[f32; 256]) -> Vec4 {
        let tap = |i: usize| {
            let p = self.texels[i];
            let c = Vec4::new(
                lut[p[0] as usize],
                lut[p[1] as usize],
                lut[p[2] as usize],
                ALPHA[p[3] as usize],
            );
            (c, self.weights[i])
        };
        filter_taps([tap(0), tap(1), tap(2), tap(3)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Wrap;

    /// The one-pass filter and the alpha-only test are `Texture::sample_bilinear` bit for
    /// bit: random textures with transparent texels, every wrap mode, UVs in and out of
    /// [0, 1].
    #[test]
    fn taps_match_sample_bilinear_bit_for_bit() {
        let mut x = 0x9e37_79b9u32;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        for (wi, wrap) in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat]
            .into_iter()
            .enumerate()
        {
            let (w, h) = (5 + wi as u32 * 3, 7);
            let texels = (0..w * h)
                .map(|_| {
                    let v = next().to_le_bytes();
                    [v[0], v[1], v[2], if v[3] < 80 { 0 } else { v[3] }]
                })
                .collect();
            let t = Texture {
                name: "t".into(),
                width: w,
                height: h,
                texels,
                wrap_u: wrap,
                wrap_v: wrap,
                encoded: None,
            };
            for _ in 0..20_000 {
                let f = |v: u32| (v % 40_000) as f32 / 10_000.0 - 1.5;
                let uv = Vec2::new(f(next()), f(next()));
                let want = t.sample_bilinear(uv);
                let taps = Taps::new(&t, uv);
                assert_eq!(
                    taps.filtered(srgb_to_linear_lut())
                        .to_array()
                        .map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{uv}"
                );
                assert_eq!(taps.alpha().clamp(0.0, 1.0).to_bits(), want.w.to_bits());
                let plane: Vec<u8> = t.texels.iter().map(|p| p[3]).collect();
                for a in [
                    Taps::alpha_only(&t, |i| t.texels[i][3], uv),
                    Taps::alpha_only(&t, |i| plane[i], uv),
                ] {
                    assert_eq!(a.to_bits(), taps.alpha().to_bits());
                }
            }
        }
    }
}
