//! `--preset` and `--target-error` on `billow voxelize` and `billow bbcloud`, driven as the
//! real binary on a small procedurally generated tree (`procgen::leafy_tree`): presets
//! resolve under explicit flags and the JSON records the result; a reachable target,
//! judged over distances and lights, picks a setting whose `billow eval` error is at most
//! the target while the next cheaper preset's (baked and evaluated on its own) is above
//! it; on this tree, whose error is not monotone in `--res`, a target every preset misses
//! is met by a resolution between them; an unreachable target exits 10 with one error
//! line, writes nothing and, with `--json`, still prints every trial. Small images (32×32,
//! 64×64) keep it quick.

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

/// `billow eval`'s covered RMSE per distance over the six axis views at `distances`, LOD 0
/// for a cloud (`cloud*.billow`), under the standard lights unless `auto`: the measure
/// `--target-error` uses.
fn eval_errors(
    dir: &Path,
    mesh: &str,
    asset: &str,
    size: &str,
    distances: &str,
    auto: bool,
) -> Vec<f64> {
    let mut args = vec![
        "eval",
        mesh,
        asset,
        "--views",
        "axes",
        "--distances",
        distances,
        "--size",
        size,
        "--json",
    ];
    if !auto {
        args.extend(["--lights", "standard"]);
    }
    let cloud = asset.starts_with("cloud");
    if cloud {
        args.extend(["--lod", "0"]);
    }
    let v = ok(&args, dir);
    let by = if cloud {
        &v["levels"][0]["by_distance"]
    } else {
        &v["by_distance"]
    };
    by.as_array()
        .unwrap()
        .iter()
        .map(|d| d["asset"]["rmse_covered"].as_f64().unwrap())
        .collect()
}

