//! What an import noticed besides the geometry: the [`ImportReport`] that comes back
//! beside the [`Scene`](crate::scene::Scene) in [`Imported`](super::Imported).

use std::path::PathBuf;

/// A non-fatal problem found during import. With `--strict` each becomes an error
/// ([`super::ImportError::Strict`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub message: String,
}

/// One texture the source referenced and whether it was loaded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureReport {
    pub name: String,
    pub found: bool,
}

/// The import's account of itself: everything `inspect` shows beside the geometry and
/// what the commands need to print warnings, hash the inputs and refuse to write over one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportReport {
    /// Non-fatal problems, each message once, in the order found.
    pub warnings: Vec<Warning>,
    /// Every texture the source referenced, found or not, in first-reference order.
    pub textures: Vec<TextureReport>,
    /// Zero-area (or non-finite-area) triangles dropped during import.
    pub dropped_triangles: usize,
    /// The files the import read besides the mesh file itself (glTF buffers and images,
    /// MTL libraries, OBJ textures), in first-read order. Callers that write files use it
    /// never to write over an input.
    pub files: Vec<PathBuf>,
}

impl ImportReport {
    /// Nothing to report: no warnings, no textures, nothing dropped, no other file read.
    pub fn is_empty(&self) -> bool {
        self.warnings.is_empty()
            && self.textures.is_empty()
            && self.dropped_triangles == 0
            && self.files.is_empty()
    }

    /// The warning messages, in order.
    pub fn messages(&self) -> Vec<String> {
        self.warnings.iter().map(|w| w.message.clone()).collect()
    }
}
