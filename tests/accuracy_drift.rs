//! The doc-drift check of issue 25: the quick headline numbers committed in
//! `docs/accuracy/quick.md` must be what the code gives at HEAD.
//!
//! It runs the real binary with its **defaults** (so changing any CLI or library default
//! that reaches these numbers fails it): `billow voxelize` and `billow bbcloud` on the
//! bundled oak, then `billow eval` of each asset (6 axes × 1×, 4×, 16×, 128×128, 16 spp,
//! the eval defaults). It records counts (grid, MIP levels, non-empty voxels, billboards
//! per LOD, texels, slices, fragments), bytes (as the baker reports them and as the file
//! is on disk) and RMSE to 3 significant digits. About 6 s in the debug-test profile on
//! 2 cores.
//!
//! Regenerate the file after an intended change (e.g. another default) with the ONE
//! command [`REGENERATE`]; `make accuracy` runs it too.

mod common;

use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};

use common::*;
use serde_json::Value;

const DOC: &str = "docs/accuracy/quick.md";
const REGENERATE: &str = "BILLOW_BLESS=1 cargo test -p billow-cli --test accuracy_drift";
const OAK: &str = "fixtures/oak/eztree_oak_medium.gltf";

/// `x` to 3 significant digits (`0.0171`, `1.23e-5` below 1e-4).
fn sig3(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if e < -4 {
        return format!("{x:.2e}");
    }
    let decimals = (2 - e).max(0) as usize;
    format!("{x:.decimals$}")
}

/// Runs `billow args...` in `dir` and parses its `--json` stdout. (`Command::output` reads
/// stdout while the child runs: an eval's JSON is larger than a pipe's buffer.)
fn billow_json(dir: &Path, args: &[&str]) -> Value {
    let out = Command::new(bin())
        .args(args)
        .current_dir(dir)
        .env("RAYON_NUM_THREADS", "2")
        .stdin(Stdio::null())
        .output()
        .expect("spawn billow");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        out.status.success(),
        "billow {}: {}: {stdout}{stderr}",
        args.join(" "),
        out.status
    );
    serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("billow {}: JSON: {e}: {stdout}", args.join(" ")))
}

/// A JSON scalar as text (strings without their quotes).
fn text(v: &Value) -> String {
    v.as_str().map_or_else(|| v.to_string(), str::to_string)
}

fn num(v: &Value, path: &[&str]) -> f64 {
    let mut cur = v;
    for k in path {
        cur = &cur[*k];
    }
    cur.as_f64()
        .unwrap_or_else(|| panic!("no number at {path:?} in {v}"))
}

fn list(v: &Value) -> String {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(" × ")
}

