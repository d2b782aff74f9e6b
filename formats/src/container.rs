//! The binary container: preamble, chunks, END. See `SPEC.md` for every byte.

use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

use crate::error::tag_str;
use crate::{
    AssetKind, FormatError, Header, FORMAT_MAJOR, FORMAT_MINOR, FORMAT_MINOR_BASE, MAGIC,
    PREAMBLE_LEN,
};

/// Size of a chunk header in bytes.
pub const CHUNK_HEADER_LEN: usize = 24;
/// Tag of the RON header chunk (always first).
pub const TAG_HEAD: [u8; 4] = *b"HEAD";
/// Tag of the terminating chunk (always last, empty).
pub const TAG_END: [u8; 4] = *b"END ";

/// Element type of a chunk payload. The payload length must be a multiple of
/// [`ElemType::size`]. The table is closed for major version 1; data of any
/// other kind goes in an `Opaque` chunk.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ElemType {
    /// Untyped bytes (also UTF-8 text).
    Opaque,
    U8,
    U16,
    U32,
    F32,
    F16,
    U64,
    F64,
    I8,
    I16,
    I32,
    I64,
}

impl ElemType {
    const ALL: [ElemType; 12] = [
        ElemType::Opaque,
        ElemType::U8,
        ElemType::U16,
        ElemType::U32,
        ElemType::F32,
        ElemType::F16,
        ElemType::U64,
        ElemType::F64,
        ElemType::I8,
        ElemType::I16,
        ElemType::I32,
        ElemType::I64,
    ];

    /// The `u32` stored in the chunk header.
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// Inverse of [`ElemType::code`].
    pub fn from_code(code: u32) -> Option<ElemType> {
        Self::ALL.get(usize::try_from(code).ok()?).copied()
    }

    /// Size of one element in bytes.
    pub const fn size(self) -> u64 {
        match self {
            ElemType::Opaque | ElemType::U8 | ElemType::I8 => 1,
            ElemType::U16 | ElemType::F16 | ElemType::I16 => 2,
            ElemType::U32 | ElemType::F32 | ElemType::I32 => 4,
            ElemType::U64 | ElemType::F64 | ElemType::I64 => 8,
        }
    }
}

/// One binary chunk (not HEAD or END).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub tag: [u8; 4],
    pub elem: ElemType,
    pub data: Vec<u8>,
}

/// A decoded asset file: the header plus every chunk between HEAD and END,
/// in file order, unknown tags included.
#[derive(Clone, Debug, PartialEq)]
pub struct Container {
    pub header: Header,
    pub chunks: Vec<Chunk>,
}

/// A tag is four printable ASCII bytes (0x20..=0x7E), not starting with a space.
pub fn valid_tag(tag: &[u8; 4]) -> bool {
    tag[0] != b' ' && tag.iter().all(|b| (0x20..=0x7e).contains(b))
}

/// CRC-32/ISO-HDLC (the zlib/PNG CRC) of the concatenation of `parts`.
fn crc(parts: &[&[u8]]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for p in parts {
        h.update(p);
    }
    h.finalize()
}

fn pad8(n: usize) -> usize {
    (8 - n % 8) % 8
}

/// A chunk's header (with its CRC over header and payload).
fn chunk_head(tag: [u8; 4], elem: ElemType, data: &[u8]) -> [u8; CHUNK_HEADER_LEN] {
    let mut head = [0u8; CHUNK_HEADER_LEN];
    head[0..4].copy_from_slice(&tag);
    head[4..8].copy_from_slice(&elem.code().to_le_bytes());
    head[8..16].copy_from_slice(&(data.len() as u64).to_le_bytes());
    // head[16..20]: reserved, zero.
    let c = crc(&[&head[..20], data]);
    head[20..24].copy_from_slice(&c.to_le_bytes());
    head
}

fn push_chunk(out: &mut Vec<u8>, tag: [u8; 4], elem: ElemType, data: &[u8]) {
    out.extend_from_slice(&chunk_head(tag, elem, data));
    out.extend_from_slice(data);
    out.resize(out.len() + pad8(data.len()), 0);
}

