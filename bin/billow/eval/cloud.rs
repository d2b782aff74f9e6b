//! `billow eval SOURCE CLOUD.billow`: every LOD level of a billboard cloud (or `--lod K`)
//! rendered by the CPU cloud renderer against the same reference (docs/eval.md).

use std::time::Instant;

use billow::eval::cloud_render::{CloudRenderer, PreparedCloud};
use billow::eval::lighting::Lighting;
use billow::eval::suite::{
    mean_errors, means_by_distance, DistanceMeans, EvalOptions, Evaluator, MeanErrors, ViewResult,
    EVAL_FOV_Y,
};
use billow::import::Imported;
use billow_format::{BakedLight, CloudAsset, Container};
use serde::Serialize;

use super::{
    bad, create_out, finish_out, image_stem, lights_json, parse_distances, parse_lights,
    parse_size, parse_views, print_rows, source_note, spp_per_axis, stage_png, Args, LightJson,
    LightingArg, LightingJson, Means, Seconds,
};
use crate::exit::{CliError, Code};
use crate::output::{print_json, progress};
use crate::Ctx;

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

pub(super) fn run(
    args: &Args,
    ctx: &Ctx,
    source: &Imported,
    container: Container,
    start: Instant,
    import_s: f64,
    t: Instant,
) -> Result<(), CliError> {
    let scene = &source.scene;
    let (width, height) = parse_size(&args.size)?;
    let per_axis = spp_per_axis(args.spp)?;
    let views = parse_views(&args.views, &parse_distances(&args.distances)?)?;
    let source_shown = args.source.display().to_string();
    let asset_shown = args.asset.display().to_string();
    let asset = CloudAsset::from_container(container)
        .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
    let prepared = PreparedCloud::new(&asset)
        .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
    let read_s = t.elapsed().as_secs_f64();
    let lods: Vec<usize> = match args.lod {
        Some(k) if k < prepared.level_count() => vec![k],
        Some(k) => {
            return Err(bad(
                "--lod",
                format!(
                    "{k}: {asset_shown} has {} LOD levels (0 to {})",
                    prepared.level_count(),
                    prepared.level_count() - 1
                ),
            ))
        }
        None => (0..prepared.level_count()).collect(),
    };
    let baked = asset
        .header
        .baked_light()
        .map_err(|e| CliError::new(Code::InvalidInput, format!("{asset_shown}: {e}")))?;
    // The colours are final (baked under a light, recorded or not) unless baked unlit.
    let lit = !baked.is_unlit();
    let light = match baked {
        BakedLight::Unlit => "unlit".to_string(),
        BakedLight::Directional { .. } => asset
            .header
            .params
            .get(billow_format::param::LIGHT)
            .cloned()
            .unwrap_or_default(),
        BakedLight::Unknown => "unknown (no light key: the colours are final)".to_string(),
    };
    let (lighting, note) = match args.lighting {
        LightingArg::Auto => (
            Lighting::for_cloud(&asset.header.params)
                .map_err(|e| CliError::new(Code::InvalidInput, format!("{asset_shown}: {e}")))?,
            None,
        ),
        LightingArg::Unlit => (
            Lighting::Unlit,
            lit.then(|| {
                "the cloud has baked lighting but --lighting unlit: the errors include the \
                 lighting difference"
                    .to_string()
            }),
        ),
    };
    let options = EvalOptions {
        width,
        height,
        fov_y: EVAL_FOV_Y,
        reference_per_axis: per_axis,
        raster_1spp: true,
        lighting,
        ..EvalOptions::default()
    };
    let mut evaluator = Evaluator::new(scene, options)
        .map_err(|e| CliError::new(Code::InvalidInput, format!("{source_shown}: {e}")))?;
    let mut stage = create_out(args)?;
    let mismatch = source_note(ctx, args, source, asset.header.source.as_ref());
    let lights = parse_lights(args)?;
    let light_list: Vec<Option<&billow::eval::lighting::EvalLight>> = match &lights {
        Some(l) => l.iter().map(Some).collect(),
        None => vec![None],
    };
    let (lighting, note) = match &lights {
        Some(_) => (
            Lighting::Scene {
                light: glam::Vec3::ZERO,
                ambient: args.ambient,
                shadows: args.shadows,
            },
            lit.then(|| {
                "the cloud's billboards carry the lighting they were baked with: under another \
                 light the errors include the difference"
                    .to_string()
            }),
        ),
        None => (lighting, note),
    };

    let bar = progress(
        ctx,
        (views.len() * lods.len() * light_list.len()) as u64,
        "eval",
    );
    let mut per_lod: Vec<Vec<ViewResult>> = vec![Vec::new(); lods.len()];
    let mut raster = Vec::new();
    let mut images = Vec::new();
    let mut reference_s = 0.0;
    let mut raster_s = 0.0;
    for light in &light_list {
        if let Some(l) = light {
            evaluator
                .set_light(l, args.shadows)
                .map_err(|e| CliError::new(Code::from(&e), format!("{source_shown}: {e}")))?;
        }
        // The kept mesh is drawn as the viewer draws meshes: lit like the reference.
        let renderer = CloudRenderer::new(&prepared, evaluator.options.lighting)
            .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
        for spec in &views {
            bar.set_message(spec.name.clone());
            let reference = evaluator
                .reference(spec)
                .map_err(|e| CliError::new(Code::from(&e), format!("{source_shown}: {e}")))?;
            reference_s += reference.seconds;
            let mut panels = Vec::new();
            for (i, &lod) in lods.iter().enumerate() {
                let (result, image) = evaluator
                    .cloud(&renderer, &prepared, lod, &reference)
                    .map_err(|e| CliError::new(Code::from(&e), format!("{asset_shown}: {e}")))?;
                per_lod[i].push(result);
                panels.push(image);
                bar.inc(1);
            }
            if let Some((img, err, s)) = &reference.raster_1spp {
                raster.push(*err);
                raster_s += s;
                panels.push(img.clone());
            }
            if let Some(dir) = &args.out {
                let path = dir.join(format!("{}.png", image_stem(*light, &spec.name)));
                let tests: Vec<_> = panels.iter().collect();
                stage_png(&mut stage, &path, &reference.image, &tests)?;
                images.push(path.display().to_string());
            }
        }
    }
    bar.finish_and_clear();

    let levels: Vec<LevelSummary> = lods
        .iter()
        .zip(per_lod)
        .map(|(&lod, results)| LevelSummary {
            lod,
            billboards: prepared.billboards(lod),
            epsilon: asset.levels[lod].epsilon,
            texel_density: prepared.texel_density(lod),
            texture_bytes: prepared.texture_bytes(&asset, lod),
            mean: mean_errors(results.iter().map(|r| &r.asset)),
            by_distance: means_by_distance(&results),
            lights: lights_json(lights.as_deref(), &results),
            seconds: results.iter().map(|r| r.seconds.asset).sum(),
            fragments: results.iter().map(|r| r.fragments).sum(),
            views: results,
        })
        .collect();
    let gpu = billow_core::gpu_memory::cloud_gpu_bytes(&asset, asset.header.compress().is_some());
    let summary = CloudSummary {
        source: source_shown,
        asset: asset_shown,
        kind: "cloud",
        asset_params: asset.header.params.clone(),
        gpu_bytes: gpu.with_bc,
        gpu_bytes_no_bc: gpu.without_bc,
        size: [width, height],
        fov_y_degrees: EVAL_FOV_Y.to_degrees(),
        reference_spp: args.spp,
        lighting: LightingJson {
            asset: light,
            reference: lighting.name(),
            reference_details: super::reference_details(&lighting, lights.as_deref(), args),
        },
        notes: mismatch.into_iter().chain(note).collect(),
        raster_1spp: mean_errors(&raster),
        seconds: Seconds {
            import: import_s,
            read_asset: read_s,
            reference: reference_s,
            asset: levels.iter().map(|l| l.seconds).sum(),
            raster_1spp: raster_s,
            total: start.elapsed().as_secs_f64(),
        },
        levels,
        images,
    };
    finish_out(args, stage, &summary)?;
    if args.json {
        print_json(&summary)?;
    } else {
        print_table(&summary);
    }
    Ok(())
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
