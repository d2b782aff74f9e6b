//! Empty-space removal for volume assets (VB paper §4 "Optimizations", Figure 14): a
//! kd-tree cuts the volume into non-empty boxes, the boxes are packed with an apron into
//! smaller 3D atlases, and each box becomes two prism cells whose texture coordinates
//! point into an atlas. The result is a volume asset with **LOD bands** (formats/SPEC.md
//! §8.6) that renders exactly as the source at every MIP level.
//!
//! Pipeline ([`prune`]):
//! 1. `--threshold`: texels with alpha ≤ T are zeroed ([`occupancy::apply_threshold`]);
//! 2. for each *tier* `k = 0, 1, …` whose level-`k` sides are even ([`tier`]): the blocks
//!    (2×2×2 texels of level `k`) that any non-empty texel of levels `k, k + 1` reaches
//!    through trilinear filtering ([`occupancy`]); kd-tree boxes over them ([`kdtree`]);
//!    slots = box + one-block apron, packed with shared zero aprons ([`pack`]); byte-exact
//!    copies of levels `k` and `k + 1` ([`brick_copy`]); two prisms per box;
//! 3. the *tail* `K`: the source's levels `K..` stored whole with the source's box cells;
//! 4. `K` is the largest tail level whose texel bytes `Σ_{k<K} tier_k + tail_K` are
//!    within 1 % of the smallest and whose last tier leaves out at least a tenth of its
//!    blocks (coarse tiers cost almost nothing and cut the work of distant views); `K = 0`
//!    keeps the source whole (nothing to gain, or odd sides).
//!
//! The output's base texture is tier 0, its bands are tiers `1..K` (first level `k`) and
//! the tail (first level `K`). A slice at LOD `λ` draws exactly one of them, sampling the
//! same texel values the source would sample at `λ` (SPEC §8.6).

pub mod brick_copy;
pub mod kdtree;
pub mod occupancy;
pub mod pack;
pub mod sparse_tier;
/// Test support (feature `test-support`, on for billow's own tests): not part of the API.
#[cfg(any(test, feature = "test-support"))]
pub mod synthetic;
pub mod tier;

use std::borrow::Cow;
use std::time::Instant;

use billow_format::{mip_dims, LodBand, Prism, VolumeAsset};
use glam::Vec3;
use serde::Serialize;

use self::kdtree::KdParams;
use self::occupancy::{apply_threshold, TierSource, TierTexels};
use self::sparse_tier::SparseTier;
use self::tier::{fill_tier, plan_tier, Tier, TierParams, TierPlan};
use crate::sparse_level::SparseLevel;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EmptySpaceError {
    #[error("the asset is invalid: {0}")]
    InvalidAsset(String),
    #[error("the asset is a shell (tileable volume with repeat addressing); empty-space removal needs a plain volume")]
    Shell,
    #[error("the asset was already pruned by `billow emptyspace` ({0}); prune the original volume instead")]
    AlreadyPruned(String),
    #[error("the asset's cells are not one box mapping the whole texture onto its bounds (cell {0}); only such volumes can be pruned")]
    NotABox(usize),
    #[error("the asset already has LOD bands; only plain volumes can be pruned")]
    HasBands,
    #[error("{0}")]
    InvalidParam(String),
    #[error("the atlas of tier {tier} would bring the prune to about {needed_gib:.1} GiB of memory, more than the limit of {limit_gib:.1} GiB; lower the resolution or raise the memory limit")]
    TooMuchMemory {
        tier: u32,
        needed_gib: f64,
        limit_gib: f64,
    },
}

/// Parameters of [`prune`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmptySpaceOptions {
    /// Texels whose alpha byte is ≤ this are dropped (zeroed); 0: nothing is dropped.
    pub threshold: u8,
    /// Smallest box edge a split may leave, in level-0 voxels (scaled to each tier,
    /// rounded up to whole blocks).
    pub min_box: u32,
    /// Deepest kd-tree level (root = 0).
    pub max_depth: u32,
    /// Smallest relative cost reduction worth a split.
    pub min_gain: f64,
    /// Per-box cost `W` of the kd-tree, in atlas texels.
    pub cell_cost: f64,
    /// Most tiers stored as bricks (`None`: as many as pay off; `Some(0)`: keep whole).
    pub max_tiers: Option<u32>,
    /// Aprons around bricks. `false` exists only to show what seams look like (tests).
    pub apron: bool,
    /// Lay bricks out for 4×4 block compression (`billow emptyspace --compress bc`): every
    /// slot's x and y start and end on the source's 4-texel grid and land on the atlas's,
    /// so each BC block of the atlas holds one source block (no block mixes two bricks,
    /// and aprons inside a source block cost no extra block).
    pub bc_blocks: bool,
    /// Refuse (before allocating it) a tier atlas that would bring the source and the
    /// atlases held to more than this (bytes). Default: no limit.
    pub memory_limit: u64,
}

