//! CPU slicer for volume assets: the rendering algorithm of Volumetric Billboards §3.3,
//! the reference the GPU viewer is compared with.
//!
//! - Cells are transformed to camera space; slicing planes `z = −depth` parallel to the
//!   screen span the depth range of all cells (clipped to near/far) and are drawn
//!   **back to front**; within a slice, cells in their fixed ID order (no popping).
//! - Spacing ([`Spacing::Adaptive`], the paper's adaptive slicing): at depth `z`,
//!   `d(z) = bias · max(z·tan(fov/2)/(h/2), v₀)` where `v₀` is the world size of a
//!   level-0 voxel ([`voxel_size`]): one pixel's footprint, never finer than the
//!   magnified voxel. `bias = 1` is the paper. [`Spacing::Uniform`]: constant `d`.
//!   Slices are placed front to back from the nearest cell depth: `z₀ = z_min + d(z_min)/2`,
//!   `z_{i+1} = z_i + d(z_i)`, then drawn in reverse.
//! - MIP level from the spacing ([`slice_lod`]): `lod = log2(d / v₀)` clamped to the stored levels,
//!   sampled trilinearly within a level and (default [`MipFilter::Linear`]) linearly
//!   between the two nearest levels.
//! - Opacity correction: `α' = 1 − (1 − α)^(d/d₀)` with `d₀ = v₀ · 2^lod` the voxel size
//!   of the sampled (clamped, fractional for linear filtering) level; premultiplied colour
//!   scaled by `α'/α` ([`billow_core::compositing`]).
//! - Each cell ∩ slice polygon comes from [`intersect_prism_plane`]. All its vertices lie
//!   at the same depth, so the perspective projection is an *affine* map on it and uvw
//!   interpolates linearly in screen space — no perspective correction needed. The convex
//!   polygon is scan-converted at pixel centres with half-open spans (`x_l ≤ x < x_r`,
//!   rows `y_min ≤ y < y_max`), computed from canonically ordered edge end points, so
//!   pixels on an edge shared by two cells are drawn exactly once.
//! - Texels are decoded to linear premultiplied ([`DecodedVolume`]) and filtered in
//!   **extinction space** ([`DecodedVolume::sample_opacity`]): each texel becomes
//!   `(σ·c, σ)` with `σ = −ln(1 − α)` (capped at `ln 510`), those are interpolated, and
//!   the sample is `α = 1 − e^(−σ)`. Interpolating α itself would give a one-voxel
//!   opaque layer a finite optical depth (2 voxels' worth of σ = 1) and let rays between
//!   texel centres through it: the see-through stripes of thin layers (docs/eval.md,
//!   "Thin layers"). The result is composited with "over" into premultiplied linear
//!   RGBA f32.
//! - Over an opaque layer ([`render_decoded_over`], the viewer's mesh depth): each slice
//!   stands for the slab `depth ± d/2` and is faded by the part of it in front of the
//!   surface ([`billow_core::slicing::slab_fade`], the ratio becomes `fade · d/d₀`), as spherical billboards
//!   clip a particle's path at the scene depth; a hard depth test leaves terraces.
//! - Rows are processed in parallel; every pixel sees the same sequence of fragments,
//!   so the result is deterministic.
//! - **LOD bands** (formats/SPEC.md §8.6, pruned volumes): `v₀` is the smallest
//!   `voxel_size(band cells) / 2^first_level` over the base texture and its bands, slices
//!   span every band's cells, `lod` is clamped to the asset's last level, and each slice
//!   draws only the band with the largest `first_level ≤ lod` ([`slice_band`], the rule
//!   the viewer's plan and shader share), sampling its texture at
//!   `lod − first_level`; opacity correction uses the slice's `lod`.
//! - **Runtime shading** ([`SlicerParams::light`]) of a volume that stores normals: its
//!   colour is albedo, multiplied by [`billow_core::shading::volume_diffuse_factor`] of the Toksvig normal
//!   sampled like the colour ([`DecodedVolume::sample_normal`]) and taken to view space
//!   by [`normal_matrix`]. A volume without normals keeps its baked colour, untouched.

// `!(a < b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::time::Instant;

use billow_format::{Prism, VolumeAsset};
use glam::{Mat3, Vec3};
use rayon::prelude::*;

use billow_core::slicing::{slice_band, slice_lod};

