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
    probe_writable(dir).map_err(|e| {
        unwritable(format!(
            "cannot create a file in directory {}: {e}",
            dir.display()
        ))
    })
}

/// Creates and removes a hidden file in `dir` (named like the staging temporaries, so a
/// kill in between leaves a file the next run sweeps): a read-only folder, a full disk's
/// quota or missing permissions are found before the work, not after it.
fn probe_writable(dir: &Path) -> std::io::Result<()> {
    crate::signals::watch(dir);
    let probe = dir.join(format!(
        ".{PROBE}.{}-{}.billow.tmp",
        std::process::id(),
        PROBES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The destination name a write probe's temporary stands for (`.probe.<pid>-<n>.billow.tmp`);
/// the staging of the next run that writes into the folder sweeps a dead run's probes.
pub const PROBE: &str = "probe";

static PROBES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Refuses, before any work, a folder output (`--slices DIR`, `--atlas DIR`, ...) whose
/// path is an existing file; a missing folder is created when the output is written.
pub fn refuse_file_as_folder(flag: &str, dir: &Path) -> Result<(), CliError> {
    let unwritable = |why: String| {
        CliError::new(
            Code::OutputIo,
            format!(
                "cannot write output: {flag} {}: {why} (nothing was written)",
                dir.display()
            ),
        )
    };
    if dir.exists() && !dir.is_dir() {
        return Err(unwritable("is a file, not a directory".into()));
    }
    // The folder, or the nearest existing one it would be created in, takes new files.
    let mut existing = dir;
    while !existing.is_dir() {
        existing = match existing.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
    }
    probe_writable(existing).map_err(|e| {
        unwritable(format!(
            "cannot create a file in directory {}: {e}",
            existing.display()
        ))
    })
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

/// The encodings an image output (`compare --diff`, `view --screenshot`) takes, chosen by
/// the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageOut {
    Png,
    /// Baseline JPEG, quality 92; alpha composited over black (a premultiplied image's
    /// colour as it is).
    Jpeg,
}

/// The encoding `flag`'s `path` asks for by its extension (`.png`, `.jpg`, `.jpeg`, any
/// case); anything else is a usage error (exit 2), found before any work.
pub fn image_out(flag: &str, path: &Path) -> Result<ImageOut, CliError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => Ok(ImageOut::Png),
        Some("jpg" | "jpeg") => Ok(ImageOut::Jpeg),
        other => Err(CliError::new(
            Code::Usage,
            format!(
                "{flag} {}: {}; name a .png or .jpg file",
                path.display(),
                match other {
                    Some(e) => format!("billow does not write .{e} images"),
                    None => "the file name has no extension".into(),
                }
            ),
        )),
    }
}

/// `png` (the bytes billow's image writers make) in the encoding `path` asks for.
pub fn encode_image(kind: ImageOut, png: Vec<u8>, path: &Path) -> Result<Vec<u8>, CliError> {
    match kind {
        ImageOut::Png => Ok(png),
        ImageOut::Jpeg => {
            let internal = |e: image::ImageError| {
                CliError::new(Code::Internal, format!("{}: {e}", path.display()))
            };
            let rgba = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
                .map_err(internal)?
                .to_rgba8();
            let rgb = image::RgbImage::from_fn(rgba.width(), rgba.height(), |x, y| {
                let p = rgba.get_pixel(x, y).0;
                let a = u32::from(p[3]);
                let over_black = |c: u8| ((u32::from(c) * a + 127) / 255) as u8;
                image::Rgb([over_black(p[0]), over_black(p[1]), over_black(p[2])])
            });
            let mut out = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 92)
                .encode_image(&rgb)
                .map_err(internal)?;
            Ok(out)
        }
    }
}

/// The summary's line on what a renderer holds on the GPU (`billow_core::gpu_memory`).
pub fn gpu_line(with_bc: u64, without_bc: u64) -> String {
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    if with_bc == without_bc {
        format!("GPU textures: {:.2} MiB", mib(without_bc))
    } else {
        format!(
            "GPU textures: {:.2} MiB where BC7 is sampled, {:.2} MiB decoded",
            mib(with_bc),
            mib(without_bc)
        )
    }
}
