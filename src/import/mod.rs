//! Mesh import: glTF 2.0 (`.gltf`/`.glb`) and OBJ+MTL into one in-memory [`Scene`] and
//! the [`ImportReport`] beside it ([`Imported`]).
//!
//! Every importer validates its input before trusting it (lengths against buffer sizes,
//! index ranges, finite positions) and reports a non-fatal problem — a missing texture,
//! a skipped point/line primitive, a missing MTL — as a [`Warning`] in
//! [`ImportReport::warnings`]. With [`ImportOptions::strict`] the first warning becomes an
//! error.
//!
//! Library code never prints: all problems come back as [`ImportError`] or [`Warning`].

mod accessor;
mod gltf;
mod images;
mod mtl;
mod obj;
mod report;
mod text;

pub use report::{ImportReport, TextureReport, Warning};

use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use glam::Vec3;

use crate::scene::{Scene, SceneBuilder};

/// Upper bound on the number of triangles one import may produce. A hostile file can
/// instance one mesh many times; this keeps that from exhausting memory (each triangle
/// costs ~150 bytes, so the cap is ~10 GB).
pub const MAX_TRIANGLES: usize = 64 << 20;

/// Largest file billow reads as an input (a mesh, an MTL library, a glTF buffer or image,
/// an asset): 4 GiB. Checked on the file's size before reading and enforced while reading.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Opens `path` for reading after checking that it is a regular file (not a FIFO, a
/// device such as `/dev/zero`, a socket or a folder; checked before opening, which would
/// block on a FIFO) of at most [`MAX_INPUT_BYTES`]. Returns the file and its size.
/// Errors are `InvalidInput` (not a regular file) or `FileTooLarge`, with a message.
pub fn open_input(path: &Path) -> std::io::Result<(std::fs::File, u64)> {
    use std::io::{Error, ErrorKind};
    let not_regular = || {
        Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a device, FIFO, socket or folder); billow reads regular files only",
        )
    };
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_large(meta.len()));
    }
    Ok((file, meta.len()))
}

fn too_large(bytes: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::FileTooLarge,
        format!(
            "{bytes} bytes or more, over billow's input limit of {MAX_INPUT_BYTES} bytes (4 GiB)"
        ),
    )
}

/// Reads a whole input file through [`open_input`]'s checks, with a reader bounded by
/// [`MAX_INPUT_BYTES`] (a file that grows while read is cut off with an error, not read
/// without end).
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let (file, len) = open_input(path)?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(MAX_INPUT_BYTES + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImportOptions {
    /// Treat every warning as an error ([`ImportError::Strict`]).
    pub strict: bool,
}

/// What went wrong, coarsely, so that a binary can map it to an exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImportErrorKind {
    /// The file (or a file it references, such as a `.bin` buffer) could not be read.
    Io,
    /// The file is not well-formed (bad JSON, bad GLB container, unparsable OBJ).
    Parse,
    /// Well-formed, but uses something billow does not implement (a required extension,
    /// an unknown file extension).
    Unsupported,
    /// Well-formed but inconsistent or hostile (out-of-range indices, lengths beyond the
    /// buffer, NaN/Inf positions, node cycles).
    Invalid,
    /// A warning raised to an error by [`ImportOptions::strict`].
    Strict,
}

/// An import failure. `Display` is one line: `<file>: <problem>`.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: parse error: {message}")]
    Parse { file: String, message: String },
    #[error("{file}: unsupported: {message}")]
    Unsupported { file: String, message: String },
    #[error("{file}: invalid: {message}")]
    Invalid { file: String, message: String },
    #[error("{file}: warning treated as error (strict): {}", warning.message)]
    Strict { file: String, warning: Warning },
}

impl ImportError {
    pub fn kind(&self) -> ImportErrorKind {
        match self {
            ImportError::Io { .. } => ImportErrorKind::Io,
            ImportError::Parse { .. } => ImportErrorKind::Parse,
            ImportError::Unsupported { .. } => ImportErrorKind::Unsupported,
            ImportError::Invalid { .. } => ImportErrorKind::Invalid,
            ImportError::Strict { .. } => ImportErrorKind::Strict,
        }
    }

    /// The file the error is about (as given, or the referenced file for Io errors).
    pub fn file(&self) -> &str {
        match self {
            ImportError::Io { file, .. }
            | ImportError::Parse { file, .. }
            | ImportError::Unsupported { file, .. }
            | ImportError::Invalid { file, .. }
            | ImportError::Strict { file, .. } => file,
        }
    }
}

/// What an import returns: the geometry, and what the import noticed on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    pub scene: Scene,
    pub report: ImportReport,
}

/// Imports `path` into a [`Scene`] and its [`ImportReport`], dispatching on the
/// (case-insensitive) extension: `.gltf`, `.glb`, `.obj`.
pub fn import(path: &Path, opts: &ImportOptions) -> Result<Imported, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let file = path.display().to_string();
    let mut ctx = Ctx {
        file,
        opts: *opts,
        warnings: Vec::new(),
        seen: HashSet::new(),
        textures: Vec::new(),
        files: Mutex::new(Vec::new()),
        missing: Mutex::new(Vec::new()),
    };
    // A folder, a device or a FIFO is "not a regular file" (exit 3), whatever its name.
    if let Err(e) = open_input(path) {
        return Err(ctx.io(path, e));
    }
    let builder = match ext.as_str() {
        "gltf" | "glb" => gltf::load(path, &mut ctx)?,
        "obj" => obj::load(path, &mut ctx)?,
        "billow" => {
            return Err(ctx.unsupported(
                "this is a baked billow asset, not a mesh (expected .gltf, .glb or .obj; \
                 `billow info` describes an asset, `billow view` shows it)",
            ))
        }
        _ => {
            return Err(ctx.unsupported(format!(
                "unknown mesh file extension {:?} (expected .gltf, .glb or .obj)",
                ext
            )))
        }
    };
    let report = ImportReport {
        warnings: ctx.warnings,
        textures: ctx.textures,
        dropped_triangles: builder.dropped(),
        files: ctx.files.into_inner().unwrap_or_else(|e| e.into_inner()),
        missing: ctx.missing.into_inner().unwrap_or_else(|e| e.into_inner()),
    };
    Ok(Imported {
        scene: builder.finish(),
        report,
    })
}

