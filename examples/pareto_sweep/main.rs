//! Combined sweeps, Pareto fronts and the preset table (issue 25, item 3) behind
//! `make accuracy-pareto`: writes `docs/accuracy/pareto.md` (every point), the plots
//! `docs/accuracy/pareto_volume.svg` and `docs/accuracy/pareto_cloud.svg` (written by hand)
//! and the section of `docs/accuracy.md` between the `pareto` markers.
//!
//! `cargo run --release --example pareto_sweep -- [--quick] [--md FILE] [--accuracy FILE]`
//!
//! - **Volumes** (the bundled oak): resolution 32/64/128 (and 256 at 4×4) × supersampling
//!   1/2/4 × compression none/bc × slice-spacing bias 0.5/1/2, baked as `billow voxelize`
//!   bakes the oak (`opaque` combine, the default `--align`, no normals: `--normals auto`
//!   drops them on foliage), scored like `billow eval`'s defaults (the 6 axis views at 1×,
//!   4× and 16×, 128×128, 16-spp reference; mean RMSE on premultiplied linear RGBA).
//! - **Clouds** (the oak): ε 0.02/0.04/0.08 × N 100/500 × atlas size 512/1024/2048 (the
//!   texel density is the most the atlas holds), 3 LODs as `billow bbcloud` bakes them,
//!   BC7 as it writes them, LOD 0 scored on the same views with the lit reference.
//! - **Fronts**: per plot panel, the points no other point beats in both cost and error
//!   ([`billow::presets::pareto_front`]).
//! - **Presets** ([`billow::presets::Preset`]): each one's settings measured on the oak
//!   (from the sweep) and on a generated tree (`procgen::leafy_tree(1500, 9, 1)`), with
//!   whether it lies on the oak's fronts.
//!
//! `--quick`: 64×64 images, res ≤ 64, fewer cloud points (a smoke run, not for the docs).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use billow::eval::suite::MeanErrors;
use billow::import::{import, ImportOptions};
use billow::presets::{pareto_front, Preset};
use billow::voxelize::Resolution;
use instr::giga;

#[path = "../common/instr.rs"]
mod instr;

const BEGIN: &str = "<!-- pareto:begin -->";
/// The generated tree's name for the counting child ([`instr`]).
const TREE: &str = "procgen:leafy_tree(1500, 9, 1)";
const END: &str = "<!-- pareto:end -->";
const DISTANCES: [f32; 3] = [1.0, 4.0, 16.0];
const COLOURS: [&str; 6] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
];

/// One measured setting.
#[derive(Clone, Debug)]
struct Point {
    /// Colour group in the plots (e.g. `64³`, `ε 0.04`).
    group: String,
    /// Hollow marker (bc for volumes, N 100 for clouds).
    hollow: bool,
    label: String,
    bake_s: f64,
    /// Instructions of the bake (compression included, import excluded, one thread;
    /// [`instr`]); `None` where callgrind could not count.
    bake_instr: Option<u64>,
    bytes: u64,
    /// Mean per view.
    fragments: f64,
    render_s: f64,
    mean: MeanErrors,
    /// RMSE at 1×, 4×, 16×.
    by_distance: [f64; 3],
    /// Extra columns for the table.
    extra: Vec<String>,
    /// Volumes at the default slice spacing (bias 1): the compression, whose points form
    /// the bake-settings fronts ([`bake_fronts`]).
    subset: Option<&'static str>,
}

mod bakes;
mod svg;

use bakes::{cloud_bakes, cloud_points, count_child, load, volume_bakes, volume_points};
use svg::svg;

