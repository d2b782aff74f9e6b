//! Combining the six direction volumes into one (VB paper §3.2, the user function `f` of
//! Figure 3), at every MIP level.
//!
//! Inputs are the six premultiplied linear RGBA values of a voxel in the order
//! `+X, −X, +Y, −Y, +Z, −Z` (`s[0] = px` is what the camera on the +X side saw).
//!
//! Presets (`c` = premultiplied rgb, `a` = alpha, `d` runs over the six directions):
//! - `mean`:  `(Σ_d s_d) / 6` on all four channels (the paper's neutral choice);
//! - `max`:   per-channel `max_d s_d` (keeps thin features; `rgb ≤ a` holds since every
//!   `c_d ≤ a_d ≤ max a`);
//! - `min`:   per-channel `min_d s_d` (only what every direction sees);
//! - `opaque`: `a = max_d a_d`, `c = a · (Σ_d c_d) / (Σ_d a_d)` — the opacity of the most
//!   opaque view with the alpha-weighted mean of the straight colours (for leaves and
//!   other thin elements that should not turn transparent); 0 when every `a_d` is 0.
//! - `expr:...` (see [`super::expr`]) and any [`Combine`] implementation.
//!
//! Every result is clamped to a valid premultiplied value by [`clamp_premultiplied`].
//!
//! Memory: the presets are **streamed** — one direction's pyramid at a time is folded into
//! an f32 accumulator per level (4 floats per voxel, 5 for `opaque`), in the fixed order
//! above, so results do not depend on scheduling. Expressions and custom functions need
//! all six values at once, so the six pyramids are kept, in f16 (8 bytes per voxel per
//! direction).

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::expr::{Expr, ExprError};
use super::mip::{Grid3, Texel};
use super::quantize::encode_rgba8;

/// A voxel combination function. `s` is premultiplied RGBA in the order
/// `+X, −X, +Y, −Y, +Z, −Z`. The result is clamped by [`clamp_premultiplied`].
pub trait Combine: Sync {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4;
}

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

/// The built-in functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    Mean,
    Max,
    Min,
    Opaque,
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Mean => "mean",
            Preset::Max => "max",
            Preset::Min => "min",
            Preset::Opaque => "opaque",
        }
    }
}

impl Combine for Preset {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4 {
        match self {
            Preset::Mean => s.iter().fold(Vec4::ZERO, |a, b| a + *b) / 6.0,
            Preset::Max => s.iter().fold(s[0], |a, b| a.max(*b)),
            Preset::Min => s.iter().fold(s[0], |a, b| a.min(*b)),
            Preset::Opaque => {
                let a = s.iter().fold(0.0f32, |a, b| a.max(b.w));
                let sum = s.iter().fold(Vec4::ZERO, |a, b| a + *b);
                opaque_colour(sum.truncate(), sum.w, a)
            }
        }
    }
}

fn opaque_colour(rgb_sum: Vec3, alpha_sum: f32, alpha_max: f32) -> Vec4 {
    if alpha_sum > 0.0 {
        (rgb_sum * (alpha_max / alpha_sum)).extend(alpha_max)
    } else {
        Vec4::ZERO
    }
}

/// What combines the six volumes.
#[derive(Clone)]
pub enum CombineFn {
    Preset(Preset),
    /// A parsed expression (`--combine 'expr:...'`).
    Expr(Expr),
    /// Any library-provided function.
    Custom(Arc<dyn Combine + Send + Sync>),
}

impl Default for CombineFn {
    fn default() -> Self {
        CombineFn::Preset(Preset::Mean)
    }
}

impl fmt::Debug for CombineFn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CombineFn::Preset(p) => write!(f, "{}", p.name()),
            CombineFn::Expr(e) => write!(f, "expr:{}", e.source()),
            CombineFn::Custom(_) => write!(f, "custom"),
        }
    }
}

impl fmt::Display for CombineFn {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

impl Combine for CombineFn {
    fn combine(&self, s: &[Vec4; 6]) -> Vec4 {
        match self {
            CombineFn::Preset(p) => p.combine(s),
            CombineFn::Expr(e) => e.combine(s),
            CombineFn::Custom(c) => c.combine(s),
        }
    }
}

/// Why a `--combine` argument was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CombineParseError {
    #[error(
        "unknown combine function '{0}': expected mean, max, min, opaque or expr:<expression>"
    )]
    Unknown(String),
    /// Columns are counted in the whole argument (including the `expr:` prefix), from 1.
    #[error("combine expression: {0}")]
    Expr(ExprError),
}