// The ranges of [`EmptySpaceOptions`]' fields, each said once: [`prune`] refuses a value
// outside them ([`EmptySpaceError::InvalidParam`]), and `billow emptyspace --help` prints
// them from these constants.

/// Deepest kd-tree level `max_depth` may ask for (the root is 0).
pub const MAX_DEPTH: u32 = 64;
/// The range of `min_gain`, the smallest relative cost reduction worth a split.
pub const MIN_GAIN_RANGE: std::ops::Range<f64> = 0.0..1.0;
/// The least `cell_cost`, atlas texels (it must be finite).
pub const MIN_CELL_COST: f64 = 0.0;

/// Default per-box cost, texels.
pub const DEFAULT_CELL_COST: f64 = 256.0;
/// Largest atlas side in texels: the smallest 3D-texture limit wgpu guarantees.
pub const MAX_ATLAS_SIDE: usize = 2048;

impl Default for EmptySpaceOptions {
    fn default() -> Self {
        EmptySpaceOptions {
            threshold: 0,
            min_box: 0,
            max_depth: 24,
            min_gain: 0.01,
            cell_cost: DEFAULT_CELL_COST,
            max_tiers: None,
            apron: true,
            bc_blocks: false,
            memory_limit: u64::MAX,
        }
    }
}

/// One band of the output.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandStats {
    pub first_level: u32,
    pub dims: [u32; 3],
    pub mip_count: u32,
    /// kd-tree boxes (0 for the tail, which keeps the source's box).
    pub boxes: usize,
    pub cells: usize,
    pub texel_bytes: u64,
    /// The tail: the source's levels stored whole.
    pub whole: bool,
}

/// What [`prune`] did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EmptySpaceStats {
    /// kd-tree boxes over all bricked tiers.
    pub boxes: usize,
    /// Prisms over all bands.
    pub cells: usize,
    pub source_dims: [u32; 3],
    pub source_mip_count: u32,
    /// The base texture (tier 0's atlas, or the source when kept whole).
    pub atlas_dims: [u32; 3],
    pub mip_count: u32,
    /// Base texture first, then the LOD bands.
    pub bands: Vec<BandStats>,
    /// First level stored whole (the tail); 0 when kept whole.
    pub tail_level: u32,
    /// Texel bytes (colour + normals, every level, every band) before and after.
    pub texel_bytes_before: u64,
    pub texel_bytes_after: u64,
    /// `1 − after / before`.
    pub saving: f64,
    pub voxels_before: u64,
    /// Level-0 voxels inside tier 0's boxes (what the renderer still rasterizes up close).
    pub voxels_kept: u64,
    /// No brick layout was smaller (or the sides are odd): the source was kept as it is.
    pub kept_whole: bool,
    /// Why the source was kept whole, if it was.
    pub note: Option<String>,
    pub seconds: f64,
}

/// A pruned asset and its statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct Pruned {
    pub asset: VolumeAsset,
    pub stats: EmptySpaceStats,
}

/// The world box of the cells, checked to be one box whose uvw spans the texture:
/// every vertex at `min + uvw · (max − min)`, uvw in `[0, 1]`.
fn world_box(cells: &[Prism]) -> Result<Option<(Vec3, Vec3)>, EmptySpaceError> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for c in cells {
        for p in &c.pos {
            lo = lo.min(Vec3::from(*p));
            hi = hi.max(Vec3::from(*p));
        }
    }
    if cells.is_empty() {
        return Ok(None);
    }
    let ext = hi - lo;
    let tol = 1e-4 * ext.max_element().max(f32::MIN_POSITIVE);
    for (i, c) in cells.iter().enumerate() {
        for k in 0..6 {
            let t = Vec3::from(c.uvw[k]);
            let p = Vec3::from(c.pos[k]);
            let inside = t.min_element() >= -1e-6 && t.max_element() <= 1.0 + 1e-6;
            if !inside || (lo + ext * t - p).abs().max_element() > tol {
                return Err(EmptySpaceError::NotABox(i));
            }
        }
    }
    Ok(Some((lo, hi)))
}

