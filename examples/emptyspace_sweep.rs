//! The measurements behind docs/emptyspace.md: what `billow emptyspace` saves in texture
//! memory and in CPU rendering work, what it changes in the image, and a sweep of
//! `--threshold` and `--min-box` (error against memory against render time).
//!
//! `cargo run --release --example emptyspace_sweep -- [--quick] [--sweep-md FILE]
//! [--accuracy FILE]` (`make accuracy-emptyspace`): writes `docs/emptyspace_sweep.md`
//! (every table) and the section of `docs/accuracy.md` between the markers
//! `<!-- emptyspace-sweep:begin -->` and `<!-- emptyspace-sweep:end -->` (appended when
//! absent) with its plot `docs/accuracy/emptyspace.svg`.
//!
//! Volumes: the bundled oak at 128³ and 256³ and, when `../shared/assets` (or
//! `$BILLOW_SHARED/assets`) exists, the spot cow at 128³, baked like `voxelize --normals
//! off --align 8` (so with the CLI's `--combine opaque`, not the library's `mean`; the
//! unaligned bake's size is reported too). Views: the eval view set (14 directions × 1×,
//! 4×, 16× the framed distance, 128×128; `--quick`: the 6 axes, 64×64, no 256³), the CPU
//! slicer, compared with the eval's 16-spp ray-traced reference of the mesh. Render times
//! are the best of 5 runs of the whole view set; fragments (slice samples shaded) are
//! exact.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::emptyspace::{prune, EmptySpaceOptions, EmptySpaceStats};
use billow::eval::suite::{
    mean_errors, EvalOptions, Evaluator, MeanErrors, PreparedAsset, ReferenceView,
};
use billow::eval::ImageF32;
use billow::import::{import, ImportOptions};
use billow::scene::Scene;
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};
use billow_core::camera::{view_set, ViewDirections};
use billow_format::VolumeAsset;

const REPEATS: usize = 5;
const BEGIN: &str = "<!-- emptyspace-sweep:begin -->";
const END: &str = "<!-- emptyspace-sweep:end -->";

fn bake(scene: &Scene, res: u32, align: u32) -> VolumeAsset {
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        align,
        // The CLI's default combine (the library's default is `mean`); normals stay off, as
        // with `--normals off`.
        combine: "opaque".parse().expect("combine opaque"),
        ..VoxelizeOptions::default()
    };
    let v = voxelize(scene, &opts, &|_, _| {}).expect("voxelize");
    v.into_asset("billow emptyspace_sweep", None, BTreeMap::new())
}

/// One asset drawn from every view.
struct Drawn {
    images: Vec<ImageF32>,
    /// Mean RMSE against the reference: all views, then 1×, 4×, 16×.
    rmse: [f64; 4],
    fragments: u64,
    /// Best of [`REPEATS`] runs over the whole view set, seconds.
    seconds: f64,
}

fn draw(ev: &Evaluator<'_>, refs: &[ReferenceView], a: &VolumeAsset) -> Drawn {
    let prepared = PreparedAsset::new(a).expect("decode");
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..REPEATS {
        let runs: Vec<_> = refs
            .iter()
            .map(|r| ev.asset(&prepared, r).expect("render"))
            .collect();
        best = best.min(runs.iter().map(|r| r.0.seconds.asset).sum());
        out = Some(runs);
    }
    let runs = out.expect("one run");
    let m = |f: Option<f32>| -> f64 {
        let e: Vec<_> = runs
            .iter()
            .filter(|r| f.is_none_or(|f| r.0.distance_factor == f))
            .map(|r| r.0.asset)
            .collect();
        let m: MeanErrors = mean_errors(&e);
        m.rmse
    };
    Drawn {
        rmse: [m(None), m(Some(1.0)), m(Some(4.0)), m(Some(16.0))],
        fragments: runs.iter().map(|r| r.0.fragments).sum(),
        seconds: best,
        images: runs.into_iter().map(|r| r.1).collect(),
    }
}

fn max_abs(a: &[ImageF32], b: &[ImageF32]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| p.data.iter().zip(&q.data))
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max)
}

struct Row {
    label: String,
    stats: EmptySpaceStats,
    drawn: Drawn,
    max_abs: f32,
}

