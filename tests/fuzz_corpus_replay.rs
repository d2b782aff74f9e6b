//! Replays every committed fuzz corpus and regression input (`fuzz/corpus/<target>/`,
//! `fuzz/regressions/<target>/`) through the same function the fuzz target calls
//! (`fuzz/harness.rs`). CI replays; it does not fuzz (docs/robustness.md, "Fuzzing").
//!
//! Each input runs on its own thread with an 8 MiB stack (a main thread's) and must
//! return, `Ok` or `Err`, within [`LIMIT`]: a panic or a timeout fails the test with the
//! file's name; a stack overflow or an abort kills the test binary, which fails it too.

#[path = "../fuzz/harness.rs"]
mod harness;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The most one input may take (a debug build; the fuzzers run with `-timeout=10`).
const LIMIT: Duration = Duration::from_secs(30);
const STACK: usize = 8 << 20;

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .map(|e| e.expect("read a corpus folder entry").path())
            .filter(|p| p.is_file())
            .collect(),
        Err(_) => Vec::new(),
    };
    v.sort();
    v
}

/// Runs one input; `Err` describes a panic or a timeout.
fn replay_one(target: &'static str, path: &Path) -> Result<Duration, String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let (tx, rx) = mpsc::channel();
    let start = Instant::now();
    std::thread::Builder::new()
        .name(format!("replay-{target}"))
        .stack_size(STACK)
        .spawn(move || {
            let r = std::panic::catch_unwind(|| harness::run(target, &data));
            harness::cleanup();
            let _ = tx.send(r.is_ok());
        })
        .expect("spawn a replay thread");
    match rx.recv_timeout(LIMIT) {
        Ok(true) => Ok(start.elapsed()),
        Ok(false) => Err("panicked".into()),
        Err(_) => Err(format!("did not return within {LIMIT:?}")),
    }
}

fn replay(target: &'static str) {
    assert!(
        harness::TARGETS.contains(&target),
        "{target} is not in TARGETS"
    );
    let root = billow::test_support::repo().join("fuzz");
    let corpus = files(&root.join("corpus").join(target));
    assert!(
        !corpus.is_empty(),
        "fuzz/corpus/{target}/ is missing or empty: the committed corpus is what CI replays"
    );
    let regressions = files(&root.join("regressions").join(target));
    let mut failures = Vec::new();
    let mut slowest = (Duration::ZERO, PathBuf::new());
    for path in corpus.iter().chain(&regressions) {
        match replay_one(target, path) {
            Ok(t) if t > slowest.0 => slowest = (t, path.clone()),
            Ok(_) => {}
            Err(e) => failures.push(format!("{}: {e}", path.display())),
        }
    }
    eprintln!(
        "{target}: {} corpus + {} regression inputs, slowest {:?} ({})",
        corpus.len(),
        regressions.len(),
        slowest.0,
        slowest.1.file_name().unwrap_or_default().to_string_lossy()
    );
    assert!(failures.is_empty(), "{target}:\n{}", failures.join("\n"));
}

#[test]
fn asset_reader() {
    replay("asset_reader");
}

#[test]
fn gltf_import() {
    replay("gltf_import");
}

#[test]
fn obj_import() {
    replay("obj_import");
}

#[test]
fn combine_expr() {
    replay("combine_expr");
}

#[test]
fn scene_ron() {
    replay("scene_ron");
}

/// Every target has a test above.
#[test]
fn every_target_is_replayed() {
    let src = include_str!("fuzz_corpus_replay.rs");
    for t in harness::TARGETS {
        assert!(
            src.contains(&format!("fn {t}()")),
            "no replay test for the fuzz target {t}"
        );
    }
    let targets = billow::test_support::repo().join("fuzz/fuzz_targets");
    let mut on_disk: Vec<String> = files(&targets)
        .iter()
        .filter_map(|p| Some(p.file_stem()?.to_string_lossy().into_owned()))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = harness::TARGETS.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        on_disk, listed,
        "fuzz/fuzz_targets/ and harness::TARGETS differ"
    );
}

/// The fuzzer's first find (`fuzz/regressions/obj_import/`): tobj 4.0.5 panics on an MTL
/// colour line with fewer than three values (`Kd 1`). billow parses MTL itself now: one
/// value is grey (g = b = r, as the MTL specification says), and two values are a warning
/// naming the line (an error with `strict`) that ignores that statement only.
#[test]
fn short_mtl_colour_line_is_a_warning() {
    use billow::import::{import, ImportErrorKind, ImportOptions, Imported};
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = dir.path().join("tri.obj");
    std::fs::write(
        &obj,
        "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    )
    .expect("write tri.obj");
    for colour in ["Ka", "Kd", "Ks", "Ke"] {
        std::fs::write(
            dir.path().join("tri.mtl"),
            format!("newmtl a\n{colour} 1 0.5\n"),
        )
        .expect("write tri.mtl");
        let Imported { scene, report } = import(&obj, &ImportOptions::default())
            .unwrap_or_else(|e| panic!("{colour}: import refused: {e}"));
        assert_eq!(scene.triangles.len(), 1, "{colour}");
        assert_eq!(
            scene.materials[0].name, "a",
            "{colour}: the material is kept"
        );
        assert!(
            report.warnings.iter().any(|w| w.message.contains("tri.mtl")
                && w.message.contains("line 2")
                && w.message.contains("ignored")),
            "{colour}: no warning about the MTL: {:?}",
            report.warnings
        );
        let strict = import(&obj, &ImportOptions { strict: true }).expect_err("strict");
        assert_eq!(strict.kind(), ImportErrorKind::Strict, "{colour}: {strict}");
        std::fs::write(
            dir.path().join("tri.mtl"),
            format!("newmtl a\n{colour} 0.5\n"),
        )
        .expect("write tri.mtl");
        let report = import(&obj, &ImportOptions { strict: true })
            .unwrap_or_else(|e| panic!("{colour} 0.5: {e}"))
            .report;
        assert!(
            report.warnings.is_empty(),
            "{colour} 0.5: {:?}",
            report.warnings
        );
    }
    // Three values are still read.
    std::fs::write(dir.path().join("tri.mtl"), "newmtl a\nKd 1 0.5 0.25\n").expect("write");
    let report = import(&obj, &ImportOptions { strict: true })
        .expect("a valid MTL")
        .report;
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}