/// The panels: (axis label, cost).
type Cost = (&'static str, fn(&Point) -> f64);

/// The panels' costs, all load-independent where callgrind counted every bake: bake
/// instructions (else wall time), asset bytes and fragments shaded per view.
fn costs(points: &[Point]) -> [Cost; 3] {
    let bake: Cost = if points.iter().all(|p| p.bake_instr.is_some()) {
        ("bake instructions (callgrind, one thread)", |p| {
            p.bake_instr.unwrap_or(0) as f64
        })
    } else {
        ("bake time (s, wall, one run)", |p| p.bake_s)
    };
    [
        bake,
        ("asset bytes", |p| p.bytes as f64),
        ("fragments per view (render cost)", |p| p.fragments),
    ]
}

fn mib(b: u64) -> f64 {
    b as f64 / 1048576.0
}

/// Which panels' fronts a point is on: `t` bake cost, `b` bytes, `f` fragments.
fn fronts(points: &[Point]) -> Vec<String> {
    let mut on = vec![String::new(); points.len()];
    for ((_, cost), tag) in costs(points).iter().zip(['t', 'b', 'f']) {
        let pts: Vec<(f64, f64)> = points.iter().map(|p| (cost(p), p.mean.rmse)).collect();
        for i in pareto_front(&pts) {
            on[i].push(tag);
        }
    }
    on
}

/// The fronts of the bake settings alone: per compression, among the volumes drawn at the
/// default slice spacing (a view setting, which a preset does not choose); `t`, `b`, `f`
/// as in [`fronts`], empty for points outside those subsets.
fn bake_fronts(points: &[Point]) -> Vec<String> {
    let mut on = vec![String::new(); points.len()];
    for c in ["none", "bc"] {
        let idx: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].subset == Some(c))
            .collect();
        let sub: Vec<Point> = idx.iter().map(|&i| points[i].clone()).collect();
        for (k, f) in fronts(&sub).into_iter().enumerate() {
            on[idx[k]] = f;
        }
    }
    on
}

fn table(points: &[Point], head: &str, bake: Option<&[String]>) -> String {
    let on = fronts(points);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| {head} | bake s | bake G instr. | MiB | fragments/view | render ms/view | RMSE | RMSE 1× / 4× / 16× | FLIP | front |{}",
        if bake.is_some() { " front at bias 1 |" } else { "" }
    );
    let cols = head.matches('|').count() + 1;
    let _ = writeln!(
        s,
        "|{}---:|---:|---:|---:|---:|---:|---|---:|---|{}",
        "---|".repeat(cols),
        if bake.is_some() { "---|" } else { "" }
    );
    for (i, (p, f)) in points.iter().zip(&on).enumerate() {
        let tail = bake.map_or(String::new(), |b| {
            format!(
                " {} |",
                if b[i].is_empty() {
                    "–"
                } else {
                    b[i].as_str()
                }
            )
        });
        let _ = writeln!(
            s,
            "| {} | {:.2} | {} | {:.2} | {:.0} | {:.1} | {:.4} | {:.4} / {:.4} / {:.4} | {:.4} | {} |{tail}",
            p.extra.join(" | "),
            p.bake_s,
            giga(p.bake_instr),
            mib(p.bytes),
            p.fragments,
            1000.0 * p.render_s,
            p.mean.rmse,
            p.by_distance[0],
            p.by_distance[1],
            p.by_distance[2],
            p.mean.flip,
            if f.is_empty() { "–" } else { f.as_str() }
        );
    }
    s
}

/// A preset's row: mesh, preset, settings, measured numbers, fronts.
struct PresetRow {
    mesh: String,
    kind: &'static str,
    preset: Preset,
    settings: String,
    point: Point,
    front: String,
}

fn preset_table(rows: &[PresetRow]) -> String {
    let mut s = String::from(
        "| mesh | asset | preset | settings | RMSE (mean) | RMSE 1× | MiB | bake s | bake G instr. | fragments/view | render ms/view | on the oak's fronts |\n|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | **{}** | {} | {:.4} | {:.4} | {:.2} | {:.2} | {} | {:.0} | {:.1} | {} |",
            r.mesh,
            r.kind,
            r.preset,
            r.settings,
            r.point.mean.rmse,
            r.point.by_distance[0],
            mib(r.point.bytes),
            r.point.bake_s,
            giga(r.point.bake_instr),
            r.point.fragments,
            1000.0 * r.point.render_s,
            if r.front.is_empty() {
                "–"
            } else {
                r.front.as_str()
            }
        );
    }
    s
}

fn volume_settings(p: Preset) -> (u32, u32) {
    let v = p.volume();
    let Resolution::Longest(res) = v.resolution else {
        panic!("presets name a longest-axis resolution")
    };
    (res, v.supersample)
}

