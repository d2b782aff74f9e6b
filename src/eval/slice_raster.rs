//! The CPU slicer's scan conversion: slice polygons projected to the screen
//! ([`ScreenPoly`]), each row's spans composited front to back with the volume sampled and
//! shaded per pixel ([`raster_row`], or per coverage sample, [`raster_row_samples`]), and
//! the samples resolved to pixels ([`resolve`]). [`super::slicer`] builds the polygons.

// `!(a > b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Mat3, Vec3, Vec4};

use super::reference::{sample_offset, Sampling};
use super::volume_sampler::{DecodedVolume, MipFilter};
use super::volume_shadow::ShadowGrid;
use super::ImageF32;
use billow_core::camera::Camera;
use billow_core::compositing::over;
use billow_core::shading::{moments_diffuse_factor, volume_diffuse_factor};
use billow_core::slicing::{shade_normal, slab_fade};

/// One polygon in screen space, ready to scan-convert.
pub(super) struct ScreenPoly {
    pub(super) n: usize,
    pub(super) xy: [[f32; 2]; 5],
    pub(super) y_min: f32,
    pub(super) y_max: f32,
    /// uvw = base + gx·(x − ox) + gy·(y − oy).
    pub(super) origin: [f32; 2],
    pub(super) base: Vec3,
    pub(super) gx: Vec3,
    pub(super) gy: Vec3,
    /// The level the normals are sampled at (`lod` of the band's texture).
    pub(super) lod: f32,
    /// Levels of the band's texture, their opacity weights for the whole slab
    /// ([`billow_core::slicing::level_weights`]) and their opaque texels' optical depth
    /// ([`billow_core::slicing::opaque_optical_depth`]).
    pub(super) weights: [(usize, f32, f32); 2],
    /// The slab the slice stands for: from `slab0` (view distance), `thickness` deep.
    pub(super) slab0: f32,
    pub(super) thickness: f32,
    /// Index of the band (0 = the base texture) whose texture this polygon samples.
    pub(super) band: usize,
    /// Normal frame → view space of the polygon's cell ([`normal_matrix`]), when it is
    /// shaded, with the light and the view axis in the cell's own axes (`Mᵀ·L`, `Mᵀ·z`,
    /// unit: what moments are lit with).
    pub(super) nmat: Option<CellFrame>,
}

/// A shaded cell's normal matrix and its `[light, view axis]` in the cell's own axes.
pub(super) type CellFrame = (Mat3, [Vec3; 2]);

/// The pixels of an image of `nn` samples per pixel: their mean.
pub(super) fn resolve(image: ImageF32, nn: usize) -> ImageF32 {
    if nn == 1 {
        return image;
    }
    let k = 1.0 / nn as f32;
    ImageF32 {
        width: image.width / nn as u32,
        height: image.height,
        data: image
            .data
            .chunks_exact(nn)
            .map(|s| s.iter().fold(Vec4::ZERO, |a, &b| a + b) * k)
            .collect(),
    }
}

pub(super) fn to_screen(
    camera: &Camera,
    pos: &[[f32; 3]; 5],
    uvw: &[[f32; 3]; 5],
    n: usize,
    lod: f32,
    weights: [(usize, f32, f32); 2],
) -> Option<ScreenPoly> {
    let mut xy = [[0.0f32; 2]; 5];
    for i in 0..n {
        let (x, y) = camera.view_to_pixel(Vec3::from(pos[i]))?;
        xy[i] = [x, y];
    }
    let (mut y_min, mut y_max) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in &xy[..n] {
        y_min = y_min.min(p[1]);
        y_max = y_max.max(p[1]);
    }
    // Affine uvw gradient from the fan triangle with the largest area.
    let (mut best, mut best_area) = (1, 0.0f32);
    for i in 1..n - 1 {
        let a = cross2(sub2(xy[i], xy[0]), sub2(xy[i + 1], xy[0]));
        if a.abs() > best_area.abs() {
            best = i;
            best_area = a;
        }
    }
    if best_area == 0.0 || !best_area.is_finite() {
        return None; // zero-area in screen: covers no pixel centre
    }
    let (e1, e2) = (sub2(xy[best], xy[0]), sub2(xy[best + 1], xy[0]));
    let t0 = Vec3::from(uvw[0]);
    let (d1, d2) = (Vec3::from(uvw[best]) - t0, Vec3::from(uvw[best + 1]) - t0);
    // Solve [e1 e2]^T-weighted: uvw(p) = t0 + a·d1 + b·d2 with p − p0 = a·e1 + b·e2.
    let inv = 1.0 / best_area;
    // a = cross(p, e2)/area, b = cross(e1, p)/area
    let gx = (d1 * e2[1] - d2 * e1[1]) * inv;
    let gy = (d2 * e1[0] - d1 * e2[0]) * inv;
    Some(ScreenPoly {
        n,
        xy,
        y_min,
        y_max,
        origin: xy[0],
        base: t0,
        gx,
        gy,
        lod,
        weights,
        slab0: 0.0,
        thickness: 0.0,
        band: 0,
        nmat: None,
    })
}

