//! Truncated, corrupt, hostile and versioned files.

mod common;

use billow_format::*;
use common::*;

fn err_of(bytes: &[u8]) -> String {
    match VolumeAsset::from_bytes(bytes) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_strict_prefix_is_rejected() {
    let f = fixture_bytes();
    for len in 0..f.len() {
        let e = from_bytes(&f[..len]).expect_err("prefix must fail");
        let msg = e.to_string();
        assert!(msg.starts_with("truncated"), "prefix {len}: {msg}");
        assert!(!msg.contains('\n'), "one-line message: {msg}");
        assert!(inspect_bytes(&f[..len]).is_err(), "inspect prefix {len}");
    }
    assert_eq!(
        from_bytes(&f[..812]).unwrap_err().to_string(),
        "truncated: file is 812 bytes but the preamble says 1112"
    );
}

#[test]
fn every_single_byte_flip_is_rejected() {
    let f = fixture_bytes();
    let mut g = f.clone();
    for i in 0..f.len() {
        for x in [0x01u8, 0x80, 0xff] {
            g[i] = f[i] ^ x;
            let r = from_bytes(&g);
            assert!(r.is_err(), "flip 0x{x:02x} at offset {i} accepted");
            assert!(!r.unwrap_err().to_string().contains('\n'));
            g[i] = f[i];
        }
    }
}

#[test]
fn messages_say_what_and_where() {
    let f = fixture_bytes();
    // Payload byte of the second VLEV chunk (header at 664, payload at 688).
    let mut g = f.clone();
    g[690] ^= 1;
    let msg = from_bytes(&g).unwrap_err().to_string();
    assert!(
        msg.starts_with("chunk 'VLEV' #2 at offset 664: checksum mismatch (stored 0x"),
        "{msg}"
    );
    // inspect reports it instead of failing.
    let r = inspect_bytes(&g).unwrap();
    assert!(!r.is_ok());
    assert_eq!(
        r.chunks.iter().map(|c| c.crc_ok).collect::<Vec<_>>(),
        [true, true, false, true, true, true, true]
    );
    // Flipped tag: not silently skipped as an unknown chunk.
    let mut g = f.clone();
    g[776] = b'D'; // CELL -> DELL
    assert!(err_of(&g).contains("checksum mismatch"));
    // Bad magic.
    let mut g = f.clone();
    g[1] = b'X';
    assert!(err_of(&g).starts_with("not a billow asset"));
    assert!(from_bytes(b"PK\x03\x04 a zip file").is_err());
    // Trailing bytes after END.
    let mut g = f.clone();
    g.extend_from_slice(&[0; 8]);
    assert!(err_of(&g).contains("trailing"), "{}", err_of(&g));
    fix_preamble(&mut g);
    assert!(
        err_of(&g).contains("8 trailing bytes after the END chunk"),
        "{}",
        err_of(&g)
    );
}

#[test]
fn newer_major_is_refused_by_name() {
    let f = fixture_bytes();
    let chunks = split_chunks(&f);
    let g = join_chunks(2, 0, 1, &chunks);
    let msg = err_of(&g);
    assert_eq!(
        msg,
        "format version 2.0 is newer than this billow supports (1.x); upgrade billow"
    );
    // Even a v2 file whose layout after the version field is unknown.
    let mut g2 = g[..12].to_vec();
    g2.extend_from_slice(&[0xee; 40]);
    assert!(err_of(&g2).contains("2.0 is newer"));
    // Major 0 is not a thing.
    assert!(err_of(&join_chunks(0, 9, 1, &chunks)).contains("0.9 is not supported"));
    // The read_file error carries the path.
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("future.billow");
    std::fs::write(&p, &g).unwrap();
    let msg = read_file(&p).unwrap_err().to_string();
    assert!(
        msg.starts_with(&format!("{}: format version 2.0", p.display())),
        "{msg}"
    );
}

#[test]
fn newer_minor_unknown_chunks_are_skipped() {
    let f = fixture_bytes();
    let want = VolumeAsset::from_bytes(&f).unwrap();
    let mut chunks = split_chunks(&f);
    // A 1.1 writer adds two chunks (odd length -> padding) and a header field.
    chunks.insert(3, (*b"XTRA", 0, b"hello from 1.1".to_vec()));
    chunks.insert(6, (*b"Ftr2", 3, vec![1, 0, 0, 0, 2, 0, 0, 0]));
    let head = String::from_utf8(chunks[0].2.clone()).unwrap();
    let head = head.replacen(
        "tool:",
        "future_field: Some((a: 1, b: [\"x\"])),\n    tool:",
        1,
    );
    chunks[0].2 = head.into_bytes();
    let g = join_chunks(1, 1, 1, &chunks);
    let got = VolumeAsset::from_bytes(&g).expect("1.1 file decodes");
    assert_eq!(got, want);
    let c = from_bytes(&g).unwrap();
    assert_eq!(c.chunks.len(), 7); // HEAD and END are not in `chunks`
    assert_eq!(c.chunks[2].tag, *b"XTRA");
    let r = inspect_bytes(&g).unwrap();
    assert_eq!(r.minor, 1);
    // The unknown chunk is still checksummed.
    let off = r.chunks.iter().find(|c| &c.tag == b"XTRA").unwrap().offset as usize;
    let mut h = g.clone();
    h[off + 24] ^= 0x20;
    let msg = err_of(&h);
    assert!(
        msg.starts_with(&format!("chunk 'XTRA' #3 at offset {off}: checksum")),
        "{msg}"
    );
}

#[test]
fn hostile_lengths_error_without_panic_or_allocation() {
    let f = fixture_bytes();
    let chunks = split_chunks(&f);
    for len in [
        u64::MAX,
        u64::MAX - 7,
        1 << 62,
        1 << 40,
        1_000_000,
        f.len() as u64,
    ] {
        // A chunk length that lies, with a CRC that matches the lie.
        let mut enc: Vec<Vec<u8>> = chunks
            .iter()
            .map(|(t, e, p)| spec_chunk(t, *e, p))
            .collect();
        enc[5] = spec_chunk_with_len(b"CELL", 4, len, &chunks[5].2);
        let g = spec_file(1, 0, 1, &enc);
        let msg = err_of(&g);
        assert!(
            msg.contains("exceeds") || msg.contains("runs past"),
            "{len}: {msg}"
        );
        // Preamble total length that lies.
        if len == f.len() as u64 {
            continue;
        }
        let mut g = f.clone();
        g[16..24].copy_from_slice(&len.to_le_bytes());
        let c = crc(&g[..28]);
        g[28..32].copy_from_slice(&c.to_le_bytes());
        assert!(from_bytes(&g).is_err());
    }
    // Lengths that fit the file but not the elem size / the volume.
    let mut bad = chunks.clone();
    bad[5].2.truncate(286); // F32 chunk of 286 bytes
    assert!(err_of(&join_chunks(1, 0, 1, &bad)).contains("not a multiple"));
    let mut bad = chunks.clone();
    bad[5].2.truncate(140);
    assert!(err_of(&join_chunks(1, 0, 1, &bad)).contains("144-byte prism"));
    let mut bad = chunks.clone();
    bad[1].2.push(0);
    assert!(err_of(&join_chunks(1, 0, 1, &bad)).contains("VLEV level 0 is 25 bytes, expected 24"));
}

#[test]
fn hostile_headers_are_rejected() {
    let f = fixture_bytes();
    let chunks = split_chunks(&f);
    let head = String::from_utf8(chunks[0].2.clone()).unwrap();
    let cases = [
        (
            "dims: (3, 2, 1)",
            "dims: (4294967295, 4294967295, 4294967295)",
            "dims",
        ),
        ("dims: (3, 2, 1)", "dims: (0, 2, 1)", "dims"),
        ("mip_count: 2", "mip_count: 3", "mip_count"),
        ("mip_count: 2", "mip_count: 0", "mip_count"),
        ("max: (1.5, 1.0, 0.5)", "max: (1.5, inf, 0.5)", "bounds"),
        ("max: (1.5, 1.0, 0.5)", "max: (1.5, NaN, 0.5)", "bounds"),
        ("kind: Volume", "kind: Cloud", "kind"),
        ("kind: Volume", "kind: Blob", "RON"),
        ("\"tiny.obj\"", "\"/home/me/tiny.obj\"", "file_name"),
        ("eaa8", "EAA8", "sha256"),
        ("Rgba8Snorm", "Rgba16Float", "RON"),
        ("volume: Some((", "volume: Some(((((((((((((((((((", "RON"),
    ];
    for (from, to, needle) in cases {
        let mut c = chunks.clone();
        c[0].2 = head.replacen(from, to, 1).into_bytes();
        let msg = err_of(&join_chunks(1, 0, 1, &c));
        assert!(msg.contains(needle), "{to}: {msg}");
    }
    // Not UTF-8.
    let mut c = chunks.clone();
    c[0].2[5] = 0xff;
    assert!(err_of(&join_chunks(1, 0, 1, &c)).contains("UTF-8"));
    // Deeply nested garbage does not overflow the stack.
    let mut c = chunks.clone();
    c[0].2 = "[".repeat(100_000).into_bytes();
    assert!(from_bytes(&join_chunks(1, 0, 1, &c)).is_err());
    // Preamble kind must agree with the header.
    assert!(err_of(&join_chunks(1, 0, 2, &chunks)).contains("disagrees"));
    assert!(err_of(&join_chunks(1, 0, 7, &chunks)).contains("unknown asset kind 7"));
}

#[test]
fn structural_rules() {
    let f = fixture_bytes();
    let chunks = split_chunks(&f);
    let check = |c: &[([u8; 4], u32, Vec<u8>)], needle: &str| {
        let msg = err_of(&join_chunks(1, 0, 1, c));
        assert!(msg.contains(needle), "{needle}: {msg}");
    };
    let mut c = chunks.clone();
    c.swap(0, 1);
    check(&c, "first chunk must be HEAD");
    let mut c = chunks.clone();
    c.insert(2, c[0].clone());
    check(&c, "HEAD may only appear once");
    let mut c = chunks.clone();
    c.pop();
    check(&c, "without an END chunk");
    let mut c = chunks.clone();
    c.insert(3, (*b"END ", 0, vec![]));
    check(&c, "trailing bytes after the END");
    let mut c = chunks.clone();
    c.last_mut().unwrap().2 = vec![0; 8];
    check(&c, "END must be empty");
    let mut c = chunks.clone();
    c[2].1 = 99;
    check(&c, "unknown element type 99");
    let mut c = chunks.clone();
    c[2].1 = 8;
    check(&c, "expected U8");
    let mut c = chunks.clone();
    c[2].0 = *b"V\0EV";
    check(&c, "printable");
    let mut c = chunks.clone();
    c.remove(4);
    check(&c, "1 VNRM levels but mip_count is 2");
    let mut c = chunks.clone();
    c.remove(5);
    check(&c, "missing CELL");
    let mut c = chunks.clone();
    c.insert(5, c[5].clone());
    check(&c, "more than one CELL");
    // Non-zero padding, with every CRC correct.
    let mut g = f.clone();
    g[692] = 1; // padding after the 4-byte VLEV #2 payload (payload at 688..692)
    assert!(err_of(&g).contains("padding bytes after the payload are not zero"));
    // Non-finite prism coordinate.
    let mut c = chunks.clone();
    c[5].2[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    check(&c, "non-finite");
}

/// Reading a file streams it ([`read_file`]: payloads read straight into their chunks,
/// so the file is never held twice); it decides exactly as [`from_bytes`] on the file's
/// bytes, with the same message after the path: every strict prefix, every byte flipped,
/// and the intact file (the same container).
#[test]
fn reading_a_file_decides_as_decoding_its_bytes() {
    let f = fixture_bytes();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.billow");
    let check = |bytes: &[u8], what: &str| {
        std::fs::write(&path, bytes).unwrap();
        let (file, mem) = (read_file(&path), from_bytes(bytes));
        match (file, mem) {
            (Ok(a), Ok(b)) => assert!(a == b, "{what}: different containers"),
            (Err(a), Err(b)) => {
                let want = format!("{}: {b}", path.display());
                assert_eq!(a.to_string(), want, "{what}");
            }
            (a, b) => panic!("{what}: file {:?}, bytes {:?}", a.is_ok(), b.is_ok()),
        }
        let typed = VolumeAsset::read(&path).map_err(|e| e.to_string());
        let want = VolumeAsset::from_bytes(bytes).map_err(|e| format!("{}: {e}", path.display()));
        assert!(typed == want, "{what}: {typed:?} against {want:?}");
    };
    check(&f, "intact");
    for len in 0..f.len() {
        check(&f[..len], &format!("prefix {len}"));
    }
    let mut g = f.clone();
    for i in 0..f.len() {
        g[i] = f[i] ^ 0x80;
        check(&g, &format!("flip at {i}"));
        g[i] = f[i];
    }
}
