//! `billow eval` and the library's `eval::evaluate` (issue 39 item 1) give the same numbers
//! for the same options: a volume under its own lighting and under the standard lights
//! with shadows, and a billboard cloud's every LOD level, compared field by field with the
//! CLI's `--json` (timings left out): integers, names and the structure exactly, real
//! numbers to 1e-12 relative (this process's numbers and the binary's can differ in the
//! last bits of some sums; the binary's own are the same from run to run).

mod common;

use billow_core::camera::{parse_direction, views_of, ViewSpec};
use std::ops::ControlFlow;

use billow::eval::evaluate::{
    evaluate, Asset, EvaluateError, EvaluateHooks, EvaluateOptions, EvaluateProgress, Evaluation,
    ReferenceLighting, ViewImages,
};
use billow::eval::lighting::light_set;
use billow::import::{import, ImportOptions};
use billow::scene::Scene;
use billow_format::read_file;
use common::{repo, run};
use serde_json::{json, Value};

const VIEWS: [&str; 2] = ["+x", "+x+y+z"];
const DISTANCES: [f32; 2] = [1.0, 4.0];

fn views() -> Vec<ViewSpec> {
    VIEWS
        .iter()
        .flat_map(|v| {
            views_of(
                vec![(v.to_string(), parse_direction(v).unwrap())],
                &DISTANCES,
            )
        })
        .collect()
}

/// `billow eval MESH ASSET --json` at 32x32, 4 spp, the views above, and `extra`.
fn cli(dir: &std::path::Path, mesh: &str, asset: &str, extra: &[&str]) -> Value {
    let mut args = vec![
        "eval",
        mesh,
        asset,
        "--json",
        "--size",
        "32x32",
        "--spp",
        "4",
        "--views",
        "+x,+x+y+z",
        "--distances",
        "1,4",
    ];
    args.extend_from_slice(extra);
    let r = run(&args, dir);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let mut v: Value = serde_json::from_str(&r.stdout).unwrap();
    strip_seconds(&mut v);
    v
}

fn strip_seconds(v: &mut Value) {
    match v {
        Value::Object(m) => {
            m.remove("seconds");
            m.values_mut().for_each(strip_seconds);
        }
        Value::Array(a) => a.iter_mut().for_each(strip_seconds),
        _ => {}
    }
}

/// The CLI calls' options.
fn options(lighting: ReferenceLighting) -> EvaluateOptions {
    EvaluateOptions {
        width: 32,
        height: 32,
        reference_per_axis: 2,
        views: views(),
        lighting,
        ..EvaluateOptions::default()
    }
}

fn library(scene: &Scene, asset: &Asset, lighting: ReferenceLighting) -> Evaluation {
    evaluate(
        scene,
        asset,
        &options(lighting),
        &mut EvaluateHooks::default(),
    )
    .unwrap()
}

/// `v` as the CLI's JSON text reads (f32 fields printed as f32), without timings.
fn value(v: impl serde::Serialize) -> Value {
    let mut v = serde_json::from_str(&serde_json::to_string(&v).unwrap()).unwrap();
    strip_seconds(&mut v);
    v
}

/// Whether `a` and `b` have the same structure, keys, strings and integers, and real
/// numbers within 1e-12 relative; the first difference's path otherwise.
fn same(a: &Value, b: &Value, path: &str) -> Result<(), String> {
    let differ = || Err(format!("{path}: {a} vs {b}"));
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            if x.keys().ne(y.keys()) {
                return differ();
            }
            x.iter()
                .try_for_each(|(k, v)| same(v, &y[k], &format!("{path}.{k}")))
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return differ();
            }
            (x.iter().zip(y).enumerate())
                .try_for_each(|(i, (v, w))| same(v, w, &format!("{path}[{i}]")))
        }
        (Value::Number(x), Value::Number(y)) if !(x.is_f64() || y.is_f64()) => {
            if x == y {
                Ok(())
            } else {
                differ()
            }
        }
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() <= 1e-12 * x.abs().max(y.abs()) {
                Ok(())
            } else {
                differ()
            }
        }
        _ if a == b => Ok(()),
        _ => differ(),
    }
}

#[track_caller]
fn assert_same(a: &Value, b: &Value) {
    if let Err(e) = same(a, b, "") {
        panic!("the library and the CLI differ at {e}");
    }
}

/// The lights' JSON entries of one level of the library's result.
fn lights(l: &billow::eval::evaluate::LevelEvaluation) -> Value {
    Value::Array(
        l.by_light
            .iter()
            .map(|r| {
                let mut m = value(&r.means);
                let o = m.as_object_mut().unwrap();
                o.insert("name".into(), json!(r.light.name));
                o.insert("dir".into(), value(r.light.dir.to_array()));
                o.insert("ambient".into(), value(r.light.ambient));
                m
            })
            .collect(),
    )
}

fn assert_same_common(lib: &Evaluation, cli: &Value) {
    assert_same(&cli["gpu_bytes"], &json!(lib.gpu_bytes.with_bc));
    assert_same(&cli["gpu_bytes_no_bc"], &json!(lib.gpu_bytes.without_bc));
    assert_same(&cli["notes"], &value(&lib.notes));
    assert_same(&cli["lighting"]["asset"], &json!(lib.lighting.asset));
    assert_same(
        &cli["lighting"]["reference"],
        &json!(lib.lighting.reference.name()),
    );
    assert_same(
        &cli["lighting"]["reference_details"],
        &json!(lib.lighting.reference_details),
    );
}

