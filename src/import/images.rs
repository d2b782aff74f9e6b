//! Image decoding for importers: bytes → [`Texture`], `data:` URIs, OBJ `map_Kd` + `map_d`.

use std::io::Cursor;

use crate::scene::{EncodedFormat, EncodedImage, Texture, Wrap};

/// Largest accepted image side, in texels.
const MAX_SIDE: u32 = 16384;
/// Largest decoder allocation for one image.
const MAX_ALLOC: u64 = 1 << 30;

/// Decodes an encoded image (PNG, JPEG, ...) into RGBA8 texels as stored
/// (RGB sRGB-encoded, alpha linear, straight). Content sniffing says the format; `mime`,
/// else `name`'s extension, where it cannot (TGA). A PNG or JPEG keeps its bytes in
/// [`Texture::encoded`].
pub(crate) fn decode(bytes: &[u8], name: &str, mime: Option<&str>) -> Result<Texture, String> {
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    if reader.format().is_none() {
        // Formats without a signature (TGA) are told by the MIME type, else by the name's
        // extension (an OBJ `map_Kd bark.tga`).
        let by_name = || image::ImageFormat::from_path(name).ok();
        match mime
            .and_then(image::ImageFormat::from_mime_type)
            .or_else(by_name)
        {
            Some(f) => reader.set_format(f),
            None => return Err("unrecognised image format".into()),
        }
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(MAX_ALLOC);
    reader.limits(limits);
    let encoded = match reader.format() {
        Some(image::ImageFormat::Png) => Some(EncodedFormat::Png),
        Some(image::ImageFormat::Jpeg) => Some(EncodedFormat::Jpeg),
        _ => None,
    };
    let img = reader.decode().map_err(|e| e.to_string())?.into_rgba8();
    let (width, height) = img.dimensions();
    if width == 0 || height == 0 {
        return Err("image has zero size".into());
    }
    let texels = img.pixels().map(|p| p.0).collect();
    Ok(Texture {
        name: name.to_owned(),
        width,
        height,
        texels,
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
        encoded: encoded.map(|format| EncodedImage {
            format,
            bytes: bytes.into(),
        }),
    })
}

/// Whether any texel has alpha below 255 (i.e. the image carries an alpha channel that matters).
pub(crate) fn has_alpha(t: &Texture) -> bool {
    t.texels.iter().any(|p| p[3] != 255)
}

/// Replaces the alpha of `color` with the coverage from `alpha_map`: its alpha channel
/// when it has one, else its (Rec. 709, sRGB-decoded) luminance. Sizes may differ; the
/// alpha map is sampled at the nearest texel.
pub(crate) fn combine_alpha(color: &mut Texture, alpha_map: &Texture) {
    let use_alpha = has_alpha(alpha_map);
    let lut = crate::texture::srgb_to_linear_lut();
    let (w, h) = (color.width as u64, color.height as u64);
    let (aw, ah) = (alpha_map.width as u64, alpha_map.height as u64);
    let mut changed = false;
    for y in 0..h {
        let sy = ((y * ah) / h).min(ah - 1);
        for x in 0..w {
            let sx = ((x * aw) / w).min(aw - 1);
            let s = alpha_map.texels[(sy * aw + sx) as usize];
            let a = if use_alpha {
                s[3]
            } else {
                let l = 0.2126 * lut[s[0] as usize]
                    + 0.7152 * lut[s[1] as usize]
                    + 0.0722 * lut[s[2] as usize];
                (l * 255.0).round().clamp(0.0, 255.0) as u8
            };
            let texel = &mut color.texels[(y * w + x) as usize];
            changed |= texel[3] != a;
            texel[3] = a;
        }
    }
    if changed {
        // The texels are no longer the source image's (an image that is its own alpha
        // map, `map_Kd` and `map_d` naming one RGBA file, is unchanged and keeps it).
        color.encoded = None;
    }
}

/// A white texture the size of `alpha_map`, for `map_d` without `map_Kd`.
pub(crate) fn white_like(alpha_map: &Texture, name: &str) -> Texture {
    Texture {
        name: name.to_owned(),
        width: alpha_map.width,
        height: alpha_map.height,
        texels: vec![[255; 4]; alpha_map.texels.len()],
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
        encoded: None,
    }
}

/// Parses a `data:[<mime>][;base64],<payload>` URI. Returns (mime, bytes).
pub(crate) fn parse_data_uri(uri: &str) -> Result<(Option<String>, Vec<u8>), String> {
    let rest = uri.strip_prefix("data:").ok_or("not a data: URI")?;
    let (header, payload) = rest.split_once(',').ok_or("data: URI without ','")?;
    let (mime, is_base64) = match header.strip_suffix(";base64") {
        Some(m) => (m, true),
        None => (header, false),
    };
    let mime = (!mime.is_empty()).then(|| mime.to_owned());
    let bytes = if is_base64 {
        base64_decode(payload)?
    } else {
        crate::import::percent_decode(payload).into_bytes()
    };
    Ok((mime, bytes))
}

/// Standard (and URL-safe) base64 decoding; whitespace ignored, padding optional.
pub(crate) fn base64_decode(s: &str) -> Result<Vec<u8>, String> {
    fn val(c: u8) -> Option<u32> {
        match c {
            b'A'..=b'Z' => Some((c - b'A') as u32),
            b'a'..=b'z' => Some((c - b'a') as u32 + 26),
            b'0'..=b'9' => Some((c - b'0') as u32 + 52),
            b'+' | b'-' => Some(62),
            b'/' | b'_' => Some(63),
            _ => None,
        }
    }
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    let mut padding = false;
    for &c in s.as_bytes() {
        if c.is_ascii_whitespace() {
            continue;
        }
        if c == b'=' {
            padding = true;
            continue;
        }
        if padding {
            return Err("invalid base64: data after padding".into());
        }
        let v = val(c).ok_or_else(|| format!("invalid base64 character {:?}", c as char))?;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_roundtrip() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAECAw==").unwrap(), vec![0, 1, 2, 3]);
        assert!(base64_decode("a*b").is_err());
    }

    #[test]
    fn data_uri() {
        let (m, b) = parse_data_uri("data:application/octet-stream;base64,AAEC").unwrap();
        assert_eq!(m.as_deref(), Some("application/octet-stream"));
        assert_eq!(b, vec![0, 1, 2]);
    }
}
