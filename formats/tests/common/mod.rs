//! Test helpers, including an independent byte-level writer that follows
//! SPEC.md directly (not the crate's encoder), used to build files the crate
//! would never write: other versions, unknown chunks, hostile lengths.
#![allow(dead_code)]

use std::path::PathBuf;

pub const FIXTURE_NAME: &str = "v1_volume_3x2x1.billow";

pub fn fixture_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("fixtures")
        .join("format")
        .join(FIXTURE_NAME)
}

pub fn fixture_bytes() -> Vec<u8> {
    std::fs::read(fixture_path()).expect("frozen fixture present (fixtures/format/)")
}

pub fn crc(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// One chunk as SPEC.md lays it out: header, payload, zero padding to 8.
pub fn spec_chunk(tag: &[u8; 4], elem: u32, payload: &[u8]) -> Vec<u8> {
    spec_chunk_with_len(tag, elem, payload.len() as u64, payload)
}

/// Like `spec_chunk` but with an arbitrary (possibly lying) length field;
/// the CRC is computed over the fields as written, so only the length is wrong.
pub fn spec_chunk_with_len(tag: &[u8; 4], elem: u32, len: u64, payload: &[u8]) -> Vec<u8> {
    let mut c = Vec::new();
    c.extend_from_slice(tag);
    c.extend_from_slice(&elem.to_le_bytes());
    c.extend_from_slice(&len.to_le_bytes());
    c.extend_from_slice(&0u32.to_le_bytes());
    let mut covered = c.clone();
    covered.extend_from_slice(payload);
    c.extend_from_slice(&crc(&covered).to_le_bytes());
    c.extend_from_slice(payload);
    while c.len() % 8 != 0 {
        c.push(0);
    }
    c
}

/// A whole file: preamble (with the given version/kind, correct length and
/// CRC) followed by the given already-encoded chunks.
pub fn spec_file(major: u16, minor: u16, kind: u32, chunks: &[Vec<u8>]) -> Vec<u8> {
    let body: Vec<u8> = chunks.concat();
    let len = 32 + body.len() as u64;
    let mut f = Vec::new();
    f.extend_from_slice(b"\x89BLW\r\n\x1a\n");
    f.extend_from_slice(&major.to_le_bytes());
    f.extend_from_slice(&minor.to_le_bytes());
    f.extend_from_slice(&kind.to_le_bytes());
    f.extend_from_slice(&len.to_le_bytes());
    f.extend_from_slice(&0u32.to_le_bytes());
    let c = crc(&f);
    f.extend_from_slice(&c.to_le_bytes());
    f.extend_from_slice(&body);
    f
}

/// Rewrite the preamble's total-length field and CRC in place.
pub fn fix_preamble(f: &mut [u8]) {
    let len = f.len() as u64;
    f[16..24].copy_from_slice(&len.to_le_bytes());
    let c = crc(&f[..28]);
    f[28..32].copy_from_slice(&c.to_le_bytes());
}

/// Split a valid file into its chunks: (tag, elem, payload) in file order.
pub fn split_chunks(f: &[u8]) -> Vec<([u8; 4], u32, Vec<u8>)> {
    let mut out = Vec::new();
    let mut off = 32;
    while off < f.len() {
        let tag: [u8; 4] = f[off..off + 4].try_into().unwrap();
        let elem = u32::from_le_bytes(f[off + 4..off + 8].try_into().unwrap());
        let len = u64::from_le_bytes(f[off + 8..off + 16].try_into().unwrap()) as usize;
        out.push((tag, elem, f[off + 24..off + 24 + len].to_vec()));
        off += 24 + len.div_ceil(8) * 8;
    }
    out
}

/// Re-assemble chunks with the reference writer.
pub fn join_chunks(
    major: u16,
    minor: u16,
    kind: u32,
    chunks: &[([u8; 4], u32, Vec<u8>)],
) -> Vec<u8> {
    let enc: Vec<Vec<u8>> = chunks
        .iter()
        .map(|(t, e, p)| spec_chunk(t, *e, p))
        .collect();
    spec_file(major, minor, kind, &enc)
}
