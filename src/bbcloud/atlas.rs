//! Atlas packing, gutters and MIP chains.
//!
//! Each billboard side becomes one allocation: its texels plus a gutter of `gutter` texels
//! on every side, rounded up to a multiple of `align = 2^k`. Packing is done in units of
//! `align` texels by the `crunch` packer (a maximal-rectangles variant; deterministic:
//! stable sort, no hashing), so every allocation starts and ends on a multiple of 2^k and
//! MIP levels 0..=k never mix two billboards in one texel. The gutter is filled by
//! extruding the billboard's edge texels (clamp-to-edge), so bilinear taps just outside the
//! billboard's UV rect read its own colour, not a neighbour's — at level j as long as the
//! gutter is at least 2^(j−1) texels (half a level-j texel). The MIP chain is cut after
//! level k (`mip_levels = k + 1`, chosen by `mod.rs` with a matching gutter), so *no* stored
//! level mixes two billboards: what the full chain would add below that (a handful of
//! texels per atlas) is left to the coarser LOD levels.
//!
//! Atlases are powers of two (the last one of a level shrunk to the smallest power-of-two
//! rectangle that holds what is left), so every MIP level halves exactly. MIPs are box
//! filtered on **premultiplied linear** colour: transparent texels contribute neither colour
//! nor coverage, so edges never darken (no dark fringes); the result is then sRGB-encoded
//! (`SrgbPremultiplied`, SPEC.md §8.3).
//!
//! **Alpha-tested coverage is kept at every level** ([`coverage_chain`]). Renderers alpha-test
//! billboards at [`ALPHA_CUTOFF`] (Lacewell §6: custom MIP code "which rounds alpha values
//! to either 0 or 1") after filtering the texture bilinearly. A box filter keeps the
//! *mean* alpha, but the area that passes the test shrinks level by level wherever leaves
//! are thinner than a texel, so distant canopies thin out and go see-through. So each
//! level k ≥ 1 of a side is scaled by the one factor `s_k` that makes its **rendered**
//! coverage (the share of its area where the bilinearly filtered, scaled alpha passes the
//! test, [`rendered_coverage`], measured at 4 × 4 points per texel) equal level 0's
//! ([`rendered_coverage_scale`]),
//! applied as `texel · min(s_k, 1/α)`: premultiplied colour and alpha together, so straight
//! colour is unchanged and alpha never exceeds 1 (Castaño's coverage-preserving MIPs, per
//! billboard side, measured as a renderer draws them). Keeping the share of *texels* at or
//! above the cut-off instead ([`coverage_scale`], the chain before 2026-12) was not
//! enough: an isolated passing texel of a coarse level draws only about 0.6 of its area
//! once filtered (`(1 − |x|)(1 − |y|) ≥ ½`), so the oak's LOD 0 lost 24 % of its coverage
//! at 4× the framed distance and 30 % at 64× (docs/bbcloud.md, "Coverage at a distance").
//! Where a level's alpha cannot reach the target (every passing texel already at 1), it
//! stays short.

// `!(a > b)` comparisons are deliberate: they also catch NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec4;
use rayon::prelude::*;

use super::bake::Image;

/// Where one image landed: atlas index and the top-left texel of its content.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    pub atlas: u32,
    pub x: u32,
    pub y: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Packing {
    pub sizes: Vec<(u32, u32)>,
    pub places: Vec<Place>,
    /// Texels of all allocations (content + gutter + alignment).
    pub allocated: u64,
    /// Texels of content only.
    pub content: u64,
}

impl Packing {
    pub fn atlas_texels(&self) -> u64 {
        self.sizes
            .iter()
            .map(|&(w, h)| u64::from(w) * u64::from(h))
            .sum()
    }
    /// Allocated texels / atlas texels.
    pub fn fill(&self) -> f64 {
        self.allocated as f64 / self.atlas_texels().max(1) as f64
    }
    pub fn content_fill(&self) -> f64 {
        self.content as f64 / self.atlas_texels().max(1) as f64
    }
}

