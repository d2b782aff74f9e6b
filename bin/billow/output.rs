//! Shared output helpers: JSON summaries on stdout, warnings and progress on stderr.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::exit::{CliError, Code};
use crate::Ctx;

/// Print `value` as pretty JSON on stdout (the only thing on stdout with `--json`).
pub fn print_json<T: Serialize>(value: &T) -> Result<(), CliError> {
    let s = serde_json::to_string_pretty(value)
        .map_err(|e| CliError::new(Code::Internal, format!("cannot encode JSON: {e}")))?;
    println!("{s}");
    Ok(())
}

pub fn warn(ctx: &Ctx, message: &str) {
    if !ctx.quiet {
        eprintln!("warning: {message}");
    }
}

/// A progress bar on stderr, shown only on a terminal and without `--quiet`.
#[allow(dead_code)] // for the baking commands
pub fn progress(ctx: &Ctx, len: u64, what: &str) -> ProgressBar {
    if ctx.quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template("{prefix:>12} [{bar:30}] {percent:>3}% {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_prefix(what.to_string());
    bar
}
