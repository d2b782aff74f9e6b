//! `billow eval SOURCE CLOUD.billow`: every LOD level of a billboard cloud (or `--lod K`)
//! rendered by the CPU cloud renderer against the same reference (docs/eval.md).

use billow::eval::evaluate::{EvaluateOptions, Evaluation};
use billow::eval::suite::{DistanceMeans, MeanErrors, ViewResult};
use serde::Serialize;

use super::table::print_rows;
use super::{emit, lights_json, Args, Head, LightJson, LightingJson, Means, Seconds};
use crate::exit::CliError;
use crate::staged::Staged;

/// One LOD level's results.
#[derive(Serialize)]
struct LevelSummary {
    lod: usize,
    billboards: usize,
    /// Slab half-width of the plane search, world units.
    epsilon: f32,
    /// Texels per world unit.
    texel_density: f32,
    /// Bytes of this level's atlases, all MIP levels.
    texture_bytes: u64,
    views: Vec<ViewResult>,
    mean: MeanErrors,
    by_distance: Vec<DistanceMeans>,
    /// With --light/--lights: each light and its means (`mean` is then over the set).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    lights: Vec<LightJson>,
    /// Cloud-render seconds, all views.
    seconds: f64,
    fragments: u64,
}

#[derive(Serialize)]
struct CloudSummary {
    source: String,
    asset: String,
    kind: &'static str,
    asset_params: std::collections::BTreeMap<String, String>,
    /// Texture bytes `billow view` holds for the whole cloud (every LOD, the kept mesh's
    /// textures) on a device that samples BC7 blocks, and on one that does not
    /// (`billow_core::gpu_memory`).
    gpu_bytes: u64,
    gpu_bytes_no_bc: u64,
    size: [u32; 2],
    fov_y_degrees: f32,
    reference_spp: u32,
    lighting: LightingJson,
    notes: Vec<String>,
    levels: Vec<LevelSummary>,
    /// The mesh at 1 spp against the reference, over the views.
    raster_1spp: MeanErrors,
    seconds: Seconds,
    images: Vec<String>,
}

/// The cloud's JSON and table.
pub(super) fn output(
    args: &Args,
    options: &EvaluateOptions,
    head: Head,
    e: Evaluation,
    stage: Option<Staged>,
) -> Result<(), CliError> {
    let levels = e
        .levels
        .into_iter()
        .filter_map(|l| {
            let c = l.cloud?;
            Some(LevelSummary {
                lod: c.lod,
                billboards: c.billboards,
                epsilon: c.epsilon,
                texel_density: c.texel_density,
                texture_bytes: c.texture_bytes,
                views: l.views,
                mean: l.mean,
                by_distance: l.by_distance,
                lights: lights_json(l.by_light),
                seconds: l.seconds,
                fragments: l.fragments,
            })
        })
        .collect();
    let summary = CloudSummary {
        source: args.source.display().to_string(),
        asset: args.asset.display().to_string(),
        kind: "cloud",
        asset_params: head.params,
        gpu_bytes: e.gpu_bytes.with_bc,
        gpu_bytes_no_bc: e.gpu_bytes.without_bc,
        size: [options.width, options.height],
        fov_y_degrees: options.fov_y.to_degrees(),
        reference_spp: args.spp,
        lighting: head.lighting,
        notes: head.notes,
        levels,
        raster_1spp: e.raster_1spp,
        seconds: head.seconds,
        images: head.images,
    };
    emit(args, stage, &summary, print_table)
}

fn print_table(s: &CloudSummary) {
    outln!(
        "{} vs {} (billboard cloud, {} LOD level(s) evaluated), {}x{} px, {} spp, lighting {}",
        s.asset,
        s.source,
        s.levels.len(),
        s.size[0],
        s.size[1],
        s.reference_spp,
        s.lighting.reference
    );
    outln!(
        "{}",
        crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc)
    );
    for n in &s.notes {
        outln!("note: {n}");
    }
    for l in &s.levels {
        outln!(
            "\nLOD {}: {} billboards, ε {:.4}, {:.3} texels/unit, {:.2} MiB of atlases",
            l.lod,
            l.billboards,
            l.epsilon,
            l.texel_density,
            l.texture_bytes as f64 / f64::from(1u32 << 20)
        );
        let mean = Means {
            asset: l.mean,
            raster_1spp: s.raster_1spp,
        };
        let hit = l.views.iter().map(|v| v.polygons).max().unwrap_or(0);
        let totals = (s.seconds.reference, l.seconds, hit, l.fragments);
        print_rows(&l.views, &l.by_distance, &l.lights, &mean, totals, "bboard");
    }
    outln!(
        "\nRMSE/PSNR on premultiplied linear RGBA; cov% = asset coverage vs reference; lum% = \
         its mean covered luminance vs the reference's; SSIM on luma; FLIP over black; bboard = \
         billboards hit. Total {:.2} s.",
        s.seconds.total
    );
}