/// Layout parameters.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    pub max_size: u32,
    pub gutter: u32,
    pub align: u32,
}

impl Layout {
    /// Allocation size of an image in `align` blocks.
    fn blocks(&self, (w, h): (u32, u32)) -> (usize, usize) {
        let b = |x: u32| (x + 2 * self.gutter).div_ceil(self.align) as usize;
        (b(w), b(h))
    }
}

type Packed = Vec<crunch::PackedItem<usize>>;

fn try_pack(items: &[crunch::Item<usize>], w: usize, h: usize) -> Result<Packed, Packed> {
    crunch::pack(crunch::Rect::of_size(w, h), items.iter().cloned())
}

/// Whether all images fit into one `size × size` atlas.
pub fn fits_one(sizes: &[(u32, u32)], layout: &Layout) -> bool {
    let n = (layout.max_size / layout.align) as usize;
    let items: Vec<_> = sizes
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let (w, h) = layout.blocks(s);
            crunch::Item::new(i, w, h, crunch::Rotation::None)
        })
        .collect();
    if items.iter().any(|it| it.w > n || it.h > n) {
        return false;
    }
    let area: usize = items.iter().map(|it| it.w * it.h).sum();
    area <= n * n && try_pack(&items, n, n).is_ok()
}

/// Pack every image (none larger than an atlas, checked by the caller) into as many atlases
/// as needed; the last one shrunk to the smallest power-of-two rectangle that holds the rest.
pub fn pack(sizes: &[(u32, u32)], layout: &Layout) -> Option<Packing> {
    let n = (layout.max_size / layout.align) as usize;
    let mut rest: Vec<crunch::Item<usize>> = sizes
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let (w, h) = layout.blocks(s);
            crunch::Item::new(i, w, h, crunch::Rotation::None)
        })
        .collect();
    if rest.iter().any(|it| it.w > n || it.h > n) {
        return None;
    }
    let mut out = Packing {
        sizes: Vec::new(),
        places: vec![
            Place {
                atlas: 0,
                x: 0,
                y: 0
            };
            sizes.len()
        ],
        allocated: 0,
        content: 0,
    };
    let a = layout.align as usize;
    while !rest.is_empty() {
        let (dims, packed) = match try_pack(&rest, n, n) {
            Ok(all) => shrink(&rest, n).unwrap_or(((n, n), all)),
            Err(part) if part.is_empty() => return None,
            Err(part) => ((n, n), fill_up(&rest, part, n)),
        };
        let atlas = out.sizes.len() as u32;
        out.sizes.push(((dims.0 * a) as u32, (dims.1 * a) as u32));
        let mut placed = vec![false; sizes.len()];
        for p in packed {
            let i = p.data;
            placed[i] = true;
            let g = layout.gutter;
            out.places[i] = Place {
                atlas,
                x: (p.rect.x * a) as u32 + g,
                y: (p.rect.y * a) as u32 + g,
            };
            out.allocated += (p.rect.w * p.rect.h * a * a) as u64;
            out.content += u64::from(sizes[i].0) * u64::from(sizes[i].1);
        }
        rest.retain(|it| !placed[it.data]);
    }
    Some(out)
}

/// crunch stops at the first item that does not fit; try the remaining (smaller) ones too,
/// one at a time in its order, keeping each that still lets everything pack.
fn fill_up(items: &[crunch::Item<usize>], mut packed: Packed, n: usize) -> Packed {
    let mut chosen: Vec<crunch::Item<usize>> = items
        .iter()
        .filter(|it| packed.iter().any(|p| p.data == it.data))
        .cloned()
        .collect();
    let free = n * n - chosen.iter().map(|it| it.w * it.h).sum::<usize>();
    let mut free = free;
    for it in items {
        if it.w * it.h > free || chosen.iter().any(|c| c.data == it.data) {
            continue;
        }
        chosen.push(it.clone());
        match try_pack(&chosen, n, n) {
            Ok(p) => {
                packed = p;
                free -= it.w * it.h;
            }
            Err(_) => {
                chosen.pop();
            }
        }
    }
    packed
}

