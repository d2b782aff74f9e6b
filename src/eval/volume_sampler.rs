//! Decoding and filtering the colour MIP levels of a [`VolumeAsset`].
//!
//! Texels are decoded once to linear premultiplied RGBA f32 (`SrgbPremultiplied`: the
//! sRGB EOTF on rgb, alpha / 255 — what an `*_SRGB` GPU format does), *then* filtered, so
//! filtering happens in linear premultiplied space. Sampling is trilinear within a level
//! with texel centres at `(i + 0.5)/n`; between levels either nearest level or linear
//! (i.e. quadrilinear, GPU `LINEAR_MIPMAP_LINEAR`).
//!
//! Addressing (formats/SPEC.md §8.5): clamp-to-edge on every axis, except for **shell**
//! assets (header `params` has the key `shell`), which repeat with period 1 in x and z
//! (the surface's tiled UV) and clamp in y (the height) — GPU `REPEAT`/`CLAMP_TO_EDGE`.
//! Wrapping happens per texel index, so a bilinear footprint straddling the tile edge
//! blends the last and the first texel, as a GPU does.
//!
//! **Normals** (SPEC §8.4, when the asset stores them) are decoded to `(α·n̄, α)`: the
//! Toksvig-shortened normal weighted by the texel's opacity (its colour alpha), next to
//! that alpha. Filtered with the same weights as the colour, `xyz / w` of a sample is the
//! alpha-weighted mean of the normals in the footprint, the filter the voxelizer's MIP
//! levels use (`src/voxelize/toksvig.rs`): an empty neighbour does not shorten a surface's
//! normal, unlike filtering `n̄` itself. The viewer uploads the same `(α·n̄, α)` texels
//! (`Rgba16Float`, viewer/src/volume_pass/textures.rs).

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use billow_format::{ColourSpace, VolumeAsset};
use glam::{Vec3, Vec4};

use super::EvalError;
use crate::texture::srgb_to_linear_lut;

/// How the MIP level is filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MipFilter {
    /// Level `round(lod)`.
    Nearest,
    /// Blend levels `floor(lod)` and `floor(lod) + 1` (default).
    Linear,
}

/// One decoded level.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub dims: [u32; 3],
    pub texels: Vec<Vec4>,
}

/// All colour levels, linear premultiplied.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedVolume {
    pub levels: Vec<Level>,
    /// Per axis (x, y, z): repeat addressing (`true`) or clamp-to-edge.
    pub repeat: [bool; 3],
    /// Per level (parallel to `levels`), the normals as `(α·n̄, α)` (module docs); empty
    /// when the asset stores no normals.
    pub normals: Vec<Level>,
    /// `normals` holds the diagonal of the normals' second moment (`(E[n∘n], tr)`,
    /// [`moments_texel`], SPEC §8.4a) instead of their mean: lit two-sided
    /// ([`billow_core::shading::moments_diffuse_factor`]).
    pub moments: bool,
    /// The asset's extra LOD bands (formats/SPEC.md §8.6), decoded; empty for an
    /// ordinary volume. The slicer draws them instead of the base levels on the slices
    /// whose LOD falls in their band.
    pub bands: Vec<DecodedBand>,
}

/// One decoded LOD band: its texture (`volume.bands` empty), level-0 size and cells.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedBand {
    pub first_level: u32,
    pub dims0: [u32; 3],
    pub volume: DecodedVolume,
    pub cells: Vec<billow_format::Prism>,
}

/// The addressing a reader must use for `asset` (SPEC §8.5): repeat in x and z for a
/// shell asset (its `params` contain the key `shell`), clamp everywhere otherwise.
pub fn repeat_axes(asset: &VolumeAsset) -> [bool; 3] {
    let shell = asset.header.is_shell();
    [shell, false, shell]
}

impl DecodedVolume {
    /// Decodes every colour level of `asset` (which must be valid).
    pub fn decode(asset: &VolumeAsset) -> Result<Self, EvalError> {
        asset
            .validate()
            .map_err(|e| EvalError::InvalidAsset(e.to_string()))?;
        let srgb = asset.header.colour_space == ColourSpace::SrgbPremultiplied;
        let repeat = repeat_axes(asset);
        let dims0 = asset.level_dims(0);
        let moments = asset.has_moments();
        let bands: Vec<DecodedBand> = asset
            .bands
            .iter()
            .map(|b| DecodedBand {
                first_level: b.first_level,
                dims0: b.dims,
                volume: Self::decode_levels(
                    &b.levels,
                    (b.normals.as_deref(), moments),
                    b.dims,
                    srgb,
                    repeat,
                ),
                cells: b.cells.clone(),
            })
            .collect();
        Ok(DecodedVolume {
            bands,
            moments,
            ..Self::decode_levels(
                &asset.levels,
                (asset.normals.as_deref(), moments),
                dims0,
                srgb,
                repeat,
            )
        })
    }