fn worst(e: &[f64]) -> f64 {
    e.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

/// The `--res` of a trial's or choice's label (`... --res 48 --supersample 4 ...`).
fn res_of(label: &str) -> u32 {
    let i = label.find("--res ").unwrap() + 6;
    label[i..].split(' ').next().unwrap().parse().unwrap()
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
fn voxelize_meets_a_reachable_target_judged_over_distances_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    // Each preset baked and scored on its own, as `--target-error` scores by default: the
    // worst over 1x, 4x and 16x of the covered RMSE, mean over the standard lights.
    let mut errors = Vec::new();
    for p in ["draft", "balanced"] {
        let out = format!("vol_{p}.billow");
        ok(
            &["voxelize", &mesh, "-o", &out, "--preset", p, "-q", "--json"],
            d,
        );
        errors.push(eval_errors(d, &mesh, &out, VSIZE, "1,4,16", false));
    }
    let (draft, balanced) = (worst(&errors[0]), worst(&errors[1]));
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
    assert_eq!(t["distances"], serde_json::json!([1.0, 4.0, 16.0]), "{t}");
    assert_eq!(t["weighting"], "worst");
    assert_eq!(t["lights"].as_array().unwrap().len(), 4, "{t}");
    assert_eq!(v["settings_from"]["resolution"], "target");
    let trials = t["trials"].as_array().unwrap();
    assert_eq!(trials[0]["preset"], "draft");
    assert_eq!(trials[0]["met"], false);
    // The search measured the draft exactly as `billow eval` scores it, per distance.
    for (i, e) in errors[0].iter().enumerate() {
        let m = trials[0]["by_distance"][i]["error"].as_f64().unwrap();
        assert!((m - e).abs() < 1e-9, "{t} vs {:?}", errors[0]);
    }
    assert!((trials[0]["error"].as_f64().unwrap() - draft).abs() < 1e-9);
    // The balanced preset meets the target and the errors fell: the choice is it or a
    // cheaper resolution between it and the draft.
    assert_eq!(
        (trials[1]["preset"].as_str(), trials[1]["met"].as_bool()),
        (Some("balanced"), Some(true)),
        "{t}"
    );
    let chosen = t["chosen"].as_str().unwrap();
    assert!((33..=64).contains(&res_of(chosen)), "{chosen}");
    let measured = t["measured_error"].as_f64().unwrap();
    assert!(measured <= target, "{measured} > {target}");
    let written = eval_errors(d, &mesh, "vol.billow", VSIZE, "1,4,16", false);
    for (i, e) in written.iter().enumerate() {
        let m = t["by_distance"][i]["error"].as_f64().unwrap();
        assert!(
            (m - e).abs() < 1e-9,
            "eval of the written asset {written:?} vs {t}"
        );
    }
    assert!((worst(&written) - measured).abs() < 1e-9);
}

/// The tree's error is not monotone in `--res` (the grid's phase against the leaves):
/// at 64×64 and the framed distance, resolutions between the presets score better than
/// every preset. A target between the two is met by one of them, where the old search
/// (bisecting only between a preset that missed and one that met) exited 10. Also: a
/// target nothing meets exits 10 and `--json` still prints every trial, and each trial
/// is one line on stderr.
#[test]
fn a_target_every_preset_misses_is_met_between_them_on_a_mesh_whose_error_is_not_monotone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = tree(d);
    let search = |e: &str, out: &str| {
        run_limited(
            &[
                "voxelize",
                &mesh,
                "-o",
                out,
                "--target-error",
                e,
                "--target-size",
                VSIZE,
                "--target-distances",
                "1",
                "--target-lights",
                "auto",
                "--json",
            ],
            d,
            Duration::from_secs(600),
            8 << 20,
        )
    };
    // Nothing reaches 1e-6: exit 10, no file, one error line naming the best, and the
    // JSON document on stdout with every trial.
    let r = search("1e-6", "none.billow");
    assert_eq!(r.code, Some(10), "{}", r.stderr);
    assert!(!d.join("none.billow").exists());
    // Stderr: one line per trial, then the one error line.
    let all: Vec<&str> = r.stderr.lines().collect();
    let (line, lines) = all.split_last().unwrap();
    assert!(
        line.starts_with("error: --target-error: no setting reaches"),
        "{line}"
    );
    let v: Value = serde_json::from_str(&r.stdout).expect("one JSON document on stdout");
    assert_eq!(v["written"], false);
    assert_eq!(&format!("error: {}", v["error"].as_str().unwrap()), line);
    let t = &v["target"];
    assert_eq!(t["chosen"], Value::Null);
    let trials = t["trials"].as_array().unwrap();
    let max = t["max_bakes"].as_u64().unwrap() as usize;
    assert!(trials.len() > 4 && trials.len() <= max, "{t}");
    let best = &t["best"];
    assert!(
        line.contains(&format!(
            "the best measured, {}, scored {:.4}",
            best["label"].as_str().unwrap(),
            best["error"].as_f64().unwrap()
        )),
        "{line}"
    );
    // One line per trial, with its error, bytes and seconds.
    assert_eq!(lines.len(), trials.len(), "{}", r.stderr);
    for (l, t) in lines.iter().zip(trials) {
        let label = t["label"].as_str().unwrap();
        assert!(
            l.starts_with(&format!(
                "--target-error: {label}: {:.4} (1x ",
                t["error"].as_f64().unwrap()
            )),
            "{l}"
        );
        assert!(
            l.contains(" KiB, ") && l.ends_with(" s") && l.contains("misses"),
            "{l}"
        );
        assert!(t["bytes"].as_u64().unwrap() > 0 && t["seconds"].as_f64().unwrap() > 0.0);
    }
    // The premise: some resolution between the presets scores below every preset.
    let err = |t: &Value| t["error"].as_f64().unwrap();
    let presets: Vec<f64> = trials
        .iter()
        .filter(|t| t["preset"].is_string())
        .map(err)
        .collect();
    let between: Vec<f64> = trials
        .iter()
        .filter(|t| t["preset"].is_null())
        .map(err)
        .collect();
    assert_eq!(presets.len(), 4, "{t}");
    let (p, b) = (
        presets.iter().copied().fold(f64::INFINITY, f64::min),
        between.iter().copied().fold(f64::INFINITY, f64::min),
    );
    assert!(
        b < p,
        "the error must not be monotone in --res for this test: {t}"
    );
    // A target between them: every preset misses it, a resolution between them meets it.
    let target = (b + p) / 2.0;
    let r = search(&format!("{target}"), "vol.billow");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let t = &v["target"];
    let trials = t["trials"].as_array().unwrap();
    assert!(
        trials[..4]
            .iter()
            .all(|t| t["phase"] == "ladder" && t["met"] == false),
        "{t}"
    );
    assert_eq!(t["chosen_preset"], Value::Null, "{t}");
    assert_eq!(v["preset"], Value::Null);
    let chosen = t["chosen"].as_str().unwrap();
    let measured = t["measured_error"].as_f64().unwrap();
    assert!(measured <= target, "{t}");
    // The cheapest measured setting that meets the target.
    let cheapest = trials
        .iter()
        .filter(|t| t["met"] == true)
        .map(|t| res_of(t["label"].as_str().unwrap()))
        .min()
        .unwrap();
    assert_eq!(res_of(chosen), cheapest, "{t}");
    assert_eq!(v["resolution"], format!("{cheapest}"));
    let written = eval_errors(d, &mesh, "vol.billow", VSIZE, "1", true);
    assert!((written[0] - measured).abs() < 1e-9, "{written:?} vs {t}");
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
fn bbcloud_meets_a_reachable_target_judged_over_distances_and_lights() {
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
        errors.push(eval_errors(d, &mesh, &out, SIZE, "1,4,16", false));
    }
    let (draft, balanced) = (worst(&errors[0]), worst(&errors[1]));
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
    let written = worst(&eval_errors(
        d,
        &mesh,
        "cloud.billow",
        SIZE,
        "1,4,16",
        false,
    ));
    assert!(
        written <= target,
        "eval of the written cloud {written} > target {target}"
    );
    assert!((written - t["measured_error"].as_f64().unwrap()).abs() < 1e-9);
}

/// A volume that keeps its normals is shaded by each light (the judge slices it once per
/// light, where a volume without normals is sliced once): the judge still equals `billow
/// eval --lights standard` of the written file, per distance.
#[test]
fn the_judge_of_a_volume_with_normals_equals_eval_under_the_lights() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let path = d.join("torus.obj");
    billow::procgen::write_obj(&billow::procgen::torus(1.0, 0.35, 24, 12), &path).unwrap();
    let mesh = path.to_str().unwrap();
    let v = ok(
        &[
            "voxelize",
            mesh,
            "-o",
            "vol.billow",
            "--normals",
            "on",
            "--target-error",
            "1",
            "--target-size",
            SIZE,
            "--target-distances",
            "1,4",
            "-q",
            "--json",
        ],
        d,
    );
    assert_eq!(v["normals"], true);
    let t = &v["target"];
    assert_eq!(t["chosen_preset"], "draft", "{t}");
    let written = eval_errors(d, mesh, "vol.billow", SIZE, "1,4", false);
    assert_eq!(written.len(), 2);
    for (i, e) in written.iter().enumerate() {
        let m = t["by_distance"][i]["error"].as_f64().unwrap();
        assert!((m - e).abs() < 1e-9, "eval {written:?} vs {t}");
    }
}
