//! Empty-space removal for volume assets (VB paper §4 "Optimizations", Figure 14): a
//! kd-tree cuts the volume into non-empty boxes, the boxes are packed with an apron into
//! a smaller 3D atlas, and each box becomes two prism cells whose texture coordinates
//! point into the atlas. The result is an ordinary volume asset (formats/SPEC.md §8.6).
//!
//! Pipeline ([`prune`]):
//! 1. [`occupancy`]: the blocks (`A³` voxels, `A = 2^(E−1)`, `E` = exact levels) that any
//!    non-empty texel of levels `0..E` reaches through trilinear filtering;
//! 2. [`kdtree`]: split into tight boxes of needed blocks by the cost in its docs;
//! 3. [`pack`]: boxes + apron (`A` voxels per side) packed block-aligned into the atlas;
//! 4. [`bricks`]: every level of colour (and normals) copied brick by brick, aprons from the
//!    source's neighbouring texels of the *same* level;
//! 5. cells: each box as two prisms (the voxelizer's box split), uvw into the atlas.
//!
//! Levels `0..E` render exactly as the source (bit-identical samples) when the source's
//! sides are multiples of `2^(E−1)`; coarser levels are kept but approximate at brick
//! borders (see docs/emptyspace.md). When the atlas would not be smaller than the source,
//! the source is kept whole (one box, no apron).

pub mod bricks;
pub mod kdtree;
pub mod occupancy;
pub mod pack;
pub mod synthetic;

use std::time::Instant;

use billow_format::{full_mip_count, mip_dims, Prism, VolumeAsset, MAX_DIM};
use glam::Vec3;
use serde::Serialize;

use self::bricks::{fill_level, Brick, Channel};
use self::kdtree::{subdivide, BlockBox, KdParams};
use self::occupancy::needed_blocks;
use crate::voxelize::box_prisms;

/// Header `params` key that marks a pruned asset (its value records the parameters).
pub const PARAM_KEY: &str = "emptyspace";

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
    #[error("{0}")]
    InvalidParam(String),
    #[error("the bricks do not fit an atlas of at most {MAX_DIM} texels per side")]
    AtlasTooLarge,
}

/// Parameters of [`prune`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmptySpaceOptions {
    /// A texel is empty when its alpha byte is ≤ this (0: and all colour bytes 0).
    pub threshold: u8,
    /// Smallest box edge a split may leave, in voxels (rounded up to whole blocks).
    pub min_box: u32,
    /// Deepest kd-tree level (root = 0).
    pub max_depth: u32,
    /// Smallest relative cost reduction worth a split.
    pub min_gain: f64,
    /// MIP levels rendered exactly, `E ≥ 1`: bricks align to `A = 2^(E−1)` voxels.
    pub exact_levels: u32,
    /// Per-box cost `W` of the kd-tree, in voxels.
    pub cell_cost: f64,
    /// Aprons around bricks. `false` exists only to show what seams look like (tests).
    pub apron: bool,
}

/// Default exact levels: enough for the eval views at 1×, 4× and 16× of a 128³ volume.
pub const DEFAULT_EXACT_LEVELS: u32 = 4;
/// Default per-box cost, voxels.
pub const DEFAULT_CELL_COST: f64 = 4096.0;

impl Default for EmptySpaceOptions {
    fn default() -> Self {
        EmptySpaceOptions {
            threshold: 0,
            min_box: 0,
            max_depth: 24,
            min_gain: 0.01,
            exact_levels: DEFAULT_EXACT_LEVELS,
            cell_cost: DEFAULT_CELL_COST,
            apron: true,
        }
    }
}

/// What [`prune`] did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EmptySpaceStats {
    pub boxes: usize,
    pub cells: usize,
    pub source_dims: [u32; 3],
    pub atlas_dims: [u32; 3],
    pub source_mip_count: u32,
    pub mip_count: u32,
    /// Levels that render exactly as the source (`E`, capped by the stored levels).
    pub exact_levels: u32,
    /// Brick alignment and apron, voxels.
    pub block: u32,
    /// The source's sides are multiples of `block`, so levels `0..exact_levels` are
    /// byte-exact copies; otherwise levels ≥ 1 are resampled at the bricks (approximate).
    pub aligned: bool,
    /// Texel bytes (colour + normals, every level) before and after.
    pub texel_bytes_before: u64,
    pub texel_bytes_after: u64,
    /// `1 − after / before`.
    pub saving: f64,
    pub voxels_before: u64,
    /// Level-0 voxels inside the boxes (what the renderer still rasterizes).
    pub voxels_kept: u64,
    /// The atlas was not smaller, so the source was kept as one box.
    pub kept_whole: bool,
    pub seconds: f64,
}

/// A pruned asset and its statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct Pruned {
    pub asset: VolumeAsset,
    pub stats: EmptySpaceStats,
}