struct Volume {
    name: String,
    unaligned: [u32; 3],
    unaligned_bytes: u64,
    source: VolumeAsset,
    base: Drawn,
    default: Row,
    sweep: Vec<(&'static str, Row)>,
    reference_s: f64,
}

fn mib(b: u64) -> f64 {
    b as f64 / f64::from(1u32 << 20)
}

fn run(name: &str, scene: &Scene, res: u32, quick: bool, sweep: bool) -> Volume {
    let t = Instant::now();
    let unaligned = bake(scene, res, 1);
    let source = bake(scene, res, 8);
    let px = if quick { 64 } else { 128 };
    let ev = Evaluator::new(
        scene,
        EvalOptions {
            width: px,
            height: px,
            raster_1spp: false,
            ..EvalOptions::default()
        },
    )
    .expect("evaluator");
    let views = view_set(if quick {
        ViewDirections::Axes
    } else {
        ViewDirections::All
    });
    let refs: Vec<ReferenceView> = views
        .iter()
        .map(|v| ev.reference(v).expect("ref"))
        .collect();
    let reference_s = t.elapsed().as_secs_f64();
    let base = draw(&ev, &refs, &source);
    let row = |label: String, o: &EmptySpaceOptions| {
        let p = prune(&source, o).expect("prune");
        let drawn = draw(&ev, &refs, &p.asset);
        let d = max_abs(&base.images, &drawn.images);
        eprintln!(
            "{name} {label}: saving {:.3}, fragments {:.2}×, max |Δ| {d:.2e}",
            p.stats.saving,
            drawn.fragments as f64 / base.fragments.max(1) as f64
        );
        Row {
            label,
            stats: p.stats,
            drawn,
            max_abs: d,
        }
    };
    let default = row("default".into(), &EmptySpaceOptions::default());
    let mut rows = Vec::new();
    if sweep {
        for t in [4u8, 16, 64, 128] {
            let o = EmptySpaceOptions {
                threshold: t,
                ..Default::default()
            };
            rows.push(("threshold", row(format!("`--threshold {t}`"), &o)));
        }
        for m in [8u32, 16, 32] {
            let o = EmptySpaceOptions {
                min_box: m,
                ..Default::default()
            };
            rows.push(("min-box", row(format!("`--min-box {m}`"), &o)));
        }
        for w in [64.0f64, 1024.0] {
            let o = EmptySpaceOptions {
                cell_cost: w,
                ..Default::default()
            };
            rows.push(("cell-cost", row(format!("`--cell-cost {w}`"), &o)));
        }
    }
    Volume {
        name: name.into(),
        unaligned: unaligned.level_dims(0),
        unaligned_bytes: unaligned.texel_bytes(),
        source,
        base,
        default,
        sweep: rows,
        reference_s,
    }
}

fn dims(d: [u32; 3]) -> String {
    format!("{}×{}×{}", d[0], d[1], d[2])
}

/// The headline table: one row per volume at default settings.
fn headline(vols: &[Volume]) -> String {
    let mut s = String::from("| volume | `voxelize --res` → `--align 8` | texel memory: unaligned / aligned → pruned | saving (vs unaligned) | bands (first levels) | boxes | fragments | render time | max \\|Δ\\| vs unpruned | RMSE vs mesh, unpruned → pruned |\n|---|---|---|---:|---|---:|---:|---:|---:|---|\n");
    for v in vols {
        let r = &v.default;
        let st = &r.stats;
        let bands: Vec<String> = st.bands.iter().map(|b| b.first_level.to_string()).collect();
        let _ = writeln!(
            s,
            "| {} | {} → {} | {:.2} / {:.2} → {:.2} MiB | {:.0} % ({:.0} %) | {} ({}) | {} | {:.2}× | {:.2}× | {:.1e} | {:.4} → {:.4} |",
            v.name,
            dims(v.unaligned),
            dims(st.source_dims),
            mib(v.unaligned_bytes),
            mib(st.texel_bytes_before),
            mib(st.texel_bytes_after),
            100.0 * st.saving,
            100.0 * (1.0 - st.texel_bytes_after as f64 / v.unaligned_bytes as f64),
            st.bands.len(),
            bands.join(", "),
            st.boxes,
            r.drawn.fragments as f64 / v.base.fragments.max(1) as f64,
            r.drawn.seconds / v.base.seconds.max(1e-9),
            r.max_abs,
            v.base.rmse[0],
            r.drawn.rmse[0],
        );
    }
    s
}

/// The sweep table of one volume.
fn sweep_table(v: &Volume) -> String {
    let mut s = String::from("| setting | texel MiB | saving | boxes | voxels kept | fragments / view | render ms / view | RMSE vs mesh (all / 1× / 4× / 16×) | max \\|Δ\\| vs unpruned |\n|---|---:|---:|---:|---:|---:|---:|---|---:|\n");
    let n = v.base.images.len().max(1) as f64;
    let line = |label: &str,
                bytes: u64,
                saving: f64,
                boxes: String,
                kept: f64,
                d: &Drawn,
                m: f32| {
        format!(
            "| {label} | {:.2} | {:.0} % | {boxes} | {:.0} % | {:.0} | {:.2} | {:.4} / {:.4} / {:.4} / {:.4} | {:.1e} |\n",
            mib(bytes),
            100.0 * saving,
            100.0 * kept,
            d.fragments as f64 / n,
            1e3 * d.seconds / n,
            d.rmse[0],
            d.rmse[1],
            d.rmse[2],
            d.rmse[3],
            m
        )
    };
    let st = &v.default.stats;
    s.push_str(&line(
        "unpruned (`--align 8`)",
        st.texel_bytes_before,
        0.0,
        "–".into(),
        1.0,
        &v.base,
        0.0,
    ));
    let mut all: Vec<&Row> = vec![&v.default];
    all.extend(v.sweep.iter().map(|x| &x.1));
    for r in all {
        let st = &r.stats;
        s.push_str(&line(
            &r.label,
            st.texel_bytes_after,
            st.saving,
            st.boxes.to_string(),
            st.voxels_kept as f64 / st.voxels_before.max(1) as f64,
            &r.drawn,
            r.max_abs,
        ));
    }
    s
}

// ---------------------------------------------------------------------------------------
// The plot (SVG by hand, like examples/accuracy.rs): RMSE against memory and render time.

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('`', "")
}

