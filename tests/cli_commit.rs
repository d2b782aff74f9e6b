//! The outputs of one command are committed together or not at all (docs/cli.md, "Outputs"):
//! `billow voxelize --ktx2 --depfile` killed with SIGKILL at many points of its run leaves
//! either all the old outputs or all the new ones, never a new .billow beside an old .ktx2
//! (a kill inside the renames themselves, which the test provokes on purpose, can leave new
//! companions beside the old .billow: the primary output is renamed last);
//! the temporary files a killed run leaves are recognisable, and the next run for the same
//! outputs removes them. Real binaries in a temp dir, the bundled oak.

mod common;

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::*;

const OUTS: [&str; 3] = ["v.billow", "v.ktx2", "v.d"];

fn bake(d: &Path, res: &str) -> Child {
    Command::new(bin())
        .args([
            "voxelize",
            "eztree_oak_medium.gltf",
            "-o",
            "v.billow",
            "--ktx2",
            "v.ktx2",
            "--depfile",
            "v.d",
            "--res",
            res,
            "-q",
        ])
        .current_dir(d)
        .env("RAYON_NUM_THREADS", "2")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn billow")
}

fn finish(mut c: Child) {
    let st = c.wait().unwrap();
    let mut err = String::new();
    use std::io::Read;
    c.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    assert!(st.success(), "bake failed: {err}");
}

fn hashes(d: &Path) -> Vec<String> {
    OUTS.iter().map(|f| sha256(&d.join(f))).collect()
}

fn temps(d: &Path) -> Vec<String> {
    let mut t: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".billow.tmp"))
        .collect();
    t.sort();
    t
}

fn inode(p: &Path) -> u64 {
    std::fs::metadata(p).map_or(0, |m| m.ino())
}

