//! The arguments of `billow voxelize` (bin/billow/voxelize.rs runs the command,
//! bin/billow/voxelize_bake.rs bakes; both read these).

use std::path::PathBuf;

use crate::target::TargetArgs;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to bake: .gltf, .glb or .obj (+ .mtl).
    pub(crate) input: PathBuf,
    /// Where to write the volume asset (.billow). Written atomically.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    // The ranges in this help are the library's constants, said once.
    #[arg(long, help = format!(
        "Voxels along the longest axis (others in proportion), or exactly XxYxZ (e.g. \
         256x128x128); each axis 1–{}, and the estimated memory must fit (default: the \
         preset's, else 128)",
        billow::voxelize::MAX_AXIS
    ))]
    pub(crate) res: Option<String>,
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(billow::voxelize::MAX_SUPERSAMPLE)),
          help = format!(
              "K: K×K coverage samples per voxel column, 1–{}; gives thin parts fractional \
               opacity (default: the preset's, else 4)",
              billow::voxelize::MAX_SUPERSAMPLE
          ))]
    pub(crate) supersample: Option<u32>,
    /// A named point of the measured accuracy/cost front, setting --res and --supersample:
    /// draft, balanced, quality or hero (docs/cli.md, "Presets"). Explicit --res or
    /// --supersample override it.
    #[arg(long, value_name = "NAME", conflicts_with = "target_error")]
    pub(crate) preset: Option<String>,
    #[command(flatten)]
    pub(crate) target: TargetArgs,
    /// How the six directional volumes merge: opaque (max opacity, averaged colour: keeps thin
    /// leaves and closed surfaces solid), mean (the paper's neutral average), max, min, or
    /// expr:<expression over px nx py ny pz nz> (see docs/voxelize.md).
    #[arg(long, default_value = "opaque")]
    pub(crate) combine: String,
    /// Normals for runtime shading: auto (the mean normal for a smooth solid surface, their
    /// second moments for thin or fuzzy ones such as foliage and fur; see docs/voxelize.md),
    /// on (the mean, Toksvig-filtered; a bare --normals), moments (the diagonal of the
    /// normals' second moment, lit two-sided), or off (the colour is shown as baked). With
    /// normals the colour is albedo and viewers shade it under the scene light.
    #[arg(long, value_enum, value_name = "WHEN", default_value_t = NormalsArg::Auto,
          num_args = 0..=1, default_missing_value = "on")]
    pub(crate) normals: NormalsArg,
    /// Number of MIP levels, 1–the full chain (default: the full chain down to 1×1×1).
    #[arg(long)]
    pub(crate) mips: Option<u32>,
    // The range is the library's (`MAX_MARGIN`), said once.
    #[arg(long, default_value_t = 0.5,
          help = format!("Empty border around the mesh, in voxels, 0–{}", billow::voxelize::MAX_MARGIN))]
    pub(crate) margin: f32,
    #[arg(long, help = format!(
        "Round every side of the grid up to a multiple of N voxels, 1–{} (the box grows evenly \
         with empty voxels). `billow emptyspace` needs even sides, and sides that are multiples \
         of 2^k to prune MIP levels 1..k as well. Default: with `--res N` and no `--bounds`, the \
         largest of 8, 4, 2, 1 that divides N (so the longest axis stays N: 8 for 128, 256, \
         512); with `--res XxYxZ` or `--bounds`, 1 (the grid is exactly as asked)",
        billow::voxelize::MAX_AXIS
    ))]
    pub(crate) align: Option<u32>,
    /// Bake exactly this box, `minx,miny,minz,maxx,maxy,maxz` (no margin), e.g. `0,0,0,1,1,1`
    /// for a tileable volume texture used by `billow shell`.
    #[arg(long)]
    pub(crate) bounds: Option<String>,
    /// Texel storage: bc (default: BC7 blocks, one byte per texel on the GPU, empty 4×4
    /// blocks not stored, format 1.2) or none (raw RGBA8, readable by format 1.0/1.1
    /// readers). --ktx2 carries the same blocks.
    #[arg(long, default_value = "bc")]
    pub(crate) compress: String,
    /// Also write the volume as a KTX2 3D texture with its MIP chain (premultiplied, sRGB).
    #[arg(long, value_name = "FILE")]
    pub(crate) ktx2: Option<PathBuf>,
    /// Supercompress the --ktx2 file's levels with Zstandard at this level, 1–22
    /// (`supercompressionScheme` 2; a loader inflates each level before upload). Needs --ktx2.
    #[arg(long, value_name = "LEVEL")]
    pub(crate) ktx2_zstd: Option<i32>,
    /// Also write every slice of one MIP level (see --slice-level) into this folder.
    #[arg(long, value_name = "DIR")]
    pub(crate) slices: Option<PathBuf>,
    /// MIP level whose slices --slices writes, 0–(MIP levels − 1).
    #[arg(long, default_value_t = 0)]
    pub(crate) slice_level: u32,
    /// Slice image format: png (8-bit, straight alpha) or exr (float, premultiplied).
    #[arg(long, default_value = "png")]
    pub(crate) slice_format: String,
    /// Baked lighting multiplied into the colour: none, or ao (ambient occlusion traced
    /// against the source mesh; see docs/voxelize.md).
    #[arg(long, default_value = "none")]
    pub(crate) bake: String,
    #[arg(long, default_value_t = billow::voxelize::DEFAULT_AO_RAYS,
          help = format!("Rays per voxel for --bake ao, 1–{}", billow::voxelize::MAX_AO_RAYS))]
    pub(crate) ao_rays: u32,
    /// Occlusion distance for --bake ao, in scene units, > 0 (default: 0.2 × the grid's diagonal).
    #[arg(long)]
    pub(crate) ao_distance: Option<f32>,
    /// Treat import warnings (e.g. a missing texture) as errors.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Write the pruned volume (what `billow emptyspace` makes of the `--compress none`
    /// volume, byte for byte, with the same --compress) straight from the brick-sparse
    /// working set, without ever holding the dense volume: for large grids (1024³). Not
    /// with --ktx2 or --slices.
    #[arg(long)]
    pub(crate) prune: bool,
    /// Refuse grids whose estimated peak memory (an upper bound, often several times the
    /// real peak) exceeds this many GiB, > 0.
    #[arg(long, value_name = "GIB", default_value_t = 16.0)]
    pub(crate) memory_limit: f64,
    /// Also write a Makefile rule listing every file the bake read (the mesh, its buffers,
    /// textures and material libraries) as prerequisites of the outputs; committed with them.
    #[arg(long, value_name = "FILE")]
    pub(crate) depfile: Option<PathBuf>,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    pub(crate) json: bool,
}

/// `--normals`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalsArg {
    Auto,
    On,
    Moments,
    Off,
}