/// The smallest power-of-two (in blocks) rectangle, sides ≤ n, that holds all items.
fn shrink(items: &[crunch::Item<usize>], n: usize) -> Option<((usize, usize), Packed)> {
    let area: usize = items.iter().map(|it| it.w * it.h).sum();
    let mut dims = Vec::new();
    let mut w = 1;
    while w <= n {
        let mut h = 1;
        while h <= n {
            if w * h >= area {
                dims.push((w, h));
            }
            h *= 2;
        }
        w *= 2;
    }
    dims.sort_by_key(|&(w, h)| (w * h, w.max(h), std::cmp::Reverse(w)));
    dims.into_iter()
        .find_map(|(w, h)| try_pack(items, w, h).ok().map(|p| ((w, h), p)))
}

/// Compose the atlases (premultiplied linear) from the images and their places, gutters
/// extruded from the edges.
pub fn compose(images: &[&Image], packing: &Packing, layout: &Layout) -> Vec<Image> {
    let mut atlases: Vec<Image> = packing
        .sizes
        .iter()
        .map(|&(w, h)| Image {
            width: w,
            height: h,
            texels: vec![Vec4::ZERO; (w * h) as usize],
        })
        .collect();
    let (g, a) = (layout.gutter, layout.align);
    for (img, p) in images.iter().zip(&packing.places) {
        let at = &mut atlases[p.atlas as usize];
        let aw = (img.width + 2 * g).div_ceil(a) * a;
        let ah = (img.height + 2 * g).div_ceil(a) * a;
        let (x0, y0) = (p.x - g, p.y - g);
        for y in 0..ah {
            let sy = (y as i64 - g as i64).clamp(0, img.height as i64 - 1) as u32;
            for x in 0..aw {
                let sx = (x as i64 - g as i64).clamp(0, img.width as i64 - 1) as u32;
                at.texels[((y0 + y) * at.width + x0 + x) as usize] =
                    img.texels[(sy * img.width + sx) as usize];
            }
        }
    }
    atlases
}

/// One side's allocation as an image: its texels with the edges extruded into the gutter
/// and the alignment padding, exactly what [`compose`] writes at its place.
pub fn allocation_image(img: &Image, layout: &Layout) -> Image {
    let (g, a) = (layout.gutter, layout.align);
    let aw = (img.width + 2 * g).div_ceil(a) * a;
    let ah = (img.height + 2 * g).div_ceil(a) * a;
    let mut texels = Vec::with_capacity((aw * ah) as usize);
    for y in 0..ah {
        let sy = (y as i64 - g as i64).clamp(0, img.height as i64 - 1) as u32;
        let row = &img.texels[(sy * img.width) as usize..][..img.width as usize];
        for x in 0..aw {
            texels.push(row[(x as i64 - g as i64).clamp(0, img.width as i64 - 1) as usize]);
        }
    }
    Image {
        width: aw,
        height: ah,
        texels,
    }
}

/// The encoded MIP chain (`levels` levels) of one side's allocation: colour
/// (`SrgbPremultiplied`) or, with `normals`, a normal map. Because allocations are aligned
/// to `2^(levels−1)` texels, level k of an atlas restricted to an allocation is level k of
/// the allocation alone, so the atlas's chain can be built per side, in parallel and without
/// the full-size float atlas ([`assemble_levels`]; same bytes as [`compose`] + [`mip_chain`],
/// tested).
pub fn side_chain(img: &Image, layout: &Layout, levels: u32, kind: Chain) -> Vec<Vec<u8>> {
    assert!(
        layout.align >= 1 << (levels.max(1) - 1),
        "allocations must be aligned to 2^(levels-1)"
    );
    let a = allocation_image(img, layout);
    match kind {
        Chain::Normals => normal_chain(a, levels),
        Chain::Colour => mip_chain(a, levels),
        Chain::Coverage(cutoff) => coverage_chain(a, levels, cutoff),
    }
}

