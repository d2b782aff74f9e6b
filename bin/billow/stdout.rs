//! Everything billow prints on stdout goes through [`outln!`]/[`out!`], which never panic
//! (std's `println!` panics when stdout is a closed pipe, exit 101).
//!
//! A closed stdout (`billow info X | head -c1`: the reader has what it wants) is a normal
//! end of the output: the rest of stdout is dropped silently, the command still completes
//! (its files are written) and exits with its usual code, as ripgrep does. Any other
//! error writing stdout (a full disk) is reported once at the end, exit 7.

use std::fmt;
use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use crate::exit::{CliError, Code};

/// Set once stdout failed: later output is dropped.
static STOPPED: AtomicBool = AtomicBool::new(false);
/// The first error other than a broken pipe.
static FAILED: Mutex<Option<String>> = Mutex::new(None);

/// `println!` that never panics (see the module docs).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` that never panics (see the module docs).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!($($arg)*))
    };
}

pub fn write(args: fmt::Arguments) {
    if STOPPED.load(Ordering::Relaxed) {
        return;
    }
    let r = std::io::stdout().lock().write_fmt(args);
    if let Err(e) = r {
        stop(e);
    }
}

fn stop(e: std::io::Error) {
    STOPPED.store(true, Ordering::Relaxed);
    if e.kind() != ErrorKind::BrokenPipe {
        let mut failed = FAILED.lock().unwrap_or_else(|p| p.into_inner());
        failed.get_or_insert_with(|| e.to_string());
    }
}

/// Flushes stdout; an error other than a closed pipe is the command's error (exit 7).
pub fn finish() -> Result<(), CliError> {
    if !STOPPED.load(Ordering::Relaxed) {
        if let Err(e) = std::io::stdout().lock().flush() {
            stop(e);
        }
    }
    let failed = FAILED.lock().unwrap_or_else(|p| p.into_inner()).take();
    match failed {
        Some(e) => Err(CliError::new(
            Code::OutputIo,
            format!("stdout: cannot write: {e}"),
        )),
        None => Ok(()),
    }
}

/// Turns a panic (a bug) into one `error: internal: ...` line on stderr and exit 1, as
/// docs/cli.md promises, instead of Rust's backtrace and exit 101.
pub fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let payload = info.payload();
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".to_string());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let line = format!(
            "error: internal: {}{at} (a bug in billow; please report it)\n",
            what.replace('\n', " ")
        );
        // Never panic here (a panic in the hook aborts): a closed stderr is ignored.
        let _ = std::io::stderr().lock().write_all(line.as_bytes());
        std::process::exit(Code::Internal as i32);
    }));
}
