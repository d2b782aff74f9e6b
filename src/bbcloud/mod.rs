//! Stochastic billboard clouds (Lacewell, Edwards, Shirley & Thompson 2006).
//!
//! Pipeline: [`foliage`] split → [`lod`] chain of [`plane_search`] (Algorithm 1) levels →
//! [`rect`] trimming → texel density → [`bake`](mod@bake) front/back textures → [`atlas`]
//! packing and MIPs → a [`CloudAsset`]. A pure function of (scene, options): the seed
//! drives one PCG32 stream per level and every parallel step reduces in a fixed order, so
//! the same inputs give the same bytes for any thread count.
//!
//! Atlas layout and MIPs: every atlas stores `mip_levels` (M) MIP levels and no more; each
//! billboard side's allocation is aligned to `2^(M−1)` texels with a gutter of at least
//! `max(gutter, 2^(M−2))` texels, so at every stored level no texel mixes two billboards and
//! bilinear taps inside a billboard's UV rectangle read only its own allocation (`atlas.rs`).
//!
//! Texel density: with `texel_density: None` it is derived from the atlas budget — level ℓ
//! gets one `(atlas_size >> ℓ)²` atlas (textures halved per level) and the largest density
//! whose allocations fit it is found by bisection; the final cross is capped at half the
//! previous level's density. With an explicit density D, level ℓ uses
//! D / 2^ℓ and as many `atlas_size²` atlases as needed (the last shrunk to a power of two).

pub mod assemble;
pub mod atlas;
pub mod bake;
pub mod element;
pub mod foliage;
pub mod limits;
pub mod lod;
pub mod plane_search;
pub mod rect;
pub mod sampler;
pub mod slab;
pub mod unfold;
pub mod view;

use std::collections::BTreeMap;
use std::time::Instant;

use billow_format::{
    AssetKind, BakedLight, Bounds, CloudAsset, CloudError, ColourSpace, Header, SourceInfo,
};
use glam::Vec3;
use rayon::prelude::*;

pub use bake::Shading;
pub use element::{Element, Plane};
pub use plane_search::{Found, SearchParams, SearchStats};
pub use unfold::Flatten;
pub use view::{ViewDirs, ViewPreference, MAX_VIEW_DIRS};

use crate::scene::Scene;
use assemble::LevelLayout;
use atlas::Layout;
use lod::{build_chain, ChainParams, Level};

/// Options of a bake. Defaults follow the paper (ε = 0.04 R, N = 500, two cloud levels and
/// the final cross).
#[derive(Clone, Debug, PartialEq)]
pub struct BbcloudOptions {
    /// Slab half-width in units of the foliage's bounding-sphere radius.
    pub epsilon: f32,
    /// Candidate planes per billboard (N).
    pub samples: u32,
    pub seed: u64,
    /// Number of levels; with 2 or more the last is the two-billboard cross.
    pub lods: u32,
    /// Largest atlas side in texels (a power of two).
    pub atlas_size: u32,
    /// Texels per world unit at level 0; `None`: derived from the atlas budget.
    pub texel_density: Option<f32>,
    pub shading: Shading,
    /// K: K×K coverage samples per texel.
    pub supersample: u32,
    /// Foliage material names; empty: every MASK/BLEND material.
    pub foliage: Vec<String>,
    /// Least gutter texels around each billboard side in the atlas (raised to 2^(M−2) so
    /// bilinear taps stay inside at every stored level).
    pub gutter: u32,
    /// M: MIP levels stored per atlas, all free of cross-billboard mixing (1..=5).
    pub mip_levels: u32,
    /// Lacewell §5's extent limit in bounding-sphere radii (doubled per LOD): a billboard
    /// only takes triangles within this distance of its seed. `None`: unlimited (the paper's
    /// default).
    pub max_extent: Option<f32>,
    /// Lacewell §5's preference for planes facing the expected view directions.
    pub view: Option<ViewPreference>,
    /// Unit up axis (the last level's two billboards contain it). +Y: glTF's.
    pub up: Vec3,
    /// Also bake a tangent-space normal map per billboard side (SPEC §9.4).
    pub normal_map: bool,
    /// How triangles are laid onto their billboard: turned into the plane (the default,
    /// which keeps their area and so the mesh's coverage) or projected (the paper's).
    pub flatten: Flatten,
}