/// RMSE per distance factor, `1× / 4× / 16×`, from a `by_distance` array.
fn by_distance(v: &Value) -> String {
    v.as_array()
        .expect("by_distance")
        .iter()
        .map(|d| {
            format!(
                "{}× {}",
                num(d, &["distance_factor"]),
                sig3(num(d, &["asset", "rmse"]))
            )
        })
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The generated page: a short header and one table row per headline number.
fn generate(dir: &Path) -> String {
    let oak = repo().join(OAK);
    let oak = oak.to_str().unwrap();
    let mut rows: Vec<(String, String, String)> = Vec::new();
    let mut row = |a: &str, q: &str, v: String| rows.push((a.into(), q.into(), v));

    // Volume: `billow voxelize` defaults.
    let v = billow_json(dir, &["voxelize", oak, "-o", "oak.billow", "--json"]);
    let vol = "volume (`voxelize` defaults)";
    row(vol, "grid", list(&v["dims"]));
    row(vol, "MIP levels", text(&v["mip_count"]));
    row(vol, "combine", text(&v["combine"]));
    row(vol, "supersample", text(&v["supersample"]));
    row(vol, "normals kept", text(&v["normals"]));
    row(vol, "normals are moments", text(&v["normal_moments"]));
    row(vol, "compress", text(&v["compress"]));
    row(vol, "non-empty voxels", text(&v["non_empty_voxels"]));
    row(vol, "bytes (reported)", text(&v["bytes"]));
    let file = std::fs::metadata(dir.join("oak.billow")).unwrap().len();
    row(vol, "file bytes", file.to_string());
    let e = billow_json(dir, &["eval", oak, "oak.billow", "--json"]);
    row(vol, "eval slices (all views)", text(&e["slices"]));
    row(vol, "eval fragments (all views)", text(&e["fragments"]));
    row(
        vol,
        "eval RMSE (mean)",
        sig3(num(&e, &["mean", "asset", "rmse"])),
    );
    row(vol, "eval RMSE by distance", by_distance(&e["by_distance"]));
    row(
        vol,
        "eval RMSE over covered pixels (mean)",
        sig3(num(&e, &["mean", "asset", "rmse_covered"])),
    );
    row(
        vol,
        "mesh 1 spp RMSE (mean)",
        sig3(num(&e, &["mean", "raster_1spp", "rmse"])),
    );

    // Billboard cloud: `billow bbcloud` defaults.
    let c = billow_json(dir, &["bbcloud", oak, "-o", "cloud.billow", "--json"]);
    let cl = "cloud (`bbcloud` defaults)";
    row(cl, "billboards per LOD", list(&c["billboards_per_lod"]));
    row(cl, "texels", text(&c["texels"]));
    row(cl, "MIP levels", text(&c["mip_levels"]));
    row(cl, "bytes (reported)", text(&c["bytes"]));
    let file = std::fs::metadata(dir.join("cloud.billow")).unwrap().len();
    row(cl, "file bytes", file.to_string());
    let e = billow_json(dir, &["eval", oak, "cloud.billow", "--json"]);
    for l in e["levels"].as_array().expect("levels") {
        let k = text(&l["lod"]);
        row(
            cl,
            &format!("LOD {k} eval fragments (all views)"),
            text(&l["fragments"]),
        );
        row(
            cl,
            &format!("LOD {k} eval RMSE (mean)"),
            sig3(num(l, &["mean", "rmse"])),
        );
        row(
            cl,
            &format!("LOD {k} eval RMSE over covered pixels (mean)"),
            sig3(num(l, &["mean", "rmse_covered"])),
        );
        row(
            cl,
            &format!("LOD {k} eval RMSE by distance"),
            by_distance(&l["by_distance"]),
        );
    }

    let mut s = String::new();
    writeln!(
        s,
        "# Quick headline numbers (the doc-drift check)\n\n\
         **Generated by `{REGENERATE}`** (`tests/accuracy_drift.rs`, also run by `make \
         accuracy`); do not edit by hand. `make test` fails when any number below differs \
         from what the code gives, so these stay current.\n\n\
         The bundled oak (`{OAK}`) baked by the real binary with its defaults: `billow \
         voxelize oak.gltf -o oak.billow` and `billow bbcloud oak.gltf -o cloud.billow`, each \
         scored by `billow eval` with its defaults (6 axes × 1×, 4×, 16× the framed distance, \
         128×128, 16-spp reference; RMSE over the whole frame, premultiplied RGBA, to 3 \
         significant digits; *over covered pixels*: over the union of the reference's and the \
         asset's coverage). Counts and bytes are exact and load-independent; no times are \
         recorded. The full sweeps are in [accuracy.md](../accuracy.md).\n"
    )
    .unwrap();
    writeln!(s, "| asset | quantity | value |\n|---|---|---|").unwrap();
    for (a, q, v) in rows {
        writeln!(s, "| {a} | {q} | {v} |").unwrap();
    }
    s
}

#[test]
fn quick_headline_numbers_match_the_committed_docs() {
    let dir = tempfile::tempdir().unwrap();
    let now = generate(dir.path());
    let path = repo().join(DOC);
    if std::env::var("BILLOW_BLESS").is_ok_and(|v| v == "1") {
        let tmp = path.with_extension("md.tmp");
        std::fs::write(&tmp, &now).unwrap();
        std::fs::rename(&tmp, &path).unwrap();
        eprintln!("wrote {DOC}");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed == now {
        return;
    }
    let rows = |s: &str| -> Vec<String> {
        s.lines()
            .filter(|l| l.starts_with("| "))
            .map(str::to_string)
            .collect()
    };
    let (old, new) = (rows(&committed), rows(&now));
    let mut diff = String::new();
    for l in old.iter().filter(|l| !new.contains(l)) {
        writeln!(diff, "  committed: {l}").unwrap();
    }
    for l in new.iter().filter(|l| !old.contains(l)) {
        writeln!(diff, "  now:       {l}").unwrap();
    }
    if diff.is_empty() {
        diff = "  (the table matches; the page's text differs)\n".into();
    }
    panic!(
        "{DOC} is stale: the code's headline numbers differ from the committed docs:\n\
         {diff}If the change is intended, regenerate with: {REGENERATE}"
    );
}

/// docs/accuracy.md keeps every section the issues ask it to show: `make accuracy`
/// regenerates the sweeps around blocks that other generators (or hand measurements)
/// wrote, and once dropped one (the compressed-texture costs of issue 23) on regenerating.
#[test]
fn the_accuracy_report_keeps_its_kept_sections() {
    let text = std::fs::read_to_string(repo().join("docs/accuracy.md")).expect("docs/accuracy.md");
    for name in [
        "emptyspace-sweep",
        "particle-layer",
        "compressed-textures",
        "pareto",
    ] {
        let (b, e) = (
            format!("<!-- {name}:begin -->"),
            format!("<!-- {name}:end -->"),
        );
        let start = text
            .find(&b)
            .unwrap_or_else(|| panic!("docs/accuracy.md lost its {name} section ({b})"));
        let end = text[start..]
            .find(&e)
            .unwrap_or_else(|| panic!("docs/accuracy.md: {b} without {e}"));
        let body = &text[start + b.len()..start + end];
        assert!(
            body.lines().filter(|l| l.starts_with('|')).count() >= 3,
            "docs/accuracy.md: the {name} section has no table"
        );
    }
}
