//! `billow voxelize`: Volumetric Billboards volume generation (Decaudin & Neyret 2009,
//! §3.1–3.2, Figure 3).
//!
//! Pipeline, one direction at a time (`+X, −X, +Y, −Y, +Z, −Z`):
//! 1. `slices`: rasterize the scene into that direction's stack of slices (level 0),
//!    kept **sparse** (the non-empty voxels of every image row); with [`Bake::Ao`],
//!    multiply its colour by the voxels' ambient occlusion (`ao`). When many triangles
//!    are double-sided, the two directions of an axis are rasterized in one pass (each
//!    triangle covered and shaded once for both, `slices::passes`; same result);
//! 2. [`mip`]: build that direction's MIP pyramid (composite along the view axis, average
//!    across), level 1 straight from the sparse level 0; every level above 0 is
//!    brick-sparse (`bricks`: 8³ bricks, only those near non-empty voxels allocated);
//! 3. [`combine`]: fold every coarser level into the combined volume as it is built
//!    (streamed for the presets; expressions and custom functions keep the six pyramids in
//!    f16 and combine at the end); with a preset, level 0 is combined at the end from the
//!    six sparse stacks, one z plane at a time, or, for [`voxelize_sparse`] (`--prune`),
//!    folded direction by direction into one sparse accumulator (`level0`) so that each
//!    stack is freed once its pyramid is built; normals, when asked for, are filtered with
//!    [`toksvig`] and summed the same way;
//! 4. [`quantize`]: RGBA8 `SrgbPremultiplied`, normals snorm8.
//!
//! [`bake()`] is all of `billow voxelize` as one call: this pipeline with normals as asked
//! ([`bake_with_normals`]), optionally pruned of its empty space ([`voxelize_sparse`] and
//! [`crate::emptyspace::prune_sparse`]), the asset with its header's bake parameters, and
//! the BC7 blocks; the CLI only adds its progress bar, warnings and exit codes.
//!
//! Everything is deterministic: parallel loops write disjoint outputs, every reduction has a
//! fixed order, so the bytes do not depend on the number of threads.
//!
//! Memory (level 0 has `N` voxels, `S ≤ N` of them non-empty from one direction; a full
//! pyramid is at most `8/7 N`): the six sparse level-0 stacks (20 bytes per non-empty voxel,
//! 32 with normals), one direction's brick-sparse f32 levels 1 and 2 while its pyramid is
//! built, the streamed brick-sparse accumulators of the levels above 0 (16 or 20 bytes per
//! voxel of an allocated brick, plus 8 for normals), and the RGBA8 (+ snorm8) output. No
//! level-0 grid is ever dense with a preset. [`voxelize_sparse`] holds instead of the six
//! stacks the level-0 accumulator (per voxel seen by any direction: 4 bytes of index, 16
//! or 20 of colour, 12 more with normals for `mean` and `opaque`, 16 for `max` and `min`)
//! beside at most the two stacks of one rasterization pass, and keeps its output packed
//! (only the texels with a non-zero byte of each brick, [`SparseLevel`]).
//! Expressions and custom functions keep six brick-sparse f16 pyramids (8 bytes per voxel
//! of every allocated brick, per direction) and evaluate the function only in bricks some
//! direction holds (elsewhere all six values are zero: `f` of six zeros, computed once).
//! The estimate still counts them dense (48 bytes per voxel of every level: 7.5 GiB at
//! 512³, 9.3 GiB with normals), an upper bound: the bench tree at 512³ peaks at 3.2 GiB.
//! AO adds 2 bytes per level-0 voxel and its BVH.
//! [`estimate_peak_bytes_sparse`] computes this (bounding `S` by the triangles' bounding
//! boxes) and [`voxelize`] refuses grids above [`VoxelizeOptions::memory_limit`] before
//! allocating anything.

mod ao;
pub mod asset;
mod bake;
pub(crate) mod brick_grid;
pub mod combine;
pub mod coverage;
pub mod dense;
pub mod expr;
mod fragments;
pub mod grid;
pub mod grid3;
mod lanes;
mod level0;
mod memory;
pub mod mip;
mod normals_mode;
pub mod quantize;
mod slices;
mod sparse;
pub mod toksvig;

use std::time::Instant;

use glam::{Vec3, Vec4};
use half::f16;