fn plot(v: &Volume) -> String {
    type Axis = (&'static str, fn(&Drawn, u64) -> f64);
    let panels: [Axis; 2] = [
        ("texel memory (MiB)", |_, b| mib(b)),
        (
            "render time per view (ms, CPU slicer, best of 5)",
            |d, _| d.seconds,
        ),
    ];
    let n = v.base.images.len().max(1) as f64;
    let mut pts: Vec<(&str, &str, &Drawn, u64)> = vec![(
        "unpruned",
        "#000000",
        &v.base,
        v.default.stats.texel_bytes_before,
    )];
    pts.push((
        "default",
        "#d62728",
        &v.default.drawn,
        v.default.stats.texel_bytes_after,
    ));
    for (fam, r) in &v.sweep {
        let colour = match *fam {
            "threshold" => "#1f77b4",
            "min-box" => "#2ca02c",
            _ => "#ff7f0e",
        };
        pts.push((&r.label, colour, &r.drawn, r.stats.texel_bytes_after));
    }
    let (pw, ml, top, bottom) = (420.0, 60.0, 40.0, 300.0);
    let (width, height) = (2.0 * pw, 370.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="100%" height="100%" fill="white"/><text x="{}" y="18" font-size="14" text-anchor="middle">{}: billow emptyspace — mean RMSE against the mesh (all views) against cost; lower left is better</text>"#,
        width / 2.0,
        esc(&v.name)
    );
    let y_max = pts.iter().map(|p| p.2.rmse[0]).fold(0.0, f64::max) * 1.1;
    let y_min = pts
        .iter()
        .map(|p| p.2.rmse[0])
        .fold(f64::INFINITY, f64::min)
        * 0.9;
    for (k, (label, f)) in panels.iter().enumerate() {
        let x0 = k as f64 * pw;
        let xs: Vec<f64> = pts
            .iter()
            .map(|p| {
                let x = f(p.2, p.3);
                if k == 1 {
                    1e3 * x / n
                } else {
                    x
                }
            })
            .collect();
        let (lo, hi) = (0.0, xs.iter().copied().fold(0.0, f64::max) * 1.1);
        let right = x0 + pw - 20.0;
        let px = |x: f64| x0 + ml + (x - lo) / (hi - lo).max(1e-12) * (right - x0 - ml);
        let py = |y: f64| top + (y_max - y) / (y_max - y_min).max(1e-12) * (bottom - top);
        let (bx, by) = (x0 + ml, bottom);
        let _ = writeln!(
            s,
            r##"<line x1="{bx}" y1="{by}" x2="{right}" y2="{by}" stroke="#444"/><line x1="{bx}" y1="{top}" x2="{bx}" y2="{by}" stroke="#444"/>"##
        );
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            (bx + right) / 2.0,
            by + 32.0,
            esc(label)
        );
        for i in 0..=4 {
            let x = lo + (hi - lo) * f64::from(i) / 4.0;
            let y = y_min + (y_max - y_min) * f64::from(i) / 4.0;
            let _ = writeln!(
                s,
                r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#444">{:.3}</text><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#444">{:.4}</text>"##,
                px(x),
                by + 14.0,
                x,
                bx - 4.0,
                py(y) + 4.0,
                y
            );
        }
        for (p, &x) in pts.iter().zip(&xs) {
            let _ = writeln!(
                s,
                r#"<g><title>{}: RMSE {:.4}</title><circle cx="{:.1}" cy="{:.1}" r="4" fill="{}" fill-opacity="0.8"/></g>"#,
                esc(p.0),
                p.2.rmse[0],
                px(x),
                py(p.2.rmse[0]),
                p.1
            );
        }
    }
    let legend = [
        ("unpruned", "#000000"),
        ("default", "#d62728"),
        ("--threshold", "#1f77b4"),
        ("--min-box", "#2ca02c"),
        ("--cell-cost", "#ff7f0e"),
    ];
    for (i, (l, c)) in legend.iter().enumerate() {
        let x = 80.0 + 150.0 * i as f64;
        let height = height - 4.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{x}" cy="{}" r="4" fill="{c}"/><text x="{}" y="{}">{}</text>"#,
            height - 10.0,
            x + 8.0,
            height - 6.0,
            esc(l)
        );
    }
    s.push_str("</svg>\n");
    s
}

