//! Shells: volumetric textures on a surface (VB paper §4 "Volumetric textures",
//! Figures 11–12; in the spirit of shell maps / \[LDS02\]).
//!
//! Every triangle of a surface is extruded along its vertex normals into one prism cell,
//! and the prisms' texture coordinates come from the surface's UVs, so one small tileable
//! volume (e.g. a patch of fur baked from `procgen::fur_tile`, a test generator) is repeated over
//! the whole surface. The rendering algorithm is unchanged: shell prisms are ordinary
//! cells (SPEC §8.5).
//!
//! # Prisms
//!
//! For a surface triangle with vertices `a₀, a₁, a₂` (counter-clockwise seen from its
//! front, the side the normals point to):
//! - bottom: `pos[k] = a_k.position` (k = 0, 1, 2);
//! - top: `pos[k + 3] = a_k.position + height · n_k`, where `n_k` is the vertex's *smooth*
//!   unit normal: the angle-weighted average of the (normalised) vertex normals of every
//!   triangle corner at exactly the same position (bit-identical coordinates), so
//!   neighbouring prisms share their top vertices even where the surface is flat-shaded
//!   and the shell has no cracks. A vertex normal that is missing (zero, non-finite) or
//!   points behind the triangle (`n · face normal ≤ 0`) is replaced by the triangle's
//!   face normal for that corner (counted in [`Shell::replaced_normals`]).
//!
//! Winding follows SPEC §8.5: `(pos1 − pos0) × (pos2 − pos0)` is the front face normal,
//! pointing from the bottom towards the top. Tops are exactly `height` from their bottom
//! vertex; the shell is the region between the surface and that offset surface.
//!
//! # Texture coordinates (the uvw → volume-axis mapping)
//!
//! Volumes are **Y-up**, like the box cells of `voxelize` ([`billow_core::cells::box_prisms`],
//! extruded along +Y) and like `procgen::fur_tile` (strands rooted in the unit
//! square of the x–z plane, growing along +Y to height 1). So a shell maps the surface's UV
//! to the volume's **x and z** and the height fraction to **y**:
//!
//! `uvw[k] = (s_u · u_k, 0, s_v · v_k)` at the bottom, `uvw[k + 3] = (s_u · u_k, 1, s_v · v_k)`
//! at the top,
//!
//! where `(s_u, s_v)` = `uv_scale`, the number of volume tiles per unit of UV. The stored
//! triple is a point of the volume texture in `[0,1]³` coordinates along (x, y, z), as for
//! every cell: texture x = surface u, texture y = height above the surface, texture z =
//! surface v. With glTF's UV convention (v grows downwards on the image, which is also
//! billow's [`crate::scene`] convention) a surface whose UV layout is not mirrored maps the
//! tile without mirroring (the surface's tangent `∂p/∂u` goes to +x, `∂p/∂v` to +z, the
//! normal to +y, and z × x = y); triangles whose UV layout is mirrored are counted in
//! [`Shell::mirrored`].
//!
//! **Tiling**: x and z coordinates outside `[0, 1]` mean the volume *repeats* (repeat /
//! wrap addressing in x and z); y stays in `[0, 1]` (clamp-to-edge). The volume must be
//! baked tileable, i.e. with its grid bounds exactly the tile (for `fur_tile`: the box
//! `(0,0,0)–(1,1,1)`, `voxelize` option `bounds`), so that texel `n − 1` continues into
//! texel 0. [`shell_asset`] marks the asset with the header parameter `"shell"`, which
//! is what tells a reader to use repeat addressing (SPEC §8.5).
//!
//! # Degenerate input
//!
//! Triangles with zero area or a non-finite position, normal or UV are **skipped and
//! counted** ([`Shell::skipped`]); a height or UV scale that is zero, negative or not
//! finite is an error, and so is a surface that leaves no prism. Triangles with a zero-area
//! UV layout are kept (their texture is smeared along a line) and counted in
//! [`Shell::uv_degenerate`]; prisms whose top triangle turns over because `height` exceeds
//! the surface's local radius of curvature on a concave part are kept and counted in
//! [`Shell::folded`].

use std::collections::HashMap;

use billow_format::{Bounds, Prism, VolumeAsset};
use glam::{Vec2, Vec3};

use crate::scene::{Scene, Triangle};