fn texel_bytes(a: &VolumeAsset) -> u64 {
    let c: usize = a.levels.iter().map(Vec::len).sum();
    let n: usize = a.normals.iter().flatten().map(Vec::len).sum();
    (c + n) as u64
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

fn params_text(o: &EmptySpaceOptions, e: u32, boxes: usize, dims: [u32; 3]) -> String {
    format!(
        "threshold={} min_box={} max_depth={} min_gain={} exact_levels={} cell_cost={} apron={} boxes={} source_dims={}x{}x{}",
        o.threshold,
        o.min_box,
        o.max_depth,
        o.min_gain,
        e,
        o.cell_cost,
        if o.apron { "on" } else { "off" },
        boxes,
        dims[0],
        dims[1],
        dims[2]
    )
}

/// Removes the empty space of `asset` (see the module docs).
pub fn prune(asset: &VolumeAsset, o: &EmptySpaceOptions) -> Result<Pruned, EmptySpaceError> {
    let start = Instant::now();
    asset
        .validate()
        .map_err(|e| EmptySpaceError::InvalidAsset(e.to_string()))?;
    if asset.header.params.contains_key("shell") {
        return Err(EmptySpaceError::Shell);
    }
    if let Some(v) = asset.header.params.get(PARAM_KEY) {
        return Err(EmptySpaceError::AlreadyPruned(v.clone()));
    }
    if o.exact_levels == 0 || o.exact_levels > 13 {
        return Err(EmptySpaceError::InvalidParam(format!(
            "exact levels {} not in 1..=13",
            o.exact_levels
        )));
    }
    if !(0.0..1.0).contains(&o.min_gain) {
        return Err(EmptySpaceError::InvalidParam(format!(
            "minimum gain {} not in [0, 1)",
            o.min_gain
        )));
    }
    if !(o.cell_cost >= 0.0 && o.cell_cost.is_finite()) {
        return Err(EmptySpaceError::InvalidParam(format!(
            "cell cost {} must be finite and ≥ 0",
            o.cell_cost
        )));
    }
    let vh = asset.header.volume.expect("validated volume header");
    let dims0 = vh.dims;
    let n0 = dims0.map(|d| d as usize);
    let e = o.exact_levels.min(vh.mip_count);
    let block = 1usize << (e - 1);
    let world = world_box(&asset.cells)?;
    let level_dims: Vec<[u32; 3]> = (0..vh.mip_count).map(|l| mip_dims(dims0, l)).collect();
    let grid = needed_blocks(
        &asset.levels,
        &level_dims,
        dims0,
        block,
        e as usize,
        o.threshold,
    );
    let kd = KdParams {
        block,
        apron: if o.apron { block } else { 0 },
        cell_cost: o.cell_cost,
        min_box: (o.min_box as usize).div_ceil(block).max(1),
        max_depth: o.max_depth,
        min_gain: o.min_gain,
    };
    let boxes: Vec<BlockBox> = match world {
        Some(_) => subdivide(&grid, &kd),
        None => Vec::new(),
    };
    let before = texel_bytes(asset);
    let mut stats = EmptySpaceStats {
        boxes: boxes.len(),
        cells: 2 * boxes.len(),
        source_dims: dims0,
        atlas_dims: dims0,
        source_mip_count: vh.mip_count,
        mip_count: vh.mip_count,
        exact_levels: e,
        block: block as u32,
        aligned: dims0.iter().all(|&d| (d as usize).is_multiple_of(block)),
        texel_bytes_before: before,
        texel_bytes_after: before,
        saving: 0.0,
        voxels_before: n0.iter().map(|&d| d as u64).product(),
        voxels_kept: 0,
        kept_whole: false,
        seconds: 0.0,
    };
    let mut out = asset.clone();
    let whole = |out: &mut VolumeAsset, stats: &mut EmptySpaceStats| {
        stats.boxes = 1;
        stats.cells = asset.cells.len();
        stats.voxels_kept = stats.voxels_before;
        stats.kept_whole = true;
        out.header
            .params
            .insert(PARAM_KEY.into(), params_text(o, e, 1, dims0));
    };
    let Some((wlo, whi)) = world else {
        // No cells: nothing is drawn, nothing needs storing.
        empty_asset(&mut out, o, e, dims0);
        stats.cells = 0;
        stats.boxes = 0;
        finish(&mut stats, &out, start);
        return Ok(Pruned { asset: out, stats });
    };
    if boxes.is_empty() {
        empty_asset(&mut out, o, e, dims0);
        finish(&mut stats, &out, start);
        return Ok(Pruned { asset: out, stats });
    }
    let grid_all = BlockBox {
        lo: [0; 3],
        hi: grid.dims,
    };
    if boxes.len() == 1 && boxes[0] == grid_all {
        whole(&mut out, &mut stats);
        finish(&mut stats, &out, start);
        return Ok(Pruned { asset: out, stats });
    }
    let apron_blocks = usize::from(o.apron);
    let sizes: Vec<[usize; 3]> = boxes
        .iter()
        .map(|b| b.size().map(|s| s + 2 * apron_blocks))
        .collect();
    let packing =
        pack::pack(&sizes, MAX_DIM as usize / block).ok_or(EmptySpaceError::AtlasTooLarge)?;
    let nd0 = packing.dims.map(|d| d * block);
    let atlas_dims = nd0.map(|d| d as u32);
    let mip_count = vh.mip_count.min(full_mip_count(atlas_dims));
    let atlas_bytes: u64 = (0..mip_count)
        .map(|l| {
            mip_dims(atlas_dims, l)
                .iter()
                .map(|&d| u64::from(d))
                .product::<u64>()
                * 4
        })
        .sum::<u64>()
        * if asset.normals.is_some() { 2 } else { 1 };
    if atlas_bytes >= before {
        whole(&mut out, &mut stats);
        finish(&mut stats, &out, start);
        return Ok(Pruned { asset: out, stats });
    }
    let bricks: Vec<Brick> = boxes
        .iter()
        .zip(&packing.origins)
        .zip(&sizes)
        .map(|((b, &org), sz)| Brick {
            src: b.lo.map(|v| v * block),
            dst: [0, 1, 2].map(|a| (org[a] + apron_blocks) * block),
            slot_lo: org.map(|v| v * block),
            slot_hi: [0, 1, 2].map(|a| (org[a] + sz[a]) * block),
        })
        .collect();
    let fill = |ch: Channel, src_levels: &[Vec<u8>]| -> Vec<Vec<u8>> {
        (0..mip_count)
            .map(|l| {
                let nd = mip_dims(atlas_dims, l).map(|d| d as usize);
                let ns = level_dims[l as usize].map(|d| d as usize);
                let mut dst = vec![0u8; nd.iter().product::<usize>() * 4];
                fill_level(
                    ch,
                    &src_levels[l as usize],
                    ns,
                    n0,
                    &mut dst,
                    nd,
                    nd0,
                    &bricks,
                );
                dst
            })
            .collect()
    };
    out.levels = fill(Channel::Colour(asset.header.colour_space), &asset.levels);
    out.normals = asset.normals.as_ref().map(|n| fill(Channel::Normal, n));
    // Cells: world box and atlas uvw of each brick (its true extent, not the rounded slot).
    let ext = whi - wlo;
    out.cells = Vec::with_capacity(2 * boxes.len());
    let mut kept = 0u64;
    for (b, br) in boxes.iter().zip(&bricks) {
        let s: [usize; 3] = [0, 1, 2].map(|a| (b.hi[a] * block).min(n0[a]) - b.lo[a] * block);
        kept += s.iter().map(|&v| v as u64).product::<u64>();
        let w = |a: usize, v: usize| wlo[a] + ext[a] * (v as f64 / n0[a] as f64) as f32;
        let pmin = Vec3::new(w(0, br.src[0]), w(1, br.src[1]), w(2, br.src[2]));
        let pmax = Vec3::new(
            w(0, br.src[0] + s[0]),
            w(1, br.src[1] + s[1]),
            w(2, br.src[2] + s[2]),
        );
        let t = |a: usize, v: usize| (v as f64 / nd0[a] as f64) as f32;
        let tlo = Vec3::new(t(0, br.dst[0]), t(1, br.dst[1]), t(2, br.dst[2]));
        let thi = Vec3::new(
            t(0, br.dst[0] + s[0]),
            t(1, br.dst[1] + s[1]),
            t(2, br.dst[2] + s[2]),
        );
        for mut p in box_prisms(pmin, pmax) {
            for uvw in p.uvw.iter_mut() {
                let u = Vec3::from(*uvw);
                *uvw = (tlo + (thi - tlo) * u).to_array();
            }
            out.cells.push(p);
        }
    }
    let v = out.header.volume.as_mut().expect("volume header");
    v.dims = atlas_dims;
    v.mip_count = mip_count;
    out.header
        .params
        .insert(PARAM_KEY.into(), params_text(o, e, boxes.len(), dims0));
    stats.atlas_dims = atlas_dims;
    stats.mip_count = mip_count;
    stats.voxels_kept = kept;
    finish(&mut stats, &out, start);
    Ok(Pruned { asset: out, stats })
}

/// A valid asset that draws nothing: 1×1×1 transparent texture, one level, no cells.
fn empty_asset(out: &mut VolumeAsset, o: &EmptySpaceOptions, e: u32, dims0: [u32; 3]) {
    out.levels = vec![vec![0; 4]];
    if let Some(n) = out.normals.as_mut() {
        *n = vec![vec![0; 4]];
    }
    out.cells = Vec::new();
    let v = out.header.volume.as_mut().expect("volume header");
    v.dims = [1, 1, 1];
    v.mip_count = 1;
    out.header
        .params
        .insert(PARAM_KEY.into(), params_text(o, e, 0, dims0));
}

fn finish(stats: &mut EmptySpaceStats, out: &VolumeAsset, start: Instant) {
    let v = out.header.volume.expect("volume header");
    stats.atlas_dims = v.dims;
    stats.mip_count = v.mip_count;
    stats.texel_bytes_after = texel_bytes(out);
    stats.saving = if stats.texel_bytes_before > 0 {
        1.0 - stats.texel_bytes_after as f64 / stats.texel_bytes_before as f64
    } else {
        0.0
    };
    stats.seconds = start.elapsed().as_secs_f64();
}
