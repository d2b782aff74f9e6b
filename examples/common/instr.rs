//! Load-independent bake costs for the report generators (`examples/accuracy`,
//! `examples/pareto_sweep`): the instructions a bake executes, counted by valgrind's
//! callgrind (`perf stat -e instructions` has no counter on the VMs this runs on).
//!
//! The example re-runs itself as a child (`--count MESH ARGS…`, single thread:
//! `RAYON_NUM_THREADS=1`) under `valgrind --tool=callgrind`: once per bake, with the
//! example's own words for the bake in `ARGS`, and once loading the mesh only (no `ARGS`;
//! `MESH` is a file to import or a name the example's loader knows, such as a generated
//! tree). A bake's count is the difference, so it excludes the import, as the wall times do. Two
//! children run at a time: the counts do not depend on the load, and callgrind runs are
//! slow (about 50× native).

use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Mutex;

use billow::import::{import, ImportOptions};
use billow::scene::Scene;

/// The scene of a mesh file.
pub(crate) fn imported(mesh: &str) -> Scene {
    import(Path::new(mesh), &ImportOptions::default())
        .expect("import")
        .scene
}

/// If this process is a counting child, loads the mesh (`load`: [`imported`] for files),
/// runs `bake` on the scene and the child's words (none: load only) and exits.
pub(crate) fn child_main(load: impl FnOnce(&str) -> Scene, bake: impl FnOnce(&Scene, &[String])) {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) != Some("--count") {
        return;
    }
    let scene = load(&args[1]);
    if args.len() > 2 {
        bake(&scene, &args[2..]);
    }
    std::process::exit(0);
}

/// Instructions of one child run, from callgrind's `Collected : N` line; `None` when
/// valgrind is missing or the child fails (said on stderr).
fn collected(args: &[String]) -> Option<u64> {
    let exe = std::env::current_exe().ok()?;
    let out = Command::new("valgrind")
        .args(["--tool=callgrind", "--callgrind-out-file=/dev/null"])
        .arg(&exe)
        .arg("--count")
        .args(args)
        .env("RAYON_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .output()
        .ok()?;
    let err = String::from_utf8_lossy(&out.stderr);
    let n = err
        .lines()
        .find_map(|l| l.split_once("Collected :").map(|x| x.1.trim().to_string()))
        .and_then(|v| v.parse().ok());
    if n.is_none() || !out.status.success() {
        eprintln!("instruction count of {args:?} failed: {}", out.status);
        return None;
    }
    n
}

/// Whether callgrind can count here; if not, one loud SKIP line naming `what` (and a
/// failure under `BILLOW_REQUIRE=all`), and the report's instruction columns say "–".
/// Call it once per run.
pub(crate) fn available(what: &str) -> bool {
    let ok = Command::new("valgrind")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        billow::test_support::skip(
            what,
            "valgrind not found (Debian: apt-get install valgrind)",
        );
    }
    ok
}

/// Instructions in G (10⁹) for a table, or "–" where they were not counted.
pub(crate) fn giga(n: Option<u64>) -> String {
    n.map_or_else(|| "–".to_string(), |n| format!("{:.2}", n as f64 * 1e-9))
}

/// Bake instructions (loading excluded) on `mesh` (a path, or a name the child's loader
/// knows) of each job (the child's words for one bake), in the jobs' order.
pub(crate) fn bake_counts(mesh: &str, jobs: &[Vec<String>]) -> Vec<Option<u64>> {
    let m = mesh.to_string();
    let all: Vec<Vec<String>> = std::iter::once(vec![m.clone()])
        .chain(jobs.iter().map(|j| {
            let mut v = vec![m.clone()];
            v.extend(j.iter().cloned());
            v
        }))
        .collect();
    let results: Mutex<Vec<Option<u64>>> = Mutex::new(vec![None; all.len()]);
    let next = Mutex::new(0usize);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = {
                    let mut n = next.lock().unwrap();
                    let i = *n;
                    *n += 1;
                    i
                };
                let Some(job) = all.get(i) else { break };
                let c = collected(job);
                results.lock().unwrap()[i] = c;
            });
        }
    });
    let r = results.into_inner().unwrap();
    let import = r[0];
    r[1..]
        .iter()
        .map(|c| Some(c.as_ref()?.saturating_sub(import?)))
        .collect()
}
