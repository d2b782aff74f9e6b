//! `billow shell SURFACE VOLUME -o OUT`: cover a surface with a tileable volume (VB paper
//! §4, Figures 11–12): one prism cell per surface triangle, extruded along its normals.

use std::path::PathBuf;

use billow::compress::{encode_volume, Compression};
use billow::import::{import, ImportOptions, Imported};
use billow::shell::{shell, shell_asset, with_surface_normals};
use billow_format::{VolumeAsset, VolumeBlocks};
use glam::Vec2;
use serde::Serialize;

use crate::bake_steps::parse_compress;
use crate::depfile;
use crate::exit::{CliError, Code};
use crate::output::{print_json, refuse_clobbering, refuse_clobbering_read, warn};
use crate::staged::{out_err, Staged};
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The surface mesh (.gltf, .glb, .obj) whose triangles become prisms; needs UVs.
    surface: PathBuf,
    /// The tileable volume (.billow, baked with `voxelize --bounds 0,0,0,1,1,1`); Y is height.
    volume: PathBuf,
    /// Where to write the shell asset (.billow). Written atomically.
    #[arg(short, long)]
    output: PathBuf,
    /// Shell thickness along the normals, in the surface's units, > 0.
    #[arg(long, allow_negative_numbers = true)]
    height: f32,
    /// Volume tiles per unit of UV, `U,V` (e.g. `8,3`), each > 0.
    #[arg(long, default_value = "1,1")]
    tiles: String,
    /// Shade the shell at runtime with the surface's normal (the VB paper's low-frequency
    /// normal for fur, §3.2): the tile's normals become its up axis, which renderers turn
    /// with each prism; the tile's colour is then albedo.
    #[arg(long)]
    surface_normals: bool,
    /// Texel storage: bc (BC7 blocks, format 1.2; a compressed volume's blocks are kept as
    /// they are) or none (raw RGBA8, readable by format 1.0/1.1 readers).
    #[arg(long, default_value = "bc")]
    compress: String,
    /// Treat import warnings as errors.
    #[arg(long)]
    strict: bool,
    /// Also write a Makefile rule listing every file read (the surface mesh and the files
    /// beside it, the volume) as prerequisites of the output; committed with it.
    #[arg(long, value_name = "FILE")]
    depfile: Option<PathBuf>,
    /// Print a machine-readable summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary {
    output: String,
    prisms: usize,
    skipped_triangles: usize,
    mirrored_uv_triangles: usize,
    folded_prisms: usize,
    bytes: u64,
}

pub fn run(args: Args, ctx: &Ctx) -> Result<(), CliError> {
    let compression: Compression = parse_compress(&args.compress)?;
    let mut outputs = vec![("-o", args.output.as_path())];
    outputs.extend(args.depfile.as_deref().map(|d| ("--depfile", d)));
    refuse_clobbering(&[&args.surface, &args.volume], &outputs)?;
    depfile::check(
        args.depfile.as_deref(),
        &[&args.surface, &args.volume, &args.output],
    )?;
    let tiles = parse_tiles(&args.tiles)?;
    let Imported {
        scene: surface,
        report,
    } = import(
        &args.surface,
        &ImportOptions {
            strict: args.strict,
        },
    )
    .map_err(|e| CliError::new(Code::from(&e), &e))?;
    refuse_clobbering_read(&args.surface, &report.files, &outputs)?;
    depfile::check_read(args.depfile.as_deref(), &report.files)?;
    for w in &report.warnings {
        warn(ctx, &format!("{}: {}", args.surface.display(), w.message));
    }
    let (volume, volume_blocks) = VolumeAsset::read_with_blocks(&args.volume)
        .map_err(|e| CliError::new(Code::from(&e), &e))?;
    let s = shell(&surface, args.height, tiles)
        .map_err(|e| CliError::new(Code::from(&e), format!("{}: {e}", args.surface.display())))?;
    let (skipped, mirrored, folded) = (s.skipped, s.mirrored, s.folded);
    if mirrored > 0 {
        warn(
            ctx,
            &format!("{mirrored} triangles have mirrored UVs: the tile appears mirrored there"),
        );
    }
    if folded > 0 {
        warn(
            ctx,
            &format!("{folded} prisms fold over (height exceeds the local curvature radius)"),
        );
    }
    let mut asset = shell_asset(&volume, s);
    if args.surface_normals {
        with_surface_normals(&mut asset);
    }
    let blocks = shell_blocks(&mut asset, volume_blocks, compression, args.surface_normals);
    let bytes = asset
        .to_bytes_with(blocks.as_ref())
        .map_err(|e| CliError::new(Code::Internal, e))?;
    let mut stage = Staged::new(&args.output);
    stage
        .stage(&args.output, &bytes)
        .map_err(|e| out_err(&args.output, e))?;
    if let Some(d) = &args.depfile {
        let mut read = report.files.clone();
        read.push(args.volume.clone());
        let text = depfile::render(&[&args.output], &args.surface, &read, &report.missing)?;
        stage.stage(d, text.as_bytes()).map_err(|e| out_err(d, e))?;
    }
    stage.commit_or_fail()?;
    let summary = Summary {
        output: args.output.display().to_string(),
        prisms: asset.cells.len(),
        skipped_triangles: skipped,
        mirrored_uv_triangles: mirrored,
        folded_prisms: folded,
        bytes: bytes.len() as u64,
    };
    if args.json {
        print_json(&summary)?;
    } else if !ctx.quiet {
        eprintln!(
            "{}: {} prisms, {} bytes",
            summary.output, summary.prisms, summary.bytes
        );
    }
    Ok(())
}

/// `--tiles U,V`.
fn parse_tiles(s: &str) -> Result<Vec2, CliError> {
    let tiles: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| CliError::new(Code::Usage, format!("--tiles '{s}': {e}")))?;
    let [u, v] = tiles[..] else {
        return Err(CliError::new(
            Code::Usage,
            format!("--tiles '{s}': expected two numbers U,V"),
        ));
    };
    Ok(Vec2::new(u, v))
}

/// The shell's BC7 blocks as `--compress` says: the shell's texture is the volume's, so its
/// blocks are reused, not encoded again (unless `--surface-normals` changed the texels).
fn shell_blocks(
    asset: &mut VolumeAsset,
    volume_blocks: Option<VolumeBlocks>,
    compression: Compression,
    surface_normals: bool,
) -> Option<VolumeBlocks> {
    match compression {
        Compression::None => {
            asset.header.clear_compress();
            None
        }
        Compression::Bc => {
            asset.header.set_compress("bc7");
            Some(match volume_blocks.filter(|_| !surface_normals) {
                Some(b) => b,
                None => encode_volume(asset),
            })
        }
    }
}
