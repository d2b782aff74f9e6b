//! The GLB binary container.

pub(super) enum GlbError {
    Version(u32),
    Malformed(String),
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk, checking every
/// length against the data (the `gltf` crate's parser can underflow on hostile headers).
pub(super) fn split_glb(data: &[u8]) -> Result<(&[u8], Option<&[u8]>), GlbError> {
    let u32_at = |o: usize| -> Option<u32> {
        data.get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let bad = |m: &str| GlbError::Malformed(m.to_owned());
    let version = u32_at(4).ok_or_else(|| bad("header truncated"))?;
    if version != 2 {
        return Err(GlbError::Version(version));
    }
    let length = u32_at(8).ok_or_else(|| bad("header truncated"))? as usize;
    if length > data.len() {
        return Err(GlbError::Malformed(format!(
            "length field {length} exceeds file size {}",
            data.len()
        )));
    }
    if length < 12 {
        return Err(GlbError::Malformed(format!(
            "length field {length} is smaller than the header"
        )));
    }
    let data = &data[..length];
    let (mut json, mut bin) = (None, None);
    let mut off = 12usize;
    while off < length {
        let (Some(len), Some(ty)) = (u32_at(off), u32_at(off + 4)) else {
            return Err(bad("chunk header truncated"));
        };
        let start = off + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= length)
            .ok_or_else(|| bad("chunk length exceeds the file"))?;
        let chunk = &data[start..end];
        match ty {
            0x4E4F_534A if json.is_none() && off == 12 => json = Some(chunk),
            0x004E_4942 if json.is_some() && bin.is_none() => bin = Some(chunk),
            0x4E4F_534A | 0x004E_4942 => {
                return Err(bad(
                    "JSON chunk must come first, then at most one BIN chunk",
                ))
            }
            _ => {} // unknown chunk types are skipped
        }
        off = end;
    }
    Ok((json.ok_or_else(|| bad("no JSON chunk"))?, bin))
}
