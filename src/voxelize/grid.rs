//! Voxel resolution (`--res N | XxYxZ`) and fitting the voxel grid to the bounds.
//!
//! # Grid conventions
//! - The grid is an axis-aligned box `[min, min + dims × voxel]`, voxel `(i, j, k)` covering
//!   `[min + (i, j, k) × voxel, min + (i + 1, j + 1, k + 1) × voxel)`. Data are stored
//!   x fastest, then y, then z.
//! - **Margin.** When the grid is fitted to the scene's bounds, it gets `margin` voxels
//!   (default ½) of empty space on every side, so that geometry lying on a face of the
//!   bounding box (a ground quad, the tip of a branch) falls inside a voxel instead of on
//!   the grid's boundary, and so a trilinear reconstruction at the edge of the volume
//!   is not clipped. An axis with a single voxel gets no margin (the voxel is the bounds).
//!   Bounds given explicitly ([`VoxelizeOptions::bounds`](super::VoxelizeOptions)) are
//!   used as they are (no margin).
//! - [`Resolution::Longest`]`(n)`: cubic voxels, `n` along the longest axis; every other
//!   axis gets as many voxels as its extent needs (plus margin), at least 1, and its box
//!   is centred on the bounds.
//! - [`Resolution::Exact`]`([x, y, z])`: the box is divided into exactly that many voxels
//!   per axis (voxels may be non-cubic). An axis of zero extent (a flat scene) gets the
//!   largest voxel size of the other axes.

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use billow_core::Aabb;

use super::limits::{check_align, OptionError, MAX_AXIS};

/// How many voxels the volume has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resolution {
    /// `n` voxels along the longest axis of the bounds, cubic voxels.
    Longest(u32),
    /// Exactly `[x, y, z]` voxels.
    Exact([u32; 3]),
}

impl Default for Resolution {
    fn default() -> Self {
        Resolution::Longest(128)
    }
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Resolution::Longest(n) => write!(f, "{n}"),
            Resolution::Exact([x, y, z]) => write!(f, "{x}x{y}x{z}"),
        }
    }
}

/// Why a resolution string or value was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ResolutionError {
    #[error("empty resolution: expected N or XxYxZ (e.g. 128 or 256x128x128)")]
    Empty,
    #[error("resolution '{text}': '{part}' is not a whole number (expected N or XxYxZ, e.g. 128 or 256x128x128)")]
    NotANumber { text: String, part: String },
    #[error("resolution '{text}': expected N or XxYxZ (three sizes), got {parts} parts")]
    WrongArity { text: String, parts: usize },
    #[error("resolution: {} is 0; every axis needs at least 1 voxel", axis_name(*axis))]
    Zero { axis: char },
    #[error("resolution: {} {value} is larger than the maximum of {max} voxels per axis", axis_name(*axis))]
    TooLarge { axis: char, value: u64, max: u32 },
    #[error("resolution '{text}': {} is negative; every axis needs 1 to {MAX_AXIS} voxels", axis_name(*axis))]
    Negative { text: String, axis: char },
}

/// `x size`, …, or `N (the longest axis)` for the single-number form (`axis` 'n').
fn axis_name(axis: char) -> String {
    if axis == 'n' {
        "N (the longest axis)".into()
    } else {
        format!("{axis} size")
    }
}

const AXES: [char; 3] = ['x', 'y', 'z'];

/// Largest empty border around the mesh, in voxels (`VoxelizeOptions::margin`, `--margin`).
pub const MAX_MARGIN: f32 = 16.0;

/// `VoxelizeOptions::align` when the caller gives none: with a [`Resolution::Longest`]
/// `N` and no explicit bounds, the largest of 8, 4, 2, 1 that divides `N`, so that
/// `emptyspace` can prune the output (it needs even sides; 8 lets it brick MIP levels
/// 0–2, and keeps levels 0 and 1 in whole 4×4 blocks for block compression) while the
/// longest axis stays `N`; 1 for an exact size or explicit bounds (the grid as asked).
pub fn default_align(res: &Resolution, explicit_bounds: bool) -> u32 {
    match res {
        Resolution::Longest(n) if !explicit_bounds => 1 << n.trailing_zeros().min(3),
        _ => 1,
    }
}

/// A margin (empty voxels around the bounds) is `0..=`[`MAX_MARGIN`]: the one check, which
/// the grid fit and the CLI's early refusal share.
pub fn check_margin(margin: f32) -> Result<(), GridError> {
    if margin.is_finite() && (0.0..=MAX_MARGIN).contains(&margin) {
        Ok(())
    } else {
        Err(GridError::BadMargin(margin))
    }
}

