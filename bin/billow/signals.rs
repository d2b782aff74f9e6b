//! SIGINT, SIGTERM and SIGHUP end a command without leaving a temporary file behind.
//!
//! [`install`] blocks the three signals in the main thread before any other thread exists
//! (every thread billow starts inherits the mask) and starts one thread that waits for
//! them. On a signal that thread removes this process's staging temporaries
//! (`.<name>.<pid>-<n>.billow.tmp`, [`temp_owner`]; written by `crate::staged`) from every folder registered with
//! [`watch`] and the empty folders registered with [`watch_created`], then ends the process
//! by the same signal (its default action), so the parent sees a process killed by it
//! (exit status 128 + the signal in a shell). Only `kill -9` (or a power cut) can still
//! leave a temporary, which the next run that writes the same output sweeps.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The end of every staging temporary's name: `.<name>.<pid>-<n>.billow.tmp`.
pub const TEMP_SUFFIX: &str = ".billow.tmp";

/// `(destination name, pid)` of a temporary file name `.<name>.<pid>-<rest>.billow.tmp`
/// (ours and [`billow_format::write_atomic`]'s).
pub fn temp_owner(temp_name: &str) -> Option<(&str, u32)> {
    let inner = temp_name.strip_prefix('.')?.strip_suffix(TEMP_SUFFIX)?;
    let (name, tail) = inner.rsplit_once('.')?;
    let (pid, _) = tail.split_once('-')?;
    Some((name, pid.parse().ok()?))
}

/// Folders this process writes temporaries into, and folders it created.
static FOLDERS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static CREATED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Notes that this process may write temporaries into `dir`.
pub fn watch(dir: &Path) {
    let mut f = FOLDERS.lock().unwrap_or_else(|e| e.into_inner());
    if !f.iter().any(|d| d == dir) {
        f.push(dir.to_path_buf());
    }
}

/// Notes that this process created `dir` (removed on a signal if it is empty then).
pub fn watch_created(dir: &Path) {
    CREATED
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(dir.to_path_buf());
}

/// Removes this process's temporaries from the watched folders, then the folders it
/// created that are empty (innermost first).
fn clean_up() {
    let me = std::process::id();
    let folders = FOLDERS.lock().unwrap_or_else(|e| e.into_inner()).clone();
    for dir in folders {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name();
            let Some(name) = name.to_str() else { continue };
            if temp_owner(name).is_some_and(|(_, pid)| pid == me) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
    let created = CREATED.lock().unwrap_or_else(|e| e.into_inner()).clone();
    for d in created.iter().rev() {
        let _ = std::fs::remove_dir(d);
    }
}

/// Blocks SIGINT, SIGTERM and SIGHUP in this (the main) thread and starts the thread that
/// handles them. Call first thing in `main`, before any thread is started.
#[cfg(unix)]
pub fn install() {
    // SAFETY: plain libc calls on a zeroed, initialised signal set owned by this frame.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for s in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            libc::sigaddset(&mut set, s);
        }
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        let spawned = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || loop {
                let mut sig: libc::c_int = 0;
                if libc::sigwait(&set, &mut sig) != 0 {
                    continue;
                }
                clean_up();
                // Die by the same signal: default action, unblocked, raised again.
                libc::signal(sig, libc::SIG_DFL);
                let mut one: libc::sigset_t = std::mem::zeroed();
                libc::sigemptyset(&mut one);
                libc::sigaddset(&mut one, sig);
                libc::pthread_sigmask(libc::SIG_UNBLOCK, &one, std::ptr::null_mut());
                libc::raise(sig);
                libc::_exit(128 + sig);
            });
        if spawned.is_err() {
            // No handler thread: let the signals act as before.
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}

#[cfg(not(unix))]
pub fn install() {}
