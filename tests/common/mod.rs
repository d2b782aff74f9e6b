//! Helpers for driving the real `billow` binary in integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The `billow` binary Cargo built for this test (only the CLI package's tests,
/// bin/billow/Cargo.toml, have one).
pub fn bin() -> PathBuf {
    match option_env!("CARGO_BIN_EXE_billow") {
        Some(p) => PathBuf::from(p),
        None => panic!(
            "this test drives the binary: declare it in bin/billow/Cargo.toml, not in the library's Cargo.toml"
        ),
    }
}

/// The repository root (the library's package; the CLI package is bin/billow).
pub fn repo() -> PathBuf {
    let m = Path::new(env!("CARGO_MANIFEST_DIR"));
    if m.ends_with("bin/billow") {
        m.join("../..").canonicalize().expect("the repository root")
    } else {
        m.to_path_buf()
    }
}

/// A test that cannot run says so on stderr (`SKIP: <test>: <reason>`, written to the
/// process's stderr so it shows even though the harness captures `eprintln!`), and fails
/// instead under CI (`CI` set) or `BILLOW_REQUIRE=all`, where every resource it needs
/// must be there.
pub fn skip(test: &str, reason: &str) {
    skip_unless_required(test, None, reason)
}

/// [`skip`] for a test that needs an external `tool` which a machine may lack for good
/// (e.g. Khronos' `ktx`, which Debian does not package): it may still skip under
/// `CI` / `BILLOW_REQUIRE=all` when the tool is named in `BILLOW_OPTIONAL` (a comma
/// list, e.g. `BILLOW_OPTIONAL=ktx`), and says so on stderr all the same.
pub fn skip_tool(test: &str, tool: &str, reason: &str) {
    skip_unless_required(test, Some(tool), reason)
}

fn skip_unless_required(test: &str, tool: Option<&str>, reason: &str) {
    let waived = tool.is_some_and(|t| {
        std::env::var("BILLOW_OPTIONAL").is_ok_and(|v| v.split(',').any(|x| x.trim() == t))
    });
    let required = !waived
        && (std::env::var_os("CI").is_some()
            || std::env::var("BILLOW_REQUIRE").is_ok_and(|v| v == "all"));
    assert!(
        !required,
        "{test}: {reason} (required under CI / BILLOW_REQUIRE=all)"
    );
    // Straight to the process's stderr: the test harness captures `eprintln!`.
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "SKIP: {test}: {reason}");
}

/// `../shared/assets`, or `None` (after [`skip`]) when absent.
pub fn shared_assets(test: &str) -> Option<PathBuf> {
    let p = repo().join("../shared/assets");
    if p.is_dir() {
        Some(p)
    } else {
        skip(test, "../shared/assets not found");
        None
    }
}

pub struct Run {
    /// `None` when killed by a signal or the timeout.
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub timed_out: bool,
}

impl Run {
    /// The single `error: ...` line a failing command must print, or a description of what is wrong.
    pub fn error_line(&self) -> Result<&str, String> {
        let lines: Vec<&str> = self
            .stderr
            .lines()
            .filter(|l| !l.starts_with("warning:"))
            .collect();
        match lines.as_slice() {
            [l] if l.starts_with("error: ") => Ok(l),
            _ => Err(format!(
                "expected one 'error:' line on stderr, got {:?}",
                self.stderr
            )),
        }
    }
}

/// Runs `billow args...` with a wall-clock limit and an address-space limit (`ulimit -v`,
/// in KiB) so that a hang or an allocation bomb fails the test instead of the machine.
pub fn run_limited(args: &[&str], dir: &Path, timeout: Duration, mem_kib: u64) -> Run {
    run_with(args, dir, timeout, mem_kib, &[("RAYON_NUM_THREADS", "2")])
}

/// [`run_limited`] with extra environment variables.
pub fn run_with(
    args: &[&str],
    dir: &Path,
    timeout: Duration,
    mem_kib: u64,
    envs: &[(&str, &str)],
) -> Run {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!("ulimit -v {mem_kib}; exec \"$0\" \"$@\""))
        .arg(bin())
        .args(args)
        .current_dir(dir)
        .envs(envs.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("spawn billow");
    let start = Instant::now();
    let mut timed_out = false;
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            timed_out = true;
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let out = child.wait_with_output().expect("output");
    Run {
        code: if timed_out { None } else { out.status.code() },
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        timed_out,
    }
}

/// Runs `billow args...` in `dir` (generous limits).
pub fn run(args: &[&str], dir: &Path) -> Run {
    run_limited(args, dir, Duration::from_secs(120), 8 << 20)
}

pub fn sha256(path: &Path) -> String {
    use sha2::{Digest, Sha256};
    let bytes = std::fs::read(path).unwrap();
    format!("{:x}", Sha256::digest(bytes))
}