/// Encode a container. Deterministic: the same container always gives the same bytes.
pub fn to_bytes(c: &Container) -> Result<Vec<u8>, FormatError> {
    let refs: Vec<ChunkRef<'_>> = c
        .chunks
        .iter()
        .map(|ch| ChunkRef {
            tag: ch.tag,
            elem: ch.elem,
            data: &ch.data,
        })
        .collect();
    encode(&c.header, &refs)
}

/// A chunk to encode, borrowing its payload.
pub(crate) struct ChunkRef<'a> {
    pub tag: [u8; 4],
    pub elem: ElemType,
    pub data: &'a [u8],
}

/// Encode header + chunks without copying the payloads first (minor version 0).
pub(crate) fn encode(header: &Header, chunks: &[ChunkRef<'_>]) -> Result<Vec<u8>, FormatError> {
    encode_with_minor(header, chunks, FORMAT_MINOR_BASE)
}

/// [`encode`] writing minor version `minor` in the preamble (SPEC §5: the lowest minor
/// whose features the file uses).
pub(crate) fn encode_with_minor(
    header: &Header,
    chunks: &[ChunkRef<'_>],
    minor: u16,
) -> Result<Vec<u8>, FormatError> {
    let gaps = frame(header, chunks, minor)?;
    Ok(parts(&gaps, chunks).concat())
}

/// [`encode_with_minor`] as the list of slices whose concatenation is the file (the
/// payloads borrowed from where they are), handed to `f`: for writers that stream a file.
pub(crate) fn with_parts_minor<R>(
    header: &Header,
    chunks: &[ChunkRef<'_>],
    minor: u16,
    f: impl FnOnce(&[&[u8]]) -> R,
) -> Result<R, FormatError> {
    let gaps = frame(header, chunks, minor)?;
    Ok(f(&parts(&gaps, chunks)))
}

/// [`encode_with_minor`] written straight to `path` with [`write_atomic_parts`]: the same
/// bytes, without assembling the file in memory first (the payloads are written from
/// where they are).
pub(crate) fn write_with_minor(
    path: &Path,
    header: &Header,
    chunks: &[ChunkRef<'_>],
    minor: u16,
) -> Result<(), FormatError> {
    let gaps = frame(header, chunks, minor)?;
    write_atomic_parts(path, &parts(&gaps, chunks))
}

/// The bytes between the payloads of the file that holds `chunks` (validated first):
/// gap 0 is the preamble, HEAD and the first chunk's header; gap i the padding of payload
/// i - 1 and chunk i's header; the last gap the last padding and END.
fn frame(
    header: &Header,
    chunks: &[ChunkRef<'_>],
    minor: u16,
) -> Result<Vec<Vec<u8>>, FormatError> {
    let ron = check_chunks(header, chunks)?;
    let mut gaps: Vec<Vec<u8>> = Vec::with_capacity(chunks.len() + 1);
    let mut first = vec![0u8; PREAMBLE_LEN];
    push_chunk(&mut first, TAG_HEAD, ElemType::Opaque, ron.as_bytes());
    gaps.push(first);
    for ch in chunks {
        let gap = gaps.last_mut().expect("gap 0");
        gap.extend_from_slice(&chunk_head(ch.tag, ch.elem, ch.data));
        gaps.push(vec![0u8; pad8(ch.data.len())]);
    }
    push_chunk(
        gaps.last_mut().expect("gap 0"),
        TAG_END,
        ElemType::Opaque,
        &[],
    );
    let total = gaps.iter().map(|g| g.len()).sum::<usize>()
        + chunks.iter().map(|c| c.data.len()).sum::<usize>();
    write_preamble(
        &mut gaps[0],
        total as u64,
        FORMAT_MAJOR,
        minor.max(minor_for(chunks)),
        header.kind.code(),
    );
    Ok(gaps)
}

/// The file as a list of slices: gap 0, payload 0, gap 1, …, the last gap.
fn parts<'a>(gaps: &'a [Vec<u8>], chunks: &[ChunkRef<'a>]) -> Vec<&'a [u8]> {
    let mut parts: Vec<&[u8]> = Vec::with_capacity(2 * chunks.len() + 1);
    parts.push(&gaps[0]);
    for (ch, gap) in chunks.iter().zip(&gaps[1..]) {
        parts.push(ch.data);
        parts.push(gap);
    }
    parts
}

/// Validates the header and chunks; the header's RON.
fn check_chunks(header: &Header, chunks: &[ChunkRef<'_>]) -> Result<String, FormatError> {
    header.validate()?;
    let ron = header.to_ron()?;
    for (i, ch) in chunks.iter().enumerate() {
        let fail = |m: String| {
            Err(FormatError::Encode(format!(
                "chunk #{} '{}': {m}",
                i + 1,
                tag_str(&ch.tag)
            )))
        };
        if !valid_tag(&ch.tag) {
            return fail("tag must be 4 printable ASCII bytes, not starting with a space".into());
        }
        if ch.tag == TAG_HEAD || ch.tag == TAG_END {
            return fail("HEAD and END are written by the encoder".into());
        }
        if !(ch.data.len() as u64).is_multiple_of(ch.elem.size()) {
            return fail(format!(
                "{} bytes is not a multiple of the {:?} element size {}",
                ch.data.len(),
                ch.elem,
                ch.elem.size()
            ));
        }
    }
    Ok(ron)
}

/// Chunk tags introduced by each minor version after 1.0 (index 0: 1.1).
const TAGS_SINCE_MINOR: [&[&[u8; 4]]; FORMAT_MINOR as usize] = [
    &[b"ANRM", b"VBND", b"BLEV", b"BNRM", b"BCEL"],
    &[b"VLB7", b"VNB7", b"ATB7", b"ANB7", b"MTB7"],
    &[b"BLB7", b"BNB7"],
    &[b"VMOM", b"BMOM", b"VMB7", b"BMB7"],
];

/// The lowest minor version that defines every chunk tag in `chunks` (SPEC §5): files that
/// use nothing newer than 1.0 are written as 1.0, byte for byte as before.
fn minor_for(chunks: &[ChunkRef<'_>]) -> u16 {
    let mut minor = 0;
    for (i, tags) in TAGS_SINCE_MINOR.iter().enumerate() {
        if chunks.iter().any(|c| tags.contains(&&c.tag)) {
            minor = i as u16 + 1;
        }
    }
    minor
}

/// Fill in the 32-byte preamble at the start of `out` for a file of `len` bytes.
fn write_preamble(out: &mut [u8], len: u64, major: u16, minor: u16, kind: u32) {
    let p = &mut out[..PREAMBLE_LEN];
    p[0..8].copy_from_slice(&MAGIC);
    p[8..10].copy_from_slice(&major.to_le_bytes());
    p[10..12].copy_from_slice(&minor.to_le_bytes());
    p[12..16].copy_from_slice(&kind.to_le_bytes());
    p[16..24].copy_from_slice(&len.to_le_bytes());
    p[24..28].fill(0);
    let c = crc(&[&p[..28]]);
    p[28..32].copy_from_slice(&c.to_le_bytes());
}

fn u16_at(b: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([b[o], b[o + 1]])
}
fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes(b[o..o + 4].try_into().expect("4 bytes"))
}
fn u64_at(b: &[u8], o: usize) -> u64 {
    u64::from_le_bytes(b[o..o + 8].try_into().expect("8 bytes"))
}

/// A chunk located by the parser; `data` borrows from the file's bytes in memory, or was
/// read from the file ([`Source`]).
pub(crate) struct RawChunk<'a> {
    pub tag: [u8; 4],
    pub elem: ElemType,
    pub offset: u64,
    pub data: Cow<'a, [u8]>,
    pub crc_stored: u32,
    pub crc_computed: u32,
}

/// The structure of a file, as found by [`parse`].
pub(crate) struct Parsed<'a> {
    pub major: u16,
    pub minor: u16,
    pub kind: AssetKind,
    /// Every chunk in file order, HEAD first and END last.
    pub chunks: Vec<RawChunk<'a>>,
}

/// Where [`parse`] reads a file: its bytes in memory (borrowed), or an open file read a
/// piece at a time ([`FileSource`]: the payloads are read straight into the chunks'
/// buffers, so reading a file never holds it twice).
pub(crate) trait Source {
    /// The file's length in bytes.
    fn len(&self) -> usize;
    /// The `len` bytes at `off` (`off + len ≤ self.len()`, checked by the caller).
    fn get(&self, off: usize, len: usize) -> Result<Cow<'_, [u8]>, FormatError>;
}

impl Source for [u8] {
    fn len(&self) -> usize {
        <[u8]>::len(self)
    }
    fn get(&self, off: usize, len: usize) -> Result<Cow<'_, [u8]>, FormatError> {
        Ok(Cow::Borrowed(&self[off..off + len]))
    }
}

/// A regular file of a known length ([`open_regular`]), read with positioned reads.
pub(crate) struct FileSource<'p> {
    file: std::fs::File,
    len: usize,
    path: &'p Path,
}

impl Source for FileSource<'_> {
    fn len(&self) -> usize {
        self.len
    }
    fn get(&self, off: usize, len: usize) -> Result<Cow<'_, [u8]>, FormatError> {
        let mut buf = vec![0u8; len];
        read_exact_at(&self.file, &mut buf, off as u64).map_err(|source| FormatError::Io {
            path: self.path.to_path_buf(),
            source,
        })?;
        Ok(Cow::Owned(buf))
    }
}

#[cfg(unix)]
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], off: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, off)
}