    fn decode_levels(
        levels: &[Vec<u8>],
        (normals, moments): (Option<&[Vec<u8>]>, bool),
        dims0: [u32; 3],
        srgb: bool,
        repeat: [bool; 3],
    ) -> DecodedVolume {
        let lut = srgb_to_linear_lut();
        let levels = levels
            .iter()
            .enumerate()
            .map(|(i, bytes)| {
                let texels = bytes
                    .chunks_exact(4)
                    .map(|t| {
                        let c = |v: u8| {
                            if srgb {
                                lut[v as usize]
                            } else {
                                f32::from(v) / 255.0
                            }
                        };
                        Vec4::new(c(t[0]), c(t[1]), c(t[2]), f32::from(t[3]) / 255.0)
                    })
                    .collect();
                Level {
                    dims: billow_format::mip_dims(dims0, i as u32),
                    texels,
                }
            })
            .collect::<Vec<Level>>();
        let normals = normals
            .map(|nl| {
                nl.iter()
                    .zip(&levels)
                    .map(|(bytes, l)| Level {
                        dims: l.dims,
                        texels: bytes
                            .chunks_exact(4)
                            .zip(&l.texels)
                            .map(|(t, c)| {
                                let t = [t[0], t[1], t[2], t[3]];
                                if moments {
                                    moments_texel(t)
                                } else {
                                    normal_texel(t, c.w)
                                }
                            })
                            .collect(),
                    })
                    .collect()
            })
            .unwrap_or_default();
        DecodedVolume {
            levels,
            normals,
            moments,
            repeat,
            bands: Vec::new(),
        }
    }

    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Whether the volume stores normals (and is shaded at runtime).
    pub fn has_normals(&self) -> bool {
        !self.normals.is_empty()
    }

    /// Trilinear sample of level `level` (clamped to the last level) at `uvw`.
    pub fn sample_level(&self, level: usize, uvw: Vec3) -> Vec4 {
        self.trilinear(&self.levels, level, uvw)
    }

