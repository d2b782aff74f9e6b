//! A structural report of an asset file, for `billow info`.

use std::fmt;

use crate::container::{decode_header, parse};
use crate::error::tag_str;
use crate::{AssetKind, ElemType, FormatError, Header};

/// What `inspect_bytes` found in a file.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    pub major: u16,
    pub minor: u16,
    pub kind: AssetKind,
    /// Total file length in bytes.
    pub file_len: u64,
    /// The decoded header, or why it could not be decoded.
    pub header: Result<Header, String>,
    /// The raw RON text of the header (lossy UTF-8).
    pub header_ron: String,
    /// Every chunk in file order, HEAD and END included.
    pub chunks: Vec<ChunkInfo>,
}

/// One chunk of a [`Report`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkInfo {
    pub tag: [u8; 4],
    pub elem: ElemType,
    /// Byte offset of the chunk's 24-byte header.
    pub offset: u64,
    /// Payload length in bytes (without padding).
    pub len: u64,
    pub crc_stored: u32,
    pub crc_computed: u32,
    pub crc_ok: bool,
}

impl Report {
    /// True when every checksum matches and the header decodes: the file
    /// would also pass [`crate::from_bytes`].
    pub fn is_ok(&self) -> bool {
        self.header.is_ok() && self.chunks.iter().all(|c| c.crc_ok)
    }
}

/// Inspect a file's structure. Structural problems (bad magic, version,
/// lengths, truncation) are errors as in [`crate::from_bytes`]; a chunk
/// checksum mismatch or an undecodable header is reported, not fatal, so a
/// damaged file can still be looked at.
pub fn inspect_bytes(bytes: &[u8]) -> Result<Report, FormatError> {
    let parsed = parse(bytes, false)?;
    let head = &parsed.chunks[0];
    let header = if head.crc_stored == head.crc_computed {
        decode_header(head, parsed.kind).map_err(|e| e.to_string())
    } else {
        Err("HEAD checksum mismatch; header not decoded".to_string())
    };
    let chunks = parsed
        .chunks
        .iter()
        .map(|r| ChunkInfo {
            tag: r.tag,
            elem: r.elem,
            offset: r.offset,
            len: r.data.len() as u64,
            crc_stored: r.crc_stored,
            crc_computed: r.crc_computed,
            crc_ok: r.crc_stored == r.crc_computed,
        })
        .collect();
    Ok(Report {
        major: parsed.major,
        minor: parsed.minor,
        kind: parsed.kind,
        file_len: bytes.len() as u64,
        header,
        header_ron: String::from_utf8_lossy(&head.data).into_owned(),
        chunks,
    })
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "billow asset, format {}.{}, kind {:?}, {} bytes",
            self.major, self.minor, self.kind, self.file_len
        )?;
        if let Err(e) = &self.header {
            writeln!(f, "header: ERROR {e}")?;
        }
        writeln!(f, "header:")?;
        for line in self.header_ron.lines() {
            writeln!(f, "    {line}")?;
        }
        writeln!(f, "chunks:")?;
        writeln!(f, "    #    tag     type      offset        length  crc32")?;
        for (i, c) in self.chunks.iter().enumerate() {
            let status = if c.crc_ok {
                "ok".to_string()
            } else {
                format!("MISMATCH (computed 0x{:08x})", c.crc_computed)
            };
            writeln!(
                f,
                "    {i:<4} {:<7} {:<7} {:>10} {:>13}  0x{:08x} {status}",
                format!("'{}'", tag_str(&c.tag)),
                format!("{:?}", c.elem),
                c.offset,
                c.len,
                c.crc_stored
            )?;
        }
        Ok(())
    }
}
