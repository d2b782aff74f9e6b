//! `billow info ASSET [--json]`: version, kind, header, chunks and checksum status.

use std::path::PathBuf;

use billow_format::{inspect_bytes, tag_str, AssetKind, Report, VolumeAsset};
use serde::Serialize;

use crate::exit::{CliError, Code};
use crate::output::print_json;
use crate::Ctx;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The .billow asset to describe.
    asset: PathBuf,
    /// Print a machine-readable JSON summary on stdout instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct ChunkJson {
    tag: String,
    elem: String,
    offset: u64,
    bytes: u64,
    crc32: String,
    crc_ok: bool,
}

#[derive(Serialize)]
struct InfoJson<'a> {
    file: String,
    format_version: String,
    kind: AssetKind,
    file_bytes: u64,
    checksums_ok: bool,
    header: Option<&'a billow_format::Header>,
    chunks: Vec<ChunkJson>,
}

pub fn run(args: Args, _ctx: &Ctx) -> Result<(), CliError> {
    let path = &args.asset;
    let shown = path.display();
    let bytes = billow_format::read_regular(path).map_err(|e| match &e {
        // Only I/O errors come from reading; the message names the file once.
        billow_format::FormatError::Io { source, .. } => {
            CliError::new(Code::from(&e), format!("{shown}: cannot read: {source}"))
        }
        _ => CliError::new(Code::from(&e), e),
    })?;
    let report = inspect_bytes(&bytes)
        .map_err(|e| CliError::new(Code::from(&e), format!("{shown}: {e}")))?;
    if args.json {
        print_json(&to_json(path, &report))?;
    } else {
        print_text(path, &report);
    }
    if let Some(bad) = report.chunks.iter().find(|c| !c.crc_ok) {
        return Err(CliError::new(
            Code::InvalidInput,
            format!(
                "{shown}: chunk '{}' at offset {}: checksum mismatch (stored {:08x}, computed {:08x})",
                tag_str(&bad.tag),
                bad.offset,
                bad.crc_stored,
                bad.crc_computed
            ),
        ));
    }
    if let Err(e) = &report.header {
        return Err(CliError::new(
            Code::InvalidInput,
            format!("{shown}: header: {e}"),
        ));
    }
    // The structure is sound; also decode the typed payload so `info` vouches for all of it.
    if report.kind == AssetKind::Volume {
        VolumeAsset::from_bytes(&bytes)
            .map_err(|e| CliError::new(Code::from(&e), format!("{shown}: {e}")))?;
    }
    Ok(())
}

fn to_json<'a>(path: &std::path::Path, r: &'a Report) -> InfoJson<'a> {
    InfoJson {
        file: path.display().to_string(),
        format_version: format!("{}.{}", r.major, r.minor),
        kind: r.kind,
        file_bytes: r.file_len,
        checksums_ok: r.chunks.iter().all(|c| c.crc_ok),
        header: r.header.as_ref().ok(),
        chunks: r
            .chunks
            .iter()
            .map(|c| ChunkJson {
                tag: tag_str(&c.tag),
                elem: format!("{:?}", c.elem),
                offset: c.offset,
                bytes: c.len,
                crc32: format!("{:08x}", c.crc_stored),
                crc_ok: c.crc_ok,
            })
            .collect(),
    }
}

fn print_text(path: &std::path::Path, r: &Report) {
    outln!("file:     {}", path.display());
    outln!(
        "format:   billow {}.{} ({} bytes)",
        r.major,
        r.minor,
        r.file_len
    );
    outln!("kind:     {:?}", r.kind);
    outln!("header:");
    for line in r.header_ron.lines() {
        outln!("  {line}");
    }
    outln!("chunks:");
    outln!(
        "  {:<6} {:<6} {:>10} {:>12}  crc32",
        "tag",
        "type",
        "offset",
        "bytes"
    );
    for c in &r.chunks {
        outln!(
            "  {:<6} {:<6} {:>10} {:>12}  {:08x} {}",
            tag_str(&c.tag),
            format!("{:?}", c.elem),
            c.offset,
            c.len,
            c.crc_stored,
            if c.crc_ok { "ok" } else { "MISMATCH" }
        );
    }
}
