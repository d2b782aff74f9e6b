//! `billow voxelize`: Volumetric Billboards volume generation (Decaudin & Neyret 2009,
//! §3.1–3.2, Figure 3).
//!
//! Pipeline, one direction at a time (`+X, −X, +Y, −Y, +Z, −Z`):
//! 1. [`slices`]: rasterize the scene into that direction's stack of slices (level 0);
//!    with [`Bake::Ao`], multiply its colour by the voxels' ambient occlusion (`ao`);
//! 2. [`mip`]: build that direction's MIP pyramid (composite along the view axis, average
//!    across);
//! 3. [`combine`]: fold every level into the combined volume (streamed for the presets;
//!    expressions and custom functions keep the six pyramids in f16 and combine at the end);
//!    normals, when asked for, are filtered with [`toksvig`] and summed the same way;
//! 4. [`quantize`]: RGBA8 `SrgbPremultiplied`, normals snorm8.
//!
//! Everything is deterministic: parallel loops write disjoint outputs, every reduction has a
//! fixed order, so the bytes do not depend on the number of threads.
//!
//! Memory (level 0 has `N` voxels; a full pyramid is at most `8/7 N`): one direction at a
//! time in f32 (16 N bytes + its next level), plus the streamed accumulator (16 or 20 bytes
//! per voxel of every level), plus f16 normals (9 N per direction + 8 per voxel of every
//! level); the RGBA8 output replaces the accumulator level by level at the end. Estimated
//! peaks at 512³: `mean` 4.6 GiB (6.9 with normals), `opaque` 5.2 GiB (7.4 with normals).
//! Expressions and custom functions keep six f16 pyramids (48 bytes per voxel of every
//! level): 7.5 GiB at 512³, 9.3 GiB with normals (over an 8 GiB budget: use a preset for
//! normals at 512³, or raise the limit).
//! AO adds 2 bytes per level-0 voxel and its BVH.
//! [`estimate_peak_bytes`] computes this and [`voxelize`] refuses grids above
//! [`VoxelizeOptions::memory_limit`] before allocating anything.

mod ao;
pub mod asset;
pub mod cells;
pub mod combine;
pub mod expr;
pub mod grid;
pub mod mip;
pub mod quantize;
mod shade;
mod slices;
pub mod toksvig;

use std::time::Instant;

use glam::{Vec3, Vec4};
use half::f16;

pub use ao::{Bake, AO_SEED, DEFAULT_AO_RAYS, DEFAULT_DISTANCE_FRACTION, MAX_AO_RAYS};
pub use asset::bake_params;
pub use cells::{box_prisms, Prism};
pub use combine::{clamp_premultiplied, Combine, CombineFn, CombineParseError, Preset};
pub use expr::{Expr, ExprError};
pub use grid::{fit_grid, GridError, GridSpec, Resolution, ResolutionError, MAX_AXIS};
pub use slices::MAX_SUPERSAMPLE;

use crate::scene::{Aabb, Scene};
use mip::{Grid3, Texel};

/// A view direction: the camera on that side of the object, looking at it.
/// `PosX` is the camera on the +X side looking towards −X.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dir {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl Dir {
    /// In the order the [`Combine`] functions receive them.
    pub const ALL: [Dir; 6] = [
        Dir::PosX,
        Dir::NegX,
        Dir::PosY,
        Dir::NegY,
        Dir::PosZ,
        Dir::NegZ,
    ];

    /// The view axis: 0 = x, 1 = y, 2 = z.
    pub fn axis(self) -> usize {
        self.index() / 2
    }
    /// Whether the camera is on the + side (front-to-back = decreasing coordinate).
    pub fn positive(self) -> bool {
        self.index().is_multiple_of(2)
    }
    /// Position in [`Dir::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
    /// The image axes (u, v): the two other axes in increasing order.
    pub fn image_axes(self) -> [usize; 2] {
        match self.axis() {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        }
    }
    /// `px nx py ny pz nz`, as in combine expressions.
    pub fn name(self) -> &'static str {
        ["px", "nx", "py", "ny", "pz", "nz"][self.index()]
    }
}

