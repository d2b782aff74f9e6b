//! Where an asset came from: the input file's name, size and SHA-256, recorded in every
//! asset header so a pipeline can tell which source a bake belongs to.

use std::io::Read;
use std::path::Path;

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
}