impl Default for BbcloudOptions {
    fn default() -> Self {
        BbcloudOptions {
            epsilon: 0.04,
            samples: 500,
            seed: 0,
            lods: 3,
            atlas_size: 2048,
            texel_density: None,
            shading: Shading {
                light: Some(billow_core::shading::DEFAULT_LIGHT.normalize()),
                ambient: billow_core::shading::DEFAULT_AMBIENT,
            },
            supersample: 3,
            foliage: Vec::new(),
            gutter: 2,
            mip_levels: 4,
            max_extent: None,
            view: None,
            up: Vec3::Y,
            normal_map: false,
            flatten: Flatten::Unfold,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BbcloudError {
    #[error(
        "nothing to bake: no foliage triangles (no MASK/BLEND material and no --foliage names)"
    )]
    NoFoliage,
    /// A valid scene without a single triangle (points, lines, an empty scene).
    #[error("nothing to bake: the mesh has no triangles")]
    EmptyScene,
    #[error("no material named {0:?} (materials: {1})")]
    UnknownMaterial(String, String),
    /// An option out of its range: `option` names the field of [`BbcloudOptions`] (so a
    /// caller can name its own flag for it), `message` the value and the range.
    #[error("{option}: {message}")]
    BadParameter {
        option: &'static str,
        message: String,
    },
    /// The atlases would exceed [`MAX_ATLAS_BYTES`] (found after the plane search, with the
    /// billboards' exact sizes, before any texture is allocated).
    #[error(
        "the atlases would take about {} MiB, more than the limit of {} MiB; lower \
         --atlas-size or --texel-density",
        .0 >> 20,
        MAX_ATLAS_BYTES >> 20
    )]
    TooLarge(u64),
    #[error(transparent)]
    Asset(#[from] CloudError),
}

/// Most bytes of atlas texels (all LOD levels, MIP levels and layers) a bake may make:
/// 1 GiB (the file is about as large, the bake's peak memory about three times that).
pub const MAX_ATLAS_BYTES: u64 = 1 << 30;

// The ranges of [`BbcloudOptions`]' fields, each said once: [`estimate`] and [`bake`]
// refuse a value outside them ([`BbcloudError::BadParameter`]), and `billow bbcloud
// --help` prints them from these constants.

/// Largest slab half-width `epsilon`, in foliage bounding-sphere radii (it must be above 0).
pub const MAX_EPSILON: f32 = 2.0;
/// Most candidate planes per billboard, `samples` (at least 1).
pub const MAX_SAMPLES: u32 = 1_000_000;
/// Most LOD levels, `lods` (at least 1).
pub const MAX_LODS: u32 = 8;
/// Smallest `atlas_size`, texels (a power of two).
pub const MIN_ATLAS_SIZE: u32 = 64;
/// Largest `atlas_size`, texels (a power of two).
pub const MAX_ATLAS_SIZE: u32 = 16384;
/// Largest `max_extent`, in foliage bounding-sphere radii (it must be above 0).
pub const LARGEST_MAX_EXTENT: f32 = 4.0;
/// Most coverage samples per texel side, `supersample` K (K×K samples; at least 1).
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Widest `gutter`, texels.
pub const MAX_GUTTER: u32 = 16;
/// Most MIP levels per atlas, `mip_levels` (at least 1).
pub const MAX_MIP_LEVELS: u32 = 5;
/// The range of the shading's ambient fraction and of the view preference's strength.
pub const UNIT_RANGE: std::ops::RangeInclusive<f32> = 0.0..=1.0;

/// Candidate-plane tests per second assumed by [`Estimate::search_seconds`] (measured: the
/// release build, a few cores).
pub const TESTS_PER_SECOND: f64 = 1e9;

/// What a bake will cost, known before any heavy work ([`estimate`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    pub foliage_triangles: usize,
    /// Billboards expected at LOD 0 (fitted on the bundled oak: `0.74 ε^-1.6`, at most one
    /// per triangle, more when `max_extent` is small).
    pub billboards: u64,
    /// Bytes of atlas texels, all levels: exact for the atlas budget (no `texel_density`),
    /// a lower bound with an explicit density (the triangles' own area at that density).
    pub atlas_bytes: u64,
    /// Plane-search work (candidate tests, all cloud levels) and its time at
    /// [`TESTS_PER_SECOND`].
    pub search_tests: f64,
    pub search_seconds: f64,
}

/// The sum over MIP levels `0..m` of `4^-k`: bytes of a MIP chain per level-0 byte.
fn mip_factor(m: u32) -> f64 {
    (0..m).map(|k| 0.25f64.powi(k as i32)).sum()
}