fn params_text(o: &EmptySpaceOptions, tail: u32, boxes: usize, dims: [u32; 3]) -> String {
    format!(
        "threshold={} min_box={} max_depth={} min_gain={} cell_cost={} apron={}{} tail_level={} boxes={} source_dims={}x{}x{}",
        o.threshold,
        o.min_box,
        o.max_depth,
        o.min_gain,
        o.cell_cost,
        if o.apron { "on" } else { "off" },
        if o.bc_blocks { " blocks=4x4" } else { "" },
        tail,
        boxes,
        dims[0],
        dims[1],
        dims[2]
    )
}

fn check_options(o: &EmptySpaceOptions) -> Result<(), EmptySpaceError> {
    if !MIN_GAIN_RANGE.contains(&o.min_gain) {
        return Err(EmptySpaceError::InvalidParam(format!(
            "minimum gain {} not in [{}, {})",
            o.min_gain, MIN_GAIN_RANGE.start, MIN_GAIN_RANGE.end
        )));
    }
    if !(o.cell_cost >= MIN_CELL_COST && o.cell_cost.is_finite()) {
        return Err(EmptySpaceError::InvalidParam(format!(
            "cell cost {} must be finite and ≥ {MIN_CELL_COST}",
            o.cell_cost
        )));
    }
    if o.max_depth > MAX_DEPTH {
        return Err(EmptySpaceError::InvalidParam(format!(
            "maximum depth {} is out of range (0 to {MAX_DEPTH})",
            o.max_depth
        )));
    }
    Ok(())
}

fn level_bytes(levels: &[Vec<u8>], normals: Option<&[Vec<u8>]>, from: usize) -> u64 {
    let n = |l: &[Vec<u8>]| l.iter().skip(from).map(|v| v.len() as u64).sum::<u64>();
    n(levels) + normals.map_or(0, n)
}

/// The levels a prune reads: dense bytes (an asset's, borrowed, or a thresholded copy) or
/// brick-sparse ([`prune_sparse`]).
enum Source<'a> {
    Dense {
        levels: Cow<'a, [Vec<u8>]>,
        normals: Option<Cow<'a, [Vec<u8>]>>,
    },
    Sparse(Vec<SparseLevel>),
}

impl Source<'_> {
    /// Texel bytes of levels `from..` (stored densely).
    fn bytes_from(&self, from: usize) -> u64 {
        match self {
            Source::Dense { levels, normals } => level_bytes(levels, normals.as_deref(), from),
            Source::Sparse(l) => l.iter().skip(from).map(SparseLevel::dense_bytes).sum(),
        }
    }
    fn all_zero(&self) -> bool {
        match self {
            Source::Dense { levels, .. } => levels.iter().all(|l| l.iter().all(|&b| b == 0)),
            Source::Sparse(l) => l.iter().all(SparseLevel::is_zero),
        }
    }
    /// Levels `from..`, dense (colour, normals).
    fn dense_from(&self, from: usize) -> (Vec<Vec<u8>>, Option<Vec<Vec<u8>>>) {
        match self {
            Source::Dense { levels, normals } => (
                levels[from..].to_vec(),
                normals.as_ref().map(|n| n[from..].to_vec()),
            ),
            Source::Sparse(l) => {
                let d: Vec<_> = l[from..].iter().map(SparseLevel::to_dense).collect();
                let has_n = d.first().is_some_and(|x| x.1.is_some());
                let normals =
                    has_n.then(|| d.iter().map(|x| x.1.clone().unwrap_or_default()).collect());
                (d.into_iter().map(|x| x.0).collect(), normals)
            }
        }
    }
    /// Bytes held in memory for this source (a dense one is the caller's asset, which
    /// is held in any case, plus its thresholded copy if there is one).
    fn held_bytes(&self) -> u64 {
        match self {
            Source::Dense { levels, .. } => {
                let copy = matches!(levels, Cow::Owned(_));
                (1 + copy as u64) * self.bytes_from(0)
            }
            Source::Sparse(l) => l.iter().map(SparseLevel::heap_bytes).sum(),
        }
    }
    /// Runs `job` on the texels of tier `k` (levels `k`, `k + 1`; level `k` is `n`).
    fn with_tier<J: TierJob>(&self, k: usize, n: [usize; 3], job: J) -> J::Out {
        match self {
            Source::Dense { levels, normals } => job.run(&TierSource {
                n,
                colour: [&levels[k], &levels[k + 1]],
                normals: normals
                    .as_ref()
                    .map(|nr| [nr[k].as_slice(), nr[k + 1].as_slice()]),
            }),
            Source::Sparse(l) => job.run(&SparseTier {
                levels: [&l[k], &l[k + 1]],
            }),
        }
    }
}

