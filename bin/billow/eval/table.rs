//! `billow eval`'s table on stdout (without `--json`): the volume's header lines, then the
//! views, the per-distance means and the mean (shared with the cloud's table).

use billow::eval::suite::{mean_errors, DistanceMeans, MeanErrors, ViewResult};

use super::{LightJson, Means, Summary};

/// `(112x128x112)` for a volume, `(grid 112x128x112, pruned into an 84x128x74 atlas)`
/// for a pruned one (its level-0 texture is the atlas, the grid is in its `dims` param).
fn dims_text(s: &Summary) -> String {
    let d = s.asset_dims;
    let atlas = format!("{}x{}x{}", d[0], d[1], d[2]);
    let pruned = s.asset_params.contains_key("emptyspace");
    match s.asset_params.get("dims") {
        Some(grid) if pruned && *grid != atlas => {
            format!("grid {grid}, pruned into an {atlas} atlas")
        }
        _ => atlas,
    }
}

pub(super) fn print_table(s: &Summary) {
    outln!(
        "{} vs {} ({}), {}x{} px, {} spp reference, spacing {}",
        s.asset,
        s.source,
        dims_text(s),
        s.size[0],
        s.size[1],
        s.reference_spp,
        s.spacing
    );
    outln!(
        "{}",
        crate::output::gpu_line(s.gpu_bytes, s.gpu_bytes_no_bc)
    );
    for n in &s.notes {
        outln!("note: {n}");
    }
    let totals = (s.seconds.reference, s.seconds.asset, s.slices, s.fragments);
    print_rows(
        &s.views,
        &s.by_distance,
        &s.lights,
        &s.mean,
        totals,
        "slices",
    );
    outln!(
        "RMSE/PSNR on premultiplied linear RGBA; cov% = asset coverage vs reference; lum% = its \
         mean covered luminance vs the reference's; SSIM on luma; FLIP over black. Total {:.2} s.",
        s.seconds.total
    );
}

/// The table of views, per-distance means and the mean; `count` names the 4th timing
/// column (`slices` for volumes, `bboards` for clouds: billboards hit).
pub(crate) fn print_rows(
    views: &[ViewResult],
    by_distance: &[DistanceMeans],
    lights: &[LightJson],
    mean: &Means,
    totals: (f64, f64, usize, u64),
    count: &str,
) {
    // Under lights the view column names the light too (`sun-east +x@4x`).
    let w = if lights.is_empty() { 14 } else { 24 };
    outln!(
        "{:<w$} {:>7} {:>6} {:>6} {:>7} {:>7} {:>6} {:>6} | {:>7} {:>6} {:>6} | {:>7} {:>7} {:>6} {:>9}",
        "view",
        "RMSE",
        "PSNR",
        "|Δα|",
        "cov%",
        "lum%",
        "SSIM",
        "FLIP",
        "1spp",
        "PSNR",
        "SSIM",
        "ref s",
        "asset s",
        count,
        "fragments"
    );
    let row = |name: &str, a: &MeanErrors, r: &MeanErrors, tail: String| {
        outln!(
            "{:<w$} {:>7.4} {:>6.2} {:>6.4} {:>+7.2} {:>+7.2} {:>6.3} {:>6.4} | {:>7.4} {:>6.2} {:>6.3} |{}",
            name,
            a.rmse,
            a.psnr,
            a.mean_abs_alpha,
            100.0 * a.coverage_rel_diff,
            100.0 * a.luminance_rel_diff,
            a.ssim_luma,
            a.flip,
            r.rmse,
            r.psnr,
            r.ssim_luma,
            tail
        );
    };
    let tail =
        |rs: f64, as_: f64, sl: usize, fr: u64| format!(" {rs:>7.2} {as_:>7.2} {sl:>6} {fr:>9}");
    for v in views {
        let a = mean_errors([&v.asset]);
        let r = v
            .raster_1spp
            .as_ref()
            .map_or_else(MeanErrors::default, |e| mean_errors([e]));
        let count = if count == "slices" {
            v.slices
        } else {
            v.polygons
        };
        let t = tail(v.seconds.reference, v.seconds.asset, count, v.fragments);
        let name = match &v.light {
            Some(l) => format!("{l} {}", v.view),
            None => v.view.clone(),
        };
        row(&name, &a, &r, t);
    }
    for m in by_distance {
        let r = m.raster_1spp.unwrap_or_default();
        row(
            &format!("mean @{}x", m.distance_factor),
            &m.asset,
            &r,
            String::new(),
        );
    }
    for l in lights {
        let r = l.means.raster_1spp.unwrap_or_default();
        row(
            &format!("mean {}", l.name),
            &l.means.asset,
            &r,
            String::new(),
        );
    }
    let t = tail(totals.0, totals.1, totals.2, totals.3);
    let name = if lights.is_empty() {
        "mean"
    } else {
        "mean over the lights"
    };
    row(name, &mean.asset, &mean.raster_1spp, t);
}