#[cfg(not(unix))]
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], off: u64) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = file;
    f.seek(SeekFrom::Start(off))?;
    f.read_exact(buf)
}

/// Walk the file structure. With `strict`, a chunk checksum mismatch is an
/// error; otherwise it is only recorded (for `inspect_bytes`). Every length is
/// checked against the file size before it is used; nothing is allocated
/// except the chunk list, whose length is bounded by `bytes.len() / 24`, and, for a
/// file, the payloads read (each once its length is known to fit the file).
pub(crate) fn parse<S: Source + ?Sized>(src: &S, strict: bool) -> Result<Parsed<'_>, FormatError> {
    let n = src.len();
    let pre_bytes = src.get(0, n.min(PREAMBLE_LEN))?;
    let bytes: &[u8] = &pre_bytes;
    let magic_len = n.min(MAGIC.len());
    if bytes[..magic_len] != MAGIC[..magic_len] {
        return Err(FormatError::BadMagic {
            found: bytes[..magic_len].to_vec(),
        });
    }
    if n < 12 {
        return Err(FormatError::Truncated(format!(
            "file is {n} bytes, shorter than the {PREAMBLE_LEN}-byte preamble"
        )));
    }
    // Magic and version fields are frozen for all majors: check them first.
    let (major, minor) = (u16_at(bytes, 8), u16_at(bytes, 10));
    if major > FORMAT_MAJOR {
        return Err(FormatError::NewerMajor { major, minor });
    }
    if major < FORMAT_MAJOR {
        return Err(FormatError::OlderMajor { major, minor });
    }
    if n < PREAMBLE_LEN {
        return Err(FormatError::Truncated(format!(
            "file is {n} bytes, shorter than the {PREAMBLE_LEN}-byte preamble"
        )));
    }
    let pre = |m: String| Err(FormatError::Preamble(m));
    let (stored, computed) = (u32_at(bytes, 28), crc(&[&bytes[..28]]));
    if stored != computed {
        return pre(format!(
            "checksum mismatch (stored 0x{stored:08x}, computed 0x{computed:08x})"
        ));
    }
    let kind_code = u32_at(bytes, 12);
    let Some(kind) = AssetKind::from_code(kind_code) else {
        return pre(format!("unknown asset kind {kind_code}"));
    };
    let file_len = u64_at(bytes, 16);
    if u32_at(bytes, 24) != 0 {
        return pre(format!(
            "reserved field is 0x{:08x}, must be 0",
            u32_at(bytes, 24)
        ));
    }
    if (n as u64) < file_len {
        return Err(FormatError::Truncated(format!(
            "file is {n} bytes but the preamble says {file_len}"
        )));
    }
    if (n as u64) > file_len {
        return pre(format!(
            "file is {n} bytes but the preamble says {file_len} (trailing data)"
        ));
    }
    if !n.is_multiple_of(8) {
        return pre(format!("file length {n} is not a multiple of 8"));
    }

    let mut chunks = Vec::new();
    let mut off = PREAMBLE_LEN;
    loop {
        let index = chunks.len();
        if off == n {
            return Err(FormatError::Truncated(format!(
                "file ends at offset {n} without an END chunk"
            )));
        }
        if n - off < CHUNK_HEADER_LEN {
            return Err(FormatError::Truncated(format!(
                "chunk #{index} at offset {off}: only {} bytes left for its {CHUNK_HEADER_LEN}-byte header",
                n - off
            )));
        }
        let h_bytes = src.get(off, CHUNK_HEADER_LEN)?;
        let h: &[u8] = &h_bytes;
        let tag: [u8; 4] = h[0..4].try_into().expect("4 bytes");
        let at = off as u64;
        let err = move |problem: String| {
            Err(FormatError::Chunk {
                tag,
                index,
                offset: at,
                problem,
            })
        };
        let elem_code = u32_at(h, 4);
        let len = u64_at(h, 8);
        let crc_stored = u32_at(h, 20);
        let payload_at = off + CHUNK_HEADER_LEN;
        let room = (n - payload_at) as u64;
        if len > room {
            return err(format!(
                "payload length {len} exceeds the {room} bytes left in the file"
            ));
        }
        let len = len as usize; // <= room, so fits
        let end = payload_at + len + pad8(len);
        if end > n {
            return err(format!(
                "payload of {len} bytes plus {} padding runs past the end of the file ({n} bytes)",
                pad8(len)
            ));
        }
        let data = src.get(payload_at, len)?;
        let crc_computed = crc(&[&h[..20], &data]);
        if crc_stored != crc_computed && strict {
            return err(format!(
                "checksum mismatch (stored 0x{crc_stored:08x}, computed 0x{crc_computed:08x})"
            ));
        }
        if !valid_tag(&tag) {
            return err("tag is not 4 printable ASCII bytes".into());
        }
        let Some(elem) = ElemType::from_code(elem_code) else {
            return err(format!("unknown element type {elem_code}"));
        };
        if u32_at(h, 16) != 0 {
            return err(format!(
                "reserved field is 0x{:08x}, must be 0",
                u32_at(h, 16)
            ));
        }
        if !(len as u64).is_multiple_of(elem.size()) {
            return err(format!(
                "payload length {len} is not a multiple of the {elem:?} element size {}",
                elem.size()
            ));
        }
        if src
            .get(payload_at + len, end - payload_at - len)?
            .iter()
            .any(|&b| b != 0)
        {
            return err("padding bytes after the payload are not zero".into());
        }
        if (index == 0) != (tag == TAG_HEAD) {
            return err(if index == 0 {
                "the first chunk must be HEAD".into()
            } else {
                "HEAD may only appear once, as the first chunk".into()
            });
        }
        if (tag == TAG_HEAD || tag == TAG_END) && elem != ElemType::Opaque {
            return err(format!("element type must be Opaque (0), found {elem:?}"));
        }
        if tag == TAG_END && len != 0 {
            return err(format!("END must be empty, has {len} bytes"));
        }
        chunks.push(RawChunk {
            tag,
            elem,
            offset: off as u64,
            data,
            crc_stored,
            crc_computed,
        });
        off = end;
        if tag == TAG_END {
            if end != n {
                return err(format!("{} trailing bytes after the END chunk", n - end));
            }
            return Ok(Parsed {
                major,
                minor,
                kind,
                chunks,
            });
        }
    }
}