fn main() {
    instr::child_main(load, count_child);
    let mut md = PathBuf::from("docs/accuracy/pareto.md");
    let mut accuracy = PathBuf::from("docs/accuracy.md");
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--md" => md = args.next().expect("--md FILE").into(),
            "--accuracy" => accuracy = args.next().expect("--accuracy FILE").into(),
            other => panic!("unknown argument {other}"),
        }
    }
    let start = Instant::now();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // Bake instruction counts (callgrind): checked once; without valgrind one SKIP line,
    // and the bake panels fall back to wall time.
    let count = !quick && instr::available("pareto_sweep: bake instruction counts");
    let oak_path = root.join("fixtures/oak/eztree_oak_medium.gltf");
    let oak_id = oak_path.display().to_string();
    let oak = import(&oak_path, &ImportOptions::default())
        .expect("import the oak")
        .scene;
    let tree = load(TREE);
    let size = if quick { 64 } else { 128 };

    // Volumes: the combined grid on the oak.
    let mut grid: Vec<(u32, u32)> = Vec::new();
    for res in if quick {
        vec![32, 64]
    } else {
        vec![32, 64, 128]
    } {
        for ss in [1, 2, 4] {
            grid.push((res, ss));
        }
    }
    if !quick {
        grid.push((256, 4));
    }
    let biases = [0.5, 1.0, 2.0];
    let t = Instant::now();
    let vb =
        volume_bakes(&oak, (&oak_id, count), size, &grid, &biases, "oak").expect("volume sweep");
    let volume_s = t.elapsed().as_secs_f64();
    let vpoints = volume_points(&vb);

    // Clouds: the combined grid on the oak.
    let mut cgrid = Vec::new();
    let (eps, ns, atlases): (&[f32], &[u32], &[u32]) = if quick {
        (&[0.04, 0.08], &[100], &[512, 1024])
    } else {
        (&[0.02, 0.04, 0.08], &[100, 500], &[512, 1024, 2048])
    };
    for &e in eps {
        for &n in ns {
            for &a in atlases {
                cgrid.push((e, n, a));
            }
        }
    }
    if !quick {
        // Finer textures for the small ε, where 2048² leaves few texels per billboard.
        cgrid.extend([(0.02, 500, 4096), (0.04, 500, 4096)]);
    }
    let t = Instant::now();
    let cb = cloud_bakes(&oak, (&oak_id, count), size, &cgrid, "oak").expect("cloud sweep");
    let cloud_s = t.elapsed().as_secs_f64();
    let cpoints = cloud_points(&cb);

    // The presets: on the oak from the sweep (BC7 volumes, the default spacing), on the tree
    // baked here.
    let vfront = bake_fronts(&vpoints);
    let cfront = fronts(&cpoints);
    let mut rows = Vec::new();
    for p in Preset::LADDER {
        let (res, ss) = volume_settings(p);
        let settings = format!("`--res {res} --supersample {ss}`");
        if let Some(i) = vpoints
            .iter()
            .position(|q| q.label == format!("{res}³ ss{ss} bc b1"))
        {
            rows.push(PresetRow {
                mesh: "oak".into(),
                kind: "volume (bc)",
                preset: p,
                settings: settings.clone(),
                point: vpoints[i].clone(),
                front: vfront[i].clone(),
            });
        }
    }
    for p in Preset::LADDER {
        let c = p.cloud();
        let label = format!("ε{} N{} {}²", c.epsilon, c.samples, c.atlas_size);
        if let Some(i) = cpoints.iter().position(|q| q.label == label) {
            rows.push(PresetRow {
                mesh: "oak".into(),
                kind: "cloud (bc, LOD 0)",
                preset: p,
                settings: format!(
                    "`--epsilon {} --samples {} --atlas-size {}`",
                    c.epsilon, c.samples, c.atlas_size
                ),
                point: cpoints[i].clone(),
                front: cfront[i].clone(),
            });
        }
    }
    let t = Instant::now();
    let tgrid: Vec<(u32, u32)> = Preset::LADDER
        .iter()
        .map(|&p| volume_settings(p))
        .filter(|&(r, _)| !quick || r <= 64)
        .collect();
    let tv =
        volume_bakes(&tree, (TREE, count), size, &tgrid, &[1.0], "tree").expect("tree volumes");
    for (p, pt) in Preset::LADDER
        .iter()
        .zip(volume_points(&tv).into_iter().filter(|q| q.hollow))
    {
        let (res, ss) = volume_settings(*p);
        rows.push(PresetRow {
            mesh: "generated tree".into(),
            kind: "volume (bc)",
            preset: *p,
            settings: format!("`--res {res} --supersample {ss}`"),
            point: pt,
            front: "n/a".into(),
        });
    }
    let cg: Vec<(f32, u32, u32)> = Preset::LADDER
        .iter()
        .map(|p| {
            let c = p.cloud();
            (c.epsilon, c.samples, c.atlas_size)
        })
        .collect();
    let tc = cloud_bakes(&tree, (TREE, count), size, &cg, "tree").expect("tree clouds");
    for (p, pt) in Preset::LADDER.iter().zip(cloud_points(&tc)) {
        let c = p.cloud();
        rows.push(PresetRow {
            mesh: "generated tree".into(),
            kind: "cloud (bc, LOD 0)",
            preset: *p,
            settings: format!(
                "`--epsilon {} --samples {} --atlas-size {}`",
                c.epsilon, c.samples, c.atlas_size
            ),
            point: pt,
            front: "n/a".into(),
        });
    }
    let spot_path = root.join("../shared/assets/spot_cow/spot.obj");
    if !spot_path.is_file() {
        // Loud on stderr; a run that must be complete (CI, BILLOW_REQUIRE=all) fails.
        billow::test_support::skip(
            "pareto_sweep: Spot presets",
            &format!("{} not found", spot_path.display()),
        );
    } else {
        let spot = import(&spot_path, &ImportOptions::default())
            .expect("import Spot")
            .scene;
        let sv = volume_bakes(
            &spot,
            (&spot_path.display().to_string(), count),
            size,
            &tgrid,
            &[1.0],
            "spot",
        )
        .expect("Spot volumes");
        for (p, pt) in Preset::LADDER
            .iter()
            .zip(volume_points(&sv).into_iter().filter(|q| q.hollow))
        {
            let (res, ss) = volume_settings(*p);
            rows.push(PresetRow {
                mesh: "Spot".into(),
                kind: "volume (bc)",
                preset: *p,
                settings: format!("`--res {res} --supersample {ss}`"),
                point: pt,
                front: String::new(),
            });
        }
    }
    let tree_s = t.elapsed().as_secs_f64();

    let plot_dir = md.parent().unwrap_or(Path::new(".")).to_path_buf();
    std::fs::create_dir_all(&plot_dir).expect("create the plot folder");
    let vsvg = svg(
        "Oak volume: resolution × supersampling × compression × slice-spacing bias — mean RMSE against cost",
        &vpoints,
    );
    let csvg = svg(
        "Oak billboard cloud (LOD 0, BC7): ε × N × atlas size — mean RMSE against cost",
        &cpoints,
    );
    billow_format::write_atomic(&plot_dir.join("pareto_volume.svg"), vsvg.as_bytes())
        .expect("write plot");
    billow_format::write_atomic(&plot_dir.join("pareto_cloud.svg"), csvg.as_bytes())
        .expect("write plot");
    let threads = rayon::current_num_threads();
    let method = format!(
        "Generated by `make accuracy-pareto` (`examples/pareto_sweep.rs`); do not edit by hand. \
         {threads} threads; volumes {volume_s:.0} s, clouds {cloud_s:.0} s, the tree's presets \
         {tree_s:.0} s, {:.0} s in all. Errors: `billow eval`'s mean RMSE (premultiplied linear \
         RGBA, whole frame) over the 6 axis views at 1×, 4× and 16× the framed distance, \
         {size}×{size}, 16-spp reference. Costs: bake = wall time of one bake (compression \
         included; the machine is shared, so read it as a rough ratio) and its \
         instructions (G = 10⁹; callgrind, one thread, import excluded, \
         `examples/common/instr.rs`: the same on a loaded machine; the plots' bake axis \
         and the t fronts use them), bytes = the file \
         `billow` writes, fragments = samples shaded per view (load-independent render cost), \
         render = CPU renderer per view (the faster of two for volumes). The front column \
         says on which panel's Pareto front a point lies: t = bake cost, b = bytes, f = \
         fragments; for volumes, *front at bias 1* says the same among the volumes drawn \
         at the default slice spacing with the same compression (the bake settings' own \
         fronts: the spacing is a view setting, which a preset does not choose).\n",
        start.elapsed().as_secs_f64()
    );
    let mut full = String::from("# Combined sweeps and Pareto fronts (every point)\n\n");
    full.push_str(&method);
    full.push_str("\n## Oak volume\n\n![Oak volume Pareto fronts](pareto_volume.svg)\n\n");
    full.push_str(&table(
        &vpoints,
        "res | supersample | compress | spacing bias",
        Some(&vfront),
    ));
    full.push_str("\n## Oak billboard cloud (3 LODs, BC7, LOD 0 scored)\n\n![Oak cloud Pareto fronts](pareto_cloud.svg)\n\n");
    full.push_str(&table(
        &cpoints,
        "ε | N | atlas | texels/unit | billboards",
        None,
    ));
    full.push_str("\n## Presets\n\n");
    full.push_str(&preset_table(&rows));
    billow_format::write_atomic(&md, full.as_bytes()).expect("write the table");

    let mut block = format!("{BEGIN}\n## Pareto fronts and presets\n\n");
    block.push_str(&method);
    block.push_str(
        "\nEvery knob combined, not one at a time; each panel marks its Pareto front (the \
         points nothing beats in both cost and error). Every point: \
         [accuracy/pareto.md](accuracy/pareto.md).\n\n\
         ![Oak volume Pareto fronts](accuracy/pareto_volume.svg)\n\n\
         ![Oak cloud Pareto fronts](accuracy/pareto_cloud.svg)\n\n\
         What the fronts said in the run of 2026-12-04 (fixed text; the \
         tables are the current run): BC7 costs little accuracy on a volume (oak 128³, \
         4×4, bias 1: RMSE 0.0181 against 0.0171 raw, +6 %) for 3 % of the bytes (0.21 against \
         7.00 MiB: empty blocks are skipped) and 13 % more bake instructions (1.87 G against 1.65 G), so every bytes front is BC7; 4×4 \
         supersampling beat 1×1 and 2×2 at the next resolution up (64³ 4×4: 0.0187; 128³ \
         1×1: 0.0227, BC7 both), so the presets keep 4×4 and step the resolution; the slice-spacing \
         bias is the cheapest accuracy at render time (bias 0.5 at 128³: 0.0147 for twice \
         the fragments of bias 1), but it is the viewer's choice, not the bake's; a cloud's \
         error follows its texel density more than ε or N: at a 2048² atlas ε 0.02 (491 \
         billboards, 1.8 texels/unit) scored 0.0263, worse than ε 0.04 (128 billboards, \
         3.2 texels/unit, 0.0212), and ε 0.02 at 512² starves the atlas (0.16 texels/unit, \
         the cloud almost vanishes); N past 100 changed little.\n\n\
         ### Presets (`--preset`, docs/cli.md)\n\n\
         Each preset is a point of the oak's fronts (volumes: at the default slice spacing, \
         adaptive bias 1, which is a view setting, not a bake one; with BC7, `--compress bc`; \
         raw RGBA8 is about 4× the bytes). `--target-error E` tries them in this order.\n\n",
    );
    block.push_str(&preset_table(&rows));
    let spot = root.join("../shared/assets/spot_cow/spot.obj");
    if !spot.is_file() {
        block.push_str(
            "\nThe Spot cow is not in the table: `../shared/assets/spot_cow/spot.obj` was \
             absent where this ran.\n",
        );
    }
    block.push_str(END);
    let old = std::fs::read_to_string(&accuracy).unwrap_or_default();
    let text = match (old.find(BEGIN), old.find(END)) {
        (Some(b), Some(e)) if e > b => format!("{}{block}{}", &old[..b], &old[e + END.len()..]),
        _ => format!("{}\n{block}\n", old.trim_end()),
    };
    billow_format::write_atomic(&accuracy, text.as_bytes()).expect("write the report");
    eprintln!(
        "wrote {} and {} in {:.0} s",
        md.display(),
        accuracy.display(),
        start.elapsed().as_secs_f64()
    );
}
