//! The arguments of `billow bbcloud` (bin/billow/bbcloud.rs runs the command).

use std::path::PathBuf;

use billow::bbcloud as bb;

use crate::target::TargetArgs;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to bake: .gltf, .glb or .obj (+ .mtl).
    pub(crate) input: PathBuf,
    /// Where to write the cloud asset (.billow). Written atomically.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    // The ranges in this help are the library's constants (billow::bbcloud), said once.
    #[arg(long, help = format!(
        "Slab half-width ε of the plane search, in foliage bounding-sphere radii (doubled per \
         LOD); in (0, {}] (default: the preset's, else 0.04)",
        bb::MAX_EPSILON
    ))]
    pub(crate) epsilon: Option<f32>,
    #[arg(long, help = format!(
        "Candidate planes tried per billboard (N), 1–{} (default: the preset's, else 500)",
        bb::MAX_SAMPLES
    ))]
    pub(crate) samples: Option<u32>,
    /// A named point of the measured accuracy/cost front, setting --epsilon, --samples and
    /// --atlas-size: draft, balanced, quality or hero (docs/cli.md, "Presets"). Explicit
    /// flags override it.
    #[arg(long, value_name = "NAME", conflicts_with = "target_error")]
    pub(crate) preset: Option<String>,
    #[command(flatten)]
    pub(crate) target: TargetArgs,
    /// Random seed (PCG32), any 64-bit number; the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    #[arg(long, default_value_t = 3, help = format!(
        "Number of LOD levels, 1–{}; with 2 or more the last is two crossed vertical billboards",
        bb::MAX_LODS
    ))]
    pub(crate) lods: u32,
    /// Up axis: +x, -x, +y, -y, +z, -z or x,y,z (the last LOD's billboards contain it;
    /// --view-dirs horizontal is perpendicular to it). glTF is +y.
    #[arg(long, default_value = "+y", allow_hyphen_values = true)]
    pub(crate) up: String,
    /// Prefer planes facing the expected view directions (Lacewell §5): "horizontal" (all
    /// directions perpendicular to --up) or directions separated by ';' (x,y,z or an axis
    /// such as +z; axes may also be separated by ',': "+z,+x").
    #[arg(long, value_name = "horizontal|DIR;DIR...", allow_hyphen_values = true)]
    pub(crate) view_dirs: Option<String>,
    #[arg(long, default_value_t = 1.0, requires = "view_dirs", help = format!(
        "Strength of --view-dirs in [{}, {}]: candidates rank by area·((1−s) + s·facing)",
        bb::UNIT_RANGE.start(),
        bb::UNIT_RANGE.end()
    ))]
    pub(crate) view_strength: f32,
    /// Also bake a tangent-space normal map per billboard side (stored as a layer of every
    /// atlas, exported as the glTF normalTexture). Pair with --unlit for runtime lighting.
    #[arg(long)]
    pub(crate) normal_map: bool,
    /// How triangles are laid onto their billboard: "unfold" turns each leaf into the
    /// plane about its centre, keeping its area and so the mesh's coverage; "project"
    /// projects it orthographically (the paper's; a leaf tilted by θ keeps cos θ of its area)
    #[arg(long, value_name = "unfold|project", default_value = "unfold")]
    pub(crate) flatten: String,
    #[arg(long, default_value_t = 4, help = format!(
        "MIP levels stored per atlas, 1–{}; allocations are aligned and padded so no stored \
         level mixes two billboards",
        bb::MAX_MIP_LEVELS
    ))]
    pub(crate) mip_levels: u32,
    #[arg(long, help = format!(
        "Largest atlas side in texels: a power of two, {}–{} (default: the preset's, else 2048)",
        bb::MIN_ATLAS_SIZE,
        bb::MAX_ATLAS_SIZE
    ))]
    pub(crate) atlas_size: Option<u32>,
    /// Texels per world unit at LOD 0, > 0 (default: the most that fits one atlas per level).
    #[arg(long)]
    pub(crate) texel_density: Option<f32>,
    /// Direction towards the light, x,y,z (finite, not zero); the default is the viewer's
    /// scene light.
    #[arg(long, default_value_t = default_light(), conflicts_with = "unlit")]
    pub(crate) light: String,
    /// Bake albedo only, no lighting.
    #[arg(long)]
    pub(crate) unlit: bool,
    #[arg(long, default_value_t = billow_core::shading::DEFAULT_AMBIENT, help = format!(
        "Ambient light fraction (the rest is diffuse), in [{}, {}]",
        bb::UNIT_RANGE.start(),
        bb::UNIT_RANGE.end()
    ))]
    pub(crate) ambient: f32,
    #[arg(long, default_value_t = 3, help = format!(
        "K: K×K coverage samples per texel, 1–{}",
        bb::MAX_SUPERSAMPLE
    ))]
    pub(crate) supersample: u32,
    #[arg(long, help = format!(
        "Limit each billboard to triangles within this distance of its seed, in foliage \
         bounding-sphere radii, > 0 and at most {} (Lacewell §5; doubled per LOD). Default: no \
         limit",
        bb::LARGEST_MAX_EXTENT
    ))]
    pub(crate) max_extent: Option<f32>,
    /// Materials that make up the foliage (default: every alpha MASK/BLEND material).
    #[arg(long, num_args = 1..)]
    pub(crate) foliage: Vec<String>,
    /// Also write the cloud (every LOD) and the kept mesh as glTF 2.0: FILE.glb binary,
    /// FILE.gltf one JSON file with its data embedded. Written atomically.
    #[arg(long, value_name = "FILE.glb|FILE.gltf")]
    pub(crate) gltf: Option<PathBuf>,
    /// Alpha mode of the billboards in the --gltf file: mask (alpha test at 0.5) or blend.
    #[arg(long, value_enum, default_value_t = GltfAlphaArg::Mask)]
    pub(crate) gltf_alpha: GltfAlphaArg,
    /// Texel storage: bc (BC7 blocks for the atlases, normal maps and mesh textures, format
    /// 1.2) or none (raw RGBA8, readable by format 1.0/1.1 readers). --gltf and --atlas
    /// stay PNG, made from the uncompressed texels.
    #[arg(long, default_value = "bc")]
    pub(crate) compress: String,
    /// Also dump every atlas (MIP level 0) as an 8-bit straight-alpha PNG into DIR
    /// (created if missing): lod{L}_atlas{I}.png.
    #[arg(long, value_name = "DIR")]
    pub(crate) atlas: Option<PathBuf>,
    /// Treat import warnings (e.g. a missing texture) as errors.
    #[arg(long)]
    pub(crate) strict: bool,
    /// Also write a Makefile rule listing every file the bake read (the mesh, its buffers,
    /// textures and material libraries) as prerequisites of the outputs; committed with them.
    #[arg(long, value_name = "FILE")]
    pub(crate) depfile: Option<PathBuf>,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    pub(crate) json: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GltfAlphaArg {
    Mask,
    Blend,
}

/// `--light`'s default, `billow_core::shading::DEFAULT_LIGHT` as the flag spells it.
fn default_light() -> String {
    let l = billow_core::shading::DEFAULT_LIGHT;
    format!("{},{},{}", l.x, l.y, l.z)
}