pub use ao::{
    voxel_stream, AoRays, Bake, AO_SEED, DEFAULT_AO_RAYS, DEFAULT_DISTANCE_FRACTION, MAX_AO_RAYS,
};
pub use asset::{bake_params, bake_params_for};
pub use bake::{bake, BakeError, BakeHooks, BakeOptions, Baked};
pub use combine::{Combine, CombineFn, CombineParseError, Preset};
pub use coverage::CoverageScales;
pub use expr::{Expr, ExprError};
use fragments::NormalSums;
pub use grid::{
    default_align, fit_grid, GridError, GridSpec, Resolution, ResolutionError, MAX_AXIS, MAX_MARGIN,
};
use memory::estimate_bytes;
pub use memory::{estimate_peak_bytes, estimate_peak_bytes_pruned, estimate_peak_bytes_sparse};
pub use normals_mode::{bake_with_normals, MemoryRefusal, NormalsMode, NormalsOutcome};
pub use quantize::clamp_premultiplied;
pub use slices::MAX_SUPERSAMPLE;
use sparse::sparse_level;
pub use sparse::{voxelize_sparse, SparseVolume};

use crate::material;
use crate::scene::Scene;
use crate::sparse_level::SparseLevel;
use billow_core::Aabb;
use grid3::Texel;

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
    /// With `normals`: store the diagonal of the normals' second moment `E[n∘n]` instead of
    /// Toksvig's mean (lit two-sided at runtime, SPEC §8.4a; [`toksvig`], "Moments"). What
    /// `--normals auto` stores where the mean normals are incoherent (foliage).
    pub moments: bool,
    /// Empty space around the scene's bounds, in voxels (default ½; see [`grid`]).
    pub margin: f32,
    /// Use exactly this box for the grid instead of the scene's bounds plus margin.
    pub bounds: Option<Aabb>,
    /// Round every side of the grid up to a multiple of this many voxels (1 = off), growing
    /// the box symmetrically with empty voxels of the same size (see [`grid::align_grid`]).
    pub align: u32,
    /// Number of MIP levels; `None` = the full chain down to 1×1×1.
    pub mip_levels: Option<u32>,
    /// Refuse grids whose estimated peak memory exceeds this (bytes). Default 16 GiB.
    pub memory_limit: u64,
    /// Baked lighting multiplied into the level-0 colour (default none; see [`Bake`]).
    pub bake: Bake,
    /// Whether the volume is a closed surface, whose level 0 keeps its opacity
    /// (`CoverageScales::settle_level0`), as judged before the bake (`--normals auto`:
    /// [`toksvig::judge_normals`]); `None`: judged on the bake's own mean normals, and
    /// not a surface without them.
    pub surface: Option<bool>,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        VoxelizeOptions {
            resolution: Resolution::default(),
            supersample: 4,
            combine: CombineFn::default(),
            normals: false,
            moments: false,
            margin: 0.5,
            bounds: None,
            align: 1,
            mip_levels: None,
            memory_limit: 16 << 30,
            bake: Bake::None,
            surface: None,
        }
    }
}

/// The stages `progress` reports, each with a fraction in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Rasterizing the slice stacks (fraction over all six directions).
    Rasterize,
    /// Building the per-direction MIP pyramids (fraction of directions done; each
    /// direction is rasterized, then its pyramid built, before the next one).
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
    /// Per MIP level, snorm8 `[x, y, z, 0]` shortened normals, when asked for (with
    /// `moments`: the diagonal of their second moment).
    pub normals: Option<Vec<Vec<u8>>>,
    /// Whether `normals` holds second moments ([`VoxelizeOptions::moments`]).
    pub moments: bool,
    pub stats: VoxelizeStats,
    /// The optical-depth scale of every level and what it matched
    /// ([`coverage`]: coverage that holds at every distance).
    pub coverage: CoverageScales,
    /// For a bake with mean normals:
    /// [`toksvig::normal_coherence`] at level [`toksvig::AUTO_NORMALS_LEVEL`] (clamped).
    /// When it passes ([`toksvig::keeps`]) the volume is a surface and its level 0 is not
    /// thinned ([`CoverageScales`]).
    pub normal_coherence: Option<f32>,
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
    #[error("nothing to bake: the scene has no triangles to voxelize")]
    EmptyScene,
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// An option out of its range, or one that does not apply: `option` says which
    /// field of [`VoxelizeOptions`], so a caller can name its own flag for it.
    #[error("invalid option: {option}: {message}")]
    InvalidOption { option: OptionName, message: String },
    #[error(
        "resolution {dims:?} needs about {needed_gib:.1} GiB of memory, more than the limit of {limit_gib:.1} GiB; lower the resolution or raise the memory limit"
    )]
    TooMuchMemory {
        dims: [u32; 3],
        needed_gib: f64,
        limit_gib: f64,
    },
}

