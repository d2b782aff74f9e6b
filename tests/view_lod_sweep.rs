//! Lacewell et al. 2006's own test of a billboard cloud (§1, §4): the two sides of an LOD
//! switch are "nearly indistinguishable". `billow view CLOUD --lod-sweep DIR` dollies at
//! constant screen size across every switch in the GPU viewer (docs/bbcloud.md, "LOD
//! switches"); here on a small frame, on the bundled oak:
//!
//! - each billboard level's opaque pixels are within 10 % of the mesh's at the distance
//!   where it takes over (met for the two billboard levels; the final two-billboard cross
//!   is checked within 30 %: shown at a constant fill it is magnified far beyond what its
//!   texels were made for, +18 % on the oak at 200²);
//! - the step at each switch at most 1.5× the median of the steps around it (met since the
//!   dithered dissolve around each switch, `viewer/src/cloud_pass` module docs; with
//!   `--dissolve 0`, the one-frame switch of before, the oak's steps are 1.3–5× here).
//!
//! Before 2026-12 the billboards were blended: the levels had 65–76 % fewer opaque pixels
//! than the mesh, and the coverage checks here failed.
//!
//! Needs a GPU adapter (lavapipe is enough): without one it prints `SKIP: …` on stderr,
//! except under CI (env `CI` set) where it fails.

mod common;

use std::path::Path;

use common::{repo, run};

/// Bakes `mesh` into a 3-level cloud and sweeps its switches on a small frame; `None`
/// (after printing `SKIP`) without a GPU adapter outside CI.
fn sweep_of(test: &str, mesh: &Path, dir: &Path) -> Option<serde_json::Value> {
    let cloud = dir.join("cloud.billow");
    let r = run(
        &[
            "bbcloud",
            mesh.to_str().unwrap(),
            "-o",
            cloud.to_str().unwrap(),
            "--lods",
            "3",
            "-q",
        ],
        dir,
    );
    assert_eq!(r.code, Some(0), "bbcloud: {}", r.stderr);
    let out = dir.join("sweep");
    let r = run(
        &[
            "view",
            cloud.to_str().unwrap(),
            "--lod-sweep",
            out.to_str().unwrap(),
            "--size",
            "200x200",
            "--sweep-fill",
            "0.9",
            "--view=-z",
            "--json",
        ],
        dir,
    );
    if r.code != Some(0) && r.stderr.contains("no GPU adapter") {
        common::skip(test, r.stderr.trim());
        return None;
    }
    assert_eq!(r.code, Some(0), "view --lod-sweep: {}", r.stderr);
    for k in 0..3 {
        assert!(out.join(format!("switch_{k}.png")).is_file());
    }
    assert!(out.join("sweep.json").is_file() && out.join("sweep.md").is_file());
    Some(serde_json::from_str(&r.stdout).unwrap())
}

/// The coverage target (module docs): billboard levels within 10 % of the mesh's opaque
/// pixels, the final cross within 30 %.
fn check_coverage(name: &str, s: &serde_json::Value) {
    let switches = s["switches"].as_array().unwrap();
    assert_eq!(switches.len(), 3, "{name}: mesh → 1 → 2 → cross: {s}");
    let levels = s["levels"].as_array().unwrap();
    for (k, l) in levels.iter().enumerate() {
        let rel = l["opaque_rel"].as_f64().unwrap();
        let limit = if k + 1 == levels.len() { 0.30 } else { 0.10 };
        assert!(
            rel.abs() <= limit,
            "{name}: level {}: {} opaque pixels against the mesh's {} ({:+.1} %)",
            l["level"],
            l["opaque_pixels"],
            l["mesh_opaque_pixels"],
            100.0 * rel
        );
    }
}

/// The step target (module docs).
fn check_steps(name: &str, s: &serde_json::Value) {
    for w in s["switches"].as_array().unwrap() {
        let ratio = w["ratio"].as_f64().unwrap();
        assert!(
            ratio <= 1.5,
            "{name}: switch {} → {} at {}: step {:.4} is {ratio:.2}× its neighbours' median {:.4}",
            w["from"],
            w["to"],
            w["distance"],
            w["step_rmse"].as_f64().unwrap(),
            w["neighbours_rmse"].as_f64().unwrap()
        );
    }
}

fn oak() -> std::path::PathBuf {
    repo().join("fixtures/oak/eztree_oak_medium.gltf")
}

fn tree(dir: &Path) -> std::path::PathBuf {
    let tree = dir.join("tree.obj");
    billow::procgen::write_obj(&billow::procgen::leafy_tree(1500, 9, 1), &tree).unwrap();
    tree
}

#[test]
fn oak_cloud_switches_are_unseen_and_levels_as_opaque_as_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let test = "oak_cloud_switches_are_unseen_and_levels_as_opaque_as_the_mesh";
    if let Some(s) = sweep_of(test, &oak(), dir.path()) {
        check_coverage("oak", &s);
        check_steps("oak", &s);
    }
}

#[test]
fn generated_tree_cloud_switches_are_unseen_and_levels_as_opaque_as_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let test = "generated_tree_cloud_switches_are_unseen_and_levels_as_opaque_as_the_mesh";
    if let Some(s) = sweep_of(test, &tree(dir.path()), dir.path()) {
        check_coverage("generated tree", &s);
        check_steps("generated tree", &s);
    }
}
