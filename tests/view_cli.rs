//! `billow view` through the real binary: the passes a scene needs (`--print-passes`,
//! no GPU needed), one-line errors for bad scene files, and a headless screenshot.
//!
//! The screenshot test needs a GPU adapter (lavapipe is enough): without one it prints
//! `SKIP: …` on stderr, except under CI (env `CI` set) where it fails —
//! `.ci/ensure-vulkan` installs lavapipe.

mod common;

use std::path::Path;

use common::{repo, run};

fn scenes() -> std::path::PathBuf {
    repo().join("fixtures/scenes")
}

fn passes(target: &Path) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        &["view", target.to_str().unwrap(), "--print-passes"],
        dir.path(),
    );
    assert_eq!(r.code, Some(0), "{}: {}", target.display(), r.stderr);
    r.stdout.lines().map(str::to_string).collect()
}

#[test]
fn print_passes_lists_only_what_the_content_needs() {
    // Only opaque meshes: no volume pass.
    assert_eq!(
        passes(&scenes().join("meshes_only.ron")),
        ["mesh", "resolve"]
    );
    // Meshes and volumes, shadows off: no shadow pass.
    assert_eq!(
        passes(&scenes().join("oak_wall.ron")),
        ["mesh", "volume", "resolve"]
    );
    // A lone asset: only the volume pass.
    assert_eq!(
        passes(&scenes().join("oak32.billow")),
        ["volume", "resolve"]
    );
    // A scene with only a ground plane and shadows on: a shadow pass and the mesh pass,
    // still no volume or cloud pass.
    let dir = tempfile::tempdir().unwrap();
    let s = dir.path().join("ground.ron");
    std::fs::write(&s, "(ground: Some((size: 4.0)), shadows: true)").unwrap();
    assert_eq!(passes(&s), ["shadow", "mesh", "resolve"]);
    // Shadows on but nothing to draw: no shadow pass either.
    std::fs::write(&s, "(shadows: true)").unwrap();
    assert_eq!(passes(&s), ["resolve"]);
}

/// `--print-passes` of a scene written from `text` into a temp dir with a copy of the oak.
fn scene_passes(text: &str) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(scenes().join("oak32.billow"), dir.path().join("oak.billow")).unwrap();
    let s = dir.path().join("s.ron");
    std::fs::write(&s, text).unwrap();
    passes(&s)
}

fn particles(kinds: &[&str]) -> String {
    let sys: Vec<String> = kinds
        .iter()
        .map(|k| {
            format!(
                "(kind: {k}, emitter: (position: (0.0, 1.0, 0.0), count: 8, \
                 radius: (0.5, 1.0), lifetime: (2.0, 3.0)))"
            )
        })
        .collect();
    format!("particles: [{}]", sys.join(", "))
}

#[test]
fn print_passes_bakes_and_runs_only_the_effects_a_scene_calls_for() {
    // The paper's explosion: every particle bake (dust and smoke scatter, fire glows),
    // animated cells for the swaying oak, shimmer asked for, no motion blur, no shadows.
    assert_eq!(
        passes(&scenes().join("explosion.ron")),
        [
            "bake:detail-noise",
            "bake:phase-lut",
            "bake:blackbody-lut",
            "animate:cells",
            "mesh",
            "volume",
            "particles",
            "shimmer",
            "composite",
            "resolve"
        ]
    );
    // Smoke alone: no black-body table, no shimmer, no mesh or volume pass.
    assert_eq!(
        scene_passes(&format!("({})", particles(&["Smoke"]))),
        [
            "bake:detail-noise",
            "bake:phase-lut",
            "particles",
            "composite",
            "resolve"
        ]
    );
    // Fire alone: the black-body table but no phase table (fire does not scatter).
    assert_eq!(
        scene_passes(&format!("({})", particles(&["Fire"]))),
        [
            "bake:detail-noise",
            "bake:blackbody-lut",
            "particles",
            "composite",
            "resolve"
        ]
    );
    // Motion blur and shimmer only when the layer asks for them, in that order.
    assert_eq!(
        scene_passes(&format!(
            "({}, particle_layer: (resolution: Half, shimmer: Some(2.0), \
             motion_blur: Some((shutter: 0.05, samples: 4))))",
            particles(&["Dust", "Fire"])
        )),
        [
            "bake:detail-noise",
            "bake:phase-lut",
            "bake:blackbody-lut",
            "particles",
            "motion-blur",
            "shimmer",
            "composite",
            "resolve"
        ]
    );
    // A layer description without particles builds nothing for them.
    assert_eq!(
        scene_passes("(volumes: [(asset: \"oak.billow\")], particle_layer: (shimmer: Some(2.0)))"),
        ["volume", "resolve"]
    );
    // Cells are animated only for a volume that asks for it.
    assert_eq!(
        scene_passes(
            "(volumes: [(asset: \"oak.billow\", \
             animation: Some((amplitude: 0.05, frequency: 0.5)))])"
        ),
        ["animate:cells", "volume", "resolve"]
    );
}

