//! `--preset` and `--target-error` on `billow voxelize` and `billow bbcloud`, driven as the
//! real binary on a small procedurally generated tree (`procgen::leafy_tree`): presets
//! resolve under explicit flags and the JSON records the result; a reachable target picks
//! a setting whose `billow eval` error is at most the target while the next cheaper
//! preset's (baked and evaluated on its own) is above it; an unreachable target exits 10
//! with one error line and writes nothing. Small images (32×32, 64×64) keep it quick.

mod common;

use std::path::Path;
use std::time::Duration;

use common::*;
use serde_json::Value;

/// Image size of the cloud checks and of the volume's unreachable target.
const SIZE: &str = "32x32";
/// Image size of the volume's reachable target: at 32×32 a 32³ volume already has about a
/// voxel per pixel at the framed distance, and 64³ does not score better there.
const VSIZE: &str = "64x64";

fn tree(dir: &Path) -> String {
    let path = dir.join("tree.obj");
    billow::procgen::write_obj(&billow::procgen::leafy_tree(120, 5, 7), &path).unwrap();
    path.to_str().unwrap().to_string()
}

fn ok(args: &[&str], dir: &Path) -> Value {
    let r = run_limited(args, dir, Duration::from_secs(600), 8 << 20);
    assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
    serde_json::from_str(&r.stdout).expect("one JSON document on stdout")
}

/// `billow eval`'s mean RMSE over the six axis views at the framed distance, LOD 0 for a
/// cloud (`cloud*.billow`): the measure `--target-error` uses.
fn eval_rmse(dir: &Path, mesh: &str, asset: &str, size: &str) -> f64 {
    let mut args = vec![
        "eval",
        mesh,
        asset,
        "--views",
        "axes",
        "--distances",
        "1",
        "--size",
        size,
        "--json",
    ];
    let cloud = asset.starts_with("cloud");
    if cloud {
        args.extend(["--lod", "0"]);
    }
    let v = ok(&args, dir);
    if cloud {
        v["levels"][0]["mean"]["rmse"].as_f64().unwrap()
    } else {
        v["mean"]["asset"]["rmse"].as_f64().unwrap()
    }
}

#[test]
fn a_preset_resolves_under_explicit_flags_and_the_json_records_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    let v = ok(
        &[
            "voxelize",
            &mesh,
            "-o",
            "vol.billow",
            "--preset",
            "draft",
            "--supersample",
            "3",
            "--json",
        ],
        d,
    );
    assert_eq!(v["preset"], "draft");
    assert_eq!(v["resolution"], "32");
    assert_eq!(v["supersample"], 3);
    assert_eq!(v["settings_from"]["resolution"], "preset");
    assert_eq!(v["settings_from"]["supersample"], "flag");
    let dims: Vec<u64> = v["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(dims.iter().max(), Some(&32), "{dims:?}");
    // No preset: the long-standing defaults, marked as such.
    let v = ok(
        &[
            "voxelize",
            &mesh,
            "-o",
            "vol2.billow",
            "--res",
            "16",
            "--json",
        ],
        d,
    );
    assert_eq!(v["preset"], Value::Null);
    assert_eq!(
        (
            v["settings_from"]["resolution"].as_str(),
            v["supersample"].as_u64()
        ),
        (Some("flag"), Some(4))
    );
    let v = ok(
        &[
            "bbcloud",
            &mesh,
            "-o",
            "cloud.billow",
            "--preset",
            "draft",
            "--samples",
            "20",
            "--lods",
            "1",
            "--json",
        ],
        d,
    );
    assert_eq!(v["preset"], "draft");
    assert_eq!(v["samples"], 20);
    assert_eq!(v["settings_from"]["samples"], "flag");
    assert_eq!(v["settings_from"]["epsilon"], "preset");
    assert_eq!(v["epsilon"].as_f64().unwrap() as f32, 0.08);
    assert_eq!(v["atlas_size"], 512);
    let r = run(
        &["voxelize", &mesh, "-o", "x.billow", "--preset", "fast"],
        d,
    );
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(!d.join("x.billow").exists());
}