/// Which chain [`side_chain`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chain {
    /// Colour, box filtered ([`mip_chain`]).
    Colour,
    /// Colour whose levels keep level 0's alpha-tested coverage at this cut-off
    /// ([`coverage_chain`]; what the bake writes).
    Coverage(f32),
    /// A normal map ([`normal_chain`]).
    Normals,
}

/// The alpha cut-off renderers test billboards at (the viewer, the CPU cloud renderer,
/// glTF `MASK`), and the one [`coverage_chain`] preserves.
pub const ALPHA_CUTOFF: f32 = 0.5;

/// Share of `img`'s texels whose alpha is at least `cutoff`.
pub fn tested_coverage(img: &Image, cutoff: f32) -> f64 {
    let n = img.texels.iter().filter(|t| t.w >= cutoff).count();
    n as f64 / img.texels.len().max(1) as f64
}

/// The factor that gives `img` tested coverage `target` (a share of its *texels*, not of
/// the area a renderer draws: see [`rendered_coverage_scale`]) at `cutoff`: with n = round(target · texels) and the alphas sorted, the cut-off is put
/// halfway between two neighbouring distinct alphas so that as close to n texels as
/// possible pass (texels of equal alpha pass or fail together, so a tie at the n-th is
/// split on the side nearer n). 1 when nothing has coverage.
pub fn coverage_scale(img: &Image, target: f64, cutoff: f32) -> f32 {
    let mut a: Vec<f32> = img
        .texels
        .iter()
        .map(|t| t.w)
        .filter(|&w| w > 0.0)
        .collect();
    if a.is_empty() {
        return 1.0;
    }
    a.sort_by(|x, y| y.total_cmp(x));
    let n = ((target * img.texels.len() as f64).round() as usize).min(a.len());
    let scale = if n == 0 {
        // Nothing may pass: the largest alpha lands halfway below the cut-off.
        0.5 * cutoff / a[0]
    } else {
        let v = a[n - 1];
        let first = a.partition_point(|&x| x > v); // texels above v
        let last = a.partition_point(|&x| x >= v); // texels at or above v
        let below = a.get(last).copied().unwrap_or(0.0);
        if first > 0 && n - first < last - n {
            // Fewer miss when the tie fails: cut between v and the next larger alpha.
            2.0 * cutoff / (a[first - 1] + v)
        } else {
            // The tie passes: cut between v and the next smaller alpha (or zero).
            2.0 * cutoff / (v + below)
        }
    };
    if scale.is_finite() && scale > 0.0 {
        scale.min(1.0 / f32::EPSILON)
    } else {
        1.0
    }
}

/// `img` with every texel scaled by `min(scale, 1/α)` (premultiplied: straight colour kept).
pub fn scale_coverage(img: &Image, scale: f32) -> Image {
    Image {
        width: img.width,
        height: img.height,
        texels: img
            .texels
            .iter()
            .map(|&t| {
                if t.w > 0.0 {
                    t * scale.min(1.0 / t.w)
                } else {
                    t
                }
            })
            .collect(),
    }
}

/// Points per texel and axis at which [`rendered_coverage`] tests the filtered alpha.
const RENDER_POINTS: usize = 4;