/// Parse the RON text of a HEAD chunk and check it against the preamble kind.
pub(crate) fn decode_header(raw: &RawChunk<'_>, kind: AssetKind) -> Result<Header, FormatError> {
    let text = std::str::from_utf8(&raw.data).map_err(|e| {
        FormatError::Header(format!("HEAD at offset {} is not UTF-8: {e}", raw.offset))
    })?;
    let header = Header::from_ron(text)?;
    if header.kind != kind {
        return Err(FormatError::Header(format!(
            "kind {:?} disagrees with the preamble kind {kind:?}",
            header.kind
        )));
    }
    header.validate()?;
    Ok(header)
}

/// Decode and fully validate a container (every checksum, every length).
/// Unknown chunks are kept in [`Container::chunks`]; skipping them is up to
/// the typed layer.
pub fn from_bytes(bytes: &[u8]) -> Result<Container, FormatError> {
    from_source(bytes)
}

/// [`from_bytes`] of a [`Source`]: a payload read from a file moves into its chunk.
fn from_source<S: Source + ?Sized>(src: &S) -> Result<Container, FormatError> {
    let parsed = parse(src, true)?;
    let mut raw = parsed.chunks.into_iter();
    let head = raw.next().expect("parse guarantees HEAD");
    let header = decode_header(&head, parsed.kind)?;
    let chunks = raw
        .filter(|r| r.tag != TAG_END)
        .map(|r| Chunk {
            tag: r.tag,
            elem: r.elem,
            data: r.data.into_owned(),
        })
        .collect();
    Ok(Container { header, chunks })
}