/// Writes `text` as a scene next to a copy of the oak asset; returns the one error line.
fn scene_error(text: &str) -> (String, Option<i32>) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(scenes().join("oak32.billow"), dir.path().join("oak.billow")).unwrap();
    let s = dir.path().join("bad.ron");
    std::fs::write(&s, text).unwrap();
    let r = run(
        &["view", "bad.ron", "--headless", "--screenshot", "x.png"],
        dir.path(),
    );
    assert!(!dir.path().join("x.png").exists(), "no output on error");
    let line = r.error_line().unwrap_or_else(|e| panic!("{e}")).to_string();
    (line, r.code)
}

#[test]
fn bad_scene_files_give_one_line_naming_file_and_field() {
    let cases = [
        // unknown field
        ("(volumes: [(asset: \"oak.billow\", colour: 3)])", "colour"),
        ("(shadow: true)", "shadow"),
        // missing field: the path to the struct that lacks it, and the field
        (
            "(volumes: [(instances: [])])",
            "volumes[0]: Unexpected missing field named `asset`",
        ),
        (
            "(volumes: [(asset: \"oak.billow\")], particles: [(kind: Dust, emitter: (count: 4))])",
            "particles[0].emitter",
        ),
        // negative sizes
        (
            "(volumes: [(asset: \"oak.billow\", instances: [(scale: -2.0)])])",
            "volumes[0].instances[0].scale",
        ),
        ("(ground: Some((size: -1.0)))", "ground.size"),
        (
            "(camera: Some((eye: (1.0, 2.0, 3.0), target: (0.0, 0.0, 0.0), fov_deg: -5.0)))",
            "camera.fov_deg",
        ),
        ("(light: (direction: (0.0, 0.0, 0.0)))", "light.direction"),
    ];
    for (text, field) in cases {
        let (line, code) = scene_error(text);
        assert!(line.contains("bad.ron"), "{text}: {line}");
        assert!(line.contains(field), "{text}: expected '{field}' in {line}");
        assert_eq!(code, Some(4), "{text}: {line}");
    }
    // A missing asset or mesh cannot be read: exit 3 (docs/cli.md), not 4.
    for (text, field) in [
        (
            "(volumes: [(asset: \"missing.billow\")])",
            "volumes[0].asset",
        ),
        ("(clouds: [(asset: \"missing.billow\")])", "clouds[0].asset"),
        ("(meshes: [(path: \"nope.obj\")])", "meshes[0].path"),
    ] {
        let (line, code) = scene_error(text);
        assert!(line.contains("bad.ron"), "{text}: {line}");
        assert!(line.contains(field), "{text}: expected '{field}' in {line}");
        assert_eq!(code, Some(3), "{text}: {line}");
    }
    // A syntax error gives the position.
    let (line, code) = scene_error("(volumes: [(asset: \"oak.billow\"]");
    assert!(line.contains("bad.ron: 1:"), "{line}");
    assert_eq!(code, Some(4));
}