/// `f(taps)` for every test point of `img` (`RENDER_POINTS²` per texel, on a regular grid)
/// whose four bilinear taps `(weight, alpha)` are not all empty, where `f` returns
/// something. Bilinear as a renderer samples: texel centres at `(i + ½)`, clamp-to-edge
/// (the allocation's gutter repeats its edge).
fn over_points<T: Send>(img: &Image, f: impl Fn([(f32, f32); 4]) -> Option<T> + Sync) -> Vec<T> {
    let (w, h) = (img.width as usize, img.height as usize);
    // Exact in f32 too: RENDER_POINTS is a power of two.
    let taps = |n: usize| -> Vec<(usize, usize, f32)> {
        crate::texture::clamp_edge_taps(n, RENDER_POINTS)
            .into_iter()
            .map(|(i0, i1, t)| (i0, i1, t as f32))
            .collect()
    };
    let (tx, ty) = (taps(w), taps(h));
    let alpha = |x: usize, y: usize| img.texels[y * w + x].w.clamp(0.0, 1.0);
    // Per texel column, whether it has any alpha in a row (a point reads two of each).
    let any: Vec<bool> = img.texels.iter().map(|t| t.w > 0.0).collect();
    let any_row: Vec<bool> = any.chunks(w.max(1)).map(|r| r.iter().any(|&a| a)).collect();
    ty.par_iter()
        .filter(|&&(y0, y1, _)| any_row[y0] || any_row[y1])
        .flat_map_iter(|&(y0, y1, fy)| {
            let f = &f;
            let any = &any;
            tx.iter().filter_map(move |&(x0, x1, fx)| {
                if !(any[y0 * w + x0] || any[y0 * w + x1] || any[y1 * w + x0] || any[y1 * w + x1]) {
                    return None;
                }
                f([
                    ((1.0 - fx) * (1.0 - fy), alpha(x0, y0)),
                    (fx * (1.0 - fy), alpha(x1, y0)),
                    ((1.0 - fx) * fy, alpha(x0, y1)),
                    (fx * fy, alpha(x1, y1)),
                ])
            })
        })
        .collect()
}

/// For every test point of `img` that can pass ([`over_points`]), the smallest scale `s`
/// at which the bilinearly filtered alpha of `img` scaled by `s` (each texel
/// `min(s·α, 1)`, [`scale_coverage`]) reaches `cutoff` there.
fn pass_scales(img: &Image, cutoff: f32) -> Vec<f32> {
    over_points(img, |taps| {
        let s = pass_scale(taps, cutoff);
        s.is_finite().then_some(s)
    })
}

/// The smallest `s` with `Σ wᵢ · min(s·αᵢ, 1) ≥ cutoff` (`∞` if none): the sum grows
/// piecewise linearly in `s`, with a kink where each `s·αᵢ` reaches 1.
fn pass_scale(mut taps: [(f32, f32); 4], cutoff: f32) -> f32 {
    // By the scale at which each tap saturates, 1/α (empty taps never count).
    taps.sort_by(|a, b| b.1.total_cmp(&a.1));
    let (mut sat, mut slope) = (0.0f32, 0.0f32);
    for &(w, a) in &taps {
        if a > 0.0 {
            slope += w * a;
        }
    }
    let mut s0 = 0.0f32;
    for &(w, a) in &taps {
        if !(a > 0.0) {
            break;
        }
        // On [s0, 1/a] the sum is sat + s·slope.
        let end = 1.0 / a;
        if slope > 0.0 {
            let s = (cutoff - sat) / slope;
            if s <= end {
                return s.max(s0);
            }
        }
        sat += w;
        slope -= w * a;
        s0 = end;
    }
    if sat >= cutoff {
        s0
    } else {
        f32::INFINITY
    }
}

/// The share of `img`'s area that a renderer alpha-testing it at `cutoff` after bilinear
/// filtering draws once its alpha is scaled by `scale` ([`scale_coverage`]), measured at
/// `RENDER_POINTS²` points per texel.
pub fn rendered_coverage(img: &Image, scale: f32, cutoff: f32) -> f64 {
    let pass = over_points(img, |taps| {
        let a: f32 = taps.iter().map(|&(w, a)| w * (scale * a).min(1.0)).sum();
        (a >= cutoff).then_some(())
    });
    let total = img.texels.len() * RENDER_POINTS * RENDER_POINTS;
    pass.len() as f64 / total.max(1) as f64
}

