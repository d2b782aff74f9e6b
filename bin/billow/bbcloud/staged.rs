//! Several output files written as one: every file is first written in full (and flushed to
//! disk) under a hidden temporary name in its destination folder, and only when all of them
//! are there are they renamed into place. If anything fails before that, the temporaries are
//! removed (also on an early return or a panic: `Drop`), and so is a folder that was created
//! for them, so a failed command leaves no new file behind and never touches existing ones.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Files staged so far, and folders created for them.
#[derive(Default)]
pub struct Staged {
    files: Vec<(PathBuf, PathBuf, bool)>, // (temporary, destination, destination existed)
    dirs: Vec<PathBuf>,
    committed: bool,
}

static COUNTER: AtomicU64 = AtomicU64::new(0);

fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

impl Staged {
    /// Create `dir` (and missing parents) if it is not there; removed again on failure.
    pub fn create_dir(&mut self, dir: &Path) -> std::io::Result<()> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        std::fs::create_dir_all(dir)?;
        // Innermost first, so they can be removed in order.
        self.dirs.extend(missing);
        Ok(())
    }

    /// Write `bytes` to a temporary file next to `dest` (`.<name>.<pid>-<n>.billow.tmp`).
    pub fn stage(&mut self, dest: &Path, bytes: &[u8]) -> std::io::Result<()> {
        let name = dest
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = folder(dest).join(format!(".{name}.{}-{n}.billow.tmp", std::process::id()));
        let mut f: File = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        self.files.push((tmp, dest.to_path_buf(), dest.exists()));
        f.write_all(bytes)?;
        f.sync_all()
    }

    /// Rename every staged file into place. On a failure, files already renamed that did not
    /// exist before are removed again (an existing destination that was replaced stays
    /// replaced: a rename cannot be undone), and the rest are cleaned up by `Drop`.
    pub fn commit(mut self) -> Result<(), (PathBuf, std::io::Error)> {
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