/// What `voxelize` does.
#[derive(Clone, Debug)]
pub struct VoxelizeOptions {
    pub resolution: Resolution,
    /// K: K×K stratified samples per voxel column (1..=8). Default 4.
    pub supersample: u32,
    pub combine: CombineFn,
    /// Capture normals (Toksvig-filtered, see [`toksvig`]).
    pub normals: bool,
    /// Empty space around the scene's bounds, in voxels (default ½; see [`grid`]).
    pub margin: f32,
    /// Use exactly this box for the grid instead of the scene's bounds plus margin.
    pub bounds: Option<Aabb>,
    /// Number of MIP levels; `None` = the full chain down to 1×1×1.
    pub mip_levels: Option<u32>,
    /// Refuse grids whose estimated peak memory exceeds this (bytes). Default 16 GiB.
    pub memory_limit: u64,
    /// Baked lighting multiplied into the level-0 colour (default none; see [`Bake`]).
    pub bake: Bake,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        VoxelizeOptions {
            resolution: Resolution::default(),
            supersample: 4,
            combine: CombineFn::default(),
            normals: false,
            margin: 0.5,
            bounds: None,
            mip_levels: None,
            memory_limit: 16 << 30,
            bake: Bake::None,
        }
    }
}

/// The stages `progress` reports, each with a fraction in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Rasterizing the slice stacks (fraction over all six directions).
    Rasterize,
    /// Building the per-direction MIP pyramids.
    Mip,
    /// Combining the six directions.
    Combine,
    /// Quantizing the output.
    Quantize,
}

/// Seconds spent per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    pub rasterize: f64,
    /// Baking lighting (AO ray tracing, BVH build included).
    pub bake: f64,
    pub mip: f64,
    pub combine: f64,
    pub quantize: f64,
    pub total: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoxelizeStats {
    /// Level-0 voxels whose alpha byte is not 0.
    pub non_empty_voxels: u64,
    /// Shaded fragments over all six directions.
    pub fragments: u64,
    pub triangles: usize,
    /// Estimated peak memory in bytes ([`estimate_peak_bytes`]).
    pub estimated_peak_bytes: u64,
    pub seconds: StageTimes,
}

/// The result: a MIP-mapped RGBA8 volume and its grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub grid: GridSpec,
    /// Per MIP level, RGBA8 `SrgbPremultiplied` (see [`quantize`]), x fastest, then y, then z.
    pub levels: Vec<Vec<u8>>,
    /// Per MIP level, snorm8 `[x, y, z, 0]` shortened normals, when asked for.
    pub normals: Option<Vec<Vec<u8>>>,
    pub stats: VoxelizeStats,
}

impl Volume {
    pub fn dims(&self) -> [u32; 3] {
        self.grid.dims
    }
    pub fn mip_count(&self) -> u32 {
        self.levels.len() as u32
    }
    pub fn level_dims(&self, level: u32) -> [u32; 3] {
        self.grid.level_dims(level)
    }
    /// Decoded premultiplied linear RGBA of voxel `p` at `level`.
    pub fn voxel(&self, level: u32, p: [u32; 3]) -> Vec4 {
        let d = self.level_dims(level);
        let (p, d) = (p.map(|x| x as usize), d.map(|x| x as usize));
        let i = 4 * (p[0] + d[0] * (p[1] + d[1] * p[2]));
        let b = &self.levels[level as usize][i..i + 4];
        quantize::decode_rgba8([b[0], b[1], b[2], b[3]])
    }
}

#[derive(Debug, thiserror::Error)]
pub enum VoxelizeError {
    #[error(transparent)]
    Resolution(#[from] ResolutionError),
    #[error("voxel grid: {0}")]
    Grid(#[from] GridError),
    #[error("the scene has no triangles to voxelize")]
    EmptyScene,
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    #[error("invalid option: {0}")]
    InvalidOption(String),
    #[error(
        "resolution {dims:?} needs about {needed_gib:.1} GiB of memory, more than the limit of {limit_gib:.1} GiB; lower the resolution or raise the memory limit"
    )]
    TooMuchMemory {
        dims: [u32; 3],
        needed_gib: f64,
        limit_gib: f64,
    },
}