/// Kills `c` (SIGKILL) as soon as `when` holds (polled every half millisecond) or after
/// `limit`; whether it was still running then.
fn kill_when(mut c: Child, limit: Duration, when: impl Fn() -> bool) -> bool {
    let start = Instant::now();
    loop {
        if c.try_wait().unwrap().is_some() {
            return false;
        }
        if when() || start.elapsed() >= limit {
            let _ = c.kill();
            let _ = c.wait();
            return true;
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

#[test]
fn killed_bakes_leave_all_old_or_all_new_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let oak = repo().join("fixtures/oak");
    for f in [
        "eztree_oak_medium.gltf",
        "eztree_oak_medium.bin",
        "oak_color.png",
        "oak_color_1k.jpg",
    ] {
        std::fs::copy(oak.join(f), d.join(f)).unwrap();
    }
    // The old outputs (a small bake) and the new ones (what every killed run would write).
    let res = "112";
    finish(bake(d, res));
    let new = hashes(d);
    finish(bake(d, "16"));
    let old = hashes(d);
    let saved: Vec<Vec<u8>> = OUTS
        .iter()
        .map(|f| std::fs::read(d.join(f)).unwrap())
        .collect();
    let restore = || {
        for (f, b) in OUTS.iter().zip(&saved) {
            std::fs::write(d.join(f), b).unwrap();
        }
    };
    let t = Instant::now();
    finish(bake(d, res));
    let full = t.elapsed();
    eprintln!("a full bake takes {:.2} s", full.as_secs_f64());

    let mut outcomes = Vec::new();
    let mut check = |what: String, killed: bool| {
        let now = hashes(d);
        let state = if now == old {
            "old"
        } else if now == new {
            "new"
        } else if now[0] == old[0]
            && now
                .iter()
                .zip(&old)
                .zip(&new)
                .all(|((n, o), w)| n == o || n == w)
        {
            // Killed between two renames: companions new, the primary (renamed last) old.
            "primary old, companions partly new (inside the renames)"
        } else {
            panic!("{what}: outputs mixed: {now:?}, old {old:?}, new {new:?}");
        };
        outcomes.push(format!(
            "{what}: {state}{}",
            if killed { "" } else { " (finished)" }
        ));
    };
    // Timed kills over the whole run, and more of them near its end (the writing).
    let mut points: Vec<f64> = vec![0.2, 0.5, 1.0];
    points.extend((1..=8).map(|i| full.as_secs_f64() * (0.5 + 0.06 * f64::from(i))));
    for s in points {
        restore();
        let killed = kill_when(bake(d, res), Duration::from_secs_f64(s), || false);
        check(format!("kill at {s:.2} s"), killed);
    }
    // The moment the first staging temporary appears (not a write probe, which lives for
    // a moment before the bake and which the next run sweeps), and the moment any output
    // is replaced.
    restore();
    let staging = |d: &Path| -> Vec<String> {
        temps(d)
            .into_iter()
            .filter(|t| !t.starts_with(".probe."))
            .collect()
    };
    let killed = kill_when(bake(d, res), full * 4, || !staging(d).is_empty());
    check("kill at the first temporary file".into(), killed);
    let stale = staging(d);
    assert_eq!(hashes(d), old, "killed before any rename");
    for out in OUTS {
        restore();
        let before = inode(&d.join(out));
        let p: PathBuf = d.join(out);
        let killed = kill_when(bake(d, res), full * 4, || inode(&p) != before);
        check(format!("kill when {out} is replaced"), killed);
    }
    eprintln!("{outcomes:#?}");
    assert!(
        !stale.is_empty(),
        "a run killed mid-write leaves its temporary files (recognisable by name)"
    );

    // Stale temporaries of dead processes go with the next run for the same outputs, and so
    // do their write probes; one of a live process (this test's) and one of another output
    // stay.
    let mut dead = Command::new("true").spawn().unwrap();
    let dead_pid = dead.id();
    dead.wait().unwrap();
    let planted = [
        format!(".v.billow.{dead_pid}-0.billow.tmp"),
        format!(".v.ktx2.{dead_pid}-7.billow.tmp"),
        // A write probe (`output::probe_writable`) a kill -9 caught.
        format!(".probe.{dead_pid}-3.billow.tmp"),
    ];
    let kept = [
        format!(".v.billow.{}-0.billow.tmp", std::process::id()),
        format!(".other.billow.{dead_pid}-0.billow.tmp"),
    ];
    for f in planted.iter().chain(&kept) {
        std::fs::write(d.join(f), b"stale").unwrap();
    }
    assert!(!temps(d).is_empty());
    finish(bake(d, res));
    assert_eq!(hashes(d), new);
    let mut want: Vec<String> = kept.to_vec();
    want.sort();
    assert_eq!(temps(d), want, "the next run removes the stale temporaries");
}

/// SIGINT, SIGTERM and SIGHUP while the outputs are staged (every byte written, nothing
/// renamed: `BILLOW_TEST_COMMIT_DELAY_MS` holds the run there) remove every temporary and
/// the folder the run created, leave the old outputs as they were, and end the process by
/// that signal. Only `kill -9` may leave a temporary (the test above).
#[test]
fn interrupted_runs_leave_no_temporary() {
    use std::os::unix::process::ExitStatusExt;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mesh = d.join("box.obj");
    std::fs::write(
        &mesh,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
    )
    .unwrap();
    for (name, sig) in [("SIGINT", 2), ("SIGTERM", 15), ("SIGHUP", 1)] {
        std::fs::write(d.join("v.billow"), b"old").unwrap();
        let mut c = Command::new(bin())
            .args([
                "voxelize",
                "box.obj",
                "-o",
                "v.billow",
                "--res",
                "16",
                "--slices",
                "new/slices",
                "-q",
            ])
            .current_dir(d)
            .env("BILLOW_TEST_COMMIT_DELAY_MS", "20000")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        let slices = d.join("new/slices");
        while temps(d).is_empty() || !slices.is_dir() || temps(&slices).is_empty() {
            assert!(
                c.try_wait().unwrap().is_none(),
                "{name}: the run ended before staging"
            );
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "{name}: no temporary"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        // The remaining slices are staged in milliseconds; the commit waits 20 s.
        std::thread::sleep(Duration::from_millis(500));
        let st = Command::new("kill")
            .args([format!("-{sig}"), c.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
        let status = c.wait().unwrap();
        assert_eq!(status.signal(), Some(sig), "{name}: {status:?}");
        assert_eq!(temps(d), Vec::<String>::new(), "{name}: temporaries left");
        assert!(
            !d.join("new").exists(),
            "{name}: the created folder is left"
        );
        assert_eq!(std::fs::read(d.join("v.billow")).unwrap(), b"old", "{name}");
    }
}

/// An output folder that takes no new file is refused before the work, also with
/// `--target-error`, whose search would bake every candidate first (exit 7, no trial).
/// `/proc/self` refuses new files even to root, who ignores permission bits.
#[test]
fn unwritable_output_folder_is_refused_before_the_bake() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let oak = repo().join("fixtures/oak");
    let mesh = oak.join("eztree_oak_medium.gltf");
    let mesh = mesh.to_str().unwrap();
    for extra in [&[][..], &["--target-error", "0.05"][..]] {
        let mut args = vec!["voxelize", mesh, "-o", "/proc/self/v.billow"];
        args.extend_from_slice(extra);
        let r = run(&args, d);
        assert_eq!(r.code, Some(7), "{args:?}: {}", r.stderr);
        let line = r.error_line().unwrap();
        assert!(
            line.contains("/proc/self") && line.contains("cannot create a file"),
            "{line}"
        );
        assert!(
            !r.stderr.contains("RMSE"),
            "baked before refusing: {}",
            r.stderr
        );
    }
}
