//! The outputs of one command, committed together or not at all. Every command that writes
//! files writes them through a [`Staged`]:
//!
//! 1. Each file is written in full under a hidden temporary name in its destination folder,
//!    `.<name>.<pid>-<n>.billow.tmp` (matches `.gitignore`'s `*.billow.tmp*`), and flushed
//!    to disk (`fsync`).
//! 2. Only when all of them are there are they renamed into place, the primary output
//!    (`-o`, `eval --out`'s `eval.json`, ...) last, and the folders synced.
//! 3. If anything fails before that, the temporaries are removed (also on an early return
//!    or a panic: `Drop`), and so is a folder that was created for them: a failed command
//!    leaves no new file behind and never touches existing ones.
//!
//! A process killed outright (`kill -9`, a power cut) cannot clean up: its temporaries stay.
//! The pid in their names tells them apart from those of a run still in progress, and the
//! next command that writes the same output removes the ones whose process is gone
//! ([`Staged::stage_with`], on Linux, where `/proc` says which processes are alive).
//!
//! The renames themselves are separate system calls, so a kill *between* two of them (a
//! window of microseconds, after every byte is on disk) can still leave some outputs new
//! and the rest old. Renaming the primary output last makes that state visible: the primary
//! is then the old one, older than its companions, so `make` (and any tool that compares
//! times with the primary) bakes again.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::exit::{CliError, Code};
use crate::signals::{temp_owner, TEMP_SUFFIX};

/// Files staged so far, and folders created for them.
pub struct Staged {
    files: Vec<(PathBuf, PathBuf, bool)>, // (temporary, destination, destination existed)
    dirs: Vec<PathBuf>,
    primary: PathBuf,
    /// Per folder: the stale temporaries found there, by the destination name they stand for.
    stale: HashMap<PathBuf, HashMap<String, Vec<PathBuf>>>,
    committed: bool,
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

fn file_name(dest: &Path) -> String {
    dest.file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned())
}

/// `cannot write output: <path>: <problem>`, exit 7.
pub fn out_err(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::new(
        Code::OutputIo,
        format!("cannot write output: {}: {e}", path.display()),
    )
}

/// Whether process `pid` may still be running: `false` only when the OS says it is gone.
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    // Linux: /proc lists the live processes (of this pid namespace). Elsewhere, or where
    // /proc is not mounted, nothing is known and nothing is removed.
    let proc = Path::new("/proc");
    !proc.join("self").exists() || proc.join(pid.to_string()).exists()
}

/// The temporaries in `dir` left by processes that are gone, by destination name.
fn stale_in(dir: &Path) -> HashMap<String, Vec<PathBuf>> {
    let mut out: HashMap<String, Vec<PathBuf>> = HashMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let Some((dest, pid)) = temp_owner(name) else {
            continue;
        };
        if e.file_type().is_ok_and(|t| t.is_file()) && !alive(pid) {
            out.entry(dest.to_string()).or_default().push(e.path());
        }
    }
    out
}

impl Staged {
    /// Staging for a command whose main output is `primary` (renamed after all others).
    pub fn new(primary: &Path) -> Self {
        Staged {
            files: Vec::new(),
            dirs: Vec::new(),
            primary: primary.to_path_buf(),
            stale: HashMap::new(),
            committed: false,
        }
    }

