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
//! This file holds the options, results and errors, the grid checks, [`voxelize`] and
//! [`slice_stack`]; `pipeline.rs` runs the steps above for [`voxelize`] and
//! [`voxelize_sparse`] (`sparse.rs`), one way.
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
//! (only the texels with a non-zero byte of each brick,
//! [`SparseLevel`](crate::sparse_level::SparseLevel)).
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
pub mod limits;
mod memory;
pub mod mip;
mod normals_mode;
mod pipeline;
pub mod quantize;
mod slices;
mod sparse;
pub mod toksvig;

use glam::{Vec3, Vec4};

pub use ao::{voxel_stream, AoRays, Bake, AO_SEED, DEFAULT_AO_RAYS, DEFAULT_DISTANCE_FRACTION};
pub use asset::{bake_params, bake_params_for};
pub use bake::{bake, BakeError, BakeHooks, BakeOptions, Baked};
pub use combine::{Combine, CombineFn, CombineParseError, Preset};
pub use coverage::CoverageScales;
pub use expr::{Expr, ExprError};
use fragments::NormalSums;
pub use grid::{
    default_align, fit_grid, GridError, GridSpec, Resolution, ResolutionError, MAX_MARGIN,
};
pub use limits::{
    check_align, check_ao_distance, check_ao_rays, check_bounds, check_memory_limit,
    memory_limit_bytes, OptionError, MAX_AO_RAYS, MAX_AXIS,
};
use memory::estimate_bytes;
pub use memory::{estimate_peak_bytes, estimate_peak_bytes_pruned, estimate_peak_bytes_sparse};
pub use normals_mode::{bake_with_normals, MemoryRefusal, NormalsMode, NormalsOutcome};
use pipeline::{ao_baker, voxelize_as, Output};
pub use quantize::clamp_premultiplied;
pub use slices::MAX_SUPERSAMPLE;
pub use sparse::{voxelize_sparse, SparseVolume};

use crate::material;
use crate::scene::Scene;
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

impl VoxelizeOptions {
    /// Every option checked against its range, before any work: `supersample`, the
    /// resolution, `margin`, `align`, `bounds`, `bake` and `memory_limit`, in that order
    /// (what [`voxelize`] and [`bake()`] check first; `mip_levels` needs the grid and is
    /// checked with it).
    pub fn validate(&self) -> Result<(), VoxelizeError> {
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(VoxelizeError::InvalidOption {
                option: OptionName::Supersample,
                message: format!(
                    "{} is out of range (1 to {MAX_SUPERSAMPLE})",
                    self.supersample
                ),
            });
        }
        self.resolution.validate()?;
        grid::check_margin(self.margin)?;
        check_align(self.align)?;
        if let Some(b) = &self.bounds {
            check_bounds(b)?;
        }
        self.bake.validate()?;
        check_memory_limit(self.memory_limit)?;
        Ok(())
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
    /// An option outside its range ([`limits`]): [`OptionError::option`] says which field.
    #[error("invalid option: {name}: {0}", name = .0.option())]
    OutOfRange(#[from] OptionError),
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
    Combine,
}

impl std::fmt::Display for OptionName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OptionName::Supersample => "supersample",
            OptionName::MipLevels => "mip_levels",
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
    opts.validate()?;
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
    let opaque_too = coverage.level0_opaque_thinned;
    coverage.settle_level0(surface, |k| {
        coverage::scale_level_rgba8(&mut levels[0], k, opaque_too)
    });
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A library caller gets the refusal the CLI gives, from `validate`, `voxelize` and
    /// `bake` (before the scene is looked at: an empty one would be `EmptyScene`).
    #[test]
    fn options_out_of_range_are_refused_by_the_library() {
        use crate::scene::SceneBuilder;
        let empty = SceneBuilder::new().finish();
        let cases = [
            (
                VoxelizeOptions {
                    align: 0,
                    ..Default::default()
                },
                OptionError::Align(0),
            ),
            (
                VoxelizeOptions {
                    align: MAX_AXIS + 1,
                    ..Default::default()
                },
                OptionError::Align(MAX_AXIS + 1),
            ),
            (
                VoxelizeOptions {
                    memory_limit: 0,
                    ..Default::default()
                },
                OptionError::MemoryLimit(0.0),
            ),
            (
                VoxelizeOptions {
                    bake: Bake::Ao {
                        rays: 0,
                        distance: None,
                    },
                    ..Default::default()
                },
                OptionError::AoRays(0),
            ),
            (
                VoxelizeOptions {
                    bake: Bake::Ao {
                        rays: MAX_AO_RAYS + 1,
                        distance: None,
                    },
                    ..Default::default()
                },
                OptionError::AoRays(MAX_AO_RAYS + 1),
            ),
            (
                VoxelizeOptions {
                    bake: Bake::Ao {
                        rays: 8,
                        distance: Some(-1.0),
                    },
                    ..Default::default()
                },
                OptionError::AoDistance(-1.0),
            ),
            (
                VoxelizeOptions {
                    bounds: Some(Aabb {
                        min: Vec3::ONE,
                        max: Vec3::ZERO,
                    }),
                    ..Default::default()
                },
                OptionError::BoundsEmpty,
            ),
            (
                VoxelizeOptions {
                    bounds: Some(Aabb {
                        min: Vec3::ZERO,
                        max: Vec3::splat(f32::NAN),
                    }),
                    ..Default::default()
                },
                OptionError::BoundsNotFinite,
            ),
        ];
        for (opts, want) in cases {
            let is_want =
                |e: &VoxelizeError| matches!(e, VoxelizeError::OutOfRange(o) if *o == want);
            let e = opts.validate().expect_err("validate");
            assert!(is_want(&e), "validate: {e} for {want:?}");
            let e = voxelize(&empty, &opts, &|_, _| {}).expect_err("voxelize");
            assert!(is_want(&e), "voxelize: {e} for {want:?}");
            let b = BakeOptions {
                voxelize: opts,
                ..BakeOptions::default()
            };
            match bake(&empty, &b, &BakeHooks::default()) {
                Err(BakeError::Voxelize(e)) => assert!(is_want(&e), "bake: {e}"),
                other => panic!("bake: {:?} for {want:?}", other.err()),
            }
        }
        // In range, the options pass, and the bake goes on to the scene.
        let good = VoxelizeOptions {
            align: 8,
            memory_limit: 1,
            bake: Bake::Ao {
                rays: MAX_AO_RAYS,
                distance: Some(0.5),
            },
            bounds: Some(Aabb {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            }),
            ..Default::default()
        };
        assert!(good.validate().is_ok());
        let no_bounds = VoxelizeOptions {
            bounds: None,
            ..good
        };
        assert!(matches!(
            voxelize(&empty, &no_bounds, &|_, _| {}),
            Err(VoxelizeError::EmptyScene)
        ));
    }
}