use super::lighting::VolumeLight;
use super::reference::validate_camera;
use super::slice_raster::{
    raster_row, raster_row_samples, resolve, to_screen, CellFrame, RowCtx, ScreenPoly,
};
use super::volume_sampler::{DecodedVolume, MipFilter};
use super::volume_shadow::ShadowGrid;
use super::{EvalError, ImageF32};
use billow_core::camera::Camera;
use billow_core::prism_plane::intersect_prism_plane;

use billow_core::slicing::{
    far_slab, level_texel_size, level_weights, normal_matrix, opaque_optical_depth, voxel_size,
    Spacing,
};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlicerParams {
    pub spacing: Spacing,
    pub mip_filter: MipFilter,
    /// Refuse to render more slices than this (guards hostile assets / tiny spacings).
    pub max_slices: usize,
    /// The scene light volumes with normals are shaded with (`None`: drawn unlit, their
    /// albedo as it is). World space, as the cells.
    pub light: Option<VolumeLight>,
    /// Coverage samples per pixel along each axis, `n × n` at the eval reference's
    /// stratified points ([`super::reference::Sampling::Stratified`]), MSAA-style: each cell ∩ slice polygon
    /// is shaded once per pixel (at the centroid of the samples it covers) and composited
    /// into every sample it covers; the pixel is their mean. So the cells' edges are
    /// anti-aliased as the reference's geometry is, and a volume a few pixels wide covers
    /// the area its box projects to, not the number of pixel centres inside it. 1 (the
    /// default, what the GPU viewer draws): the pixel centre only. At most 16; lowered
    /// until the image holds at most 2²⁴ samples.
    pub coverage_samples: u32,
    /// Shadow the direct light of a lit plain volume by its own transmittance towards the
    /// light ([`ShadowGrid`], `billow eval --shadows`); pruned and shell volumes stay
    /// unshadowed ([`SliceStats::shadowed`] says which).
    pub shadows: bool,
}

/// Most coverage samples per axis ([`SlicerParams::coverage_samples`]).
pub const MAX_COVERAGE_SAMPLES: u32 = 16;

impl Default for SlicerParams {
    fn default() -> Self {
        SlicerParams {
            spacing: Spacing::Adaptive { bias: 1.0 },
            mip_filter: MipFilter::Linear,
            max_slices: 100_000,
            light: Some(VolumeLight::default()),
            coverage_samples: 1,
            shadows: false,
        }
    }
}

/// What a render did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SliceStats {
    pub slices: usize,
    /// Non-empty cell ∩ slice polygons.
    pub polygons: usize,
    /// Pixels shaded (polygon × covered pixel centre).
    pub fragments: u64,
    pub seconds: f64,
    /// World size of a level-0 voxel, `v₀`.
    pub voxel_size: f32,
    pub min_spacing: f32,
    pub max_spacing: f32,
    /// The direct light was shadowed by the volume's transmittance
    /// ([`SlicerParams::shadows`]).
    pub shadowed: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct SliceRender {
    pub image: ImageF32,
    pub stats: SliceStats,
}

/// The base texture or one LOD band: what a slice may draw.
struct Part<'a> {
    vol: &'a DecodedVolume,
    dims0: [u32; 3],
    cells: &'a [Prism],
    first_level: u32,
}

/// Renders a volume asset from `camera`.
pub fn render_volume(
    asset: &VolumeAsset,
    camera: &Camera,
    params: &SlicerParams,
) -> Result<SliceRender, EvalError> {
    let vol = DecodedVolume::decode(asset)?;
    let dims = asset.level_dims(0);
    render_decoded(&vol, dims, &asset.cells, camera, params)
}

/// An opaque layer under the volume (the CPU counterpart of the viewer's mesh pass):
/// per pixel (row 0 at the top) its view distance along the view axis (`∞` where there
/// is none) and its premultiplied linear colour.
#[derive(Clone, Debug, PartialEq)]
pub struct OpaqueBackdrop {
    pub depth: Vec<f32>,
    pub colour: ImageF32,
}