    fn trilinear(&self, levels: &[Level], level: usize, uvw: Vec3) -> Vec4 {
        let l = &levels[level.min(levels.len() - 1)];
        let [w, h, d] = l.dims.map(|v| v as i64);
        let (x0, x1, tx) = texel_pair(uvw.x, w, self.repeat[0]);
        let (y0, y1, ty) = texel_pair(uvw.y, h, self.repeat[1]);
        let (z0, z1, tz) = texel_pair(uvw.z, d, self.repeat[2]);
        let (w, h) = (w as usize, h as usize);
        let at = |x: usize, y: usize, z: usize| l.texels[x + w * (y + h * z)];
        let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), tx);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), tx);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), tx);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), tx);
        lerp(lerp(c00, c10, ty), lerp(c01, c11, ty), tz)
    }

    /// Trilinear sample of level `level` (clamped to the last level) at `uvw`, filtered
    /// in **extinction space** (see [`billow_core::extinction::to_extinction`]): the result is `(σ·c, σ)`, the
    /// weighted sum of the eight texels' extinction-weighted straight colours.
    pub fn sample_level_extinction(&self, level: usize, uvw: Vec3) -> Vec4 {
        self.sample_level_extinction_capped(level, uvw, MAX_OPTICAL_DEPTH)
    }

    /// [`DecodedVolume::sample_level_extinction`] with opaque texels given the optical
    /// depth `cap` ([`to_extinction_capped`]).
    pub fn sample_level_extinction_capped(&self, level: usize, uvw: Vec3, cap: f32) -> Vec4 {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        let [w, h, d] = l.dims.map(|v| v as i64);
        let (x0, x1, tx) = texel_pair(uvw.x, w, self.repeat[0]);
        let (y0, y1, ty) = texel_pair(uvw.y, h, self.repeat[1]);
        let (z0, z1, tz) = texel_pair(uvw.z, d, self.repeat[2]);
        let (w, h) = (w as usize, h as usize);
        let at =
            |x: usize, y: usize, z: usize| to_extinction_capped(l.texels[x + w * (y + h * z)], cap);
        let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
        let c00 = lerp(at(x0, y0, z0), at(x1, y0, z0), tx);
        let c10 = lerp(at(x0, y1, z0), at(x1, y1, z0), tx);
        let c01 = lerp(at(x0, y0, z1), at(x1, y0, z1), tx);
        let c11 = lerp(at(x0, y1, z1), at(x1, y1, z1), tx);
        lerp(lerp(c00, c10, ty), lerp(c01, c11, ty), tz)
    }

    /// The sample the slicer composites: like [`DecodedVolume::sample`] but filtered in
    /// extinction space (trilinear within a level and linear between levels on
    /// [`billow_core::extinction::to_extinction`] values), returned as premultiplied RGBA ([`billow_core::extinction::from_extinction`]).
    pub fn sample_opacity(&self, lod: f32, uvw: Vec3, filter: MipFilter) -> Vec4 {
        let max = (self.levels.len() - 1) as f32;
        let lod = if lod.is_finite() {
            lod.clamp(0.0, max)
        } else {
            0.0
        };
        let e = match filter {
            MipFilter::Nearest => self.sample_level_extinction(lod.round() as usize, uvw),
            MipFilter::Linear => {
                let l0 = lod.floor();
                let t = lod - l0;
                let a = self.sample_level_extinction(l0 as usize, uvw);
                if t <= 0.0 {
                    a
                } else {
                    let b = self.sample_level_extinction(l0 as usize + 1, uvw);
                    a + (b - a) * t
                }
            }
        };
        from_extinction(e)
    }

    /// The sample a slice composites with its opacity correction folded in: the levels'
    /// extinction-space samples ([`DecodedVolume::sample_level_extinction_capped`], an
    /// opaque texel given `cap`) weighted by `weights` (`(level, slab thickness / that
    /// level's texel thickness, cap)`, from [`billow_core::slicing::level_weights`] and
    /// [`billow_core::slicing::opaque_optical_depth`]) and summed, `α = 1 − e^(−Σ wᵢ σᵢ)`,
    /// colour the weighted straight colour times `α` (premultiplied). Exactly 1 where every
    /// texel under the filter is opaque (as [`billow_core::extinction::from_extinction`]):
    /// [`billow_core::extinction::slab_sample`] of the sum.
    pub fn sample_weighted(&self, weights: [(usize, f32, f32); 2], uvw: Vec3) -> Vec4 {
        let mut e = Vec4::ZERO;
        let mut total = 0.0f32;
        for (l, w, cap) in weights {
            if w > 0.0 {
                e += self.sample_level_extinction_capped(l, uvw, cap) * w;
                total += w * (cap - 1e-4);
            }
        }
        slab_sample(e, 1.0, total)
    }

    /// Sample at fractional level `lod` (clamped to the stored levels).
    pub fn sample(&self, lod: f32, uvw: Vec3, filter: MipFilter) -> Vec4 {
        self.filtered(&self.levels, lod, uvw, filter)
    }

    /// The Toksvig normal at `uvw` (fractional level `lod`, filtered like the colour): the
    /// alpha-weighted mean of the texels' shortened normals, `|n̄| ≤ 1` (module docs);
    /// `None` without normals, zero where the footprint is empty.
    pub fn sample_normal(&self, lod: f32, uvw: Vec3, filter: MipFilter) -> Option<Vec3> {
        if self.normals.is_empty() {
            return None;
        }
        Some(normal_from_weighted(self.filtered(
            &self.normals,
            lod,
            uvw,
            filter,
        )))
    }

    fn filtered(&self, levels: &[Level], lod: f32, uvw: Vec3, filter: MipFilter) -> Vec4 {
        let max = (levels.len() - 1) as f32;
        let lod = if lod.is_finite() {
            lod.clamp(0.0, max)
        } else {
            0.0
        };
        match filter {
            MipFilter::Nearest => self.trilinear(levels, lod.round() as usize, uvw),
            MipFilter::Linear => {
                let l0 = lod.floor();
                let t = lod - l0;
                let a = self.trilinear(levels, l0 as usize, uvw);
                if t <= 0.0 {
                    return a;
                }
                let b = self.trilinear(levels, l0 as usize + 1, uvw);
                a + (b - a) * t
            }
        }
    }
}

/// A stored normal texel (snorm8, SPEC §8.4) and its colour alpha → `(α·n̄, α)`.
#[inline]
pub fn normal_texel(snorm: [u8; 4], alpha: f32) -> Vec4 {
    (crate::voxelize::quantize::decode_normal(snorm) * alpha).extend(alpha)
}

/// A normal-moment texel (SPEC §8.4a) as the slicer filters it: `(m, tr m)`, the moments
/// as stored, unweighted, with their trace, so that [`normal_from_weighted`] of a filtered
/// sample is the filtered moments over their filtered trace — what `volume.wgsl`'s
/// `moments_cosine` computes from the stored texels.
pub fn moments_texel(snorm: [u8; 4]) -> Vec4 {
    let m = crate::voxelize::quantize::decode_normal(snorm);
    m.extend(m.x + m.y + m.z)
}