/// Per-import context: the file name for messages, options and collected warnings.
pub(crate) struct Ctx {
    pub file: String,
    pub opts: ImportOptions,
    pub warnings: Vec<Warning>,
    seen: HashSet<String>,
    /// Every texture referenced ([`ImportReport::textures`]).
    textures: Vec<TextureReport>,
    /// The files read besides the mesh file ([`ImportReport::files`]).
    files: Mutex<Vec<PathBuf>>,
    /// The files looked for and not read ([`ImportReport::missing`]).
    missing: Mutex<Vec<PathBuf>>,
}

impl Ctx {
    /// Notes that texture `name` was referenced and whether it loaded (the first
    /// reference of a name is the one reported).
    pub fn texture(&mut self, name: &str, found: bool) {
        if !self.textures.iter().any(|t| t.name == name) {
            self.textures.push(TextureReport {
                name: name.to_owned(),
                found,
            });
        }
    }
    /// Notes that `path` was read (once per path), whatever its bytes then turn out to be.
    pub fn read_from(&self, path: &Path) {
        let mut files = self.files.lock().unwrap_or_else(|e| e.into_inner());
        if !files.iter().any(|f| f == path) {
            files.push(path.to_path_buf());
        }
    }
    /// Notes that `path` was looked for and could not be read (once per path).
    pub fn not_read(&self, path: &Path) {
        let mut missing = self.missing.lock().unwrap_or_else(|e| e.into_inner());
        if !missing.iter().any(|f| f == path) {
            missing.push(path.to_path_buf());
        }
    }
    /// Reads a file the mesh refers to through [`read_input`], noting it in
    /// [`ImportReport::files`] when read and in [`ImportReport::missing`] when not.
    pub fn read_referenced(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let r = read_input(path);
        match &r {
            Ok(_) => self.read_from(path),
            Err(_) => self.not_read(path),
        }
        r
    }
    /// Records a warning (identical messages once, e.g. for an instanced mesh), or
    /// fails with [`ImportError::Strict`] in strict mode.
    pub fn warn(&mut self, message: impl fmt::Display) -> Result<(), ImportError> {
        let warning = Warning {
            message: one_line(message),
        };
        if self.opts.strict {
            return Err(ImportError::Strict {
                file: self.file.clone(),
                warning,
            });
        }
        if self.seen.insert(warning.message.clone()) {
            self.warnings.push(warning);
        }
        Ok(())
    }
    pub fn parse(&self, message: impl fmt::Display) -> ImportError {
        ImportError::Parse {
            file: self.file.clone(),
            message: one_line(message),
        }
    }
    pub fn unsupported(&self, message: impl fmt::Display) -> ImportError {
        ImportError::Unsupported {
            file: self.file.clone(),
            message: one_line(message),
        }
    }
    pub fn invalid(&self, message: impl fmt::Display) -> ImportError {
        ImportError::Invalid {
            file: self.file.clone(),
            message: one_line(message),
        }
    }
    pub fn io(&self, path: &Path, source: std::io::Error) -> ImportError {
        let file = if path.display().to_string() == self.file {
            self.file.clone()
        } else {
            format!("{} (referenced by {})", path.display(), self.file)
        };
        ImportError::Io { file, source }
    }
}

/// Collapses any line breaks so that every message stays on one line.
fn one_line(message: impl fmt::Display) -> String {
    let s = message.to_string();
    if s.contains(['\n', '\r']) {
        s.split(['\n', '\r'])
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join("; ")
    } else {
        s
    }
}

/// Reserves room for `n` more triangles in `b`, or fails when the import would then hold
/// more than [`MAX_TRIANGLES`] (kept and dropped alike).
pub(crate) fn reserve(b: &mut SceneBuilder, n: usize, ctx: &Ctx) -> Result<(), ImportError> {
    if b.offered().saturating_add(n) > MAX_TRIANGLES {
        return Err(ctx.invalid(format!(
            "more than {MAX_TRIANGLES} triangles after instancing; refusing to expand"
        )));
    }
    b.reserve(n);
    Ok(())
}

/// Unit normal of the counter-clockwise triangle (a, b, c), or +Z when degenerate.
pub(crate) fn face_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z)
}

/// Decodes `%XX` escapes in a URI path (invalid escapes are kept verbatim).
pub(crate) fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = |b: u8| (b as char).to_digit(16);
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Resolves a relative reference (URI or MTL path) against `base_dir`:
/// backslashes become slashes; absolute paths are kept.
pub(crate) fn resolve_relative(base_dir: &Path, reference: &str) -> PathBuf {
    let normalized = reference.replace('\\', "/");
    let p = Path::new(&normalized);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base_dir.join(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.png"), "a b.png");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%4"), "%4");
        assert_eq!(percent_decode("%zz%41"), "%zzA");
    }

    #[test]
    fn one_line_messages() {
        assert_eq!(one_line("a\nb\r\n c"), "a; b; c");
    }
}
