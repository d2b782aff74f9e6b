//! The accuracy-versus-cost sweep behind `make accuracy`: regenerates `docs/accuracy.md`
//! and its plots (`docs/accuracy/*.svg`, written by hand: no plotting dependency).
//!
//! `cargo run --release --example accuracy -- [REPORT.md] [--quick]`
//!
//! For each mesh (the bundled oak; `../shared/assets/spot_cow/spot.obj` and
//! `../shared/assets/stanford_bunny/bunny.obj` when `../shared` exists), one factor at a
//! time is varied from the baseline (128³, 4×4 supersampling, `opaque`, adaptive slicing
//! with bias 1): voxel resolution 32/64/128/256, supersampling 1/2/4, combine
//! mean/max/opaque, slice spacing adaptive 0.5/1/2 and uniform (one level-0 voxel, always
//! MIP level 0). Each volume is rendered from every view of the evaluation set (14
//! directions × 1/4/16× the framed distance, 128×128, see docs/eval.md) and compared with
//! the 16-spp reference. `--quick` uses 64×64 images, the axis views and no 256³.
//!
//! Then the oak as a billboard cloud ([`cloud`]): ε, N and texel density swept against
//! bake time and texture bytes, and a 4-level LOD chain's error against distance.
//!
//! Every block between `<!-- NAME:begin -->` and `<!-- NAME:end -->` in the existing report
//! is kept as it is, whatever its name (`emptyspace-sweep`, `particle-layer`, `pareto`:
//! written by other generators; `compressed-textures`: measured by hand); the markers of
//! the other generators' blocks are written when absent.

mod cloud;
#[path = "../common/instr.rs"]
mod instr;
mod plot;
mod report;
mod volume;

use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    instr::child_main(instr::imported, |scene, words| match words[0].as_str() {
        "volume" => volume::count_child(scene, &words[1..]),
        "cloud" => cloud::count_child(scene, &words[1..]),
        w => panic!("unknown bake {w}"),
    });
    let mut out = PathBuf::from("docs/accuracy.md");
    let mut quick = false;
    for a in std::env::args().skip(1) {
        if a == "--quick" {
            quick = true;
        } else {
            out = PathBuf::from(a);
        }
    }
    let start = Instant::now();
    // Bake instruction counts (callgrind): checked once; without valgrind one SKIP line.
    let count = !quick && instr::available("accuracy: bake instruction counts");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shared = root.join("../shared/assets");
    let oak = "fixtures/oak/eztree_oak_medium.gltf";
    let mut meshes = vec![("Oak".to_string(), root.join(oak), oak.to_string())];
    let mut skipped = Vec::new();
    for (name, rel) in [
        ("Spot", "spot_cow/spot.obj"),
        ("Bunny", "stanford_bunny/bunny.obj"),
    ] {
        let p = shared.join(rel);
        if p.is_file() {
            meshes.push((name.to_string(), p, format!("../shared/assets/{rel}")));
        } else {
            let why = format!("`../shared/assets/{rel}` not found (run where `../shared` exists)");
            // Loud on stderr; a run that must be complete (CI, BILLOW_REQUIRE=all) fails.
            billow::test_support::skip(&format!("accuracy: {name}"), &why);
            skipped.push(format!("{name}: {why}"));
        }
    }
    let mut reports = Vec::new();
    for (name, path, shown) in &meshes {
        match volume::run_mesh(name, path, shown, quick, count) {
            Ok(r) => reports.push(r),
            Err(e) => {
                eprintln!("{name}: {e}");
                skipped.push(format!("{name}: {e}"));
            }
        }
    }
    let cloud_section = match cloud::run(&root.join(oak), oak, quick, count) {
        Ok(c) => Some(c),
        Err(e) => {
            eprintln!("cloud: {e}");
            skipped.push(format!("Oak billboard cloud: {e}"));
            None
        }
    };
    let plot_dir = out.parent().unwrap_or(Path::new(".")).join("accuracy");
    std::fs::create_dir_all(&plot_dir).expect("create the plot folder");
    for m in &reports {
        let p = plot_dir.join(format!("{}.svg", m.name.to_lowercase().replace(' ', "_")));
        billow_format::write_atomic(&p, plot::plot(m).as_bytes()).expect("write plot");
    }
    let mut extra = String::new();
    if let Some(c) = &cloud_section {
        let (sweep, lods) = cloud::plots(c);
        billow_format::write_atomic(&plot_dir.join("oak_cloud.svg"), sweep.as_bytes())
            .expect("write plot");
        billow_format::write_atomic(&plot_dir.join("oak_lods.svg"), lods.as_bytes())
            .expect("write plot");
        extra.push_str(&cloud::section(c));
    }
    extra.push_str(&kept_blocks(&out));
    // Relative paths in the report assume the plots sit next to it in `accuracy/`.
    let text = report::report(
        &reports,
        &skipped,
        start.elapsed().as_secs_f64(),
        quick,
        &extra,
    );
    billow_format::write_atomic(&out, text.as_bytes()).expect("write report");
    eprintln!(
        "wrote {} and {} plots in {:.0} s",
        out.display(),
        reports.len(),
        start.elapsed().as_secs_f64()
    );
}

/// The blocks between `<!-- NAME:begin -->` and `<!-- NAME:end -->` of the existing report
/// at `path`, markers included, kept byte for byte in their order: sections another
/// generator writes (the empty-space sweep, the particle-layer bench, `make
/// accuracy-pareto`) or that were measured by hand (compressed textures). Every such block
/// is kept, whatever its name, so that regenerating the report never drops one; where a
/// known block is absent (a first run) its empty markers are written for its generator.
fn kept_blocks(path: &Path) -> String {
    let old = std::fs::read_to_string(path).unwrap_or_default();
    let mut out = String::new();
    let mut names = Vec::new();
    let mut rest = old.as_str();
    while let Some(b) = rest.find("<!-- ") {
        let tail = &rest[b..];
        let Some(name) = tail[5..]
            .find(":begin -->")
            .map(|e| &tail[5..5 + e])
            .filter(|n| !n.contains(char::is_whitespace))
        else {
            rest = &tail[5..];
            continue;
        };
        let end = format!("<!-- {name}:end -->");
        let Some(e) = tail.find(&end) else {
            rest = &tail[5..];
            continue;
        };
        out.push_str(&tail[..e + end.len()]);
        out.push_str("\n\n");
        names.push(name.to_string());
        rest = &tail[e + end.len()..];
    }
    for name in KNOWN_BLOCKS {
        if !names.iter().any(|n| n == name) {
            out.push_str(&format!("<!-- {name}:begin -->\n<!-- {name}:end -->\n\n"));
        }
    }
    out
}

/// Blocks written by other generators: the empty-space sweep (`examples/emptyspace_sweep.rs`),
/// the particle-layer bench, `examples/pareto_sweep` (`make accuracy-pareto`).
const KNOWN_BLOCKS: [&str; 3] = ["emptyspace-sweep", "particle-layer", "pareto"];