/// [`Estimate`] of baking `scene` with `opts` (the options are checked first).
pub fn estimate(scene: &Scene, opts: &BbcloudOptions) -> Result<Estimate, BbcloudError> {
    check(opts)?;
    if scene.triangles.is_empty() {
        return Err(BbcloudError::EmptyScene);
    }
    let is_leaf = foliage::classify(scene, &opts.foliage)?;
    let leaves: Vec<u32> = (0..scene.triangles.len() as u32)
        .filter(|&i| is_leaf[i as usize])
        .collect();
    if leaves.is_empty() {
        return Err(BbcloudError::NoFoliage);
    }
    let t = leaves.len() as f64;
    let per_texel = 4.0 * mip_factor(opts.mip_levels) * if opts.normal_map { 2.0 } else { 1.0 };
    let cloud_levels = if opts.lods >= 2 { opts.lods - 1 } else { 1 };
    let atlas = f64::from(opts.atlas_size);
    let mut texels = 0.0f64;
    for l in 0..opts.lods {
        texels += match opts.texel_density {
            None => (f64::from((opts.atlas_size >> l).max(64))).powi(2),
            Some(d) => {
                let d = f64::from(d) / f64::from(1u32 << l);
                leaves
                    .iter()
                    .map(|&i| {
                        let a = f64::from(scene.triangles[i as usize].area());
                        (2.0 * a * d * d).min(2.0 * atlas * atlas)
                    })
                    .sum::<f64>()
            }
        };
    }
    let billboards_at = |eps: f64| -> f64 {
        let by_eps = 0.74 * eps.max(1e-12).powf(-1.6);
        let by_extent = opts
            .max_extent
            .map_or(0.0, |m| (1.0 / f64::from(m).max(1e-12)).powi(2));
        by_eps.max(by_extent).clamp(1.0, t)
    };
    let eps = f64::from(opts.epsilon);
    let search_tests: f64 = (0..cloud_levels)
        .map(|l| billboards_at(eps * f64::from(1u32 << l)) * f64::from(opts.samples) * t)
        .sum();
    Ok(Estimate {
        foliage_triangles: leaves.len(),
        billboards: billboards_at(eps) as u64,
        atlas_bytes: (texels * per_texel).min(u64::MAX as f64) as u64,
        search_tests,
        search_seconds: search_tests / TESTS_PER_SECOND,
    })
}