// ---------------------------------------------------------------------------------------
// Reports.

fn method(quick: bool) -> String {
    let (px, views) = if quick {
        (64, "6 axis")
    } else {
        (128, "14 (6 axes + 8 diagonals)")
    };
    format!(
        "Volumes baked with `voxelize --normals off --align 8` (the CLI's other defaults, including `--combine opaque`; even sides, required for MIP-exact bricks; \"unaligned\" is the same bake without it), pruned with `billow emptyspace` at the given settings. Views: the eval view set, {views} directions × 1×, 4×, 16× the framed distance, {px}×{px}, the CPU slicer (`billow eval`'s renderer, adaptive spacing, linear MIP filter). *fragments* = slice samples shaded (machine-independent), *render time* = slicer wall time, best of {REPEATS} runs over the whole view set (2 cores shared with other jobs: times of equal work still differ by up to ±30 %; fragments are exact); both as pruned / unpruned. *RMSE vs mesh*: against the 16-spp ray-traced reference (premultiplied RGBA), mean over the views. *max \\|Δ\\|*: largest per-pixel channel difference between the pruned and the unpruned renders over all views.\n"
    )
}

fn paper_note(vols: &[Volume]) -> String {
    let sav: Vec<String> = vols
        .iter()
        .map(|v| format!("{} {:.0} %", v.name, 100.0 * v.default.stats.saving))
        .collect();
    let fr: Vec<String> = vols
        .iter()
        .map(|v| {
            format!(
                "{} {:.2}×",
                v.name,
                v.default.drawn.fragments as f64 / v.base.fragments.max(1) as f64
            )
        })
        .collect();
    format!(
        "Against the paper (Vidal, Mei & Decaudin 2008, cited in VB §4: 50–75 % less texture memory, 50–200 % faster): memory saving at lossless default settings {}; fragments {} of the unpruned volume's over the view set (render time in the table).\n",
        sav.join(", "),
        fr.join(", ")
    )
}

fn sweep_md(vols: &[Volume], quick: bool, total_s: f64) -> String {
    let mut md = String::from("# Empty-space removal: measurements\n\n**Generated by `make accuracy-emptyspace`** (`examples/emptyspace_sweep.rs`); do not edit by hand. Design and reading guide: [emptyspace.md](emptyspace.md).\n\n");
    md.push_str(&method(quick));
    md.push_str("\n## At default settings\n\n");
    md.push_str(&headline(vols));
    md.push('\n');
    md.push_str(&paper_note(vols));
    for v in vols {
        let st = &v.default.stats;
        let _ = write!(
            md,
            "\n## {} ({} voxels, {} MIP levels; references {:.0} s)\n\nBands of the default prune:\n\n| band | first level | texture | levels | boxes | cells | texel bytes |\n|---:|---:|---|---:|---:|---:|---:|\n",
            v.name,
            dims(st.source_dims),
            v.source.levels.len(),
            v.reference_s
        );
        for (i, b) in st.bands.iter().enumerate() {
            let _ = writeln!(
                md,
                "| {i} | {} | {}{} | {} | {} | {} | {} |",
                b.first_level,
                dims(b.dims),
                if b.whole {
                    " (source levels, whole)"
                } else {
                    ""
                },
                b.mip_count,
                b.boxes,
                b.cells,
                b.texel_bytes
            );
        }
        if !v.sweep.is_empty() {
            md.push_str("\nSettings (one changed at a time from the default):\n\n");
            md.push_str(&sweep_table(v));
        }
    }
    let _ = writeln!(md, "\nWhole run: {total_s:.0} s.");
    md
}