/// [`render_decoded`] composited over an opaque layer. Each slice stands for the slab
/// `depth ± d/2`; where the opaque surface at depth `Z` cuts that slab, the slice's
/// opacity is corrected for the part in front of it only, `f = clamp((Z − (depth −
/// d/2))/d, 0, 1)` times the spacing (ratio `f·d/d₀`), as spherical billboards clip a
/// particle's path at the scene depth. A hard depth test instead (the slice drawn whole
/// or not at all) leaves a terrace per slice where the surface cuts the volume.
pub fn render_decoded_over(
    vol: &DecodedVolume,
    dims0: [u32; 3],
    cells: &[Prism],
    camera: &Camera,
    params: &SlicerParams,
    backdrop: &OpaqueBackdrop,
) -> Result<SliceRender, EvalError> {
    let n = camera.width as usize * camera.height as usize;
    if backdrop.depth.len() != n
        || backdrop.colour.width != camera.width
        || backdrop.colour.height != camera.height
    {
        return Err(EvalError::InvalidParam(format!(
            "opaque backdrop of {}x{} ({} depths) for a {}x{} camera",
            backdrop.colour.width,
            backdrop.colour.height,
            backdrop.depth.len(),
            camera.width,
            camera.height
        )));
    }
    let extras = Extras {
        backdrop: Some(backdrop),
        ..Extras::default()
    };
    render_sliced(vol, dims0, cells, camera, params, extras)
}

/// [`render_decoded`] with `--shadows`' transmittance grid built once by the caller
/// ([`ShadowGrid::for_volume`] of `vol`, `cells` and the params' light): it depends on
/// the light alone, and a view set renders many views under one light. `None` draws no
/// shadow. Used only where the params ask for shadows and the volume is lit.
pub fn render_decoded_with_shadow(
    vol: &DecodedVolume,
    dims0: [u32; 3],
    cells: &[Prism],
    camera: &Camera,
    params: &SlicerParams,
    shadow: Option<&ShadowGrid>,
) -> Result<SliceRender, EvalError> {
    let extras = Extras {
        shadow: Some(shadow),
        ..Extras::default()
    };
    render_sliced(vol, dims0, cells, camera, params, extras)
}

/// Renders already-decoded levels (reuse across views) with the given cells.
pub fn render_decoded(
    vol: &DecodedVolume,
    dims0: [u32; 3],
    cells: &[Prism],
    camera: &Camera,
    params: &SlicerParams,
) -> Result<SliceRender, EvalError> {
    render_decoded_in_depth_range(vol, dims0, cells, camera, params, None)
}

/// [`render_decoded`] with the slices placed over `depth_range` (view-space distances
/// `(near, far)`) instead of the cells' own depth range, so two assets covering the same
/// object with different cells (e.g. before and after `billow emptyspace`) are sliced at
/// the same depths. `None`: the cells' range, as [`render_decoded`].
pub fn render_decoded_in_depth_range(
    vol: &DecodedVolume,
    dims0: [u32; 3],
    cells: &[Prism],
    camera: &Camera,
    params: &SlicerParams,
    depth_range: Option<(f32, f32)>,
) -> Result<SliceRender, EvalError> {
    let extras = Extras {
        depth_range,
        ..Extras::default()
    };
    render_sliced(vol, dims0, cells, camera, params, extras)
}

/// What a render may be given besides the volume and the view.
#[derive(Clone, Copy, Default)]
struct Extras<'a> {
    /// The slices' depth range (view-space distances), instead of the cells' own.
    depth_range: Option<(f32, f32)>,
    /// An opaque scene behind and in front of the volume.
    backdrop: Option<&'a OpaqueBackdrop>,
    /// `Some`: the shadow grid the caller built (or `Some(None)`: none); `None`: built
    /// here when the params ask for shadows.
    shadow: Option<Option<&'a ShadowGrid>>,
}

