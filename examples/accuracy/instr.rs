//! Load-independent bake costs: the instructions a bake executes, counted by valgrind's
//! callgrind (`perf stat -e instructions` has no counter on the VMs this runs on).
//!
//! The example re-runs itself as a child (`--count-bake MESH RES SS COMBINE`, single
//! thread: `RAYON_NUM_THREADS=1`) under `valgrind --tool=callgrind`, once per bake setting
//! and once importing only (`--count-import MESH`); a bake's count is the difference, so
//! it excludes the import, as the wall time does. Two children run at a time: the counts
//! do not depend on the load, and callgrind runs are slow (about 50× native).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

use billow::import::{import, ImportOptions};
use billow::voxelize::Preset;

/// The bake settings one count is for.
pub(crate) type Key = (u32, u32, Preset);

/// If this process is a counting child, does its work and exits.
pub(crate) fn child_main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mode = args.first().map(String::as_str);
    if !matches!(mode, Some("--count-bake" | "--count-import")) {
        return;
    }
    let scene = import(Path::new(&args[1]), &ImportOptions::default())
        .expect("import")
        .scene;
    if mode == Some("--count-bake") {
        let num = |i: usize| args[i].parse::<u32>().expect("a number");
        let combine = crate::volume::preset(&args[4]);
        crate::volume::bake(&scene, num(2), num(3), combine).expect("bake");
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

/// Whether callgrind can count here; if not, one loud SKIP line (and a failure under
/// `BILLOW_REQUIRE=all`), and the report's instruction columns say "–".
pub(crate) fn available() -> bool {
    let ok = Command::new("valgrind")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        billow::test_support::skip(
            "accuracy: bake instruction counts",
            "valgrind not found (Debian: apt-get install valgrind)",
        );
    }
    ok
}

/// Bake instructions (import excluded) of each key on `mesh`, in the keys' order.
pub(crate) fn bake_counts(mesh: &Path, keys: &[Key]) -> Vec<Option<u64>> {
    let mesh: PathBuf = mesh.to_path_buf();
    let m = mesh.display().to_string();
    let mut jobs: Vec<Vec<String>> = vec![vec!["--count-import".into(), m.clone()]];
    for &(res, ss, combine) in keys {
        jobs.push(vec![
            "--count-bake".into(),
            m.clone(),
            res.to_string(),
            ss.to_string(),
            combine.name().to_string(),
        ]);
    }
    let results: Mutex<Vec<Option<u64>>> = Mutex::new(vec![None; jobs.len()]);
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
                let Some(job) = jobs.get(i) else { break };
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