fn sub2(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross2(a: [f32; 2], b: [f32; 2]) -> f32 {
    a[0] * b[1] - a[1] * b[0]
}

/// What every row of a batch reads: the volumes (per band), the MIP filter, the light in
/// view space, and an opaque layer's view distances for the row (slices fade at it).
pub(super) struct RowCtx<'a> {
    pub(super) vols: &'a [&'a DecodedVolume],
    pub(super) filter: MipFilter,
    pub(super) light: Option<(Vec3, f32)>,
    pub(super) depth: Option<&'a [f32]>,
    /// The base part's transmittance towards the light (`--shadows`).
    pub(super) shadow: Option<&'a ShadowGrid>,
}

impl RowCtx<'_> {
    /// Polygon `p` shaded at `uvw`, for pixel `x`: `None` where its slab lies behind the
    /// opaque layer.
    #[inline]
    fn shade(&self, p: &ScreenPoly, x: usize, uvw: Vec3) -> Option<Vec4> {
        let fade = self
            .depth
            .map_or(1.0, |z| slab_fade(z[x], p.slab0, p.thickness));
        if !(fade > 0.0) {
            return None;
        }
        let w = p.weights.map(|(l, w, cap)| (l, w * fade, cap));
        let mut s = self.vols[p.band].sample_weighted(w, uvw);
        if let (Some((m, [light, view])), Some((l, ambient))) = (p.nmat, self.light) {
            let vol = &self.vols[p.band];
            let n = vol
                .sample_normal(p.lod, uvw, self.filter)
                .unwrap_or(Vec3::ZERO);
            let vis = match self.shadow {
                Some(g) if p.band == 0 => g.sample(uvw),
                _ => 1.0,
            };
            let k = if vol.moments {
                moments_diffuse_factor(n, light, view, ambient, vis)
            } else {
                volume_diffuse_factor(shade_normal(m, n), l, ambient, vis)
            };
            s = (s.truncate() * k).extend(s.w);
        }
        Some(s)
    }
}

