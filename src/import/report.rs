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
    /// MTL libraries, OBJ textures), in first-read order, each once, as the import resolved
    /// them (relative to the mesh's folder as given). A file is listed once its bytes were
    /// read, whether or not they then decoded or parsed (an MTL library with a bad line, an
    /// image that is not one), since changing it changes the import. Callers that write
    /// files use it never to write over an input; depfiles and the source hash list it.
    pub files: Vec<PathBuf>,
    /// The files the import looked for besides the mesh file and could not read (not
    /// found, permission denied, not a regular file, over the size limit): a missing
    /// texture, MTL library or glTF image, resolved as in [`ImportReport::files`], in the
    /// order first looked for, each once. Each also has a warning. Its appearing would
    /// change the import, so a depfile lists it too. (A glTF buffer that cannot be read
    /// fails the import instead.)
    pub missing: Vec<PathBuf>,
}

impl ImportReport {
    /// Nothing to report: no warnings, no textures, nothing dropped, no other file read or
    /// looked for.
    pub fn is_empty(&self) -> bool {
        self.warnings.is_empty()
            && self.textures.is_empty()
            && self.dropped_triangles == 0
            && self.files.is_empty()
            && self.missing.is_empty()
    }

    /// The warning messages, in order.
    pub fn messages(&self) -> Vec<String> {
        self.warnings.iter().map(|w| w.message.clone()).collect()
    }
}