/// Work on one tier's texels, whichever way the source stores them.
trait TierJob {
    type Out;
    fn run<S: TierTexels>(self, src: &S) -> Self::Out;
}

/// Lays a tier out ([`plan_tier`]).
struct Plan<'a>(&'a TierParams);

impl TierJob for Plan<'_> {
    type Out = Option<TierPlan>;
    fn run<S: TierTexels>(self, src: &S) -> Option<TierPlan> {
        plan_tier(src, self.0)
    }
}

/// Fills a laid-out tier ([`fill_tier`]) whose world box is `.0`.
struct Fill((Vec3, Vec3), TierPlan);

impl TierJob for Fill {
    type Out = Tier;
    fn run<S: TierTexels>(self, src: &S) -> Tier {
        fill_tier(src, self.0, self.1)
    }
}

/// Removes the empty space of `asset` (see the module docs).
pub fn prune(asset: &VolumeAsset, o: &EmptySpaceOptions) -> Result<Pruned, EmptySpaceError> {
    let start = Instant::now();
    asset
        .validate()
        .map_err(|e| EmptySpaceError::InvalidAsset(e.to_string()))?;
    check_prunable(asset)?;
    check_options(o)?;
    // The source as it will be kept: faint texels dropped (in a copy; none without a
    // threshold).
    let mut levels = Cow::Borrowed(asset.levels.as_slice());
    let mut normals = asset.normals.as_deref().map(Cow::Borrowed);
    if o.threshold > 0 {
        let mut n = normals.as_mut().map(|n| n.to_mut());
        for (i, level) in levels.to_mut().iter_mut().enumerate() {
            apply_threshold(level, n.as_mut().map(|n| n[i].as_mut_slice()), o.threshold);
        }
    }
    prune_source(asset, Source::Dense { levels, normals }, o, start)
}

/// What a volume must be for [`prune`] and [`prune_sparse`] alike: not a shell (its
/// texture tiles), not pruned already, without LOD bands.
fn check_prunable(asset: &VolumeAsset) -> Result<(), EmptySpaceError> {
    if asset.header.is_shell() {
        return Err(EmptySpaceError::Shell);
    }
    if let Some(v) = asset.header.pruned() {
        return Err(EmptySpaceError::AlreadyPruned(v.to_string()));
    }
    if !asset.bands.is_empty() {
        return Err(EmptySpaceError::HasBands);
    }
    Ok(())
}

/// [`prune`] of a volume given brick-sparse: `asset` carries the header and cells (its
/// `levels` are ignored, and `normals` need only be `Some` when `levels` have normals),
/// `levels` the MIP levels `0..mip_count` of the header's dims. The result is the same
/// as [`prune`] of the dense asset, byte for byte; the dense volume is never
/// materialised (only the levels stored whole, the tail, and all of them when no brick
/// layout pays off).
pub fn prune_sparse(
    asset: &VolumeAsset,
    mut levels: Vec<SparseLevel>,
    o: &EmptySpaceOptions,
) -> Result<Pruned, EmptySpaceError> {
    let start = Instant::now();
    check_options(o)?;
    let bad = |m: String| Err(EmptySpaceError::InvalidAsset(m));
    let Some(vh) = asset.header.volume else {
        return bad("header has no `volume` section".into());
    };
    if levels.len() != vh.mip_count as usize {
        return bad(format!(
            "{} sparse levels for {} MIP levels",
            levels.len(),
            vh.mip_count
        ));
    }
    for (l, s) in levels.iter().enumerate() {
        let d = mip_dims(vh.dims, l as u32).map(|d| d as usize);
        if s.dims != d || s.has_normals() != vh.normal_kind().is_some() {
            return bad(format!("sparse level {l} is {:?}, expected {d:?}", s.dims));
        }
    }
    check_prunable(asset)?;
    for l in &mut levels {
        l.apply_threshold(o.threshold);
    }
    let shell = VolumeAsset {
        header: asset.header.clone(),
        levels: Vec::new(),
        normals: vh.normal_kind().map(|_| Vec::new()),
        bands: Vec::new(),
        cells: asset.cells.clone(),
    };
    prune_source(&shell, Source::Sparse(levels), o, start)
}