/// Voxel counts of every level.
fn level_sizes(grid: &GridSpec, mip_count: u32) -> Vec<usize> {
    (0..mip_count)
        .map(|l| grid.level_dims(l).iter().map(|&d| d as usize).product())
        .collect()
}

/// Estimated peak memory of [`voxelize`] for a grid (see the module docs), in bytes: the
/// larger of the two phases — while the directions are processed (one direction's level 0
/// and next level, the accumulators or stored pyramids, the normal sums) and while the
/// levels are finished (accumulators turning into the RGBA8/snorm8 output level by level).
pub fn estimate_peak_bytes(
    dims: [u32; 3],
    mip_count: u32,
    combine: &CombineFn,
    normals: bool,
) -> u64 {
    let n: u64 = dims.iter().map(|&d| d as u64).product();
    let all: u64 = (0..mip_count)
        .map(|l| {
            grid::level_dims(dims, l)
                .iter()
                .map(|&d| d as u64)
                .product::<u64>()
        })
        .sum();
    let output = 4 * all * (1 + normals as u64);
    // Per direction: weighted normals in f16 (level 0 + next); sums (Σ Nw, Σ α) in f16.
    let (nrm_dir, nrm_acc) = if normals {
        (8 * n + n, 8 * all)
    } else {
        (0, 0)
    };
    let (dir, acc) = match combine {
        CombineFn::Preset(p) => (
            16 * n + 2 * n,
            if *p == Preset::Opaque { 20 } else { 16 } * all,
        ),
        // Six f16 pyramids (the direction being built is one of them) + its next level.
        _ => (n, 48 * all),
    };
    let building = dir + acc + nrm_dir + nrm_acc;
    let finishing = acc + nrm_acc + output;
    building.max(finishing) + (64 << 20)
}

/// [`estimate_peak_bytes`] plus what the bake needs (AO: its cache and the BVH).
fn estimate_bytes(scene: &Scene, opts: &VoxelizeOptions, dims: [u32; 3], mips: u32) -> u64 {
    let bake = match opts.bake {
        Bake::None => 0,
        Bake::Ao { .. } => ao::AoBaker::estimate_bytes(dims, scene.triangles.len()),
    };
    estimate_peak_bytes(dims, mips, &opts.combine, opts.normals) + bake
}

/// The grid `voxelize` would use for this scene and these options.
pub fn grid_for(scene: &Scene, opts: &VoxelizeOptions) -> Result<GridSpec, VoxelizeError> {
    opts.resolution.validate()?;
    match opts.bounds {
        Some(b) => Ok(fit_grid(&b, opts.resolution, 0.0)?),
        None => {
            let mut b = Aabb::EMPTY;
            for t in &scene.triangles {
                for v in &t.v {
                    if v.position.is_finite() {
                        b.grow(v.position);
                    }
                }
            }
            if b.is_empty() {
                return Err(VoxelizeError::EmptyScene);
            }
            Ok(fit_grid(&b, opts.resolution, opts.margin)?)
        }
    }
}

fn check(scene: &Scene, opts: &VoxelizeOptions) -> Result<(GridSpec, u32), VoxelizeError> {
    if !(1..=MAX_SUPERSAMPLE).contains(&opts.supersample) {
        return Err(VoxelizeError::InvalidOption(format!(
            "supersample must be 1..={MAX_SUPERSAMPLE}, got {}",
            opts.supersample
        )));
    }
    let grid = grid_for(scene, opts)?;
    let full = grid.full_mip_count();
    let mips = match opts.mip_levels {
        None => full,
        Some(m) if (1..=full).contains(&m) => m,
        Some(m) => {
            return Err(VoxelizeError::InvalidOption(format!(
                "mip levels must be 1..={full} for {:?}, got {m}",
                grid.dims
            )))
        }
    };
    opts.bake.validate().map_err(VoxelizeError::InvalidOption)?;
    let need = estimate_bytes(scene, opts, grid.dims, mips);
    if need > opts.memory_limit {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        return Err(VoxelizeError::TooMuchMemory {
            dims: grid.dims,
            needed_gib: gib(need),
            limit_gib: gib(opts.memory_limit),
        });
    }
    shade::validate_scene(scene).map_err(VoxelizeError::InvalidScene)?;
    Ok((grid, mips))
}