/// What a progress callback is told.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Search { level: u32 },
    Render,
    Pack,
}

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Seconds {
    pub split: f64,
    pub search: f64,
    pub trim_and_density: f64,
    pub render: f64,
    pub pack: f64,
    pub mips: f64,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LevelStats {
    pub billboards: usize,
    pub epsilon: f32,
    pub texel_density: f32,
    pub atlases: Vec<(u32, u32)>,
    pub fill: f64,
    pub content_fill: f64,
    pub texels: u64,
    /// Mean alpha over the level's atlases (MIP 0): how much of the atlas shows leaves.
    pub alpha_coverage: f64,
    pub search: SearchStats,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BbcloudStats {
    pub foliage_triangles: usize,
    pub kept_triangles: usize,
    pub radius: f32,
    pub levels: Vec<LevelStats>,
    pub seconds: Seconds,
}

/// `ambient` within [`UNIT_RANGE`] (as [`estimate`] and [`bake()`] check it; a caller may
/// check it before any heavy work).
pub fn check_ambient(ambient: f32) -> Result<(), BbcloudError> {
    check_unit("ambient", ambient)
}

/// A view preference's `strength` within [`UNIT_RANGE`] (as [`estimate`] and [`bake()`]
/// check it; a caller may check it before any heavy work).
pub fn check_view_strength(strength: f32) -> Result<(), BbcloudError> {
    check_unit("view_strength", strength)
}

fn check_unit(option: &'static str, v: f32) -> Result<(), BbcloudError> {
    if UNIT_RANGE.contains(&v) {
        return Ok(());
    }
    Err(BbcloudError::BadParameter {
        option,
        message: format!(
            "must be in [{}, {}], got {v}",
            UNIT_RANGE.start(),
            UNIT_RANGE.end()
        ),
    })
}

fn check(opts: &BbcloudOptions) -> Result<(), BbcloudError> {
    let bad =
        |option: &'static str, message: String| Err(BbcloudError::BadParameter { option, message });
    if !(opts.epsilon.is_finite() && opts.epsilon > 0.0 && opts.epsilon <= MAX_EPSILON) {
        return bad(
            "epsilon",
            format!(
                "{} is out of range (above 0, at most {MAX_EPSILON} bounding-sphere radii)",
                opts.epsilon
            ),
        );
    }
    if !(1..=MAX_SAMPLES).contains(&opts.samples) {
        return bad(
            "samples",
            format!("{} is out of range (1 to {MAX_SAMPLES})", opts.samples),
        );
    }
    if !(1..=MAX_LODS).contains(&opts.lods) {
        return bad(
            "lods",
            format!("{} is out of range (1 to {MAX_LODS})", opts.lods),
        );
    }
    if !opts.atlas_size.is_power_of_two()
        || !(MIN_ATLAS_SIZE..=MAX_ATLAS_SIZE).contains(&opts.atlas_size)
    {
        return bad(
            "atlas_size",
            format!(
                "{} is out of range (a power of two from {MIN_ATLAS_SIZE} to {MAX_ATLAS_SIZE})",
                opts.atlas_size
            ),
        );
    }
    if let Some(d) = opts.texel_density.filter(|d| !(d.is_finite() && *d > 0.0)) {
        return bad("texel_density", format!("{d} is out of range (above 0)"));
    }
    if let Some(r) = opts
        .max_extent
        .filter(|r| !(r.is_finite() && *r > 0.0 && *r <= LARGEST_MAX_EXTENT))
    {
        return bad(
            "max_extent",
            format!(
                "{r} is out of range (above 0, at most {LARGEST_MAX_EXTENT} bounding-sphere radii)"
            ),
        );
    }
    if !(1..=MAX_SUPERSAMPLE).contains(&opts.supersample) {
        return bad(
            "supersample",
            format!(
                "{} is out of range (1 to {MAX_SUPERSAMPLE})",
                opts.supersample
            ),
        );
    }
    if opts.gutter > MAX_GUTTER {
        return bad(
            "gutter",
            format!("{} is out of range (0 to {MAX_GUTTER} texels)", opts.gutter),
        );
    }
    if !(1..=MAX_MIP_LEVELS).contains(&opts.mip_levels) {
        return bad(
            "mip_levels",
            format!(
                "{} is out of range (1 to {MAX_MIP_LEVELS})",
                opts.mip_levels
            ),
        );
    }
    check_ambient(opts.shading.ambient)?;
    if !(opts.up.is_finite() && (opts.up.length() - 1.0).abs() < 1e-3) {
        return bad("up", "must be a finite unit vector".into());
    }
    if let Some(v) = &opts.view {
        check_view_strength(v.strength)?;
        if !v.is_valid() {
            return bad(
                "view",
                format!(
                    "must be 1 to {MAX_VIEW_DIRS} finite unit vectors, strength from {} to {}",
                    UNIT_RANGE.start(),
                    UNIT_RANGE.end()
                ),
            );
        }
    }
    if let Some(l) = opts.shading.light {
        if !(l.is_finite() && l.length() > 0.0) {
            return bad("light", "must be finite and non-zero".into());
        }
    }
    Ok(())
}

/// Gutter and alignment of the atlas allocations for `M` clean MIP levels: alignment
/// `2^(M−1)` keeps every level-k texel (k < M) inside one allocation; a gutter of
/// `2^(M−2)` level-0 texels is half a texel at level M−1, what a bilinear tap at the edge
/// of the UV rectangle reaches out.
pub fn gutter_and_align(min_gutter: u32, mip_levels: u32) -> (u32, u32) {
    let m = mip_levels.clamp(1, 31);
    let bilinear = if m >= 2 { 1 << (m - 2) } else { 0 };
    (min_gutter.max(bilinear), 1 << (m - 1))
}

/// Texture size of a rectangle at `density`.
fn tex_size(r: &rect::PlaneRect, d: f32) -> (u32, u32) {
    let s = |x: f32| ((x * d).ceil() as u32).max(1);
    (s(r.width), s(r.height))
}

/// The largest density whose two sides per board fit one atlas (bisection on the packer).
fn budget_density(level: &Level, layout: &Layout) -> f32 {
    let sizes = |d: f32| -> Vec<(u32, u32)> {
        level
            .boards
            .iter()
            .flat_map(|b| [tex_size(&b.rect, d); 2])
            .collect()
    };
    let area: f64 = level
        .boards
        .iter()
        .map(|b| 2.0 * f64::from(b.rect.width.max(1e-6) * b.rect.height.max(1e-6)))
        .sum();
    let side = level
        .boards
        .iter()
        .map(|b| b.rect.width.max(b.rect.height))
        .fold(1e-6f32, f32::max);
    let m = layout.max_size as f32;
    let mut hi = ((m - 2.0 * layout.gutter as f32) / side)
        .min((f64::from(m) * f64::from(m) / area).sqrt() as f32);
    let mut lo = hi / 2.0;
    while !atlas::fits_one(&sizes(lo), layout) && lo > 1e-6 {
        (hi, lo) = (lo, lo / 2.0);
    }
    if atlas::fits_one(&sizes(hi), layout) {
        return hi;
    }
    for _ in 0..10 {
        let mid = 0.5 * (lo + hi);
        if atlas::fits_one(&sizes(mid), layout) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Bake a billboard cloud. `progress(stage, fraction)` is called from worker threads.
pub fn bake(
    scene: &Scene,
    opts: &BbcloudOptions,
    tool: &str,
    source: Option<SourceInfo>,
    progress: &(dyn Fn(Stage, f32) + Sync),
) -> Result<(CloudAsset, BbcloudStats), BbcloudError> {
    check(opts)?;
    let mut secs = Seconds::default();
    let t = Instant::now();
    if scene.triangles.is_empty() {
        return Err(BbcloudError::EmptyScene);
    }
    let is_leaf = foliage::classify(scene, &opts.foliage)?;
    let leaves: Vec<u32> = (0..scene.triangles.len() as u32)
        .filter(|&i| is_leaf[i as usize])
        .collect();
    if leaves.is_empty() {
        return Err(BbcloudError::NoFoliage);
    }
    let (centre, radius) = lod::bounding_sphere(scene, &leaves);
    let trunk = foliage::trunk_mesh(scene, &is_leaf);
    secs.split = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let chain = ChainParams {
        epsilon: opts.epsilon * radius.max(1e-12),
        samples: opts.samples,
        seed: opts.seed,
        levels: opts.lods,
        max_extent: opts.max_extent.map(|r| r * radius.max(1e-12)),
        view: opts.view.clone(),
        up: opts.up.normalize(),
        flatten: opts.flatten,
    };
    let levels = build_chain(scene, &leaves, centre, &chain, &|l, a, n| {
        progress(Stage::Search { level: l }, a as f32 / n.max(1) as f32)
    });
    secs.search = t.elapsed().as_secs_f64();

    // Texel density and snapped rectangles per level (levels in parallel).
    let t = Instant::now();
    let (gutter, align) = gutter_and_align(opts.gutter, opts.mip_levels);
    let mut per_level: Vec<LevelLayout> = levels
        .par_iter()
        .enumerate()
        .map(|(l, level)| {
            let mut layout = Layout {
                max_size: opts.atlas_size,
                gutter,
                align,
            };
            let d = match opts.texel_density {
                None => {
                    layout.max_size = (opts.atlas_size >> l).max(64);
                    budget_density(level, &layout)
                }
                Some(d0) => {
                    let side = level
                        .boards
                        .iter()
                        .map(|b| b.rect.width.max(b.rect.height))
                        .fold(1e-6f32, f32::max);
                    let cap = (opts.atlas_size - 2 * gutter - align) as f32 / side;
                    (d0 / (1u32 << l) as f32).min(cap)
                }
            };
            (d, layout, Vec::new())
        })
        .collect();
    // The cross (last level of a chain) is never denser than half the previous level:
    // filling its atlas would give it a density above level 0's, and it would cost more to
    // render than all of level 0.
    if opts.texel_density.is_none() && per_level.len() > 1 {
        let n = per_level.len();
        per_level[n - 1].0 = per_level[n - 1].0.min(0.5 * per_level[n - 2].0);
    }
    let mut texels = 0u64;
    for (level, (d, _, rects)) in levels.iter().zip(per_level.iter_mut()) {
        for b in &level.boards {
            let (w, h) = tex_size(&b.rect, *d);
            let mut r = b.rect;
            (r.width, r.height) = (w as f32 / *d, h as f32 / *d);
            rects.push((r, w, h));
            texels = texels.saturating_add(2 * u64::from(w) * u64::from(h));
        }
    }
    // Front and back of every billboard, all MIP levels and layers, before any allocation.
    let per_texel = 4.0 * mip_factor(opts.mip_levels) * if opts.normal_map { 2.0 } else { 1.0 };
    let bytes = (texels as f64 * per_texel) as u64;
    if bytes > MAX_ATLAS_BYTES {
        return Err(BbcloudError::TooLarge(bytes));
    }
    secs.trim_and_density = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut used = vec![false; scene.textures.len()];
    for &t in &leaves {
        let m = scene.material(&scene.triangles[t as usize]);
        if let Some(u) = m.base_color_texture.and_then(|i| used.get_mut(i as usize)) {
            *u = true;
        }
    }
    let textures: Vec<Option<sampler::Decoded>> = scene
        .textures
        .par_iter()
        .zip(&used)
        .map(|(t, &u)| u.then(|| sampler::Decoded::new(t)))
        .collect();
    let jobs: Vec<(usize, usize)> = levels
        .iter()
        .enumerate()
        .flat_map(|(l, lv)| (0..lv.boards.len()).map(move |b| (l, b)))
        .collect();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let images: Vec<assemble::Sides> = jobs
        .par_iter()
        .map(|&(l, b)| {
            let (r, w, h) = per_level[l].2[b];
            let board = &levels[l].boards[b];
            let job = bake::Job {
                rect: r,
                normal: board.plane.normal,
                density: per_level[l].0,
                width: w,
                height: h,
                triangles: &board.sources,
                positions: &board.unfolded,
                textures: &textures,
            };
            let out = bake::render(
                scene,
                &job,
                opts.supersample,
                &opts.shading,
                opts.normal_map,
            );
            // Its MIP chains now, while the floats are at hand (`assemble.rs`).
            let out = assemble::Sides::new(out, &per_level[l].1, opts.mip_levels);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(Stage::Render, n as f32 / jobs.len() as f32);
            out
        })
        .collect();
    secs.render = t.elapsed().as_secs_f64();

    let header = Header {
        kind: AssetKind::Cloud,
        tool: tool.to_string(),
        source,
        bounds: Bounds {
            min: scene.bounds.min.to_array(),
            max: scene.bounds.max.to_array(),
        },
        colour_space: ColourSpace::SrgbPremultiplied,
        seed: Some(opts.seed),
        params: params(opts),
        volume: None,
    };
    let (asset, stats_levels) = assemble::assemble(
        scene,
        &levels,
        &per_level,
        &images,
        opts.mip_levels,
        &leaves,
        trunk,
        header,
        &mut secs,
        progress,
    )?;

    let stats = BbcloudStats {
        foliage_triangles: leaves.len(),
        kept_triangles: scene.triangles.len() - leaves.len(),
        radius,
        levels: stats_levels,
        seconds: secs,
    };
    Ok((asset, stats))
}

/// The bake parameters recorded in the header.
pub fn params(o: &BbcloudOptions) -> BTreeMap<String, String> {
    let mut p = BTreeMap::new();
    let mut put = |k: &str, v: String| p.insert(k.to_string(), v);
    put("epsilon", o.epsilon.to_string());
    put("samples", o.samples.to_string());
    put("lods", o.lods.to_string());
    put("atlas_size", o.atlas_size.to_string());
    put(
        "texel_density",
        o.texel_density.map_or("budget".into(), |d| d.to_string()),
    );
    put("ambient", o.shading.ambient.to_string());
    put("supersample", o.supersample.to_string());
    put(
        "foliage",
        if o.foliage.is_empty() {
            "alpha-mode".into()
        } else {
            o.foliage.join(",")
        },
    );
    let (gutter, align) = gutter_and_align(o.gutter, o.mip_levels);
    put("gutter", gutter.to_string());
    put("mip_levels", o.mip_levels.to_string());
    // Every stored level keeps level 0's alpha-tested coverage at this cut-off
    // (atlas::coverage_chain).
    put("mip_alpha", format!("coverage@{}", atlas::ALPHA_CUTOFF));
    put("up", format!("{},{},{}", o.up.x, o.up.y, o.up.z));
    if let Some(v) = &o.view {
        put("view_dirs", v.describe());
        put("view_strength", v.strength.to_string());
    }
    if o.normal_map {
        put("normal_map", "tangent".into());
    }
    if let Some(r) = o.max_extent {
        put("max_extent", r.to_string());
    }
    put("mip_align", align.to_string());
    put("flatten", o.flatten.name().into());
    // The baked light, as every reader reads it (SPEC §9).
    match o.shading.light {
        Some(l) => BakedLight::Directional {
            dir: l.to_array(),
            ambient: o.shading.ambient,
        },
        None => BakedLight::Unlit,
    }
    .write(&mut p);
    p
}