/// The span `[x_l, x_r)` of polygon `p` on the horizontal line at `yc` (from canonically
/// ordered edge end points: the same edge gives the same x in every polygon); empty
/// (`x_l ≥ x_r`) where it does not cross it.
#[inline]
fn span(p: &ScreenPoly, yc: f32) -> (f32, f32) {
    let (mut xl, mut xr) = (f32::INFINITY, f32::NEG_INFINITY);
    if !(p.y_min <= yc && yc < p.y_max) {
        return (xl, xr);
    }
    for i in 0..p.n {
        let (a, b) = (p.xy[i], p.xy[(i + 1) % p.n]);
        if (a[1] <= yc) == (b[1] <= yc) {
            continue;
        }
        let (a, b) = if (a[1], a[0]) <= (b[1], b[0]) {
            (a, b)
        } else {
            (b, a)
        };
        let x = a[0] + (yc - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
        xl = xl.min(x);
        xr = xr.max(x);
    }
    (xl, xr)
}

/// Composites every polygon covering row `y` into `row`, in order; returns fragments.
pub(super) fn raster_row(row: &mut [Vec4], y: usize, polys: &[ScreenPoly], ctx: &RowCtx) -> u64 {
    let yc = y as f32 + 0.5;
    let w = row.len() as i64;
    let mut frags = 0;
    for p in polys {
        let (xl, xr) = span(p, yc);
        if !(xl < xr) {
            continue;
        }
        let x0 = ((xl - 0.5).ceil() as i64).max(0);
        let x1 = ((xr - 0.5).ceil() as i64).min(w);
        let dy = yc - p.origin[1];
        for x in x0..x1 {
            let xc = x as f32 + 0.5;
            let uvw = p.base + p.gx * (xc - p.origin[0]) + p.gy * dy;
            let Some(s) = ctx.shade(p, x as usize, uvw) else {
                continue;
            };
            let px = &mut row[x as usize];
            *px = over(s, *px);
            frags += 1;
        }
    }
    frags
}

/// [`raster_row`] with `n × n` coverage samples per pixel ([`SlicerParams::coverage_samples`];
/// `row` holds `n²` samples per pixel, in the order of [`sample_offset`]'s `(sx, sy)`,
/// x fastest). A sample is covered when it lies in the polygon's half-open span on its own
/// horizontal line (so a sample on an edge two cells share is drawn once); the polygon is
/// shaded once per pixel, at the centroid of the samples it covers (inside the convex
/// polygon, so a pruned volume's cell never reads a neighbour's texels), or at the pixel
/// centre when it covers the whole pixel, and composited into each covered sample.
pub(super) fn raster_row_samples(
    row: &mut [Vec4],
    n: u32,
    y: usize,
    polys: &[ScreenPoly],
    ctx: &RowCtx,
) -> u64 {
    let nn = (n * n) as usize;
    let w = (row.len() / nn) as i64;
    let sampling = Sampling::Stratified { per_axis: n };
    // The pattern of every pixel of the row: (x offset, y) per sample.
    let offsets: Vec<Vec<(f32, f32)>> = (0..w as u32)
        .map(|x| {
            (0..nn as u32)
                .map(|q| {
                    let (ox, oy) = sample_offset(sampling, x, y as u32, q % n, q / n, n);
                    (ox, y as f32 + oy)
                })
                .collect()
        })
        .collect();
    let (top, bottom) = (y as f32, (y + 1) as f32);
    let mut frags = 0;
    let mut covered = vec![false; nn];
    for p in polys {
        if !(p.y_min < bottom && top < p.y_max) {
            continue;
        }
        // Pixels fully inside: every point of [top, bottom] within the spans at both ends
        // (the polygon is convex).
        let (a, b) = (span(p, top), span(p, bottom));
        let (inner_l, inner_r) = if p.y_min <= top && bottom < p.y_max {
            (a.0.max(b.0), a.1.min(b.1))
        } else {
            (f32::INFINITY, f32::NEG_INFINITY)
        };
        // The pixels the polygon may touch: its x extent over the row.
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for v in &p.xy[..p.n] {
            lo = lo.min(v[0]);
            hi = hi.max(v[0]);
        }
        let x0 = (lo.floor() as i64).max(0);
        let x1 = (hi.ceil() as i64 + 1).min(w);
        for x in x0..x1 {
            let xs = x as usize;
            let px = &mut row[xs * nn..(xs + 1) * nn];
            let whole = inner_l <= x as f32 && ((x + 1) as f32) < inner_r;
            let (xc, yc) = if whole {
                (x as f32 + 0.5, y as f32 + 0.5)
            } else {
                let (mut cx, mut cy, mut k) = (0.0f32, 0.0f32, 0u32);
                for (c, &(ox, sy)) in covered.iter_mut().zip(&offsets[xs]) {
                    let sx = x as f32 + ox;
                    let (l, r) = span(p, sy);
                    *c = l <= sx && sx < r;
                    if *c {
                        cx += sx;
                        cy += sy;
                        k += 1;
                    }
                }
                if k == 0 {
                    continue;
                }
                (cx / k as f32, cy / k as f32)
            };
            let uvw = p.base + p.gx * (xc - p.origin[0]) + p.gy * (yc - p.origin[1]);
            let Some(s) = ctx.shade(p, xs, uvw) else {
                continue;
            };
            for (v, &c) in px.iter_mut().zip(&covered) {
                if whole || c {
                    *v = over(s, *v);
                }
            }
            frags += 1;
        }
    }
    frags
}