#[test]
fn voxelize_meets_a_reachable_target_that_the_next_cheaper_preset_misses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    // Each preset baked and scored on its own.
    let mut errors = Vec::new();
    for p in ["draft", "balanced"] {
        let out = format!("vol_{p}.billow");
        ok(
            &["voxelize", &mesh, "-o", &out, "--preset", p, "-q", "--json"],
            d,
        );
        errors.push(eval_rmse(d, &mesh, &out, VSIZE));
    }
    let (draft, balanced) = (errors[0], errors[1]);
    assert!(
        balanced < draft,
        "the ladder must gain accuracy: {errors:?}"
    );
    let target = (draft + balanced) / 2.0;
    let e = format!("{target}");
    let v = ok(
        &[
            "voxelize",
            &mesh,
            "-o",
            "vol.billow",
            "--target-error",
            &e,
            "--target-size",
            VSIZE,
            "--json",
        ],
        d,
    );
    let t = &v["target"];
    assert_eq!(t["chosen_preset"], "balanced", "{t}");
    assert_eq!(v["preset"], "balanced");
    assert_eq!(v["settings_from"]["resolution"], "target");
    let trials = t["trials"].as_array().unwrap();
    assert_eq!(trials[0]["preset"], "draft");
    assert_eq!(trials[0]["met"], false);
    // The search measured the draft exactly as `billow eval` scores it.
    assert!(
        (trials[0]["error"].as_f64().unwrap() - draft).abs() < 1e-9,
        "{t} vs {draft}"
    );
    let measured = t["measured_error"].as_f64().unwrap();
    let written = eval_rmse(d, &mesh, "vol.billow", VSIZE);
    assert!(
        written <= target,
        "eval of the written asset {written} > target {target}"
    );
    assert!(
        (written - measured).abs() < 1e-9,
        "{written} vs reported {measured}"
    );
}

#[test]
fn an_unreachable_target_exits_10_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    // --res pinned: the ladder keeps only the supersampling steps (quick).
    let r = run_limited(
        &[
            "voxelize",
            &mesh,
            "-o",
            "vol.billow",
            "--res",
            "24",
            "--target-error",
            "1e-6",
            "--target-size",
            SIZE,
            "-q",
        ],
        d,
        Duration::from_secs(600),
        8 << 20,
    );
    assert_eq!(r.code, Some(10), "{}", r.stderr);
    let line = r.error_line().unwrap();
    assert!(
        line.starts_with("error: --target-error: no setting reaches"),
        "{line}"
    );
    assert!(!d.join("vol.billow").exists());
    let r = run_limited(
        &[
            "bbcloud",
            &mesh,
            "-o",
            "cloud.billow",
            "--lods",
            "1",
            "--atlas-size",
            "256",
            "--samples",
            "20",
            "--epsilon",
            "0.1",
            "--target-error",
            "1e-6",
            "--target-size",
            SIZE,
            "-q",
        ],
        d,
        Duration::from_secs(600),
        8 << 20,
    );
    assert_eq!(r.code, Some(10), "{}", r.stderr);
    assert!(r.error_line().unwrap().contains("no setting reaches"));
    assert!(!d.join("cloud.billow").exists());
    // A target that is not a positive number is a bad parameter, before any work.
    let r = run(
        &["voxelize", &mesh, "-o", "v.billow", "--target-error", "0"],
        d,
    );
    assert_eq!(r.code, Some(8), "{}", r.stderr);
}

#[test]
fn bbcloud_meets_a_reachable_target_that_the_next_cheaper_preset_misses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    let mut errors = Vec::new();
    for p in ["draft", "balanced"] {
        let out = format!("cloud_{p}.billow");
        ok(
            &[
                "bbcloud", &mesh, "-o", &out, "--preset", p, "--lods", "1", "-q", "--json",
            ],
            d,
        );
        errors.push(eval_rmse(d, &mesh, &out, SIZE));
    }
    let (draft, balanced) = (errors[0], errors[1]);
    assert!(
        balanced < draft,
        "the ladder must gain accuracy: {errors:?}"
    );
    let target = (draft + balanced) / 2.0;
    let e = format!("{target}");
    let v = ok(
        &[
            "bbcloud",
            &mesh,
            "-o",
            "cloud.billow",
            "--lods",
            "1",
            "--target-error",
            &e,
            "--target-size",
            SIZE,
            "--json",
        ],
        d,
    );
    let t = &v["target"];
    assert_eq!(t["chosen_preset"], "balanced", "{t}");
    let trials = t["trials"].as_array().unwrap();
    assert_eq!(
        (trials[0]["preset"].as_str(), trials[0]["met"].as_bool()),
        (Some("draft"), Some(false))
    );
    assert!(
        (trials[0]["error"].as_f64().unwrap() - draft).abs() < 1e-9,
        "{t} vs {draft}"
    );
    let written = eval_rmse(d, &mesh, "cloud.billow", SIZE);
    assert!(
        written <= target,
        "eval of the written cloud {written} > target {target}"
    );
    assert!((written - t["measured_error"].as_f64().unwrap()).abs() < 1e-9);
}