/// Why no shell could be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ShellError {
    #[error("shell height must be a positive finite number, got {0}")]
    InvalidHeight(f32),
    #[error("shell UV scale must be positive and finite on both axes, got ({}, {})", .0.x, .0.y)]
    InvalidUvScale(Vec2),
    #[error("nothing to bake: the surface has no triangles to build a shell on")]
    EmptySurface,
    #[error(
        "no usable triangle in the surface: all {skipped} are degenerate (zero area or non-finite)"
    )]
    NoPrisms { skipped: usize },
}

/// A shell: its prisms and what happened building them.
#[derive(Clone, Debug, PartialEq)]
pub struct Shell {
    /// One prism per usable surface triangle, in the surface's triangle order.
    pub prisms: Vec<Prism>,
    /// World-space bounds of all prism vertices.
    pub bounds: Bounds,
    pub height: f32,
    pub uv_scale: Vec2,
    /// Surface triangles skipped as degenerate (zero area, non-finite data).
    pub skipped: usize,
    /// Triangle corners whose normal was unusable and replaced by the face normal.
    pub replaced_normals: usize,
    /// Prisms whose UV layout is mirrored (the tile appears mirrored on them).
    pub mirrored: usize,
    /// Prisms whose UV triangle has zero area.
    pub uv_degenerate: usize,
    /// Prisms whose top triangle faces the other way from the bottom one.
    pub folded: usize,
}

impl Shell {
    /// The value [`shell_asset`] stores under the header parameter `"shell"`, e.g.
    /// `"height=0.1 uv_scale=6x2 prisms=2304 skipped=0"`.
    pub fn describe(&self) -> String {
        format!(
            "height={} uv_scale={}x{} prisms={} skipped={}",
            self.height,
            self.uv_scale.x,
            self.uv_scale.y,
            self.prisms.len(),
            self.skipped
        )
    }
}

/// The shell prisms of `surface` (see the module docs). Shorthand for [`shell`]`(..).prisms`.
pub fn shell_prisms(
    surface: &Scene,
    height: f32,
    uv_scale: Vec2,
) -> Result<Vec<Prism>, ShellError> {
    shell(surface, height, uv_scale).map(|s| s.prisms)
}

/// Builds the shell of `surface`: one prism per usable triangle, `height` thick, with
/// `uv_scale` volume tiles per unit of UV (see the module docs for every convention).
pub fn shell(surface: &Scene, height: f32, uv_scale: Vec2) -> Result<Shell, ShellError> {
    if !(height.is_finite() && height > 0.0) {
        return Err(ShellError::InvalidHeight(height));
    }
    if !(uv_scale.is_finite() && uv_scale.x > 0.0 && uv_scale.y > 0.0) {
        return Err(ShellError::InvalidUvScale(uv_scale));
    }
    if surface.triangles.is_empty() {
        return Err(ShellError::EmptySurface);
    }
    let usable: Vec<&Triangle> = surface.triangles.iter().filter(|t| usable(t)).collect();
    let skipped = surface.triangles.len() - usable.len();
    if usable.is_empty() {
        return Err(ShellError::NoPrisms { skipped });
    }

    // Smooth normals: angle-weighted sum of corner normals per exact position.
    let mut replaced_normals = 0;
    let mut corner_normals = Vec::with_capacity(usable.len());
    let mut sums: HashMap<[u32; 3], Vec3> = HashMap::new();
    for t in &usable {
        let face = t.cross().normalize();
        let ns: [Vec3; 3] = std::array::from_fn(|k| {
            let n = t.v[k].normal.normalize_or_zero();
            let n = if n.dot(face) > 0.0 {
                n
            } else {
                replaced_normals += 1;
                face
            };
            *sums.entry(key(t.v[k].position)).or_insert(Vec3::ZERO) += n * corner_angle(t, k);
            n
        });
        corner_normals.push((face, ns));
    }

    let mut out = Shell {
        prisms: Vec::with_capacity(usable.len()),
        bounds: Bounds {
            min: [f32::INFINITY; 3],
            max: [f32::NEG_INFINITY; 3],
        },
        height,
        uv_scale,
        skipped,
        replaced_normals,
        mirrored: 0,
        uv_degenerate: 0,
        folded: 0,
    };
    for (t, (face, ns)) in usable.iter().zip(corner_normals) {
        let mut pos = [[0.0; 3]; 6];
        let mut uvw = [[0.0; 3]; 6];
        for k in 0..3 {
            let p = t.v[k].position;
            // The smooth normal, unless it points behind this triangle (sharp crease).
            let smooth = sums[&key(p)].normalize_or_zero();
            let n = if smooth.dot(face) > 0.0 {
                smooth
            } else {
                ns[k]
            };
            pos[k] = p.to_array();
            pos[k + 3] = (p + n * height).to_array();
            let uv = t.v[k].uv * uv_scale;
            uvw[k] = [uv.x, 0.0, uv.y];
            uvw[k + 3] = [uv.x, 1.0, uv.y];
        }
        // Texture-space orientation seen from +y: (dx1·dz2 − dz1·dx2) < 0 is counter-clockwise.
        let (d1, d2) = (t.v[1].uv - t.v[0].uv, t.v[2].uv - t.v[0].uv);
        let uv_cross = d1.x * d2.y - d1.y * d2.x;
        if uv_cross == 0.0 {
            out.uv_degenerate += 1;
        } else if uv_cross > 0.0 {
            out.mirrored += 1;
        }
        let top = |k: usize| Vec3::from(pos[k + 3]);
        if (top(1) - top(0)).cross(top(2) - top(0)).dot(face) <= 0.0 {
            out.folded += 1;
        }
        out.prisms.push(Prism { pos, uvw });
    }
    out.bounds = prism_bounds(&out.prisms).expect("at least one prism");
    Ok(out)
}

