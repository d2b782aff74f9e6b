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

use crate::scene::{AlphaMode, Material, Scene, Texture, Wrap};
use crate::texture::srgb_to_linear_lut;

/// Validated view of a scene's materials and textures.
pub(crate) struct Shader<'a> {
    materials: &'a [Material],
    textures: &'a [Texture],
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
        Shader {
            materials: &scene.materials,
            textures: &scene.textures,
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
    #[inline]
    pub(crate) fn shade_tested(&self, m: &Material, uv: Vec2, vertex_color: Vec4) -> Option<Vec4> {
        let mut c = m.base_color_factor * vertex_color;
        if let Some(t) = m.base_color_texture {
            let taps = Taps::new(&self.textures[t as usize], uv);
            c *= taps.colour(taps.alpha());
        }
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
                let alpha = Taps::alpha_only(&self.textures[t as usize], uv);
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

fn finite_or_zero(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// `x.floor()` without the libm call in the common range (same value).
#[inline]
fn floor(x: f64) -> f64 {
    if x.abs() < 4.0e15 {
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

/// `wrap_index` of `crate::texture`, with the in-range case first.
#[inline]
fn wrap(i: i64, n: u32, mode: Wrap) -> usize {
    let n = n as i64;
    if (0..n).contains(&i) {
        return i as usize;
    }
    (match mode {
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
    }) as usize
}

impl Taps {
    #[inline]
    fn new(t: &Texture, uv: Vec2) -> Self {
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
        let at = |x: usize, y: usize| t.texels[y * w + x];
        Taps {
            texels: [at(xa, ya), at(xb, ya), at(xa, yb), at(xb, yb)],
            weights: [
                (1.0 - fx) * (1.0 - fy),
                fx * (1.0 - fy),
                (1.0 - fx) * fy,
                fx * fy,
            ],
        }
    }

    /// [`Taps::new`] followed by [`Taps::alpha`] (same value), reading only the alpha bytes.
    #[inline]
    fn alpha_only(t: &Texture, uv: Vec2) -> f32 {
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
        let at = |x: usize, y: usize| t.texels[y * w + x][3] as f32 / 255.0;
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
            alpha += p[3] as f32 / 255.0 * w;
        }
        alpha
    }

    /// The filtered linear straight RGBA, given [`Taps::alpha`].
    #[inline]
    fn colour(&self, alpha: f32) -> Vec4 {
        let lut = srgb_to_linear_lut();
        let mut premul = Vec3::ZERO;
        let mut plain = Vec3::ZERO;
        for (p, w) in self.texels.iter().zip(self.weights) {
            let c = Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]);
            let a = p[3] as f32 / 255.0;
            premul += c * (a * w);
            plain += c * w;
        }
        let rgb = if alpha > 1e-6 { premul / alpha } else { plain };
        rgb.extend(alpha.clamp(0.0, 1.0))
    }
}