fn check_axis(axis: char, value: u64) -> Result<u32, ResolutionError> {
    if value == 0 {
        Err(ResolutionError::Zero { axis })
    } else if value > MAX_AXIS as u64 {
        Err(ResolutionError::TooLarge {
            axis,
            value,
            max: MAX_AXIS,
        })
    } else {
        Ok(value as u32)
    }
}

impl Resolution {
    /// Checks every axis is within `1..=MAX_AXIS` (for values built in code).
    pub fn validate(&self) -> Result<(), ResolutionError> {
        match *self {
            Resolution::Longest(n) => check_axis('n', n as u64).map(|_| ()),
            Resolution::Exact(d) => {
                for (a, v) in AXES.iter().zip(d) {
                    check_axis(*a, v as u64)?;
                }
                Ok(())
            }
        }
    }
}

impl FromStr for Resolution {
    type Err = ResolutionError;

    /// `"N"` → [`Resolution::Longest`], `"XxYxZ"` → [`Resolution::Exact`] (`x` or `X`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let text = s.trim();
        if text.is_empty() {
            return Err(ResolutionError::Empty);
        }
        let parts: Vec<&str> = text.split(['x', 'X']).collect();
        let num = |p: &str, axis: char| -> Result<u64, ResolutionError> {
            let p = p.trim();
            // `-5`: a number, out of range (not "not a number").
            if p.len() > 1 && p.starts_with('-') && p[1..].bytes().all(|b| b.is_ascii_digit()) {
                return Err(ResolutionError::Negative {
                    text: text.into(),
                    axis,
                });
            }
            if p.is_empty() || !p.bytes().all(|b| b.is_ascii_digit()) {
                return Err(ResolutionError::NotANumber {
                    text: text.into(),
                    part: p.into(),
                });
            }
            // Saturate absurdly long digit strings: they are "too large", not "not a number".
            Ok(p.parse::<u64>().unwrap_or(u64::MAX))
        };
        match parts.len() {
            1 => Ok(Resolution::Longest(check_axis('n', num(parts[0], 'n')?)?)),
            3 => {
                let mut d = [0u32; 3];
                for i in 0..3 {
                    d[i] = check_axis(AXES[i], num(parts[i], AXES[i])?)?;
                }
                Ok(Resolution::Exact(d))
            }
            n => {
                // "abc" splits into 1 part and is caught above; report non-numbers first.
                for p in &parts {
                    num(p, 'n')?;
                }
                Err(ResolutionError::WrongArity {
                    text: text.into(),
                    parts: n,
                })
            }
        }
    }
}

/// The voxel grid: where the volume lies and how it is divided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Voxels per axis at MIP level 0.
    pub dims: [u32; 3],
    /// Corner of voxel (0, 0, 0).
    pub min: Vec3,
    /// Size of one level-0 voxel per axis.
    pub voxel: Vec3,
}

impl GridSpec {
    pub fn max(&self) -> Vec3 {
        self.min
            + self.voxel
                * Vec3::new(
                    self.dims[0] as f32,
                    self.dims[1] as f32,
                    self.dims[2] as f32,
                )
    }
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.min,
            max: self.max(),
        }
    }
    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }
    /// Dimensions of MIP level `level`: `max(1, d >> level)` per axis.
    pub fn level_dims(&self, level: u32) -> [u32; 3] {
        level_dims(self.dims, level)
    }
    /// Number of levels of the full MIP chain (down to 1×1×1).
    pub fn full_mip_count(&self) -> u32 {
        full_mip_count(self.dims)
    }
}

/// `max(1, d >> level)` per axis (the GPU convention for 3D textures).
pub fn level_dims(dims: [u32; 3], level: u32) -> [u32; 3] {
    dims.map(|d| d.checked_shr(level).unwrap_or(0).max(1))
}

/// `floor(log2(max dim)) + 1`.
pub fn full_mip_count(dims: [u32; 3]) -> u32 {
    let m = dims.iter().copied().max().unwrap_or(1).max(1);
    32 - m.leading_zeros()
}