/// `volume` with its cells replaced by the shell's prisms, the header bounds set to
/// `shell.bounds`, and the header parameter `"shell"` set to [`Shell::describe`] (which
/// also marks the asset as tiled: repeat addressing in x and z, SPEC §8.5). The texels,
/// normals, colour space, source and other parameters are the volume's.
pub fn shell_asset(volume: &VolumeAsset, shell: Shell) -> VolumeAsset {
    let mut header = volume.header.clone();
    header.bounds = shell.bounds;
    header.set_shell(shell.describe());
    VolumeAsset {
        header,
        levels: volume.levels.clone(),
        normals: volume.normals.clone(),
        bands: Vec::new(),
        cells: shell.prisms,
    }
}

/// Gives a shell asset the **surface's normal** as its stored normal (VB §3.2: "we might
/// approximate the lighting as a separable low-frequency and high-frequency lighting,
/// precalculating the local high-frequency lighting and storing a low-frequency normal for
/// runtime shading"; the paper's fur, Figure 11, has no usable per-voxel normal): every
/// texel with opacity, at every level, gets the tile's up axis `(0, 1, 0)` (snorm8 `[0,
/// 127, 0, 0]`), empty texels zero. Renderers take a shell's normals to world space with
/// each prism's uvw Jacobian, which turns +Y (height) into the surface normal, so fur on a
/// torus is lit by the torus' own terminator. Replaces any normals the tile had.
pub fn with_surface_normals(asset: &mut VolumeAsset) {
    let up = |levels: &[Vec<u8>]| -> Vec<Vec<u8>> {
        levels
            .iter()
            .map(|l| {
                l.chunks_exact(4)
                    .flat_map(|c| if c[3] > 0 { [0, 127, 0, 0] } else { [0; 4] })
                    .collect()
            })
            .collect()
    };
    asset.normals = Some(up(&asset.levels));
    for b in &mut asset.bands {
        b.normals = Some(up(&b.levels));
    }
    if let Some(v) = asset.header.volume.as_mut() {
        v.normals = Some(billow_format::NormalEncoding::Rgba8Snorm);
    }
    asset
        .header
        .params
        .insert("normals".into(), "surface".into());
}

/// World-space bounds of `prisms`' vertices; `None` when there are none.
pub fn prism_bounds(prisms: &[Prism]) -> Option<Bounds> {
    let points = prisms
        .iter()
        .flat_map(|p| p.pos.iter().map(|&q| Vec3::from(q)));
    let (min, max) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), q| {
        (lo.min(q), hi.max(q))
    });
    (!prisms.is_empty()).then_some(Bounds {
        min: min.to_array(),
        max: max.to_array(),
    })
}

fn usable(t: &Triangle) -> bool {
    let finite =
        t.v.iter()
            .all(|v| v.position.is_finite() && v.normal.is_finite() && v.uv.is_finite());
    finite && t.area() > 0.0 && t.cross().normalize().is_finite()
}

/// Welding key: the exact bits of a position (with −0 folded onto +0).
fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Interior angle of triangle `t` at corner `k`, in radians.
fn corner_angle(t: &Triangle, k: usize) -> f32 {
    let p = t.v[k].position;
    let a = (t.v[(k + 1) % 3].position - p).normalize_or_zero();
    let b = (t.v[(k + 2) % 3].position - p).normalize_or_zero();
    a.dot(b).clamp(-1.0, 1.0).acos()
}