/// A filtered `(α·n̄, α)` sample → the alpha-weighted mean normal (length clamped to 1,
/// zero where `α` is 0): what `volume.wgsl`'s `toksvig_normal` computes.
#[inline]
pub fn normal_from_weighted(s: Vec4) -> Vec3 {
    if s.w.is_nan() || s.w <= 0.0 {
        return Vec3::ZERO;
    }
    let n = s.truncate() / s.w;
    let len = n.length();
    if len > 1.0 {
        n / len
    } else {
        n
    }
}

/// Texel indices and weight of a linear filter along one axis of `n` texels (texel
/// centres at `(i + ½)/n`); repeat wraps per index, clamp-to-edge clamps.
fn texel_pair(u: f32, n: i64, repeat: bool) -> (usize, usize, f32) {
    let u = if u.is_finite() { u } else { 0.0 };
    let u = if repeat { u - u.floor() } else { u };
    let x = u * n as f32 - 0.5;
    let x0 = x.floor();
    let t = x - x0;
    let (i0, i1) = if repeat {
        ((x0 as i64).rem_euclid(n), (x0 as i64 + 1).rem_euclid(n))
    } else {
        ((x0 as i64).clamp(0, n - 1), (x0 as i64 + 1).clamp(0, n - 1))
    };
    (i0 as usize, i1 as usize, t)
}

use billow_core::extinction::{
    from_extinction, slab_sample, to_extinction_capped, MAX_OPTICAL_DEPTH,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×2×4 level whose texel alpha encodes its x index (and z index in blue).
    fn ramp(repeat: [bool; 3]) -> DecodedVolume {
        let dims = [4u32, 2, 4];
        let mut texels = Vec::new();
        for z in 0..4 {
            for y in 0..2 {
                for x in 0..4 {
                    texels.push(Vec4::new(
                        0.0,
                        y as f32 * 0.1,
                        z as f32 * 0.1,
                        x as f32 * 0.1,
                    ));
                }
            }
        }
        DecodedVolume {
            levels: vec![Level { dims, texels }],
            normals: Vec::new(),
            repeat,
            moments: false,
            bands: Vec::new(),
        }
    }

    #[test]
    fn shells_repeat_in_x_and_z_and_clamp_in_y() {
        let v = ramp([true, false, true]);
        // Texel centres: u = (i + 0.5)/4. One period further gives the same value.
        for (u, w) in [(0.125f32, 0.375f32), (0.625, 0.875)] {
            let a = v.sample_level(0, Vec3::new(u, 0.25, w));
            for k in [-3.0f32, -1.0, 1.0, 2.0, 17.0] {
                let b = v.sample_level(0, Vec3::new(u + k, 0.25, w + k));
                assert!(
                    (a - b).abs().max_element() < 1e-5,
                    "u={u} k={k}: {a} vs {b}"
                );
            }
        }
        // At u = 0 the footprint straddles the tile edge: half the last texel (x = 3),
        // half the first (x = 0) — not clamped to the first.
        let e = v.sample_level(0, Vec3::new(0.0, 0.25, 0.125));
        assert!((e.w - 0.15).abs() < 1e-6, "{e}");
        let e = v.sample_level(0, Vec3::new(1.0, 0.25, 0.125));
        assert!((e.w - 0.15).abs() < 1e-6, "{e}");
        // Same in z.
        let e = v.sample_level(0, Vec3::new(0.125, 0.25, 0.0));
        assert!((e.z - 0.15).abs() < 1e-6, "{e}");
        // y clamps: far above the top equals the top row.
        let top = v.sample_level(0, Vec3::new(0.125, 0.75, 0.125));
        let above = v.sample_level(0, Vec3::new(0.125, 1.7, 0.125));
        assert_eq!(top, above);
        assert!((above.y - 0.1).abs() < 1e-6);
    }

    #[test]
    fn other_assets_clamp_everywhere() {
        let v = ramp([false; 3]);
        let e = v.sample_level(0, Vec3::new(0.0, 0.25, 0.125));
        assert!((e.w - 0.0).abs() < 1e-6, "{e}");
        let e = v.sample_level(0, Vec3::new(1.6, 0.25, 0.125));
        assert!((e.w - 0.3).abs() < 1e-6, "{e}");
    }

    #[test]
    fn the_shell_param_selects_repeat() {
        use billow_format::Header;
        let mut asset = VolumeAsset {
            header: Header::volume("test", ColourSpace::SrgbPremultiplied, [1, 1, 1], 1, false),
            levels: vec![vec![0, 0, 0, 0]],
            normals: None,
            bands: Vec::new(),
            cells: vec![],
        };
        assert_eq!(repeat_axes(&asset), [false; 3]);
        asset.header.set_shell("height=0.1");
        assert_eq!(repeat_axes(&asset), [true, false, true]);
    }
}
