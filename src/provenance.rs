//! Where an asset came from: the input file's name, size and SHA-256, recorded in every
//! asset header so a pipeline can tell which source a bake belongs to. The hash covers every
//! file the import read: the mesh and, where there are any, the files beside it (glTF
//! buffers and images, MTL libraries, OBJ textures; [`with_companions`], formats/SPEC.md §6).

use std::io::Read;
use std::path::{Component, Path, PathBuf};

use billow_format::SourceInfo;
use sha2::{Digest, Sha256};

/// Hashes `path` (streaming; the file is only read). The name is the file name alone,
/// without folders, so the same input baked on two machines gives the same header.
pub fn source_info(path: &Path) -> std::io::Result<SourceInfo> {
    // A FIFO or a device (`/dev/zero`) is refused, and no more than the input limit is
    // hashed, so a hostile path cannot keep this thread reading forever.
    let (file, _) = crate::import::open_input(path)?;
    let mut file = file.take(crate::import::MAX_INPUT_BYTES);
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        bytes += n as u64;
    }
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().replace(['/', '\\'], "_"))
        .unwrap_or_default();
    Ok(SourceInfo {
        file_name,
        sha256: format!("{:x}", hasher.finalize()),
        bytes,
    })
}

/// The source of a mesh whose import also read `files` (its [`crate::import::ImportReport::files`]),
/// given `mesh`, the [`source_info`] of the mesh file itself. Without companion files this
/// is `mesh` unchanged. Otherwise `sha256` is the SHA-256 of a manifest with one line per
/// file, the mesh first, then the companions sorted by their path relative to the mesh's
/// folder (bytewise, `/` separators): `<sha256 hex> <bytes> <path>\n`, where the mesh's path
/// is its file name; `bytes` is the sum of all the files' sizes; `file_name` stays the
/// mesh's. So a changed buffer, texture or material library changes the recorded hash.
pub fn with_companions(
    mesh_path: &Path,
    mesh: SourceInfo,
    files: &[PathBuf],
) -> std::io::Result<SourceInfo> {
    if files.is_empty() {
        return Ok(mesh);
    }
    let folder = mesh_path.parent().unwrap_or(Path::new(""));
    let mut rows: Vec<(String, SourceInfo)> = Vec::with_capacity(files.len());
    for f in files {
        rows.push((relative(folder, f), source_info(f)?));
    }
    rows.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    let mut manifest = format!("{} {} {}\n", mesh.sha256, mesh.bytes, mesh.file_name);
    let mut bytes = mesh.bytes;
    for (path, info) in &rows {
        manifest.push_str(&format!("{} {} {path}\n", info.sha256, info.bytes));
        bytes += info.bytes;
    }
    Ok(SourceInfo {
        file_name: mesh.file_name,
        sha256: format!("{:x}", Sha256::digest(manifest.as_bytes())),
        bytes,
    })
}

/// `file`'s path relative to `folder`, `/`-separated (its file name alone when it is not
/// under `folder` by its spelling, e.g. an absolute URI).
fn relative(folder: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(folder).unwrap_or(file);
    if rel.is_absolute() {
        return file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
    }
    let parts: Vec<String> = rel
        .components()
        .filter(|c| !matches!(c, Component::CurDir))
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

/// [`source_info`] of `mesh_path` and [`with_companions`] of the files its import read.
pub fn source_info_all(mesh_path: &Path, files: &[PathBuf]) -> std::io::Result<SourceInfo> {
    with_companions(mesh_path, source_info(mesh_path)?, files)
}

/// "billow X.Y.Z", the tool string written into every header.
pub fn tool_version() -> String {
    format!("billow {}", env!("CARGO_PKG_VERSION"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_a_known_input() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("abc.obj");
        std::fs::write(&p, b"abc").unwrap();
        let s = source_info(&p).unwrap();
        assert_eq!(s.file_name, "abc.obj");
        assert_eq!(s.bytes, 3);
        assert_eq!(
            s.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn companions_change_the_hash() {
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("m.obj");
        std::fs::write(&m, b"abc").unwrap();
        std::fs::create_dir(dir.path().join("tex")).unwrap();
        let (a, b) = (dir.path().join("m.mtl"), dir.path().join("tex/b.png"));
        std::fs::write(&a, b"A").unwrap();
        std::fs::write(&b, b"BB").unwrap();
        let alone = source_info_all(&m, &[]).unwrap();
        assert_eq!(alone, source_info(&m).unwrap());
        let all = source_info_all(&m, &[b.clone(), a.clone()]).unwrap();
        // The order the files were read in does not matter.
        assert_eq!(all, source_info_all(&m, &[a.clone(), b.clone()]).unwrap());
        assert_eq!((all.file_name.as_str(), all.bytes), ("m.obj", 6));
        let hex = |d: &[u8]| format!("{:x}", Sha256::digest(d));
        let manifest = format!(
            "{} 3 m.obj\n{} 1 m.mtl\n{} 2 tex/b.png\n",
            hex(b"abc"),
            hex(b"A"),
            hex(b"BB")
        );
        assert_eq!(all.sha256, hex(manifest.as_bytes()));
        std::fs::write(&b, b"BC").unwrap();
        assert_ne!(source_info_all(&m, &[a, b]).unwrap().sha256, all.sha256);
    }
}
