//! The report text: tables, findings, method.

use std::fmt::Write as _;

use crate::volume::{MeshReport, Row, BASE_COMBINE};

pub(crate) fn mib(b: u64) -> f64 {
    b as f64 / f64::from(1u32 << 20)
}

pub(crate) fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

pub(crate) fn find<'a>(m: &'a MeshReport, family: &str, label: &str) -> Option<&'a Row> {
    m.rows
        .iter()
        .find(|r| r.config.family == family && r.config.label == label)
}

pub(crate) fn table(m: &MeshReport) -> String {
    let mut s = String::new();
    let dist = |r: &Row, f: f32| {
        r.by_distance
            .iter()
            .find(|d| d.0 == f)
            .map(|d| d.1)
            .unwrap_or_default()
    };
    let _ = writeln!(
        s,
        "| sweep | setting | bake s | bake G instr. | asset MiB | render ms/view | slices/view | fragments/view | RMSE | PSNR dB | SSIM | FLIP | RMSE 1× / 4× / 16× | covered RMSE 1× / 4× / 16× | coverage 1× / 4× / 16× |"
    );
    let _ = writeln!(
        s,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|"
    );
    for r in &m.rows {
        let instr = crate::instr::giga(r.bake_instr);
        let (a, b, c) = (dist(r, 1.0), dist(r, 4.0), dist(r, 16.0));
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {instr} | {:.2} | {:.1} | {:.0} | {:.0} | {:.4} | {:.2} | {:.3} | {:.4} | {:.4} / {:.4} / {:.4} | {:.4} / {:.4} / {:.4} | {:+.0}% / {:+.0}% / {:+.0}% |",
            r.config.family,
            r.config.label,
            r.bake_s,
            mib(r.bytes),
            1e3 * r.render_s,
            r.slices,
            r.fragments,
            r.mean.rmse,
            r.mean.psnr,
            r.mean.ssim_luma,
            r.mean.flip,
            a.rmse,
            b.rmse,
            c.rmse,
            a.rmse_covered,
            b.rmse_covered,
            c.rmse_covered,
            100.0 * a.coverage_rel_diff,
            100.0 * b.coverage_rel_diff,
            100.0 * c.coverage_rel_diff,
        );
    }
    let rd = |f: f32| {
        m.raster_by_distance
            .iter()
            .find(|d| d.0 == f)
            .map(|d| d.1)
            .unwrap_or_default()
    };
    let (a, b, c) = (rd(1.0), rd(4.0), rd(16.0));
    let _ = writeln!(
        s,
        "| mesh, 1 spp | no anti-aliasing | – | – | – | – | – | – | {:.4} | {:.2} | {:.3} | {:.4} | {:.4} / {:.4} / {:.4} | {:+.0}% / {:+.0}% / {:+.0}% |",
        m.raster.rmse,
        m.raster.psnr,
        m.raster.ssim_luma,
        m.raster.flip,
        a.rmse,
        b.rmse,
        c.rmse,
        100.0 * a.coverage_rel_diff,
        100.0 * b.coverage_rel_diff,
        100.0 * c.coverage_rel_diff,
    );
    s
}

/// Data-driven observations for one mesh.
pub(crate) fn findings(m: &MeshReport) -> String {
    let mut s = String::new();
    let best_of = |family: &str| {
        m.rows
            .iter()
            .filter(|r| r.config.family == family)
            .min_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse))
    };
    let base = find(m, "combine", BASE_COMBINE.name());
    let Some(base) = base else { return s };
    let _ = writeln!(
        s,
        "- Baseline (128³, ss 4×4, opaque, adaptive 1): RMSE {:.4}, PSNR {:.1} dB, {:.2} s bake, {:.1} MiB; the mesh at 1 spp: RMSE {:.4} ({}).",
        base.mean.rmse,
        base.mean.psnr,
        base.bake_s,
        mib(base.bytes),
        m.raster.rmse,
        if base.mean.rmse < m.raster.rmse {
            format!("the volume is {:.0}% lower", 100.0 * (1.0 - base.mean.rmse / m.raster.rmse))
        } else {
            format!("the volume is {:.0}% higher", 100.0 * (base.mean.rmse / m.raster.rmse - 1.0))
        }
    );
    for family in ["resolution", "supersampling", "combine", "spacing"] {
        if let Some(b) = best_of(family) {
            let worst = m
                .rows
                .iter()
                .filter(|r| r.config.family == family)
                .max_by(|a, b| a.mean.rmse.total_cmp(&b.mean.rmse))
                .unwrap();
            let _ = writeln!(
                s,
                "- {family}: lowest error {} (RMSE {:.4}), highest {} ({:.4}).",
                b.config.label, b.mean.rmse, worst.config.label, worst.mean.rmse
            );
        }
    }
    s
}

