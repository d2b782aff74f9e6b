//! `billow info ASSET [--json]`: version, kind, header, chunks and checksum status.

use std::path::PathBuf;

use billow_core::gpu_memory::{cloud_gpu_bytes, volume_gpu_bytes, GpuBytes};
use billow_format::{
    inspect_bytes, tag_str, AssetKind, CloudAsset, NormalKind, Report, VolumeAsset,
};
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
    /// A volume's normal texels: `"mean"` (mean normals, `VNRM`), `"moments"` (normal
    /// moments, `VMOM`, format 1.4) or `null` (none, a cloud, or an undecodable header).
    normals: Option<&'static str>,
    chunks: Vec<ChunkJson>,
    /// Texture bytes `billow view` holds on a device that samples BC7 blocks, and on one
    /// that does not (`billow_core::gpu_memory`).
    /// `null` when the payload does not decode.
    gpu_bytes: Option<u64>,
    gpu_bytes_no_bc: Option<u64>,
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
    // The typed payload, decoded when the structure is sound (so `info` vouches for all of
    // it), and what a renderer holds for it.
    let sound = report.chunks.iter().all(|c| c.crc_ok) && report.header.is_ok();
    let decoded = sound.then(|| decode_gpu_bytes(&bytes, &report));
    let gpu = decoded.as_ref().and_then(|d| d.as_ref().ok()).copied();
    if args.json {
        print_json(&to_json(path, &report, gpu))?;
    } else {
        print_text(path, &report, gpu);
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
    if let Some(Err((code, e))) = decoded {
        return Err(CliError::new(code, format!("{shown}: {e}")));
    }
    Ok(())
}

/// Decodes the asset's payload and counts its GPU texture bytes (`Err`: the exit code and
/// the message of a payload that does not decode).
fn decode_gpu_bytes(bytes: &[u8], r: &Report) -> Result<GpuBytes, (Code, String)> {
    let compressed = r.header.as_ref().is_ok_and(|h| h.compress().is_some());
    match r.kind {
        AssetKind::Volume => VolumeAsset::from_bytes(bytes)
            .map(|a| volume_gpu_bytes(&a, compressed))
            .map_err(|e| (Code::from(&e), e.to_string())),
        AssetKind::Cloud => CloudAsset::from_bytes(bytes)
            .map(|a| cloud_gpu_bytes(&a, compressed))
            .map_err(|e| (Code::from(&e), e.to_string())),
    }
}

/// What a volume's normal texels are, by the header ([`InfoJson::normals`]).
fn normal_kind(r: &Report) -> Option<&'static str> {
    let v = r.header.as_ref().ok()?.volume?;
    v.normal_kind().map(|k| match k {
        NormalKind::Mean => "mean",
        NormalKind::Moments => "moments",
    })
}

fn to_json<'a>(path: &std::path::Path, r: &'a Report, gpu: Option<GpuBytes>) -> InfoJson<'a> {
    InfoJson {
        file: path.display().to_string(),
        format_version: format!("{}.{}", r.major, r.minor),
        kind: r.kind,
        file_bytes: r.file_len,
        checksums_ok: r.chunks.iter().all(|c| c.crc_ok),
        header: r.header.as_ref().ok(),
        normals: normal_kind(r),
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
        gpu_bytes: gpu.map(|g| g.with_bc),
        gpu_bytes_no_bc: gpu.map(|g| g.without_bc),
    }
}

fn print_text(path: &std::path::Path, r: &Report, gpu: Option<GpuBytes>) {
    outln!("file:     {}", path.display());
    outln!(
        "format:   billow {}.{} ({} bytes)",
        r.major,
        r.minor,
        r.file_len
    );
    outln!("kind:     {:?}", r.kind);
    if r.header.as_ref().is_ok_and(|h| h.volume.is_some()) {
        outln!("normals:  {}", normal_kind(r).unwrap_or("none"));
    }
    if let Some(g) = gpu {
        outln!(
            "gpu:      {}",
            crate::output::gpu_line(g.with_bc, g.without_bc)
        );
    }
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