/// Write `bytes` to `path` atomically: a temporary file in the same directory
/// is written, fsynced and renamed over `path`. On error the temporary file is
/// removed and an existing `path` is untouched.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FormatError> {
    write_atomic_parts(path, &[bytes])
}

/// [`write_atomic`] of the concatenation of `parts`.
pub fn write_atomic_parts(path: &Path, parts: &[&[u8]]) -> Result<(), FormatError> {
    let io = |source: std::io::Error| FormatError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // `.<name>.<pid>-<random>.billow.tmp`: hidden, recognisable (matches `*.billow.tmp*`),
    // and naming the writing process, so that a later run can tell the temporary file of a
    // killed writer (whose process is gone) from one still being written.
    let name = path
        .file_name()
        .map_or_else(|| "asset".into(), |n| n.to_string_lossy().into_owned());
    let prefix = format!(".{name}.{}-", std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".billow.tmp");
    #[cfg(unix)]
    {
        // Like `File::create`: 0o666 minus the umask (NamedTempFile defaults to 0o600).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    if !dir.is_dir() {
        // Said plainly (the temporary file's own error would name its random path).
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("directory {} does not exist", dir.display()),
        )));
    }
    let mut tmp = builder.tempfile_in(dir).map_err(io)?;
    for p in parts {
        tmp.write_all(p).map_err(io)?;
    }
    tmp.as_file().sync_all().map_err(io)?;
    tmp.persist(path).map_err(|e| io(e.error))?;
    // Make the rename itself durable; best effort (not possible on every platform).
    #[cfg(unix)]
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Largest asset file the readers accept: 16 GiB (a 2048³ volume with its MIPs is
/// under 40 GiB only with normals; this bounds what a hostile path can make billow read).
pub const MAX_ASSET_BYTES: u64 = 16 << 30;

/// Reads a whole asset file after checking that it is a regular file (not a FIFO or a
/// device such as `/dev/zero`, checked before opening) of at most [`MAX_ASSET_BYTES`],
/// with a reader bounded by that limit. Errors are [`FormatError::Io`].
pub fn read_regular(path: &Path) -> Result<Vec<u8>, FormatError> {
    use std::io::Read;
    let (file, len) = open_regular(path)?;
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(MAX_ASSET_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| FormatError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    if bytes.len() as u64 > MAX_ASSET_BYTES {
        return Err(too_large(path, bytes.len() as u64));
    }
    Ok(bytes)
}

fn too_large(path: &Path, n: u64) -> FormatError {
    FormatError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("{n} bytes or more, over the asset size limit of {MAX_ASSET_BYTES} bytes"),
        ),
    }
}