/// One direction's level-0 slices, decoded to f32 (for inspection, tests and slice export).
#[derive(Clone, Debug, PartialEq)]
pub struct SliceStack {
    pub grid: GridSpec,
    pub dir: Dir,
    /// Premultiplied linear RGBA, x fastest, then y, then z (the grid's layout, whatever `dir`).
    pub rgba: Vec<Vec4>,
    /// Alpha-weighted normal sums (`|n| ≤ α`), when normals were asked for.
    pub normals: Option<Vec<Vec3>>,
}

/// Rasterizes only the slice stack of direction `dir` (step 1 of the pipeline).
pub fn slice_stack(
    scene: &Scene,
    opts: &VoxelizeOptions,
    dir: Dir,
) -> Result<SliceStack, VoxelizeError> {
    let (grid, _) = check(scene, opts)?;
    let shader = shade::Shader::new(scene);
    let mut s = slices::rasterize::<[f32; 4]>(
        scene,
        &shader,
        &grid,
        dir,
        opts.supersample,
        opts.normals,
        &mut |_| {},
    );
    if let Some(mut ao) = ao_baker(scene, &shader, &grid, opts) {
        ao.apply(&mut s.rgba);
    }
    Ok(SliceStack {
        grid,
        dir,
        rgba: s.rgba.data.into_iter().map(Vec4::from_array).collect(),
        normals: s.nrm.map(|g| {
            g.data
                .into_iter()
                .map(|n| Vec3::from_slice(&n.load()[..3]))
                .collect()
        }),
    })
}

fn ao_baker<'a>(
    scene: &'a Scene,
    shader: &'a shade::Shader<'a>,
    grid: &GridSpec,
    opts: &VoxelizeOptions,
) -> Option<ao::AoBaker<'a>> {
    match opts.bake {
        Bake::None => None,
        Bake::Ao { rays, .. } => {
            let distance = opts.bake.ao_distance(grid).expect("AO distance");
            Some(ao::AoBaker::new(scene, shader, *grid, rays, distance))
        }
    }
}

/// Builds the pyramid of one direction from its level 0, handing each level to `sink`
/// (colour, weighted normals) as soon as the next one is built.
fn pyramid<T: Texel>(
    dir: Dir,
    mips: u32,
    mut rgba: Grid3<T>,
    mut nrm: Option<Grid3<[f16; 4]>>,
    mip_secs: &mut f64,
    mut sink: impl FnMut(usize, Grid3<T>, Option<Grid3<[f16; 4]>>),
) {
    for level in 0..mips as usize {
        if level + 1 == mips as usize {
            sink(level, rgba, nrm);
            return;
        }
        let t = Instant::now();
        let next_n = nrm
            .as_ref()
            .map(|n| toksvig::downsample_normals(n, &rgba, dir));
        let next = mip::downsample(&rgba, dir);
        *mip_secs += t.elapsed().as_secs_f64();
        sink(level, rgba, nrm);
        rgba = next;
        nrm = next_n;
    }
}