/// Why a grid could not be fitted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("bounds are empty or not finite ({min:?} .. {max:?})")]
    BadBounds { min: [f32; 3], max: [f32; 3] },
    #[error("margin {0} is out of range (0 to {MAX_MARGIN} voxels)")]
    BadMargin(f32),
    #[error(transparent)]
    Resolution(#[from] ResolutionError),
    /// An alignment outside its range ([`check_align`]).
    #[error("{name}: {0}", name = .0.option())]
    BadAlign(#[from] OptionError),
    #[error("aligning {dims:?} to multiples of {align} exceeds {MAX_AXIS} voxels per axis")]
    AlignTooLarge { dims: [u32; 3], align: u32 },
}

/// Rounds every side of `g` up to a multiple of `align` voxels, keeping the voxel size and
/// the box centre (the added voxels are split evenly between both ends, the odd one at the
/// max end). `align = 1` returns `g` unchanged. With `align = 2^k` every MIP level `< k`
/// halves exactly, which `billow emptyspace` needs for MIP-exact bricks.
pub fn align_grid(g: &GridSpec, align: u32) -> Result<GridSpec, GridError> {
    check_align(align)?;
    if align == 1 {
        return Ok(*g);
    }
    let dims = g.dims.map(|d| d.div_ceil(align) * align);
    if dims.iter().any(|&d| d > MAX_AXIS) {
        return Err(GridError::AlignTooLarge {
            dims: g.dims,
            align,
        });
    }
    let mut min = g.min;
    for a in 0..3 {
        let extra = dims[a] - g.dims[a];
        min[a] = (f64::from(g.min[a]) - f64::from(extra / 2) * f64::from(g.voxel[a])) as f32;
    }
    Ok(GridSpec {
        dims,
        min,
        voxel: g.voxel,
    })
}

/// Fits a grid of resolution `res` around `bounds` with `margin` voxels of empty space on
/// every side (see the module docs).
pub fn fit_grid(bounds: &Aabb, res: Resolution, margin: f32) -> Result<GridSpec, GridError> {
    let bad = || GridError::BadBounds {
        min: bounds.min.to_array(),
        max: bounds.max.to_array(),
    };
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        return Err(bad());
    }
    check_margin(margin)?;
    res.validate()?;
    let ext = bounds.size().to_array().map(|e| e as f64);
    let longest = ext.iter().copied().fold(0.0, f64::max);
    if !longest.is_finite() || longest <= 0.0 {
        return Err(bad());
    }
    // Extents below this count as flat.
    let tiny = longest * 1e-6;
    let m = margin as f64;
    let (dims, voxel) = match res {
        Resolution::Longest(n) => {
            let s = longest / (n as f64 - 2.0 * m).max(1.0);
            let mut dims = [1u32; 3];
            for a in 0..3 {
                let need = (ext[a] / s + 2.0 * m - 1e-4).ceil();
                dims[a] = (need as u32).clamp(1, n);
            }
            (dims, [s; 3])
        }
        Resolution::Exact(d) => {
            let mut voxel = [0.0f64; 3];
            for a in 0..3 {
                if ext[a] > tiny {
                    voxel[a] = ext[a] / (d[a] as f64 - 2.0 * m).max(1.0);
                }
            }
            let fallback = voxel.iter().copied().fold(0.0, f64::max);
            for v in &mut voxel {
                if *v == 0.0 {
                    *v = fallback;
                }
            }
            (d, voxel)
        }
    };
    let centre = bounds.center().to_array().map(|c| c as f64);
    let min = [0, 1, 2].map(|a| (centre[a] - 0.5 * dims[a] as f64 * voxel[a]) as f32);
    Ok(GridSpec {
        dims,
        min: Vec3::from_array(min),
        voxel: Vec3::from_array(voxel.map(|v| v as f32)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligning_grows_every_side_to_a_multiple_and_keeps_voxels_and_centre() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::new(1.0, 0.8, 0.3),
        };
        let g = fit_grid(&b, Resolution::Longest(64), 0.5).unwrap();
        let a = align_grid(&g, 8).unwrap();
        assert!(a.dims.iter().all(|d| d % 8 == 0), "{:?}", a.dims);
        assert!((0..3).all(|i| a.dims[i] >= g.dims[i] && a.dims[i] < g.dims[i] + 8));
        assert_eq!(a.voxel, g.voxel);
        // The old grid lies inside the new one, on whole voxels.
        for i in 0..3 {
            let shift = (g.min[i] - a.min[i]) / g.voxel[i];
            assert!((shift - shift.round()).abs() < 1e-3 && shift >= 0.0);
            assert!(a.max()[i] >= g.max()[i] - 1e-5);
        }
        assert_eq!(align_grid(&g, 1).unwrap(), g);
        assert!(matches!(
            align_grid(&g, 0),
            Err(GridError::BadAlign(OptionError::Align(0)))
        ));
        let big = GridSpec {
            dims: [MAX_AXIS - 1, 4, 4],
            ..g
        };
        assert!(matches!(
            align_grid(&big, 3),
            Err(GridError::AlignTooLarge { .. })
        ));
    }
}
