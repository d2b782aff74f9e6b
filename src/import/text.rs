//! The text of an imported OBJ or MTL file and how messages show its lines.

use std::borrow::Cow;

/// The text of an OBJ or MTL file: UTF-8, its byte-order mark dropped and bytes that are
/// not UTF-8 (a Latin-1 `©`) replaced by U+FFFD, or UTF-16, little or big endian, told by
/// its byte-order mark or, without one, by NUL bytes in every other byte (as ASCII text in
/// UTF-16 has; text in UTF-8 has none).
pub(super) fn decode_text(raw: &[u8]) -> Cow<'_, str> {
    let utf16 = match raw {
        [0xEF, 0xBB, 0xBF, rest @ ..] => return String::from_utf8_lossy(rest),
        [0xFF, 0xFE, rest @ ..] => Some((rest, false)),
        [0xFE, 0xFF, rest @ ..] => Some((rest, true)),
        _ => utf16_without_bom(raw).map(|big_endian| (raw, big_endian)),
    };
    match utf16 {
        None => String::from_utf8_lossy(raw),
        Some((bytes, big_endian)) => {
            let units = bytes.chunks_exact(2).map(|c| {
                if big_endian {
                    u16::from_be_bytes([c[0], c[1]])
                } else {
                    u16::from_le_bytes([c[0], c[1]])
                }
            });
            Cow::Owned(
                char::decode_utf16(units)
                    .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
                    .collect(),
            )
        }
    }
}

/// Whether text without a byte-order mark looks like UTF-16: `Some(big_endian)` when at
/// least three quarters of the odd (LE) or even (BE) bytes of its first 4 KiB are NUL and
/// almost none of the others.
pub(super) fn utf16_without_bom(raw: &[u8]) -> Option<bool> {
    let head = &raw[..raw.len().min(4096) & !1];
    let pairs = head.len() / 2;
    if pairs < 2 {
        return None;
    }
    let zeros = |k: usize| head.iter().skip(k).step_by(2).filter(|&&b| b == 0).count();
    let (even, odd) = (zeros(0), zeros(1));
    let mostly = |n: usize| 4 * n >= 3 * pairs;
    let hardly = |n: usize| 16 * n <= pairs;
    if mostly(odd) && hardly(even) {
        Some(false)
    } else if mostly(even) && hardly(odd) {
        Some(true)
    } else {
        None
    }
}

/// A line as a message shows it: at most 60 characters, control characters escaped.
pub(super) fn shown(line: &str) -> String {
    let line = line.trim();
    let mut out: String = line
        .chars()
        .take(60)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_debug().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if line.chars().count() > 60 {
        out.push('…');
    }
    out
}