/// Voxelizes `scene` (see the module docs). `progress(stage, fraction)` is called from the
/// calling thread only.
pub fn voxelize(
    scene: &Scene,
    opts: &VoxelizeOptions,
    progress: &dyn Fn(Stage, f32),
) -> Result<Volume, VoxelizeError> {
    let t_all = Instant::now();
    let (grid, mips) = check(scene, opts)?;
    let shader = shade::Shader::new(scene);
    let sizes = level_sizes(&grid, mips);
    let mut times = StageTimes::default();
    let mut fragments = 0u64;
    let mut nacc = opts.normals.then(|| toksvig::NormalAccum::new(&sizes));
    let t = Instant::now();
    let mut baker = ao_baker(scene, &shader, &grid, opts);
    times.bake += t.elapsed().as_secs_f64();
    let k = opts.supersample;
    fn raster<T: Texel>(
        ctx: (&Scene, &shade::Shader, &GridSpec, u32, bool),
        dir: Dir,
        times: &mut StageTimes,
        baker: Option<&mut ao::AoBaker>,
        progress: &dyn Fn(Stage, f32),
    ) -> slices::DirSlices<T> {
        let (scene, shader, grid, k, normals) = ctx;
        let t = Instant::now();
        let d = dir.index() as f32;
        let mut s = slices::rasterize::<T>(scene, shader, grid, dir, k, normals, &mut |x| {
            progress(Stage::Rasterize, (d + x) / 6.0)
        });
        times.rasterize += t.elapsed().as_secs_f64();
        if let Some(b) = baker {
            let t = Instant::now();
            b.apply(&mut s.rgba);
            times.bake += t.elapsed().as_secs_f64();
        }
        s
    }
    let ctx = (scene, &shader, &grid, k, opts.normals);
    let levels: Vec<Vec<u8>> = match &opts.combine {
        CombineFn::Preset(p) => {
            let mut acc = combine::Accum::new(*p, &sizes);
            for dir in Dir::ALL {
                let s = raster::<[f32; 4]>(ctx, dir, &mut times, baker.as_mut(), progress);
                fragments += s.fragments;
                let mut fold_secs = 0.0;
                pyramid(dir, mips, s.rgba, s.nrm, &mut times.mip, |level, c, n| {
                    let t = Instant::now();
                    acc.fold(level, &c);
                    if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                        na.fold(level, n, &c);
                    }
                    fold_secs += t.elapsed().as_secs_f64();
                });
                times.combine += fold_secs;
                progress(Stage::Combine, (dir.index() + 1) as f32 / 6.0);
            }
            let t = Instant::now();
            let out = (0..mips as usize).map(|l| acc.finish_level(l)).collect();
            times.quantize += t.elapsed().as_secs_f64();
            out
        }
        f => {
            let mut pyrs: Vec<Vec<Option<Grid3<[f16; 4]>>>> = Vec::with_capacity(6);
            for dir in Dir::ALL {
                // Stored in f16 from the start (the arithmetic stays f32/f64).
                let s = raster::<[f16; 4]>(ctx, dir, &mut times, baker.as_mut(), progress);
                fragments += s.fragments;
                let mut levels = Vec::with_capacity(mips as usize);
                pyramid(dir, mips, s.rgba, s.nrm, &mut times.mip, |level, c, n| {
                    if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                        na.fold(level, n, &c);
                    }
                    levels.push(Some(c));
                });
                pyrs.push(levels);
                progress(Stage::Mip, (dir.index() + 1) as f32 / 6.0);
            }
            let t = Instant::now();
            let mut out = Vec::with_capacity(mips as usize);
            for l in 0..mips as usize {
                let grids: Vec<Grid3<[f16; 4]>> = pyrs
                    .iter_mut()
                    .map(|p| p[l].take().expect("level stored"))
                    .collect();
                let refs = [
                    &grids[0], &grids[1], &grids[2], &grids[3], &grids[4], &grids[5],
                ];
                out.push(combine::combine_level(f, refs));
                progress(Stage::Combine, (l + 1) as f32 / mips as f32);
            }
            times.combine += t.elapsed().as_secs_f64();
            out
        }
    };
    let t = Instant::now();
    let normals = nacc.map(|mut na| (0..mips as usize).map(|l| na.finish_level(l)).collect());
    let non_empty_voxels = levels[0].chunks_exact(4).filter(|p| p[3] != 0).count() as u64;
    times.quantize += t.elapsed().as_secs_f64();
    progress(Stage::Quantize, 1.0);
    times.total = t_all.elapsed().as_secs_f64();
    Ok(Volume {
        grid,
        levels,
        normals,
        stats: VoxelizeStats {
            non_empty_voxels,
            fragments,
            triangles: scene.triangles.len(),
            estimated_peak_bytes: estimate_bytes(scene, opts, grid.dims, mips),
            seconds: times,
        },
    })
}
