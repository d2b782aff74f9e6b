//! Shared output helpers: JSON summaries on stdout, warnings and progress on stderr.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::exit::{CliError, Code};
use crate::Ctx;

/// Print `value` as pretty JSON on stdout (the only thing on stdout with `--json`).
pub fn print_json<T: Serialize>(value: &T) -> Result<(), CliError> {
    let s = serde_json::to_string_pretty(value)
        .map_err(|e| CliError::new(Code::Internal, format!("cannot encode JSON: {e}")))?;
    outln!("{s}");
    Ok(())
}

pub fn warn(ctx: &Ctx, message: &str) {
    if !ctx.quiet {
        eprintln!("warning: {message}");
    }
}

/// A progress bar on stderr, shown only on a terminal and without `--quiet`.
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

/// Peak resident memory of this process so far (Linux `VmHWM`), if the OS tells.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses, before any work, outputs that would replace one of the `inputs` or each
/// other: inputs are never touched, and every output names its own file. `outputs` are
/// `(option, path)`. Files are compared by identity where they exist (device and inode on
/// Unix, so links are caught), else by their resolved path. Also refuses an output whose
/// folder does not exist or whose path is a folder (the write would fail only after the
/// whole bake).
pub fn refuse_clobbering(inputs: &[&Path], outputs: &[(&str, &Path)]) -> Result<(), CliError> {
    for (i, &(flag, out)) in outputs.iter().enumerate() {
        writable_destination(flag, out)?;
        if let Some(input) = inputs.iter().find(|p| same_file(p, out)) {
            return Err(CliError::new(
                Code::BadParameter,
                format!(
                    "{flag} {}: is the input {}; write the output elsewhere (nothing was written)",
                    out.display(),
                    input.display()
                ),
            ));
        }
        if let Some((other, _)) = outputs[..i].iter().find(|(_, p)| same_file(p, out)) {
            return Err(CliError::new(
                Code::BadParameter,
                format!(
                    "{flag} {}: {other} writes that file too; give each output its own path",
                    out.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The checks of [`refuse_clobbering`] on one output file's destination.
fn writable_destination(flag: &str, out: &Path) -> Result<(), CliError> {
    let unwritable = |why: String| {
        CliError::new(
            Code::OutputIo,
            format!(
                "cannot write output: {flag} {}: {why} (nothing was written)",
                out.display()
            ),
        )
    };
    if out.is_dir() {
        return Err(unwritable("is a directory; name a file".into()));
    }
    let dir = folder_of(out);
    if !dir.is_dir() {
        return Err(unwritable(format!(
            "directory {} does not exist",
            dir.display()
        )));
    }
    Ok(())
}

/// Refuses, before any work, a folder output (`--slices DIR`, `--atlas DIR`, ...) whose
/// path is an existing file; a missing folder is created when the output is written.
pub fn refuse_file_as_folder(flag: &str, dir: &Path) -> Result<(), CliError> {
    if dir.exists() && !dir.is_dir() {
        return Err(CliError::new(
            Code::OutputIo,
            format!(
                "cannot write output: {flag} {}: is a file, not a directory (nothing was written)",
                dir.display()
            ),
        ));
    }
    Ok(())
}

/// [`refuse_clobbering`] for the files an import of `mesh` read beside it (its
/// [`billow::scene::Scene::files`]), named as such in the message.
pub fn refuse_clobbering_read(
    mesh: &Path,
    files: &[PathBuf],
    outputs: &[(&str, &Path)],
) -> Result<(), CliError> {
    for &(flag, out) in outputs {
        if let Some(f) = files.iter().find(|f| same_file(f, out)) {
            return Err(CliError::new(
                Code::BadParameter,
                format!(
                    "{flag} {}: {} reads that file ({}); write the output elsewhere \
                     (nothing was written)",
                    out.display(),
                    mesh.display(),
                    f.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Whether `a` and `b` name the same file (see [`refuse_clobbering`]).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(ma), Ok(mb)) => match (identity(a, &ma), identity(b, &mb)) {
            (Some(ia), Some(ib)) => ia == ib,
            _ => false,
        },
        (Err(_), Err(_)) => resolved(a).is_some_and(|ra| resolved(b) == Some(ra)),
        _ => false,
    }
}

#[cfg(unix)]
fn identity(_: &Path, m: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn identity(p: &Path, _: &std::fs::Metadata) -> Option<PathBuf> {
    std::fs::canonicalize(p).ok()
}

/// A path that does not exist yet, made absolute through its (existing) parent.
fn resolved(p: &Path) -> Option<PathBuf> {
    let name = p.file_name()?;
    Some(std::fs::canonicalize(folder_of(p)).ok()?.join(name))
}

/// The folder a path's file lives in (`.` for a bare file name).
fn folder_of(p: &Path) -> &Path {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}