/// The factor that makes [`rendered_coverage`] of `img` as close as it can be to `target`
/// (a share of its area): the points are ordered by the scale at which they start to
/// pass, and the factor lies halfway between the `n`-th and the next (`n` the target's
/// share of the points). 1 when nothing can pass.
pub fn rendered_coverage_scale(img: &Image, target: f64, cutoff: f32) -> f32 {
    let mut p = pass_scales(img, cutoff);
    if p.is_empty() {
        return 1.0;
    }
    let total = img.texels.len() * RENDER_POINTS * RENDER_POINTS;
    let n = ((target * total as f64).round() as usize).min(p.len());
    // The n-th smallest and the next (order statistics, no full sort).
    let nth = |p: &mut [f32], k: usize| *p.select_nth_unstable_by(k, f32::total_cmp).1;
    let scale = match n {
        0 => 0.5 * nth(&mut p, 0),
        n if n == p.len() => nth(&mut p, n - 1) * 1.0001,
        n => {
            let a = nth(&mut p, n - 1);
            // After the selection, everything past n - 1 is at least `a`.
            let b = p[n..].iter().copied().fold(f32::INFINITY, f32::min);
            0.5 * (a + b)
        }
    };
    if scale.is_finite() && scale > 0.0 {
        scale.min(1.0 / f32::EPSILON)
    } else {
        1.0
    }
}

/// The MIP chain of a colour allocation every level of which covers what level 0 covers,
/// **as a renderer draws it** (module docs): the area where its bilinearly filtered alpha
/// passes the test at `cutoff` equals level 0's. Levels are box filtered from the unscaled
/// level above, then scaled by [`rendered_coverage_scale`]; level 0 is stored as baked.
pub fn coverage_chain(atlas: Image, levels: u32, cutoff: f32) -> Vec<Vec<u8>> {
    let n = mip_count(atlas.width, atlas.height, levels);
    let target = rendered_coverage(&atlas, 1.0, cutoff);
    let mut out = vec![encode_srgb_premultiplied(&atlas)];
    let mut cur = atlas;
    while (out.len() as u32) < n {
        cur = downsample(&cur);
        let s = rendered_coverage_scale(&cur, target, cutoff);
        out.push(encode_srgb_premultiplied(&scale_coverage(&cur, s)));
    }
    out
}

/// Every atlas's encoded levels from the sides' chains ([`side_chain`], in packing order)
/// and their content sizes; texels outside every allocation are `empty`.
pub fn assemble_levels(
    chains: &[&[Vec<u8>]],
    sizes: &[(u32, u32)],
    packing: &Packing,
    layout: &Layout,
    levels: u32,
    empty: [u8; 4],
) -> Vec<Vec<Vec<u8>>> {
    let mut out: Vec<Vec<Vec<u8>>> = packing
        .sizes
        .iter()
        .map(|&(w, h)| {
            (0..mip_count(w, h, levels))
                .map(|k| empty.repeat(((w >> k).max(1) * (h >> k).max(1)) as usize))
                .collect()
        })
        .collect();
    let (g, a) = (layout.gutter, layout.align);
    for ((chain, &(w, h)), p) in chains.iter().zip(sizes).zip(&packing.places) {
        let (aw, ah) = ((w + 2 * g).div_ceil(a) * a, (h + 2 * g).div_ceil(a) * a);
        let (x0, y0) = (p.x - g, p.y - g);
        let atlas_w = packing.sizes[p.atlas as usize].0;
        for (k, dst) in out[p.atlas as usize].iter_mut().enumerate() {
            let (lw, lh, row) = (aw >> k, ah >> k, ((atlas_w >> k).max(1) * 4) as usize);
            let src = &chain[k];
            for yy in 0..lh as usize {
                let d = ((y0 >> k) as usize + yy) * row + (x0 >> k) as usize * 4;
                let n = lw as usize * 4;
                dst[d..d + n].copy_from_slice(&src[yy * n..(yy + 1) * n]);
            }
        }
    }
    out
}

