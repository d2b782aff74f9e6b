//! `billow emptyspace IN.billow -o OUT.billow`: kd-tree empty-space removal with packed,
//! seam-free bricks (VB paper §4, Figure 14; docs/emptyspace.md, formats/SPEC.md §8.6).

use std::path::PathBuf;
use std::time::Instant;

use billow::compress::{encode_volume, Compression};
use billow::emptyspace::{
    prune, EmptySpaceOptions, EmptySpaceStats, DEFAULT_CELL_COST, MAX_DEPTH, MIN_CELL_COST,
    MIN_GAIN_RANGE,
};
use billow_core::gpu_memory::volume_gpu_bytes;
use billow_format::{read_file, AssetKind, VolumeAsset};
use serde::Serialize;

use crate::bake_steps::parse_compress;
use crate::depfile;
use crate::exit::{CliError, Code};
use crate::output::{print_json, refuse_clobbering, warn};
use crate::staged::{out_err, Staged};
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The volume asset to prune (.billow, from `billow voxelize`).
    input: PathBuf,
    /// Where to write the pruned volume asset (.billow). Written atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// Texels whose alpha byte (0–255) is ≤ this are dropped; 0 (default): only exactly
    /// transparent, colourless texels count as empty, so nothing visible is lost.
    #[arg(long, default_value_t = 0)]
    threshold: u8,
    /// Smallest box edge a kd-tree split may leave, in level-0 voxels (rounded up to whole
    /// 2-voxel blocks; halved for each coarser tier).
    #[arg(long, default_value_t = 0)]
    min_box: u32,
    // The ranges and defaults in this help are the library's (billow::emptyspace), said once.
    #[arg(long, default_value_t = EmptySpaceOptions::default().max_depth,
          help = format!("Deepest kd-tree level (the root is 0), 0–{MAX_DEPTH}"))]
    max_depth: u32,
    #[arg(long, default_value_t = EmptySpaceOptions::default().min_gain, help = format!(
        "Smallest relative cost reduction worth a split, in [{}, {})",
        MIN_GAIN_RANGE.start, MIN_GAIN_RANGE.end
    ))]
    min_gain: f64,
    #[arg(long, default_value_t = DEFAULT_CELL_COST, help = format!(
        "Cost of one more box in the kd-tree's split cost, in atlas texels, ≥ {MIN_CELL_COST}"
    ))]
    cell_cost: f64,
    /// Most MIP tiers stored as bricks (default: as many as save memory); 0 keeps the
    /// volume whole.
    #[arg(long)]
    max_tiers: Option<u32>,
    /// Texel storage of the output: bc (default; BC7 blocks for the base texture and every
    /// LOD band, format 1.3, empty texels kept exactly empty) or none (raw RGBA8, format 1.1).
    #[arg(long, default_value = "bc")]
    compress: String,
    /// Also write a Makefile rule with the input asset as the output's prerequisite;
    /// committed with the output.
    #[arg(long, value_name = "FILE")]
    depfile: Option<PathBuf>,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary {
    input: String,
    output: String,
    #[serde(flatten)]
    stats: EmptySpaceStats,
    file_bytes_before: u64,
    file_bytes_after: u64,
    /// Texture memory `billow view` holds on a device with BC7 support, before and after
    /// (`billow_core::gpu_memory`).
    gpu_bytes_before: u64,
    gpu_bytes_after: u64,
    /// The same on a device without it (every texture decoded).
    gpu_bytes_before_no_bc: u64,
    gpu_bytes_after_no_bc: u64,
    seconds_total: f64,
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let start = Instant::now();
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(args.depfile.as_deref().map(|d| ("--depfile", d)));
    let compression: Compression = parse_compress(&args.compress)?;
    refuse_clobbering(&[&args.input], &outputs)?;
    depfile::check(args.depfile.as_deref(), &[&args.input, &args.output])?;
    let shown = args.input.display().to_string();
    let container = read_file(&args.input).map_err(|e| CliError::new(Code::from(&e), e))?;
    if container.header.kind != AssetKind::Volume {
        return Err(CliError::new(
            Code::Unsupported,
            format!(
                "{shown}: a {:?} asset; billow emptyspace prunes volume assets only",
                container.header.kind
            ),
        ));
    }
    let asset = VolumeAsset::from_container(container)
        .map_err(|e| CliError::new(Code::from(&e), format!("{shown}: {e}")))?;
    let file_bytes_before = std::fs::metadata(&args.input).map_or(0, |m| m.len());
    let options = EmptySpaceOptions {
        threshold: args.threshold,
        min_box: args.min_box,
        max_depth: args.max_depth,
        min_gain: args.min_gain,
        cell_cost: args.cell_cost,
        max_tiers: args.max_tiers,
        apron: true,
        bc_blocks: compression == Compression::Bc,
        ..EmptySpaceOptions::default()
    };
    let mut pruned = prune(&asset, &options)
        .map_err(|e| CliError::new(Code::from(&e), format!("{shown}: {e}")))?;
    if let Some(note) = &pruned.stats.note {
        warn(ctx, &format!("{shown}: {note}"));
    }
    // A volume kept whole is written as it came (apart from the marker): a raw input stays
    // raw, a compressed one is compressed again.
    let input_compressed = asset.header.compress().is_some();
    let gpu_before = volume_gpu_bytes(&asset, input_compressed);
    // The source is not read again: freed before the output is encoded and written.
    drop(asset);
    let compress = compression == Compression::Bc && (!pruned.stats.kept_whole || input_compressed);
    let blocks = compress.then(|| {
        let a = &mut pruned.asset;
        a.header.set_compress("bc7");
        encode_volume(a)
    });
    if blocks.is_none() {
        pruned.asset.header.clear_compress();
    }
    let mut stage = Staged::new(&args.output);
    // Streamed from the texel data (no file-sized copy in memory).
    let file_bytes_after = pruned
        .asset
        .with_parts_with(blocks.as_ref(), |parts| {
            let len = parts.iter().map(|p| p.len() as u64).sum::<u64>();
            stage.stage_parts(&args.output, parts).map(|()| len)
        })
        .map_err(|e| CliError::new(Code::Internal, e))?
        .map_err(|e| out_err(&args.output, e))?;
    if let Some(d) = &args.depfile {
        let text = depfile::render(&[&args.output], &args.input, &[], &[])?;
        stage.stage(d, text.as_bytes()).map_err(|e| out_err(d, e))?;
    }
    stage.commit_or_fail()?;
    let gpu_after = volume_gpu_bytes(&pruned.asset, blocks.is_some());
    let summary = Summary {
        input: shown,
        output: args.output.display().to_string(),
        stats: pruned.stats,
        file_bytes_before,
        file_bytes_after,
        gpu_bytes_before: gpu_before.with_bc,
        gpu_bytes_after: gpu_after.with_bc,
        gpu_bytes_before_no_bc: gpu_before.without_bc,
        gpu_bytes_after_no_bc: gpu_after.without_bc,
        seconds_total: start.elapsed().as_secs_f64(),
    };
    if args.json {
        print_json(&summary)?;
    } else if !ctx.quiet {
        print_text(&summary);
    }
    Ok(())
}