fn render_sliced(
    vol: &DecodedVolume,
    dims0: [u32; 3],
    cells: &[Prism],
    camera: &Camera,
    params: &SlicerParams,
    extras: Extras,
) -> Result<SliceRender, EvalError> {
    let Extras {
        depth_range,
        backdrop,
        shadow: given_shadow,
    } = extras;
    let start = Instant::now();
    validate_camera(camera)?;
    match params.spacing {
        Spacing::Adaptive { bias } if !(bias > 0.0 && bias.is_finite()) => {
            return Err(EvalError::InvalidParam(format!(
                "spacing bias {bias} must be > 0"
            )));
        }
        Spacing::Uniform { spacing } if !(spacing > 0.0 && spacing.is_finite()) => {
            return Err(EvalError::InvalidParam(format!(
                "spacing {spacing} must be > 0"
            )));
        }
        _ => {}
    }
    // Coverage samples per axis, and per pixel (contiguous in the working image).
    let ns = coverage_samples(params.coverage_samples, camera);
    let nn = (ns * ns) as usize;
    let mut image = match backdrop {
        Some(b) if nn == 1 => b.colour.clone(),
        Some(b) => ImageF32 {
            width: camera.width * nn as u32,
            height: camera.height,
            data: b
                .colour
                .data
                .iter()
                .flat_map(|&c| std::iter::repeat_n(c, nn))
                .collect(),
        },
        None => ImageF32::new(camera.width * nn as u32, camera.height),
    };
    let mut stats = SliceStats::default();
    if vol.level_count() == 0 {
        return Err(EvalError::InvalidAsset("no MIP levels".into()));
    }
    let mut parts = vec![Part {
        vol,
        dims0,
        cells,
        first_level: 0,
    }];
    parts.extend(vol.bands.iter().map(|b| Part {
        vol: &b.volume,
        dims0: b.dims0,
        cells: &b.cells,
        first_level: b.first_level,
    }));
    let v0 = parts
        .iter()
        .filter_map(|p| voxel_size(p.cells, p.dims0).map(|s| s / 2f32.powi(p.first_level as i32)))
        .reduce(f32::min);
    let Some(v0) = v0 else {
        stats.seconds = start.elapsed().as_secs_f64();
        return Ok(SliceRender {
            image: resolve(image, nn),
            stats,
        });
    };
    stats.voxel_size = v0;
    let view = camera.view();
    // Runtime shading: the light in view space, and per part (its volume has normals)
    // the normal matrix of every cell.
    let light_view = params.light.and_then(|l| {
        let d = view.transform_vector3(l.dir).normalize_or_zero();
        (d != Vec3::ZERO && (0.0..=1.0).contains(&l.ambient)).then_some((d, l.ambient))
    });
    // Camera-relative: `R·(p − eye)`, not `view·p = R·p + t`. Equal in exact arithmetic
    // (`t = −R·eye`), but far from the origin (a cell at 1e5) `R·p` and `t` are both large
    // and their f32 sum cancels, moving each vertex by its own ~1e5·2⁻²⁴ per product
    // (tests/eval_slicer.rs, the 1e5 offset); `p − eye` is exact for points near the eye.
    let object_to_view = Mat3::from_mat4(view);
    let cam_cells: Vec<Vec<[[f32; 3]; 6]>> = parts
        .iter()
        .map(|part| {
            part.cells
                .iter()
                .map(|c| {
                    c.pos
                        .map(|p| (object_to_view * (Vec3::from(p) - camera.eye)).to_array())
                })
                .collect()
        })
        .collect();
    let nmats: Vec<Option<Vec<CellFrame>>> = parts
        .iter()
        .zip(&cam_cells)
        .map(|(part, cc)| {
            let shell = part.vol.repeat[0] || part.vol.repeat[2];
            let (l, _) = light_view.filter(|_| part.vol.has_normals())?;
            Some(
                cc.iter()
                    .zip(part.cells)
                    .map(|(c, cell)| {
                        let m = normal_matrix(object_to_view, shell, c, &cell.uvw);
                        // The light and the view axis in the cell's own axes: n_view·L =
                        // n·(Mᵀ L).
                        let axes = [l, Vec3::Z].map(|v| (m.transpose() * v).normalize_or_zero());
                        (m, axes)
                    })
                    .collect(),
            )
        })
        .collect();
    let (mut z_min, mut z_max) = (f32::INFINITY, f32::NEG_INFINITY);
    for c in cam_cells.iter().flatten() {
        for p in c {
            z_min = z_min.min(-p[2]);
            z_max = z_max.max(-p[2]);
        }
    }
    let (z_min, z_max) = depth_range.unwrap_or((z_min, z_max));
    let z_min = z_min.max(camera.near);
    let z_max = z_max.min(camera.far);
    if !(z_min < z_max) {
        stats.seconds = start.elapsed().as_secs_f64();
        return Ok(SliceRender {
            image: resolve(image, nn),
            stats,
        });
    }
    let mut slices = billow_core::slicing::slice_depths(
        |z| camera.pixel_size_at(z),
        params.spacing,
        v0,
        z_min,
        z_max,
        params.max_slices,
    )?;
    slices.reverse(); // back to front
    stats.slices = slices.len();
    stats.min_spacing = slices.iter().map(|s| s.1).fold(f32::INFINITY, f32::min);
    stats.max_spacing = slices.iter().map(|s| s.1).fold(0.0, f32::max);
    let last = parts.last().expect("the base part");
    let max_lod = (last.first_level as usize + last.vol.level_count() - 1) as f32;
    let vols: Vec<&DecodedVolume> = parts.iter().map(|p| p.vol).collect();
    let first_levels: Vec<u32> = parts.iter().map(|p| p.first_level).collect();
    // Per part, the world size of a texel of each of its levels (the opacity correction's
    // `s_l`); a level without one (degenerate cells) takes `v₀ · 2^level`.
    let sizes: Vec<Vec<f32>> = parts
        .iter()
        .map(|p| {
            (0..p.vol.level_count() as u32)
                .map(|j| {
                    level_texel_size(p.cells, p.dims0, j)
                        .unwrap_or(v0 * ((p.first_level + j) as f32).exp2())
                })
                .collect()
        })
        .collect();
    let far_z = slices.first().map(|&(z, d)| (z, far_slab(z, d, z_max)));
    // `--shadows`: the base part's transmittance towards the light, when it is lit.
    let built;
    let shadow = match params
        .light
        .filter(|_| params.shadows && nmats[0].is_some())
    {
        None => None,
        Some(_) if given_shadow.is_some() => given_shadow.flatten(),
        Some(l) => {
            built = ShadowGrid::for_volume(vol, cells, l.dir);
            built.as_ref()
        }
    };
    stats.shadowed = shadow.is_some();
    let w = camera.width as usize;
    const BATCH: usize = 1 << 16;
    let mut polys: Vec<ScreenPoly> = Vec::new();
    let flush = |polys: &mut Vec<ScreenPoly>, image: &mut ImageF32| -> u64 {
        let frags = image
            .data
            .par_chunks_mut(w * nn)
            .enumerate()
            .map(|(y, row)| {
                let depth = backdrop.map(|b| &b.depth[y * w..(y + 1) * w]);
                let ctx = RowCtx {
                    vols: &vols,
                    filter: params.mip_filter,
                    light: light_view,
                    depth,
                    shadow,
                };
                if nn == 1 {
                    raster_row(row, y, polys, &ctx)
                } else {
                    raster_row_samples(row, ns, y, polys, &ctx)
                }
            })
            .sum();
        polys.clear();
        frags
    };
    for &(depth, d) in &slices {
        let lod = slice_lod(d, v0, max_lod);
        // The slab this slice stands for; the farthest reaches the end of the range.
        let thickness = match far_z {
            Some((z, t)) if z == depth => t,
            _ => d,
        };
        let z = -depth;
        // The band this slice draws: the last one starting at or below `lod`.
        let band = slice_band(&first_levels, lod);
        let part_lod = lod - parts[band].first_level as f32;
        let weights = level_weights(
            part_lod,
            thickness,
            &sizes[band],
            params.mip_filter == MipFilter::Nearest,
        )
        .map(|(l, w)| (l, w, opaque_optical_depth(sizes[band][l], sizes[band][0])));
        for (ci, c) in cam_cells[band].iter().enumerate() {
            let poly = intersect_prism_plane(c, &parts[band].cells[ci].uvw, z);
            if poly.is_empty() {
                continue;
            }
            let sp = to_screen(camera, &poly.pos, &poly.uvw, poly.count, part_lod, weights);
            if let Some(mut sp) = sp {
                sp.band = band;
                sp.nmat = nmats[band].as_ref().map(|m| m[ci]);
                sp.slab0 = depth - 0.5 * d;
                sp.thickness = thickness;
                polys.push(sp);
                stats.polygons += 1;
            }
        }
        if polys.len() >= BATCH {
            stats.fragments += flush(&mut polys, &mut image);
        }
    }
    stats.fragments += flush(&mut polys, &mut image);
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(SliceRender {
        image: resolve(image, nn),
        stats,
    })
}

/// Coverage samples per axis for `camera`: `asked` clamped to
/// `1..=`[`MAX_COVERAGE_SAMPLES`], then lowered until the image holds at most 2²⁴.
pub fn coverage_samples(asked: u32, camera: &Camera) -> u32 {
    let px = u64::from(camera.width) * u64::from(camera.height);
    let mut n = asked.clamp(1, MAX_COVERAGE_SAMPLES);
    while n > 1 && px * u64::from(n * n) > 1 << 24 {
        n -= 1;
    }
    n
}