fn assert_same_level(lib: &billow::eval::evaluate::LevelEvaluation, cli: &Value, mean: &Value) {
    assert_same(&cli["views"], &value(&lib.views));
    assert_same(mean, &value(lib.mean));
    assert_same(&cli["by_distance"], &value(&lib.by_distance));
    let l = lights(lib);
    if l.as_array().unwrap().is_empty() {
        assert!(cli.get("lights").is_none());
    } else {
        assert_same(&cli["lights"], &l);
    }
}

#[test]
fn the_library_evaluation_is_the_cli_s() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mesh = repo().join("fixtures/oak/eztree_oak_medium.gltf");
    let m = mesh.to_str().unwrap();
    let scene = import(&mesh, &ImportOptions { strict: false })
        .unwrap()
        .scene;
    let r = run(&["voxelize", m, "-o", "v.billow", "--res", "32", "-q"], d);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let r = run(
        &[
            "bbcloud", m, "-o", "c.billow", "--preset", "draft", "--lods", "2", "-q",
        ],
        d,
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let asset = |name: &str| Asset::from_container(read_file(&d.join(name)).unwrap()).unwrap();
    let (volume, cloud) = (asset("v.billow"), asset("c.billow"));
    let standard = ReferenceLighting::Lights {
        lights: light_set("standard", billow_core::shading::DEFAULT_AMBIENT).unwrap(),
        shadows: true,
    };

    // The volume, under its own lighting and under the standard set with shadows.
    for (lighting, extra) in [
        (ReferenceLighting::Own, &[][..]),
        (standard.clone(), &["--lights", "standard", "--shadows"][..]),
    ] {
        let c = cli(d, m, "v.billow", extra);
        let lib = library(&scene, &volume, lighting);
        assert_same_common(&lib, &c);
        assert_same(&c["asset_dims"], &json!(lib.volume_dims.unwrap()));
        assert_eq!(lib.levels.len(), 1);
        assert_same_level(&lib.levels[0], &c, &c["mean"]["asset"]);
        assert_same(&c["mean"]["raster_1spp"], &value(lib.raster_1spp));
        assert_same(&c["slices"], &json!(lib.levels[0].slices));
        assert_same(&c["fragments"], &json!(lib.levels[0].fragments));
    }

    // The cloud: both LOD levels, then only the coarser one.
    let c = cli(d, m, "c.billow", &[]);
    let lib = library(&scene, &cloud, ReferenceLighting::Own);
    assert_same_common(&lib, &c);
    assert_same(&c["raster_1spp"], &value(lib.raster_1spp));
    let levels = c["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 2);
    assert_eq!(lib.levels.len(), 2);
    for (l, cl) in lib.levels.iter().zip(levels) {
        let info = l.cloud.unwrap();
        assert_same(&cl["lod"], &json!(info.lod));
        assert_same(&cl["billboards"], &json!(info.billboards));
        assert_same(&cl["texture_bytes"], &json!(info.texture_bytes));
        assert_same(&cl["fragments"], &json!(l.fragments));
        assert_same_level(l, cl, &cl["mean"]);
    }

    // The hooks: progress after each of the 4 views × 2 levels, the images once a view (both
    // levels' and the 1-spp mesh's); a hook's Break stops the evaluation.
    let (mut progress, mut images) = (Vec::new(), 0);
    let mut on_progress = |p: EvaluateProgress| {
        progress.push((p.done, p.total));
        ControlFlow::Continue(())
    };
    let mut on_images = |v: ViewImages| {
        assert_eq!(v.assets.len(), 2);
        assert!(v.light.is_none() && v.raster_1spp.is_some());
        images += 1;
        ControlFlow::Continue(())
    };
    let mut hooks = EvaluateHooks {
        progress: Some(&mut on_progress),
        images: Some(&mut on_images),
    };
    let with_hooks = evaluate(&scene, &cloud, &options(ReferenceLighting::Own), &mut hooks);
    // The same numbers with hooks as without (the seconds aside).
    let (a, b) = (&with_hooks.unwrap().levels, &lib.levels);
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(b) {
        assert_eq!(value(&a.views), value(&b.views));
        assert_eq!((a.mean, a.cloud), (b.mean, b.cloud));
    }
    assert_eq!(progress, (1..=8).map(|d| (d, 8)).collect::<Vec<_>>());
    assert_eq!(images, 4);
    let mut stop = |_: EvaluateProgress| ControlFlow::Break(());
    let mut hooks = EvaluateHooks {
        progress: Some(&mut stop),
        images: None,
    };
    let stopped = evaluate(&scene, &cloud, &options(ReferenceLighting::Own), &mut hooks);
    assert!(
        matches!(stopped, Err(EvaluateError::Stopped)),
        "{stopped:?}"
    );

    // What is refused, before any rendering.
    let refused = |asset: &Asset, o: EvaluateOptions| {
        evaluate(&scene, asset, &o, &mut EvaluateHooks::default()).unwrap_err()
    };
    let lod = |lod| EvaluateOptions {
        lod: Some(lod),
        ..options(ReferenceLighting::Own)
    };
    assert!(matches!(
        refused(&volume, lod(0)),
        EvaluateError::LodOfVolume
    ));
    let e = refused(&cloud, lod(2));
    assert!(
        matches!(e, EvaluateError::NoSuchLod { lod: 2, levels: 2 }),
        "{e:?}"
    );
    let no_views = EvaluateOptions {
        views: Vec::new(),
        ..options(ReferenceLighting::Own)
    };
    let no_lights = options(ReferenceLighting::Lights {
        lights: Vec::new(),
        shadows: false,
    });
    for o in [no_views, no_lights] {
        assert!(matches!(
            refused(&volume, o),
            EvaluateError::InvalidOption(_)
        ));
    }
}