impl FromStr for CombineFn {
    type Err = CombineParseError;
    /// `mean | max | min | opaque | expr:<expression>`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        const PREFIX: &str = "expr:";
        match s.trim() {
            "mean" => Ok(CombineFn::Preset(Preset::Mean)),
            "max" => Ok(CombineFn::Preset(Preset::Max)),
            "min" => Ok(CombineFn::Preset(Preset::Min)),
            "opaque" => Ok(CombineFn::Preset(Preset::Opaque)),
            _ if s.starts_with(PREFIX) => Expr::parse(&s[PREFIX.len()..])
                .map(CombineFn::Expr)
                .map_err(|mut e| {
                    e.column += PREFIX.chars().count();
                    CombineParseError::Expr(e)
                }),
            other => Err(CombineParseError::Unknown(other.into())),
        }
    }
}

/// Streaming accumulator of a preset: one f32 buffer per MIP level, folded one direction at
/// a time in direction order.
pub(crate) struct Accum {
    preset: Preset,
    /// Per level, `width` floats per voxel: 4 (`mean`, `max`, `min`) or 5 (`opaque`:
    /// Σ rgb, Σ a, max a).
    levels: Vec<Vec<f32>>,
    width: usize,
    folded: Vec<u32>,
}

impl Accum {
    pub fn new(preset: Preset, level_sizes: &[usize]) -> Self {
        let width = if preset == Preset::Opaque { 5 } else { 4 };
        Accum {
            preset,
            levels: level_sizes.iter().map(|&n| vec![0.0; n * width]).collect(),
            width,
            folded: vec![0; level_sizes.len()],
        }
    }

    /// Folds one direction's volume of MIP level `level`.
    pub fn fold<T: Texel>(&mut self, level: usize, grid: &Grid3<T>) {
        let (w, preset) = (self.width, self.preset);
        let first = self.folded[level] == 0;
        self.folded[level] += 1;
        const CH: usize = 4096;
        self.levels[level]
            .par_chunks_mut(CH * w)
            .zip(grid.data.par_chunks(CH))
            .for_each(|(acc, src)| {
                for (a, v) in acc.chunks_exact_mut(w).zip(src) {
                    let v = v.load();
                    // Empty voxels change nothing but a running minimum.
                    if v == [0.0; 4] && preset != Preset::Min {
                        continue;
                    }
                    match preset {
                        Preset::Mean => (0..4).for_each(|c| a[c] += v[c]),
                        Preset::Max | Preset::Min if first => a.copy_from_slice(&v),
                        Preset::Max => (0..4).for_each(|c| a[c] = a[c].max(v[c])),
                        Preset::Min => (0..4).for_each(|c| a[c] = a[c].min(v[c])),
                        Preset::Opaque => {
                            (0..4).for_each(|c| a[c] += v[c]);
                            a[4] = a[4].max(v[3]);
                        }
                    }
                }
            });
    }

    /// The combined, clamped level, encoded RGBA8 (see [`super::quantize`]); frees the
    /// level's buffer.
    pub fn finish_level(&mut self, level: usize) -> Vec<u8> {
        let (w, preset) = (self.width, self.preset);
        let acc = std::mem::take(&mut self.levels[level]);
        let mut out = vec![0u8; acc.len() / w * 4];
        const CH: usize = 4096;
        out.par_chunks_mut(4 * CH)
            .zip(acc.par_chunks(w * CH))
            .for_each(|(o, a)| {
                for (o, a) in o.chunks_exact_mut(4).zip(a.chunks_exact(w)) {
                    let v = match preset {
                        Preset::Mean => Vec4::from_slice(a) / 6.0,
                        Preset::Max | Preset::Min => Vec4::from_slice(a),
                        Preset::Opaque => opaque_colour(Vec3::from_slice(a), a[3], a[4]),
                    };
                    o.copy_from_slice(&encode_rgba8(clamp_premultiplied(v)));
                }
            });
        out
    }
}

/// Combines six stored pyramids' level voxel by voxel with any [`Combine`], encoded RGBA8.
pub(crate) fn combine_level<T: Texel>(f: &(dyn Combine + Sync), dirs: [&Grid3<T>; 6]) -> Vec<u8> {
    let n = dirs[0].data.len();
    let mut out = vec![0u8; n * 4];
    const CH: usize = 4096;
    out.par_chunks_mut(4 * CH).enumerate().for_each(|(ci, o)| {
        for (j, o) in o.chunks_exact_mut(4).enumerate() {
            let i = ci * CH + j;
            let s = dirs.map(|g| Vec4::from_array(g.data[i].load()));
            o.copy_from_slice(&encode_rgba8(clamp_premultiplied(f.combine(&s))));
        }
    });
    out
}