/// Next MIP level: 2×2 box filter of premultiplied colour (floor halving, clamped at 1).
pub fn downsample(img: &Image) -> Image {
    let (w, h) = ((img.width / 2).max(1), (img.height / 2).max(1));
    let get = |x: u32, y: u32| {
        img.texels[(y.min(img.height - 1) * img.width + x.min(img.width - 1)) as usize]
    };
    let texels = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (2 * (i % w), 2 * (i / w));
            0.25 * (get(x, y) + get(x + 1, y) + get(x, y + 1) + get(x + 1, y + 1))
        })
        .collect();
    Image {
        width: w,
        height: h,
        texels,
    }
}

/// Linear → sRGB byte: moved to [`crate::texture::encode_srgb`] (the exporter uses it
/// too), re-exported here.
pub use crate::texture::encode_srgb;

/// Encode premultiplied linear RGBA to `SrgbPremultiplied` bytes.
pub fn encode_srgb_premultiplied(img: &Image) -> Vec<u8> {
    img.texels
        .par_iter()
        .flat_map_iter(|p| {
            if *p == Vec4::ZERO {
                return [0; 4]; // most of an atlas
            }
            let a = p.w.clamp(0.0, 1.0);
            let c = |v: f32| encode_srgb(v.clamp(0.0, a));
            [c(p.x), c(p.y), c(p.z), (a * 255.0).round() as u8]
        })
        .collect()
}

/// Number of MIP levels of a `w × h` atlas: the full chain, cut at `cap`.
pub fn mip_count(w: u32, h: u32, cap: u32) -> u32 {
    (32 - w.max(h).max(1).leading_zeros()).min(cap.max(1))
}

/// The first `levels` levels (at most the full chain) of an atlas, each encoded by `enc`.
fn chain(atlas: Image, levels: u32, enc: fn(&Image) -> Vec<u8>) -> Vec<Vec<u8>> {
    let n = mip_count(atlas.width, atlas.height, levels);
    let mut out = vec![enc(&atlas)];
    let mut cur = atlas;
    while (out.len() as u32) < n {
        cur = downsample(&cur);
        out.push(enc(&cur));
    }
    out
}

/// The MIP chain of a colour atlas (premultiplied linear), `levels` levels at most, encoded.
pub fn mip_chain(atlas: Image, levels: u32) -> Vec<Vec<u8>> {
    chain(atlas, levels, encode_srgb_premultiplied)
}

/// Encode a coverage-premultiplied tangent-space normal image (SPEC §9.4): RGB = the unit
/// mean normal · 0.5 + 0.5, A = the length of the mean normal (1 where the normals agree);
/// texels without coverage (or with a zero mean) encode the flat normal (0, 0, 1), A = 1.
pub fn encode_normals(img: &Image) -> Vec<u8> {
    let q = |c: f32| ((c * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0).round() as u8;
    img.texels
        .par_iter()
        .flat_map_iter(|p| {
            let (m, a) = (p.truncate(), p.w);
            let len = if a > 0.0 { m.length() / a } else { 0.0 };
            if !(len > 1e-6 && len.is_finite()) {
                return [128, 128, 255, 255];
            }
            let n = m / (len * a);
            [q(n.x), q(n.y), q(n.z), (len.min(1.0) * 255.0).round() as u8]
        })
        .collect()
}

/// The MIP chain of a normal atlas: box-filtered premultiplied normals, encoded.
pub fn normal_chain(atlas: Image, levels: u32) -> Vec<Vec<u8>> {
    chain(atlas, levels, encode_normals)
}
