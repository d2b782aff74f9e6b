//! glTF materials and their base colour textures.

use ::gltf::json;
use glam::{Mat2, Vec2, Vec4};
use json::validation::Checked;

use super::{name_or, Importer, MatInfo};
use crate::import::{images, percent_decode, resolve_relative, Ctx, ImportError};
use crate::scene::{AlphaMode, Material, Texture, Wrap};

impl Importer<'_> {
    pub(super) fn material(
        &mut self,
        index: Option<usize>,
        ctx: &mut Ctx,
    ) -> Result<MatInfo, ImportError> {
        let Some(mi) = index else {
            let index = match self.default_material {
                Some(i) => i,
                None => {
                    let i = self.b.material(Material::default());
                    self.default_material = Some(i);
                    i
                }
            };
            return Ok(MatInfo {
                index,
                tex_coord: 0,
                uv_transform: None,
            });
        };
        if let Some(info) = self.materials.get(&mi) {
            return Ok(*info);
        }
        let m = self
            .root
            .materials
            .get(mi)
            .ok_or_else(|| ctx.invalid(format!("material {mi} does not exist")))?;
        let label = name_or(&m.name, "material", mi);
        let factor = Vec4::from_array(m.pbr_metallic_roughness.base_color_factor.0);
        if !factor.is_finite() {
            return Err(ctx.invalid(format!("{label}: non-finite baseColorFactor")));
        }
        let alpha_mode = match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Opaque) => AlphaMode::Opaque,
            Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask {
                cutoff: m.alpha_cutoff.map_or(0.5, |c| c.0),
            },
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            Checked::Invalid => {
                ctx.warn(format!("{label}: unknown alphaMode, using OPAQUE"))?;
                AlphaMode::Opaque
            }
        };
        let mut info = MatInfo {
            index: 0,
            tex_coord: 0,
            uv_transform: None,
        };
        let mut texture = None;
        if let Some(ti) = &m.pbr_metallic_roughness.base_color_texture {
            info.tex_coord = ti.tex_coord;
            if let Some(tt) = ti
                .extensions
                .as_ref()
                .and_then(|e| e.texture_transform.as_ref())
            {
                info.tex_coord = tt.tex_coord.unwrap_or(ti.tex_coord);
                let (s, c) = tt.rotation.0.sin_cos();
                let r = Mat2::from_cols(Vec2::new(c, -s), Vec2::new(s, c))
                    * Mat2::from_diagonal(Vec2::from_array(tt.scale.0));
                let off = Vec2::from_array(tt.offset.0);
                if r.is_finite() && off.is_finite() {
                    info.uv_transform = Some((r, off));
                } else {
                    ctx.warn(format!("{label}: non-finite KHR_texture_transform ignored"))?;
                }
            }
            texture = self.texture(ti.index.value(), &label, ctx)?;
        }
        info.index = self.b.material(Material {
            name: m.name.clone().unwrap_or_else(|| format!("material {mi}")),
            base_color_factor: factor,
            base_color_texture: texture,
            alpha_mode,
            double_sided: m.double_sided,
            unlit: m.extensions.as_ref().is_some_and(|e| e.unlit.is_some()),
        });
        self.materials.insert(mi, info);
        Ok(info)
    }

    /// Loads the image of glTF texture `ti` (cached). A missing or undecodable image is
    /// a warning and `None`.
    fn texture(
        &mut self,
        ti: usize,
        label: &str,
        ctx: &mut Ctx,
    ) -> Result<Option<u32>, ImportError> {
        let t = self
            .root
            .textures
            .get(ti)
            .ok_or_else(|| ctx.invalid(format!("{label}: texture {ti} does not exist")))?;
        let wrap = |w: Checked<json::texture::WrappingMode>| match w {
            Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
            Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
            _ => Wrap::Repeat,
        };
        let (wrap_u, wrap_v) = match t.sampler.and_then(|s| self.root.samplers.get(s.value())) {
            Some(s) => (wrap(s.wrap_s), wrap(s.wrap_t)),
            None => (Wrap::Repeat, Wrap::Repeat),
        };
        let ii = t.source.value();
        if let Some(&r) = self.images.get(&(ii, wrap_u as u8, wrap_v as u8)) {
            return Ok(r);
        }
        let img = self
            .root
            .images
            .get(ii)
            .ok_or_else(|| ctx.invalid(format!("{label}: image {ii} does not exist")))?;
        let name = img
            .uri
            .clone()
            .filter(|u| !u.starts_with("data:"))
            .or_else(|| img.name.clone())
            .unwrap_or_else(|| format!("image {ii}"));
        let loaded: Result<Texture, String> = (|| {
            let mime = img.mime_type.as_ref().map(|m| m.0.as_str());
            if let Some(uri) = &img.uri {
                if uri.starts_with("data:") {
                    let (m, bytes) = images::parse_data_uri(uri)?;
                    images::decode(&bytes, &name, m.as_deref().or(mime))
                } else if uri.contains("://") {
                    Err(format!("external URI {uri} is not fetched"))
                } else {
                    let p = resolve_relative(self.base, &percent_decode(uri));
                    let bytes = ctx
                        .read_referenced(&p)
                        .map_err(|e| format!("{}: {e}", p.display()))?;
                    images::decode(&bytes, &name, mime)
                }
            } else if let Some(v) = img.buffer_view {
                let bytes = self
                    .acc
                    .view_bytes(v.value(), ctx)
                    .map_err(|e| e.to_string())?;
                images::decode(bytes, &name, mime)
            } else {
                Err("image has neither uri nor bufferView".into())
            }
        })();
        let (result, error) = match loaded {
            Ok(mut tex) => {
                tex.wrap_u = wrap_u;
                tex.wrap_v = wrap_v;
                (Some(self.b.texture(tex)), None)
            }
            Err(e) => (None, Some(e)),
        };
        ctx.texture(&name, result.is_some());
        self.images.insert((ii, wrap_u as u8, wrap_v as u8), result);
        if let Some(e) = error {
            ctx.warn(format!(
                "{label}: base colour texture '{name}' not loaded ({e}); using the factor colour"
            ))?;
        }
        Ok(result)
    }
}