fn accuracy_section(vols: &[Volume], quick: bool) -> String {
    let mut s = format!("{BEGIN}\n\n## Empty-space removal (`billow emptyspace`)\n\n*Generated by `make accuracy-emptyspace` (`examples/emptyspace_sweep.rs`), which rewrites only what lies between the `emptyspace-sweep` markers. Method, design and more tables: [emptyspace.md](emptyspace.md), [emptyspace_sweep.md](emptyspace_sweep.md).*\n\n");
    s.push_str(&method(quick));
    s.push_str("\nAt default settings (lossless: every band is an exact copy of the source's MIP levels):\n\n");
    s.push_str(&headline(vols));
    s.push('\n');
    s.push_str(&paper_note(vols));
    if let Some(v) = vols.iter().find(|v| !v.sweep.is_empty()) {
        let _ = write!(
            s,
            "\nSweep on the {} (`--threshold` drops texels with alpha ≤ T: lossy; `--min-box` and `--cell-cost` only change the boxes: lossless):\n\n",
            v.name
        );
        s.push_str(&sweep_table(v));
        let _ = writeln!(
            s,
            "\n![{} emptyspace sweep](accuracy/emptyspace.svg)",
            v.name
        );
    }
    let _ = write!(s, "\n{END}\n");
    s
}

/// `doc` with its marked section replaced by `section` (appended when absent; a
/// hand-written emptyspace paragraph at the end is replaced).
fn splice(doc: &str, section: &str) -> String {
    if let (Some(a), Some(b)) = (doc.find(BEGIN), doc.find(END)) {
        if a < b {
            let end = b + END.len();
            let rest = doc[end..].strip_prefix('\n').unwrap_or(&doc[end..]);
            return format!("{}{}{}", &doc[..a], section, rest);
        }
    }
    let mut base = doc.trim_end().to_string();
    if let Some(i) = base.rfind("\n\nEmpty-space removal (`billow emptyspace`)") {
        base.truncate(i);
    }
    format!("{base}\n\n{section}")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let value = |flag: &str, default: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .map_or(PathBuf::from(default), PathBuf::from)
    };
    let sweep_path = value("--sweep-md", "docs/emptyspace_sweep.md");
    let accuracy_path = value("--accuracy", "docs/accuracy.md");
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let oak = repo.join("fixtures/oak/eztree_oak_medium.gltf");
    // `BILLOW_SHARED` names the optional corpus where `../shared` is not beside the
    // checkout (a git worktree elsewhere).
    let shared = std::env::var_os("BILLOW_SHARED").map_or(repo.join("../shared"), PathBuf::from);
    let cow = shared.join("assets/spot_cow/spot.obj");
    let start = Instant::now();
    let load = |p: &Path| import(p, &ImportOptions::default()).expect("import").scene;
    let oak_scene = load(&oak);
    let mut vols = vec![run("oak 128³", &oak_scene, 128, quick, true)];
    if !quick {
        vols.push(run("oak 256³", &oak_scene, 256, quick, false));
    }
    if cow.exists() {
        vols.push(run("spot cow 128³", &load(&cow), 128, quick, false));
    } else {
        // Loud on stderr; a run that must be complete (CI, BILLOW_REQUIRE=all) fails.
        billow::test_support::skip(
            "emptyspace_sweep: spot cow",
            &format!("{} not found", cow.display()),
        );
    }
    let total = start.elapsed().as_secs_f64();
    std::fs::write(&sweep_path, sweep_md(&vols, quick, total)).expect("write sweep");
    let doc = std::fs::read_to_string(&accuracy_path).unwrap_or_default();
    std::fs::write(
        &accuracy_path,
        splice(&doc, &accuracy_section(&vols, quick)),
    )
    .expect("write accuracy");
    let svg = accuracy_path
        .parent()
        .unwrap_or(Path::new("."))
        .join("accuracy/emptyspace.svg");
    if let Some(d) = svg.parent() {
        std::fs::create_dir_all(d).expect("plot folder");
    }
    std::fs::write(&svg, plot(&vols[0])).expect("write plot");
    eprintln!(
        "wrote {}, {} and {} in {total:.0} s",
        sweep_path.display(),
        accuracy_path.display(),
        svg.display()
    );
}
