//! `billow voxelize --prune` and `billow eval` from Rust, through the library's public API
//! only: imports a mesh, bakes it into a pruned, BC7-compressed volumetric billboard with
//! [`billow::voxelize::bake`] — the same bytes as `billow voxelize MESH --res RES --prune`
//! writes —, and compares it with the mesh from two views with [`billow::eval::evaluate`],
//! `billow eval`'s numbers for the same options.
//!
//! `cargo run --release --example bake_from_rust [-- MESH [RES [OUT.billow]]]`
//! (default: the oak fixture at 128 voxels, nothing written).

use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::compress::Compression;
use billow::eval::evaluate::{evaluate, Asset, EvaluateHooks, EvaluateOptions};
use billow::eval::suite::spec;
use billow::import::{import, ImportOptions, Imported};
use billow::provenance::source_info_all;
use billow::voxelize::{bake, BakeHooks, BakeOptions, NormalsMode, Resolution};
use glam::Vec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mesh = args.next().map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/oak/eztree_oak_medium.gltf"),
        PathBuf::from,
    );
    let res: u32 = args.next().map_or(Ok(128), |r| r.parse())?;
    let out = args.next().map(PathBuf::from);

    let t = Instant::now();
    let Imported { scene, report } = import(&mesh, &ImportOptions { strict: false })?;
    // `billow voxelize --res N --prune`: the opaque combine, the grid's sides a multiple of
    // 8 (for N = 128, so that the prune can cut MIP levels 1–3 into bricks as well).
    let opts = BakeOptions {
        normals: NormalsMode::Auto,
        prune: true,
        compression: Compression::Bc,
        // The evaluation below reads the texels: make them what a reader of the file gets.
        decode_blocks: true,
        // The mesh and the files it read (buffers, textures), as the CLI records them.
        source: Some(source_info_all(&mesh, &report.files)?),
        ..BakeOptions::at(Resolution::Longest(res))
    };
    let note = |m: &str| eprintln!("warning: {m}");
    let hooks = BakeHooks {
        note: &note,
        ..BakeHooks::default()
    };
    let baked = bake(&scene, &opts, &hooks)?;
    let bytes = baked.asset.to_bytes_with(baked.blocks.as_ref())?;
    let d = baked.dims;
    println!(
        "{}: {} triangles, {}x{}x{} voxels, {} MIP levels, {} non-empty",
        mesh.display(),
        baked.stats.triangles,
        d[0],
        d[1],
        d[2],
        baked.mip_count,
        baked.stats.non_empty_voxels
    );
    let normals = &baked.asset.header.params["normals"];
    match &baked.pruned {
        Some(p) => println!(
            "{} bytes (BC7, normals {normals}), pruned into {} cells, in {:.2} s",
            bytes.len(),
            p.cells,
            t.elapsed().as_secs_f64()
        ),
        None => println!("{} bytes (normals {normals})", bytes.len()),
    }
    if let Some(path) = &out {
        std::fs::write(path, &bytes)?;
        println!("wrote {}", path.display());
    }

    // `billow eval MESH ASSET --views +x@1x,+x+y+z@4x`: 128×128, 4×4 reference samples per
    // pixel, the reference lit as the asset's normals are shaded.
    let options = EvaluateOptions {
        views: vec![spec("+x", Vec3::X, 1.0), spec("+x+y+z", Vec3::ONE, 4.0)],
        ..EvaluateOptions::default()
    };
    let asset = Asset::Volume(baked.asset);
    let evaluation = evaluate(&scene, &asset, &options, &mut EvaluateHooks::default())?;
    for n in &evaluation.notes {
        eprintln!("note: {n}");
    }
    let volume = &evaluation.levels[0];
    for result in &volume.views {
        println!(
            "{:>10}: RMSE {:.4}, PSNR {:.1} dB, coverage {:+.3}, FLIP {:.3}",
            result.view,
            result.asset.rmse,
            result.asset.psnr,
            result.asset.coverage_rel_diff,
            result.asset.flip
        );
    }
    println!(
        "      mean: RMSE {:.4}, PSNR {:.1} dB (the mesh at 1 spp: {:.4}); {} bytes on a GPU \
         with BC7",
        volume.mean.rmse,
        volume.mean.psnr,
        evaluation.raster_1spp.rmse,
        evaluation.gpu_bytes.with_bc
    );
    Ok(())
}