/// The checks of [`read_regular`] (a regular file, checked before and after opening, of
/// at most [`MAX_ASSET_BYTES`]): the open file and its length.
fn open_regular(path: &Path) -> Result<(std::fs::File, u64), FormatError> {
    use std::io::{Error, ErrorKind};
    let io = |source: Error| FormatError::Io {
        path: path.to_path_buf(),
        source,
    };
    let not_regular = || {
        io(Error::new(
            ErrorKind::InvalidInput,
            "not a regular file (a device, FIFO, socket or folder); billow reads regular files only",
        ))
    };
    if !std::fs::metadata(path).map_err(io)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > MAX_ASSET_BYTES {
        return Err(too_large(path, meta.len()));
    }
    Ok((file, meta.len()))
}

/// Read and decode an asset file (the checks of [`read_regular`], then [`from_bytes`]'s).
/// Each chunk's payload is read straight into its buffer, so the peak is the file's size
/// once, not the file plus its decoded chunks. Errors carry the path: `"<path>:
/// <problem>"`.
pub fn read_file(path: &Path) -> Result<Container, FormatError> {
    let (file, len) = open_regular(path)?;
    let src = FileSource {
        file,
        len: len as usize,
        path,
    };
    from_source(&src).map_err(|e| e.in_file(path))
}