/// The prune of `src`, whose header and cells are `asset`'s (see the module docs).
fn prune_source(
    asset: &VolumeAsset,
    src: Source,
    o: &EmptySpaceOptions,
    start: Instant,
) -> Result<Pruned, EmptySpaceError> {
    let vh = asset.header.volume.expect("validated volume header");
    let dims0 = vh.dims;
    let world = world_box(&asset.cells)?;
    let before = src.bytes_from(0);
    let mut stats = EmptySpaceStats {
        boxes: 0,
        cells: asset.cells.len(),
        source_dims: dims0,
        source_mip_count: vh.mip_count,
        atlas_dims: dims0,
        mip_count: vh.mip_count,
        bands: Vec::new(),
        tail_level: 0,
        texel_bytes_before: before,
        texel_bytes_after: before,
        saving: 0.0,
        voxels_before: dims0.iter().map(|&d| u64::from(d)).product(),
        voxels_kept: 0,
        kept_whole: false,
        note: None,
        seconds: 0.0,
    };
    // The header and cells; every path below sets the texels (a clone of a dense
    // asset's levels would double the memory).
    let mut out = VolumeAsset {
        header: asset.header.clone(),
        levels: Vec::new(),
        normals: asset.normals.as_ref().map(|_| Vec::new()),
        bands: asset.bands.clone(),
        cells: asset.cells.clone(),
    };
    let all_zero = src.all_zero();
    let Some(world) = world.filter(|_| !all_zero) else {
        empty_asset(&mut out, o, dims0);
        stats.cells = 0;
        return Ok(finish(stats, out, start));
    };
    // Tiers while the level's sides are even and the next level exists.
    let tier_params = |k: u32| TierParams {
        kd: KdParams {
            block: 2,
            apron: o.apron,
            cell_cost: o.cell_cost,
            min_box: (o.min_box as usize).div_ceil(2 << k).max(1),
            max_depth: o.max_depth,
            min_gain: o.min_gain,
            pair_align: o.bc_blocks,
        },
        max_side: MAX_ATLAS_SIDE / 2,
    };
    let max_tiers = o.max_tiers.unwrap_or(u32::MAX).min(vh.mip_count - 1);
    let mut tiers: Vec<Tier> = Vec::new();
    let mut note = None;
    for k in 0..max_tiers {
        let n = mip_dims(dims0, k);
        if n.iter().any(|&d| d % 2 != 0) {
            if k == 0 {
                note = Some(format!(
                    "sides {}x{}x{} are not all even, so no brick can hold MIP level 1 exactly; bake with `billow voxelize --align 8`",
                    n[0], n[1], n[2]
                ));
            }
            break;
        }
        let n = n.map(|d| d as usize);
        let Some(plan) = src.with_tier(k as usize, n, Plan(&tier_params(k))) else {
            break;
        };
        // Refused before the atlas is allocated: the source, the tiers so far and this one.
        let held = src.held_bytes() + tiers.iter().map(Tier::bytes).sum::<u64>();
        if held + plan.bytes() > o.memory_limit {
            let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
            return Err(EmptySpaceError::TooMuchMemory {
                tier: k,
                needed_gib: gib(held + plan.bytes()),
                limit_gib: gib(o.memory_limit),
            });
        }
        tiers.push(src.with_tier(k as usize, n, Fill(world, plan)));
    }
    // The tail level K: the most tiers whose bytes are within 1 % of the fewest bytes
    // (coarse tiers cost next to nothing and cut the fragments of distant views), each
    // of them leaving out at least a tenth of its level.
    let cost = |k: usize| tiers[..k].iter().map(Tier::bytes).sum::<u64>() + src.bytes_from(k);
    let least = (0..=tiers.len()).map(cost).min().unwrap_or(0);
    let prunes = |t: &Tier| {
        let kept: u64 = t
            .boxes
            .iter()
            .map(|b| b.size().iter().map(|&v| v as u64).product::<u64>())
            .sum();
        10 * kept < 9 * t.blocks
    };
    let tail = (0..=tiers.len())
        .rev()
        .find(|&k| cost(k) as f64 <= 1.01 * least as f64 && (k == 0 || prunes(&tiers[k - 1])))
        .unwrap_or(0);
    if tail == 0 {
        (out.levels, out.normals) = src.dense_from(0);
        out.header.set_pruned(params_text(o, 0, 0, dims0));
        stats.kept_whole = true;
        stats.voxels_kept = stats.voxels_before;
        stats.note =
            note.or_else(|| Some("no brick layout is smaller than the source; kept whole".into()));
        stats.bands.push(BandStats {
            first_level: 0,
            dims: dims0,
            mip_count: vh.mip_count,
            boxes: 1,
            cells: asset.cells.len(),
            texel_bytes: before,
            whole: true,
        });
        return Ok(finish(stats, out, start));
    }
    tiers.truncate(tail);
    let mut tiers = tiers.into_iter();
    let base = tiers.next().expect("tier 0");
    stats.voxels_kept = base
        .boxes
        .iter()
        .map(|b| b.size().iter().map(|&s| 2 * s as u64).product::<u64>())
        .sum();
    let band_stats = |first_level: u32, t: &Tier| BandStats {
        first_level,
        dims: t.dims,
        mip_count: 2,
        boxes: t.boxes.len(),
        cells: t.cells.len(),
        texel_bytes: t.bytes(),
        whole: false,
    };
    stats.bands.push(band_stats(0, &base));
    stats.boxes = base.boxes.len();
    let v = out.header.volume.as_mut().expect("volume header");
    v.dims = base.dims;
    v.mip_count = 2;
    out.levels = base.colour;
    out.normals = base.normals;
    out.cells = base.cells;
    out.bands = Vec::new();
    for (k, t) in tiers.enumerate() {
        let k = k as u32 + 1;
        stats.bands.push(band_stats(k, &t));
        stats.boxes += t.boxes.len();
        out.bands.push(LodBand {
            first_level: k,
            dims: t.dims,
            levels: t.colour,
            normals: t.normals,
            cells: t.cells,
        });
    }
    let k = tail;
    let tail_bytes = src.bytes_from(k);
    let (tail_levels, tail_normals) = src.dense_from(k);
    drop(src);
    let tail_band = LodBand {
        first_level: k as u32,
        dims: mip_dims(dims0, k as u32),
        levels: tail_levels,
        normals: tail_normals,
        cells: asset.cells.clone(),
    };
    stats.bands.push(BandStats {
        first_level: tail_band.first_level,
        dims: tail_band.dims,
        mip_count: tail_band.levels.len() as u32,
        boxes: 0,
        cells: tail_band.cells.len(),
        texel_bytes: tail_bytes,
        whole: true,
    });
    out.bands.push(tail_band);
    stats.tail_level = k as u32;
    stats.cells = out.cells.len() + out.bands.iter().map(|b| b.cells.len()).sum::<usize>();
    out.header
        .set_pruned(params_text(o, k as u32, stats.boxes, dims0));
    Ok(finish(stats, out, start))
}

/// A valid asset that draws nothing: 1×1×1 transparent texture, one level, no cells.
fn empty_asset(out: &mut VolumeAsset, o: &EmptySpaceOptions, dims0: [u32; 3]) {
    out.levels = vec![vec![0; 4]];
    if let Some(n) = out.normals.as_mut() {
        *n = vec![vec![0; 4]];
    }
    out.cells = Vec::new();
    out.bands = Vec::new();
    let v = out.header.volume.as_mut().expect("volume header");
    v.dims = [1, 1, 1];
    v.mip_count = 1;
    out.header.set_pruned(params_text(o, 0, 0, dims0));
}

fn finish(mut stats: EmptySpaceStats, out: VolumeAsset, start: Instant) -> Pruned {
    let v = out.header.volume.expect("volume header");
    stats.atlas_dims = v.dims;
    stats.mip_count = v.mip_count;
    stats.texel_bytes_after = out.texel_bytes();
    stats.saving = if stats.texel_bytes_before > 0 {
        1.0 - stats.texel_bytes_after as f64 / stats.texel_bytes_before as f64
    } else {
        0.0
    };
    stats.seconds = start.elapsed().as_secs_f64();
    Pruned { asset: out, stats }
}