    /// Create `dir` (and missing parents) if it is not there; removed again on failure.
    pub fn create_dir(&mut self, dir: &Path) -> std::io::Result<()> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        std::fs::create_dir_all(dir)?;
        for d in missing.iter().rev() {
            crate::signals::watch_created(d);
        }
        // Innermost first, so they can be removed in order.
        self.dirs.extend(missing);
        Ok(())
    }

    /// Removes the temporaries a killed earlier run left for `dest`, and the write probes
    /// (`crate::output::PROBE`) a killed run left in its folder.
    fn sweep(&mut self, dest: &Path) {
        let dir = folder(dest).to_path_buf();
        let stale = self.stale.entry(dir).or_insert_with_key(|d| stale_in(d));
        let probes = stale.remove(crate::output::PROBE).unwrap_or_default();
        for t in stale
            .remove(&file_name(dest))
            .unwrap_or_default()
            .into_iter()
            .chain(probes)
        {
            let _ = std::fs::remove_file(t);
        }
    }

    /// Stages `bytes` as the new content of `dest`.
    pub fn stage(&mut self, dest: &Path, bytes: &[u8]) -> std::io::Result<()> {
        self.stage_with(dest, |w| w.write_all(bytes))
    }

    /// Stages the concatenation of `parts` as the new content of `dest`.
    pub fn stage_parts(&mut self, dest: &Path, parts: &[&[u8]]) -> std::io::Result<()> {
        self.stage_with(dest, |w| parts.iter().try_for_each(|p| w.write_all(p)))
    }

    /// Stages what `write` writes as the new content of `dest`: into a temporary file next
    /// to it, flushed to disk before this returns. Stale temporaries of `dest` (of killed
    /// runs) are removed first.
    pub fn stage_with(
        &mut self,
        dest: &Path,
        write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        self.sweep(dest);
        crate::signals::watch(folder(dest));
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = folder(dest).join(format!(
            ".{}.{}-{n}{TEMP_SUFFIX}",
            file_name(dest),
            std::process::id()
        ));
        let f: File = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        self.files.push((tmp, dest.to_path_buf(), dest.exists()));
        let mut w = BufWriter::with_capacity(1 << 20, f);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()
    }

    /// Renames every staged file into place, the primary output last. On a failure, files
    /// already renamed that did not exist before are removed again (an existing destination
    /// that was replaced stays replaced: a rename cannot be undone), and the rest are
    /// cleaned up by `Drop`.
    pub fn commit(mut self) -> Result<(), (PathBuf, std::io::Error)> {
        // For tests of interruption: a pause with every output staged, before any rename
        // (`BILLOW_TEST_COMMIT_DELAY_MS`; not for users, documented in docs/cli.md).
        if let Some(ms) = std::env::var("BILLOW_TEST_COMMIT_DELAY_MS")
            .ok()
            .and_then(|v| v.parse::<u64>().ok())
        {
            std::thread::sleep(std::time::Duration::from_millis(ms));
        }
        // Stable: the others keep their staging order.
        let primary = self.primary.clone();
        self.files.sort_by_key(|(_, d, _)| *d == primary);
        for i in 0..self.files.len() {
            let (tmp, dest, _) = &self.files[i];
            if let Err(e) = std::fs::rename(tmp, dest) {
                let dest = dest.clone();
                for (_, d, existed) in &self.files[..i] {
                    if !existed {
                        let _ = std::fs::remove_file(d);
                    }
                }
                self.files.drain(..i);
                return Err((dest, e));
            }
        }
        let mut synced = Vec::new();
        for (_, dest, _) in &self.files {
            let d = folder(dest).to_path_buf();
            if !synced.contains(&d) {
                if let Ok(f) = File::open(&d) {
                    let _ = f.sync_all();
                }
                synced.push(d);
            }
        }
        self.committed = true;
        Ok(())
    }

    /// [`Staged::commit`] with its error as the command's error (exit 7).
    pub fn commit_or_fail(self) -> Result<(), CliError> {
        self.commit().map_err(|(p, e)| out_err(&p, e))
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for (tmp, _, _) in &self.files {
            let _ = std::fs::remove_file(tmp);
        }
        for d in &self.dirs {
            let _ = std::fs::remove_dir(d); // only if empty
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names() {
        assert_eq!(
            temp_owner(".a.billow.123-0.billow.tmp"),
            Some(("a.billow", 123))
        );
        assert_eq!(
            temp_owner(".x y.ktx2.77-AbC9.billow.tmp"),
            Some(("x y.ktx2", 77))
        );
        assert_eq!(temp_owner("a.billow.123-0.billow.tmp"), None);
        assert_eq!(temp_owner(".a.billow.abc-0.billow.tmp"), None);
        assert_eq!(temp_owner(".a.billow"), None);
    }
}