/// The field of [`VoxelizeOptions`] an [`VoxelizeError::InvalidOption`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OptionName {
    Supersample,
    MipLevels,
    Bake,
    Combine,
}

impl std::fmt::Display for OptionName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OptionName::Supersample => "supersample",
            OptionName::MipLevels => "mip_levels",
            OptionName::Bake => "bake",
            OptionName::Combine => "combine",
        })
    }
}

/// The grid `voxelize` would use for this scene and these options.
pub fn grid_for(scene: &Scene, opts: &VoxelizeOptions) -> Result<GridSpec, VoxelizeError> {
    opts.resolution.validate()?;
    let g = unaligned_grid(scene, opts)?;
    Ok(grid::align_grid(&g, opts.align)?)
}

fn unaligned_grid(scene: &Scene, opts: &VoxelizeOptions) -> Result<GridSpec, VoxelizeError> {
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

/// The grid, the MIP count and the memory estimate of a bake, after checking the options
/// and the estimate against the limit.
fn check(
    scene: &Scene,
    opts: &VoxelizeOptions,
    sparse: bool,
) -> Result<(GridSpec, u32, u64), VoxelizeError> {
    if !(1..=MAX_SUPERSAMPLE).contains(&opts.supersample) {
        return Err(VoxelizeError::InvalidOption {
            option: OptionName::Supersample,
            message: format!(
                "{} is out of range (1 to {MAX_SUPERSAMPLE})",
                opts.supersample
            ),
        });
    }
    let grid = grid_for(scene, opts)?;
    let full = grid.full_mip_count();
    let mips = match opts.mip_levels {
        None => full,
        Some(m) if (1..=full).contains(&m) => m,
        Some(m) => {
            return Err(VoxelizeError::InvalidOption {
                option: OptionName::MipLevels,
                message: format!(
                    "{m} is out of range (1 to {full} for a {}x{}x{} grid)",
                    grid.dims[0], grid.dims[1], grid.dims[2]
                ),
            })
        }
    };
    opts.bake
        .validate()
        .map_err(|message| VoxelizeError::InvalidOption {
            option: OptionName::Bake,
            message,
        })?;
    let need = estimate_bytes(scene, opts, &grid, mips, sparse);
    if need > opts.memory_limit {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        return Err(VoxelizeError::TooMuchMemory {
            dims: grid.dims,
            needed_gib: gib(need),
            limit_gib: gib(opts.memory_limit),
        });
    }
    material::validate_scene(scene).map_err(VoxelizeError::InvalidScene)?;
    Ok((grid, mips, need))
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
    let (grid, ..) = check(scene, opts, false)?;
    let shader = material::Shader::new(scene);
    let side = if dir.positive() { 1 } else { 2 };
    let mut s = slices::rasterize(
        &mut Default::default(),
        scene,
        &shader,
        &grid,
        dir.axis(),
        side,
        opts.supersample,
        NormalSums::of(opts.normals, opts.moments),
        &mut |_| {},
    )
    .pop()
    .expect("one direction");
    if let Some(mut ao) = ao_baker(scene, &shader, &grid, opts) {
        ao.apply_sparse(&mut s);
    }
    let rgba = s.to_dense::<[f32; 4]>();
    let normals = s.dense_normals();
    Ok(SliceStack {
        grid,
        dir,
        rgba: rgba.data.into_iter().map(Vec4::from_array).collect(),
        normals: normals.map(|g| {
            g.data
                .into_iter()
                .map(|n| Vec3::from_slice(&n.load()[..3]))
                .collect()
        }),
    })
}

fn ao_baker<'a>(
    scene: &'a Scene,
    shader: &'a material::Shader<'a>,
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

/// One level of a direction's pyramid, as [`pyramid`] hands it on.
// One value per MIP step, moved not copied: its size does not matter.
#[allow(clippy::large_enum_variant)]
enum Level<'a, T> {
    /// Level 0, sparse.
    Zero(&'a slices::DirSlices),
    /// A coarser level: colour and weighted normals, brick-sparse (the normals on the
    /// colour's bricks).
    Dense(
        brick_grid::Bricked<T>,
        Option<brick_grid::Bricked<[f16; 4]>>,
    ),
}

/// Builds the pyramid of one direction from its sparse level 0: level 1 is filtered
/// straight from it ([`mip::downsample_sparse`]) and every further level from the one
/// before; each level goes to `sink` as soon as the next one is built.
fn pyramid<T: Texel>(
    s: &slices::DirSlices,
    mips: u32,
    mip_secs: &mut f64,
    mut sink: impl FnMut(usize, Level<T>),
) {
    let dir = s.dir;
    let t = Instant::now();
    let first = (mips > 1).then(|| mip::downsample_sparse::<T>(s));
    *mip_secs += t.elapsed().as_secs_f64();
    sink(0, Level::Zero(s));
    let Some((mut rgba, mut nrm)) = first else {
        return;
    };
    for level in 1..mips as usize {
        if level + 1 == mips as usize {
            sink(level, Level::Dense(rgba, nrm));
            return;
        }
        let t = Instant::now();
        let next = mip::downsample_bricks::<T, T>(&rgba, None, dir, None);
        let next_n = nrm
            .as_ref()
            .map(|n| toksvig::downsample_normals(n, &rgba, dir, &next.layout));
        *mip_secs += t.elapsed().as_secs_f64();
        sink(level, Level::Dense(rgba, nrm));
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
    let (grid, out, stats, mut coverage) = voxelize_as(scene, opts, progress, false)?;
    let Output::Dense(mut levels, normals) = out else {
        unreachable!("a dense voxelize")
    };
    let (normal_coherence, surface) = toksvig::judge_baked(
        levels.len(),
        normals.is_some() && !opts.moments,
        opts.surface,
        |l| {
            let n = normals.as_ref()?;
            toksvig::normal_coherence(levels.get(l)?, n.get(l)?)
        },
    );
    coverage.settle_level0(surface, |k| coverage::scale_level_rgba8(&mut levels[0], k));
    let moments = opts.moments && normals.is_some();
    Ok(Volume {
        grid,
        levels,
        normals,
        moments,
        stats,
        coverage,
        normal_coherence,
    })
}

/// What [`voxelize_as`] produces.
enum Output {
    /// RGBA8 levels and snorm8 normals, dense.
    Dense(Vec<Vec<u8>>, Option<Vec<Vec<u8>>>),
    Sparse(Vec<SparseLevel>),
}

fn voxelize_as(
    scene: &Scene,
    opts: &VoxelizeOptions,
    progress: &dyn Fn(Stage, f32),
    sparse: bool,
) -> Result<(GridSpec, Output, VoxelizeStats, CoverageScales), VoxelizeError> {
    let t_all = Instant::now();
    let (grid, mips, estimated_peak_bytes) = check(scene, opts, sparse)?;
    let shader = material::Shader::new(scene);
    let dims: Vec<[usize; 3]> = (0..mips)
        .map(|l| grid.level_dims(l).map(|d| d as usize))
        .collect();
    let mut times = StageTimes::default();
    let mut fragments = 0u64;
    // Level-0 voxels with a non-zero alpha byte, when the level-0 combine counted them.
    let mut non_empty = None;
    // With a preset, level 0's normals are combined with its colour (see below).
    let mut nacc = match opts.combine {
        CombineFn::Preset(_) => None,
        _ => opts.normals.then(|| toksvig::NormalAccum::new(&dims, true)),
    };
    let t = Instant::now();
    let mut baker = ao_baker(scene, &shader, &grid, opts);
    times.bake += t.elapsed().as_secs_f64();
    let k = opts.supersample;
    /// The directions of `axis` in `sides` (see `slices::passes`), + first.
    fn raster(
        bufs: &mut slices::SetupBufs,
        ctx: (&Scene, &material::Shader, &GridSpec, u32, NormalSums),
        (axis, sides): (usize, u8),
        times: &mut StageTimes,
        baker: Option<&mut ao::AoBaker>,
        progress: &dyn Fn(Stage, f32),
    ) -> Vec<slices::DirSlices> {
        let (scene, shader, grid, k, normals) = ctx;
        let t = Instant::now();
        // Progress in directions done: this pass covers [d, d + n).
        let (d, n) = (
            (2 * axis) as f32 + sides.trailing_zeros() as f32,
            sides.count_ones() as f32,
        );
        let mut stacks = slices::rasterize(
            bufs,
            scene,
            shader,
            grid,
            axis,
            sides,
            k,
            normals,
            &mut |x| progress(Stage::Rasterize, (d + n * x) / 6.0),
        );
        times.rasterize += t.elapsed().as_secs_f64();
        if let Some(b) = baker {
            let t = Instant::now();
            stacks.iter_mut().for_each(|s| b.apply_sparse(s));
            times.bake += t.elapsed().as_secs_f64();
        }
        stacks
    }
    let ctx = (
        scene,
        &shader,
        &grid,
        k,
        NormalSums::of(opts.normals, opts.moments),
    );
    // (axis, sides) in the order the directions are combined: +X, −X, +Y, …
    let sides = slices::passes(scene);
    let passes: Vec<(usize, u8)> = (0..3)
        .flat_map(|a| sides.iter().map(move |&p| (a, p)))
        .collect();
    let mut bufs = slices::SetupBufs::default();
    let voxel = grid.voxel.as_dvec3().to_array();
    let mut cover = CoverageScales::default();
    let levels: Vec<Vec<u8>> = match &opts.combine {
        CombineFn::Preset(p) => {
            // Level 0 is combined at the end from the six sparse stacks, plane by plane;
            // the coarser levels are folded as each direction's pyramid is built.
            let mut acc = combine::Accum::new(*p, &dims);
            nacc = opts
                .normals
                .then(|| toksvig::NormalAccum::new(&dims, false));
            let mut zero = Vec::with_capacity(6);
            // `--prune`: level 0 folded direction by direction, each stack then freed.
            let mut level0 = sparse.then(|| level0::Level0::new(*p, dims[0], opts.normals));
            // Each direction's projected coverage at level 0 (the mesh's, as rasterized).
            let mut seen = [0.0f64; 6];
            for &pass in &passes {
                let stacks = raster(&mut bufs, ctx, pass, &mut times, baker.as_mut(), progress);
                for s in stacks {
                    let dir = s.dir;
                    fragments += s.fragments;
                    let mut fold_secs = 0.0;
                    seen[dir.index()] = coverage::stack_coverage(&s);
                    pyramid::<[f32; 4]>(&s, mips, &mut times.mip, |level, data| {
                        if let Level::Dense(c, n) = data {
                            let t = Instant::now();
                            acc.fold(level, &c);
                            if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                                na.fold(level, n, &c);
                            }
                            fold_secs += t.elapsed().as_secs_f64();
                        }
                    });
                    match level0.as_mut() {
                        Some(l0) => {
                            let t = Instant::now();
                            l0.fold(&s);
                            drop(s);
                            fold_secs += t.elapsed().as_secs_f64();
                        }
                        None => zero.push(s),
                    }
                    times.combine += fold_secs;
                    progress(Stage::Mip, (dir.index() + 1) as f32 / 6.0);
                }
            }
            drop(std::mem::take(&mut bufs)); // before the level-0 combine's peak
            let t = Instant::now();
            cover.mesh = coverage::mesh_coverage(&seen);
            // Level 0's scale (thinned to the mesh), then each coarser level's (to level 0).
            let level0_scale = |cols: coverage::Columns, cover: &mut CoverageScales| {
                let (k, before, after) = coverage::level0_scale(&cols, voxel, &cover.mesh, true);
                (cover.level0_before, cover.level0_after) = (before, after);
                cover.scales.push(k);
                k
            };
            let coarse_scale = |acc: &combine::Accum, l: usize, cover: &mut CoverageScales| {
                let k = coverage::level_scale(&acc.columns(l), dims[0], voxel, &cover.mesh);
                cover.scales.push(k);
                k
            };
            // Level 0's scale is applied once the normals are settled (`settle_level0`).
            if let Some(l0) = level0 {
                let (level0, count) = l0.finish_sparse();
                level0_scale(coverage::Columns::from_sparse(&level0), &mut cover);
                progress(Stage::Combine, 1.0);
                let mut out = vec![level0];
                for (l, &d) in dims.iter().enumerate().skip(1) {
                    let k = coarse_scale(&acc, l, &mut cover);
                    let c = acc.finish_level_bricks(l, k);
                    let n = nacc.as_mut().map(|na| na.finish_level_bricks(l));
                    out.push(sparse_level(d, c, n));
                }
                times.combine += t.elapsed().as_secs_f64();
                progress(Stage::Quantize, 1.0);
                times.total = t_all.elapsed().as_secs_f64();
                let stats = VoxelizeStats {
                    non_empty_voxels: count,
                    fragments,
                    triangles: scene.triangles.len(),
                    estimated_peak_bytes,
                    seconds: times,
                };
                return Ok((grid, Output::Sparse(out), stats, cover));
            }
            let (level0, normals0, count) = combine::combine_level0(*p, &zero, opts.normals);
            non_empty = Some(count);
            drop(zero);
            level0_scale(coverage::Columns::from_rgba8(dims[0], &level0), &mut cover);
            progress(Stage::Combine, 1.0);
            let mut out = vec![level0];
            for l in 1..mips as usize {
                let k = coarse_scale(&acc, l, &mut cover);
                out.push(acc.finish_level(l, k));
            }
            if let (Some(na), Some(n0)) = (nacc.as_mut(), normals0) {
                na.set_level0(n0);
            }
            times.combine += t.elapsed().as_secs_f64();
            out
        }
        f => {
            // Six brick-sparse f16 pyramids: only the bricks a direction's voxels reach.
            let mut pyrs: Vec<Vec<Option<brick_grid::Bricked<[f16; 4]>>>> = Vec::with_capacity(6);
            let mut seen = [0.0f64; 6];
            for &pass in &passes {
                let stacks = raster(&mut bufs, ctx, pass, &mut times, baker.as_mut(), progress);
                for s in stacks {
                    // Stored in f16 (the arithmetic stays f32/f64).
                    let dir = s.dir;
                    fragments += s.fragments;
                    seen[dir.index()] = coverage::stack_coverage(&s);
                    let mut levels = Vec::with_capacity(mips as usize);
                    pyramid::<[f16; 4]>(&s, mips, &mut times.mip, |level, data| match data {
                        Level::Zero(s) => {
                            if let Some(na) = nacc.as_mut() {
                                na.fold_sparse(s);
                            }
                            levels.push(Some(brick_grid::Bricked::from_slices(s)));
                        }
                        Level::Dense(c, n) => {
                            if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                                na.fold(level, n, &c);
                            }
                            levels.push(Some(c));
                        }
                    });
                    pyrs.push(levels);
                    progress(Stage::Mip, (dir.index() + 1) as f32 / 6.0);
                }
            }
            drop(std::mem::take(&mut bufs));
            cover.mesh = coverage::mesh_coverage(&seen);
            let t = Instant::now();
            let mut out = Vec::with_capacity(mips as usize);
            for l in 0..mips as usize {
                let grids: Vec<brick_grid::Bricked<[f16; 4]>> = pyrs
                    .iter_mut()
                    .map(|p| p[l].take().expect("level stored"))
                    .collect();
                let refs = [
                    &grids[0], &grids[1], &grids[2], &grids[3], &grids[4], &grids[5],
                ];
                out.push(combine::combine_level_bricks(f, refs));
                progress(Stage::Combine, (l + 1) as f32 / mips as f32);
            }
            // The function's level 0 is kept; the coarser levels keep its coverage.
            let cols = coverage::Columns::from_rgba8(dims[0], &out[0]);
            let (k, before, after) = coverage::level0_scale(&cols, voxel, &cover.mesh, false);
            (cover.level0_before, cover.level0_after) = (before, after);
            cover.scales.push(k);
            for l in 1..out.len() {
                let cols = coverage::Columns::from_rgba8(dims[l], &out[l]);
                let k = coverage::level_scale(&cols, dims[0], voxel, &after);
                coverage::scale_level_rgba8(&mut out[l], k);
                cover.scales.push(k);
            }
            times.combine += t.elapsed().as_secs_f64();
            out
        }
    };
    let t = Instant::now();
    let normals = nacc.map(|mut na| (0..mips as usize).map(|l| na.finish_level(l)).collect());
    let non_empty_voxels =
        non_empty.unwrap_or_else(|| levels[0].chunks_exact(4).filter(|p| p[3] != 0).count() as u64);
    times.quantize += t.elapsed().as_secs_f64();
    progress(Stage::Quantize, 1.0);
    times.total = t_all.elapsed().as_secs_f64();
    let stats = VoxelizeStats {
        non_empty_voxels,
        fragments,
        triangles: scene.triangles.len(),
        estimated_peak_bytes,
        seconds: times,
    };
    Ok((grid, Output::Dense(levels, normals), stats, cover))
}