/// The summary on stderr: the boxes and bands, the atlas, what is drawn, and the GPU and
/// file sizes before and after.
fn print_text(summary: &Summary) {
    let s = &summary.stats;
    let pct = |a: u64, b: u64| 100.0 * (b as f64 / a.max(1) as f64 - 1.0);
    eprintln!(
        "{}: {} boxes, {} bands ({} cells), atlas {}x{}x{} from {}x{}x{}, voxels drawn {:.1}% of the source's, GPU textures {} -> {} bytes ({:+.1}%; without BC7 {} -> {}), file {} -> {} bytes ({:+.1}%){}",
        summary.output,
        s.boxes,
        s.bands.len(),
        s.cells,
        s.atlas_dims[0],
        s.atlas_dims[1],
        s.atlas_dims[2],
        s.source_dims[0],
        s.source_dims[1],
        s.source_dims[2],
        100.0 * s.voxels_kept as f64 / s.voxels_before.max(1) as f64,
        summary.gpu_bytes_before,
        summary.gpu_bytes_after,
        pct(summary.gpu_bytes_before, summary.gpu_bytes_after),
        summary.gpu_bytes_before_no_bc,
        summary.gpu_bytes_after_no_bc,
        summary.file_bytes_before,
        summary.file_bytes_after,
        pct(summary.file_bytes_before, summary.file_bytes_after),
        if s.kept_whole {
            "; kept whole"
        } else {
            ""
        }
    );
}
