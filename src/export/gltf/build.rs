//! Building blocks of the glTF export: the binary chunk with its views and accessors,
//! images and textures, samplers, materials, and base64 for a `.gltf`'s `data:` URI.

use ::gltf::json;
use json::validation::{Checked::Valid, USize64};
use json::Index;

/// Binary chunk under construction: 4-byte aligned views.
pub(super) struct Bin<'a> {
    pub root: &'a mut json::Root,
    pub data: Vec<u8>,
}

impl Bin<'_> {
    pub fn view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> Index<json::buffer::View> {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let offset = self.data.len();
        self.data.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }

    /// A float accessor of `N`-vectors (with min/max when `bounds`).
    pub fn floats<const N: usize>(
        &mut self,
        v: &[[f32; N]],
        bounds: bool,
    ) -> Index<json::Accessor> {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ArrayBuffer));
        let (min, max) = if bounds && !v.is_empty() {
            let mut lo = [f32::INFINITY; N];
            let mut hi = [f32::NEG_INFINITY; N];
            for p in v {
                for k in 0..N {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (
                Some(serde_json::json!(lo.to_vec())),
                Some(serde_json::json!(hi.to_vec())),
            )
        } else {
            (None, None)
        };
        let type_ = match N {
            2 => json::accessor::Type::Vec2,
            3 => json::accessor::Type::Vec3,
            _ => json::accessor::Type::Vec4,
        };
        self.accessor(
            view,
            v.len(),
            json::accessor::ComponentType::F32,
            type_,
            min,
            max,
        )
    }

    pub fn indices(&mut self, idx: &[u32]) -> Index<json::Accessor> {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ElementArrayBuffer));
        self.accessor(
            view,
            idx.len(),
            json::accessor::ComponentType::U32,
            json::accessor::Type::Scalar,
            None,
            None,
        )
    }

    pub fn accessor(
        &mut self,
        view: Index<json::buffer::View>,
        count: usize,
        ct: json::accessor::ComponentType,
        type_: json::accessor::Type,
        min: Option<serde_json::Value>,
        max: Option<serde_json::Value>,
    ) -> Index<json::Accessor> {
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: Valid(json::accessor::GenericComponentType(ct)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    pub fn png_texture(
        &mut self,
        png: &[u8],
        name: String,
        sampler: Index<json::texture::Sampler>,
    ) -> Index<json::Texture> {
        let image = self.image(png, "image/png", name.clone());
        self.texture(image, name, sampler)
    }

    /// An image: `bytes` (encoded as `mime_type` says) as a buffer view.
    pub fn image(&mut self, bytes: &[u8], mime_type: &str, name: String) -> Index<json::Image> {
        let view = self.view(bytes, None);
        self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType(mime_type.into())),
            name: Some(name),
            uri: None,
            extensions: None,
            extras: None,
        })
    }

    pub fn texture(
        &mut self,
        image: Index<json::Image>,
        name: String,
        sampler: Index<json::texture::Sampler>,
    ) -> Index<json::Texture> {
        self.root.push(json::Texture {
            name: Some(name),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        })
    }
}

/// Standard base64 with padding (RFC 4648 §4), for `data:` URIs.
pub(super) fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from_be_bytes([0, b[0], b[1], b[2]]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

pub(super) fn extras(v: serde_json::Value) -> json::Extras {
    serde_json::value::to_raw_value(&v).ok()
}

pub(super) fn sampler(root: &mut json::Root, wrap: [u32; 2]) -> Index<json::texture::Sampler> {
    use json::texture::{MagFilter, MinFilter, WrappingMode};
    let w = |m: u32| {
        Valid(match m {
            1 => WrappingMode::ClampToEdge,
            2 => WrappingMode::MirroredRepeat,
            _ => WrappingMode::Repeat,
        })
    };
    root.push(json::texture::Sampler {
        mag_filter: Some(Valid(MagFilter::Linear)),
        min_filter: Some(Valid(MinFilter::LinearMipmapLinear)),
        name: None,
        wrap_s: w(wrap[0]),
        wrap_t: w(wrap[1]),
        extensions: None,
        extras: None,
    })
}

#[allow(clippy::too_many_arguments)]
pub(super) fn material(
    root: &mut json::Root,
    name: String,
    colour: [f32; 4],
    texture: Option<Index<json::Texture>>,
    alpha: (json::material::AlphaMode, f32),
    double_sided: bool,
    unlit: bool,
) -> Index<json::Material> {
    let mode = alpha.0;
    root.push(json::Material {
        alpha_cutoff: (mode == json::material::AlphaMode::Mask)
            .then_some(json::material::AlphaCutoff(alpha.1)),
        alpha_mode: Valid(mode),
        double_sided,
        name: Some(name),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(colour),
            base_color_texture: texture.map(|index| json::texture::Info {
                index,
                tex_coord: 0,
                extensions: None,
                extras: None,
            }),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(1.0),
            metallic_roughness_texture: None,
            extensions: None,
            extras: None,
        },
        extensions: unlit.then(|| json::extensions::material::Material {
            unlit: Some(json::extensions::material::Unlit {}),
            ..Default::default()
        }),
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn base64_of_rfc_4648_test_vectors() {
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, encoded) in cases {
            assert_eq!(super::base64(plain.as_bytes()), encoded);
        }
        assert_eq!(super::base64(&[0xfb, 0xff]), "+/8=");
    }
}