/// The whole report; `extra` (the cloud section, the emptyspace block) goes before the
/// fixed advice.
pub(crate) fn report(
    meshes: &[MeshReport],
    skipped: &[String],
    total_s: f64,
    quick: bool,
    extra: &str,
) -> String {
    let mut s = String::new();
    let threads = rayon::current_num_threads();
    s.push_str("# Accuracy against cost\n\n");
    s.push_str(
        "How close a volumetric billboard looks to its source mesh, and what it costs to bake, \
         store and draw, as each bake or render setting varies. **Generated by `make accuracy`** \
         (`examples/accuracy/`); do not edit by hand — change the generator and rerun.\n\n",
    );
    s.push_str(
        "The quick headline numbers of the CLI's defaults (billboards, bytes, slices, fragments, \
         RMSE), which `make test` checks against the code, are in \
         [accuracy/quick.md](accuracy/quick.md) (`tests/accuracy_drift.rs`).\n\n",
    );
    let _ = writeln!(
        s,
        "Measured on {} with {threads} threads; the whole sweep took {:.0} s{}.\n",
        cpu_model(),
        total_s,
        if quick {
            " (`--quick`: 64×64, axis views, no 256³)"
        } else {
            ""
        }
    );
    s.push_str("## Method\n\n");
    s.push_str(
        "- **Error**: `billow eval`'s metrics (docs/eval.md): each volume is drawn by the CPU \
         slicer (the paper's §3.3 algorithm, the GPU viewer's reference) and compared with a \
         16-spp ray-traced reference of the mesh, unlit, at 128×128 from all 14 directions of \
         the view set (6 axes, 8 diagonals) at 1×, 4× and 16× the framed distance (42 views; \
         45° field of view; at 16× the object is about 8 pixels wide). RMSE is on premultiplied \
         linear RGBA over the whole image, averaged over the views; *covered RMSE* is the same \
         over the covered pixels only (the union of the reference's and the volume's coverage, \
         α above half an 8-bit step), which the empty background does not dilute at a \
         distance; PSNR is that of the mean \
         MSE; SSIM on luma; FLIP (LDR-ꟻLIP via `nv-flip`, over black, 0 = identical); coverage is the relative difference of the summed alpha (+ = the \
         volume is more opaque than the mesh).\n\
         - **Baseline**: 128³ (voxels along the longest axis), 4×4 coverage samples per voxel \
         column, `opaque` combine, adaptive slicing with bias 1 (one pixel's footprint, never \
         finer than a voxel). Each sweep varies one setting from the baseline.\n\
         - **Uniform** spacing is one level-0 voxel at every depth, so it always samples MIP \
         level 0 (what a slicer without distance-dependent MIP selection does).\n\
         - **Costs**: bake = `voxelize` wall time, one run (release build, import excluded), \
         and its instructions (G = 10⁹; callgrind, one thread, import excluded: \
         `examples/common/instr.rs`; unlike the time, the same on a loaded machine); \
         asset = the `.billow` file size; render = CPU slicer wall time per view, the best of \
         three runs (a proxy for the GPU's fill cost; fragments = volume samples shaded per \
         view, the machine-independent measure). The machine is shared, so times of a few \
         milliseconds are noisy; compare fragments for rendering cost.\n\
         - **Mesh, 1 spp**: the same reference renderer with one sample at each pixel centre, \
         i.e. the mesh drawn without anti-aliasing: the error the volume should beat at a \
         distance (the paper's claim).\n\n",
    );
    for m in meshes {
        let _ = writeln!(
            s,
            "## {} (`{}`, {} triangles)\n",
            m.name, m.path, m.triangles
        );
        let _ = writeln!(
            s,
            "![{} accuracy against cost](accuracy/{}.svg)\n",
            m.name,
            m.name.to_lowercase().replace(' ', "_")
        );
        s.push_str(&table(m));
        let _ = writeln!(
            s,
            "\nReference rendering (42 views at 16 spp + 42 at 1 spp): {:.1} s.\n",
            m.reference_s
        );
        s.push_str(&findings(m));
        s.push('\n');
    }
    for sk in skipped {
        let _ = writeln!(s, "- skipped: {sk}");
    }
    if !skipped.is_empty() {
        s.push('\n');
    }
    s.push_str(extra);
    s.push_str(include_str!("advice.md"));
    s
}
