//! The functions the fuzz targets call, shared with the corpus replay test
//! (`tests/fuzz_corpus_replay.rs` includes this file with `#[path]`), so that CI replays
//! every committed corpus and regression input through exactly what was fuzzed.
//!
//! Each function takes arbitrary bytes and must return (with an `Ok` or an `Err`, both
//! fine) without panicking, aborting, hanging or allocating without bound.

#![allow(dead_code)]

use std::cell::RefCell;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The fuzz targets, by name (the names of `fuzz_targets/*.rs` and of the corpus folders).
pub const TARGETS: &[&str] = &[
    "asset_reader",
    "gltf_import",
    "obj_import",
    "combine_expr",
    "scene_ron",
];

/// Runs `data` through the target `name`.
pub fn run(name: &str, data: &[u8]) {
    match name {
        "asset_reader" => asset_reader(data),
        "gltf_import" => gltf_import(data),
        "obj_import" => obj_import(data),
        "combine_expr" => combine_expr(data),
        "scene_ron" => scene_ron(data),
        other => panic!("unknown fuzz target {other}"),
    }
}

/// The asset reader: the untyped container, both typed decoders and `inspect`.
pub fn asset_reader(data: &[u8]) {
    if let Ok(c) = billow_format::from_bytes(data) {
        let _ = billow_format::VolumeAsset::from_container(c.clone());
        let _ = billow_format::CloudAsset::from_container(c);
    }
    let _ = billow_format::VolumeAsset::from_bytes(data);
    let _ = billow_format::CloudAsset::from_bytes(data);
    let _ = billow_format::inspect_bytes(data);
}

thread_local! {
    /// This thread's scratch folder, once made.
    static SCRATCH: RefCell<Option<PathBuf>> = const { RefCell::new(None) };
}

/// A scratch folder for this thread (the importers read files): one per process and
/// thread, so parallel fuzz jobs and test threads do not share files.
fn scratch() -> PathBuf {
    SCRATCH.with(|d| {
        d.borrow_mut()
            .get_or_insert_with(|| {
                static NEXT: AtomicUsize = AtomicUsize::new(0);
                let n = NEXT.fetch_add(1, Ordering::Relaxed);
                let d =
                    std::env::temp_dir().join(format!("billow-fuzz-{}-{n}", std::process::id()));
                std::fs::create_dir_all(&d).expect("create the fuzz scratch folder");
                // A small buffer and a tiny PNG beside the input, for inputs that name them.
                let bin: Vec<u8> = (0..4096u32)
                    .map(|i| (i.wrapping_mul(2654435761) >> 24) as u8)
                    .collect();
                std::fs::write(d.join("buf.bin"), bin).expect("write buf.bin");
                std::fs::write(d.join("tex.png"), TINY_PNG).expect("write tex.png");
                d
            })
            .clone()
    })
}

/// Removes this thread's scratch folder, if it made one.
pub fn cleanup() {
    if let Some(d) = SCRATCH.with(|d| d.borrow_mut().take()) {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A 2×2 RGBA PNG.
const TINY_PNG: &[u8] = &[
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x06, 0x00, 0x00, 0x00, 0x72, 0xb6, 0x0d,
    0x24, 0x00, 0x00, 0x00, 0x16, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0, 0xf0,
    0x1f, 0x08, 0x19, 0x18, 0xfe, 0x03, 0x00, 0x11, 0x1f, 0x03, 0xfd, 0xd4, 0x6f, 0x0f, 0x1d, 0x00,
    0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
];

fn import_file(name: &str, data: &[u8]) {
    let path = scratch().join(name);
    std::fs::write(&path, data).expect("write the fuzz input");
    for strict in [false, true] {
        let _ = billow::import::import(&path, &billow::import::ImportOptions { strict });
    }
}

/// glTF import: the bytes as a `.glb` and as a `.gltf` (JSON).
pub fn gltf_import(data: &[u8]) {
    import_file("in.glb", data);
    import_file("in.gltf", data);
}

/// OBJ import: the bytes up to the first NUL are `in.obj`, the rest `in.mtl` (which the
/// OBJ names with `mtllib in.mtl`).
pub fn obj_import(data: &[u8]) {
    let (obj, mtl) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    std::fs::write(scratch().join("in.mtl"), mtl).expect("write in.mtl");
    import_file("in.obj", obj);
}

/// The combine expression parser, as the CLI calls it (`--combine expr:...`), and
/// evaluation of what parses.
pub fn combine_expr(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = text.parse::<billow::voxelize::CombineFn>();
    if let Ok(e) = billow::voxelize::Expr::parse(text) {
        let s = [glam::Vec4::new(0.5, 0.25, 0.0, 1.0); 6];
        let _ = e.eval(&s);
    }
}

/// The viewer's scene file: RON parse and validation.
pub fn scene_ron(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = billow_view::scene::SceneFile::parse(text);
}