#[test]
fn headless_screenshot_of_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes().join("oak_wall.ron");
    let r = run(
        &[
            "view",
            scene.to_str().unwrap(),
            "--headless",
            "--screenshot",
            "shot.png",
            "--size",
            "96x64",
            "--json",
        ],
        dir.path(),
    );
    if r.code != Some(0) && r.stderr.contains("no GPU adapter") {
        common::skip("headless_screenshot_of_a_scene", r.stderr.trim());
        return;
    }
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let img = image::open(dir.path().join("shot.png")).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (96, 64));
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(
        v["passes"],
        serde_json::json!(["mesh", "volume", "resolve"])
    );
    assert!(v["stats"]["slices"].as_u64().unwrap() > 10, "{}", r.stdout);
    // Something opaque (wall, ground) and something green (leaves) are in the picture.
    let opaque = img.pixels().filter(|p| p[3] == 255).count();
    let green = img
        .pixels()
        .filter(|p| p[3] > 0 && p[1] > p[0] && p[1] > p[2])
        .count();
    assert!(opaque > 96 * 64 / 4, "opaque pixels: {opaque}");
    assert!(green > 50, "green pixels: {green}");
}

#[test]
fn a_missing_adapter_says_how_to_install_a_driver() {
    // No Metal backend on this platform (and DX12 only on Windows): no adapter at all,
    // exactly what a machine without a Vulkan driver sees.
    let backend = if cfg!(target_os = "macos") {
        "dx12"
    } else {
        "metal"
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let r = common::run_with(
        &[
            "view",
            scenes().join("oak32.billow").to_str().unwrap(),
            "--headless",
            "--screenshot",
            out.to_str().unwrap(),
        ],
        dir.path(),
        std::time::Duration::from_secs(60),
        8 << 20,
        &[("WGPU_BACKEND", backend)],
    );
    assert_eq!(r.code, Some(5), "{}", r.stderr);
    assert_eq!(r.stderr.lines().count(), 1, "one line: {}", r.stderr);
    assert!(
        r.stderr.contains("no GPU adapter") && r.stderr.contains("mesa-vulkan-drivers"),
        "{}",
        r.stderr
    );
    assert!(!out.exists(), "no screenshot without a GPU");
}

/// Runs `view TARGET --headless --json` (64×48) in `dir` and returns its JSON, or `None`
/// after `skip` when there is no GPU adapter.
fn headless_json(test: &str, target: &Path, dir: &Path) -> Option<serde_json::Value> {
    let r = run(
        &[
            "view",
            target.to_str().unwrap(),
            "--headless",
            "--screenshot",
            "shot.png",
            "--size",
            "64x48",
            "--json",
        ],
        dir,
    );
    if r.code != Some(0) && r.stderr.contains("no GPU adapter") {
        common::skip(test, r.stderr.trim());
        return None;
    }
    assert_eq!(r.code, Some(0), "{}: {}", target.display(), r.stderr);
    Some(serde_json::from_str(&r.stdout).unwrap())
}

/// Issue 25, item 6: what the renderer *records* — the bakes it made and the passes its
/// frame encoded (`record` of `--json`, written where each is built or encoded, see
/// `billow_view::gpu::RenderRecord`) — equals `--print-passes`, for every scene under
/// fixtures/scenes and for scenes written here with shadows (with and without
/// something to cast), particles with and without detail, motion blur and shimmer.
/// `shadow_slices` is 0 and no shadow map is made without a shadow pass; the detail
/// noise is not baked and the particle pipeline is the one without it when every
/// `detail` is 0 (and no shimmer). The gallery scenes need `make gallery`'s assets and
/// are not run here.
#[test]
fn recorded_passes_equal_print_passes_for_every_scene() {
    let name = "recorded_passes_equal_print_passes_for_every_scene";
    let dir = tempfile::tempdir().unwrap();
    for f in ["oak32.billow", "wall.obj"] {
        std::fs::copy(scenes().join(f), dir.path().join(f)).unwrap();
    }
    let mut targets: Vec<std::path::PathBuf> = std::fs::read_dir(scenes())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron" || e == "billow"))
        .collect();
    targets.sort();
    let extra = [
        (
            "shadows.ron",
            "(volumes: [(asset: \"oak32.billow\")], ground: Some((size: 4.0)), shadows: true)"
                .to_string(),
        ),
        (
            "shadows_nothing.ron",
            format!("(shadows: true, {})", particles(&["Dust"])),
        ),
        (
            "no_detail.ron",
            "(particles: [(kind: Smoke, emitter: (position: (0.0, 1.0, 0.0), count: 8, \
             radius: (0.5, 1.0), lifetime: (2.0, 3.0)), detail: 0.0)])"
                .to_string(),
        ),
        (
            "blur.ron",
            format!(
                "({}, particle_layer: (resolution: Half, shimmer: Some(2.0), \
                 motion_blur: Some((shutter: 0.05, samples: 3))))",
                particles(&["Dust", "Fire"])
            ),
        ),
    ];
    for (f, text) in &extra {
        let p = dir.path().join(f);
        std::fs::write(&p, text).unwrap();
        targets.push(p);
    }
    let mut checked = 0;
    for t in &targets {
        let printed = passes(t);
        let Some(v) = headless_json(name, t, dir.path()) else {
            return;
        };
        let rec = &v["record"];
        let built: Vec<String> = serde_json::from_value(rec["built"].clone()).unwrap();
        let ran: Vec<String> = serde_json::from_value(rec["passes"].clone()).unwrap();
        let recorded: Vec<String> = built
            .iter()
            .filter(|b| b.starts_with("bake:"))
            .chain(&ran)
            .cloned()
            .collect();
        assert_eq!(recorded, printed, "{}: built {built:?}", t.display());
        let shadow = printed.iter().any(|p| p == "shadow");
        let slices = v["stats"]["shadow_slices"].as_u64().unwrap();
        assert_eq!(
            slices > 0,
            shadow && printed.iter().any(|p| p == "volume"),
            "{}",
            t.display()
        );
        if !shadow {
            assert_eq!(slices, 0, "{}", t.display());
        }
        assert_eq!(
            built.iter().any(|b| b == "texture:shadow-map"),
            shadow,
            "{}: {built:?}",
            t.display()
        );
        let has = |b: &str| built.iter().any(|x| x == b);
        let detail = printed.iter().any(|p| p == "bake:detail-noise");
        if printed.iter().any(|p| p == "particles") {
            assert_eq!(
                has("pipeline:particles"),
                detail,
                "{}: {built:?}",
                t.display()
            );
            assert_eq!(
                has("pipeline:particles-no-detail"),
                !detail,
                "{}: {built:?}",
                t.display()
            );
        }
        for (pass, pipeline) in [
            ("volume", "pipeline:volume"),
            ("cloud", "pipeline:cloud"),
            ("shimmer", "pipeline:shimmer"),
            ("motion-blur", "pipeline:motion-blur"),
            ("composite", "pipeline:composite"),
        ] {
            assert_eq!(
                has(pipeline),
                printed.iter().any(|p| p == pass),
                "{}: {pipeline} built without its pass, or the pass without it: {built:?}",
                t.display()
            );
        }
        // The shadow pipelines only with a shadow pass, each with its caster's pass
        // (issue 37: a scene without shadows built the volumes' shadow pipeline).
        for (pass, pipeline) in [
            ("volume", "pipeline:volume-shadow"),
            ("mesh", "pipeline:mesh-shadow"),
            ("cloud", "pipeline:cloud-shadow"),
        ] {
            assert_eq!(
                has(pipeline),
                shadow && printed.iter().any(|p| p == pass),
                "{}: {pipeline}: {built:?}",
                t.display()
            );
        }
        // Each pipeline is built once.
        for b in &built {
            assert_eq!(
                built.iter().filter(|x| *x == b).count(),
                1,
                "{}: {b} built twice: {built:?}",
                t.display()
            );
        }
        // The start-up, step by step (ms).
        let startup = &v["startup_ms"];
        for k in [
            "read",
            "adapter",
            "upload",
            "pipelines",
            "first_frame",
            "total",
        ] {
            let ms = startup[k].as_f64().unwrap_or(-1.0);
            assert!(
                ms >= 0.0,
                "{}: startup_ms.{k} = {}",
                t.display(),
                startup[k]
            );
        }
        assert!(
            startup["total"].as_f64().unwrap() >= startup["first_frame"].as_f64().unwrap(),
            "{}: {startup}",
            t.display()
        );
        checked += 1;
    }
    assert_eq!(checked, 9, "scenes checked");
    // The detail-0 scene bakes no noise.
    let nd = passes(&dir.path().join("no_detail.ron"));
    assert_eq!(nd, ["bake:phase-lut", "particles", "composite", "resolve"]);
}
