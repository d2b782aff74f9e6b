//! The one error type of the format crate.
//!
//! Every message is a single line that says what is wrong and, for chunk
//! problems, where (tag, position in the file, byte offset).

use std::path::PathBuf;

use thiserror::Error;

use crate::{FORMAT_MAJOR, PREAMBLE_LEN};

/// Everything that can go wrong encoding, decoding, reading or writing an asset.
///
/// Not `#[non_exhaustive]`: the `billow` binary maps every variant to an exit code with an
/// exhaustive `match` (docs/cli.md), so a new variant must not compile until it has one.
#[derive(Debug, Error)]
pub enum FormatError {
    /// An operating-system error while reading or writing `path`.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A decoding error in the file at `path` (added by [`crate::read_file`]).
    #[error("{path}: {source}")]
    InFile {
        path: PathBuf,
        #[source]
        source: Box<FormatError>,
    },
    /// The first eight bytes are not the billow magic.
    #[error("not a billow asset: magic bytes are {}, expected {}", hex(found), hex(&crate::MAGIC))]
    BadMagic { found: Vec<u8> },
    /// The file is shorter than what its own structure says.
    #[error("truncated: {0}")]
    Truncated(String),
    /// The file has a major version newer than this reader.
    #[error(
        "format version {major}.{minor} is newer than this billow supports ({FORMAT_MAJOR}.x); upgrade billow"
    )]
    NewerMajor { major: u16, minor: u16 },
    /// The file has a major version older than this reader (there is none yet: 0 is invalid).
    #[error(
        "format version {major}.{minor} is not supported (this billow reads {FORMAT_MAJOR}.x)"
    )]
    OlderMajor { major: u16, minor: u16 },
    /// The fixed 32-byte preamble is inconsistent.
    #[error("preamble (bytes 0..{PREAMBLE_LEN}): {0}")]
    Preamble(String),
    /// A chunk is malformed. `index` is the chunk's position in the file
    /// (HEAD is #0), `offset` the byte offset of its 24-byte chunk header.
    #[error("chunk '{}' #{index} at offset {offset}: {problem}", tag_str(tag))]
    Chunk {
        tag: [u8; 4],
        index: usize,
        offset: u64,
        problem: String,
    },
    /// The RON header is not valid (syntax or content).
    #[error("header: {0}")]
    Header(String),
    /// A typed volume asset is inconsistent with its header or the format rules.
    #[error("volume asset: {0}")]
    Volume(String),
    /// A container handed to the writer breaks a format rule.
    #[error("cannot encode: {0}")]
    Encode(String),
}

impl FormatError {
    /// Wrap a decoding error with the path of the file it came from.
    pub(crate) fn in_file(self, path: &std::path::Path) -> FormatError {
        match self {
            e @ (FormatError::Io { .. } | FormatError::InFile { .. }) => e,
            e => FormatError::InFile {
                path: path.to_path_buf(),
                source: Box::new(e),
            },
        }
    }
}

/// `ABCD` for printable tags, otherwise `\xNN` escapes, so a corrupt tag still
/// prints on one line.
pub fn tag_str(tag: &[u8; 4]) -> String {
    tag.iter()
        .flat_map(|&b| std::ascii::escape_default(b))
        .map(char::from)
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
