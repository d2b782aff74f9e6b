//! Exporting a billboard cloud ([`CloudAsset`]) as standard glTF 2.0 binary (`.glb`).
//!
//! The document is built with `gltf-json` (re-exported as `gltf::json`) and packed with
//! `::gltf::binary::Glb`; every image is a PNG inside the binary chunk.
//!
//! - **One node per LOD** (`lod0`, `lod1`, …) and a `trunk` node with the kept mesh. Scene
//!   `k` (named `lod{k}`) shows LOD k with the trunk; scene 0 is the default, so a viewer
//!   shows the finest level. Each LOD node's `extras` hold its level, ε and texel density.
//! - **Quads**: every billboard is two quads in its plane, facing opposite ways: the front
//!   quad (counter-clockwise seen from +normal, normal +n) textured with the front
//!   texture, the back quad (counter-clockwise from −normal) with the back texture. Both
//!   single-sided, so each side shows its own bake. Corner i of a billboard gets UV
//!   `(u0|u1, v0|v1)` of its atlas rectangle as in SPEC §9 (corner 0 → (u0, v0),
//!   corner 2 → (u1, v1)).
//! - **Materials**: one per (atlas, side), named `lod{l}/atlas{a}/front|back`, the atlas as
//!   `baseColorTexture`, `KHR_materials_unlit` (lighting is baked in; the fallback is
//!   metallic 0, roughness 1), alpha mode `MASK` (cutoff 0.5, default) or `BLEND`.
//! - **Atlases**: level 0 of each atlas as an 8-bit PNG with **straight** alpha (what glTF
//!   specifies), colour dilated into transparent texels so viewer-made MIPs have no dark
//!   fringes ([`crate::bbcloud::straight`]); sampler linear / linear-mipmap-linear, clamp.
//! - **Morph**: each LOD mesh has one morph target (`extras.targetNames = ["parent"]`,
//!   weight 0): the displacement of each corner to its projection onto the parent
//!   billboard in the next level, so a renderer can morph between levels (Lacewell §3).
//! - **Trunk**: the kept mesh with its materials (base colour factor and texture, alpha
//!   mode, double-sided) and textures as authored (PNG, straight alpha, wrap modes).
//!
//! Deterministic: the same asset gives the same bytes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ::gltf::json;
use billow_format::{CloudAsset, CloudError, FormatError, Mesh};
use json::validation::{Checked::Valid, USize64};
use json::Index;

use crate::bbcloud::straight;

/// How billboard coverage is turned into visibility by a viewer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GltfAlpha {
    /// Alpha test at `cutoff`: order-independent, crisp (default, cutoff 0.5).
    Mask { cutoff: f32 },
    /// Alpha blending: soft edges, but viewers sort per object, not per quad.
    Blend,
}

impl Default for GltfAlpha {
    fn default() -> Self {
        GltfAlpha::Mask { cutoff: 0.5 }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GltfOptions {
    pub alpha: GltfAlpha,
}

/// Why a cloud could not be exported. `Display` names the file.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    #[error("{path}: cannot export an invalid cloud asset: {source}")]
    InvalidAsset {
        path: PathBuf,
        #[source]
        source: CloudError,
    },
    #[error("{path}: cannot encode glTF: {message}")]
    Encode { path: PathBuf, message: String },
    #[error(transparent)]
    Write(FormatError),
}

/// Writes `asset` as a `.glb` at `path`, atomically.
pub fn write_cloud_glb(
    asset: &CloudAsset,
    path: &Path,
    opts: &GltfOptions,
) -> Result<(), GltfError> {
    let bytes = cloud_glb_bytes(asset, opts).map_err(|e| match e {
        GltfError::InvalidAsset { source, .. } => GltfError::InvalidAsset {
            path: path.to_path_buf(),
            source,
        },
        GltfError::Encode { message, .. } => GltfError::Encode {
            path: path.to_path_buf(),
            message,
        },
        other => other,
    })?;
    billow_format::write_atomic(path, &bytes).map_err(GltfError::Write)
}

/// Binary chunk under construction: 4-byte aligned views.
struct Bin<'a> {
    root: &'a mut json::Root,
    data: Vec<u8>,
}

impl Bin<'_> {
    fn view(
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
    fn floats<const N: usize>(&mut self, v: &[[f32; N]], bounds: bool) -> Index<json::Accessor> {
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

    fn indices(&mut self, idx: &[u32]) -> Index<json::Accessor> {
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

    fn accessor(
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

    fn png_texture(
        &mut self,
        png: &[u8],
        name: String,
        sampler: Index<json::texture::Sampler>,
    ) -> Index<json::Texture> {
        let view = self.view(png, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(name.clone()),
            uri: None,
            extensions: None,
            extras: None,
        });
        self.root.push(json::Texture {
            name: Some(name),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        })
    }
}

fn extras(v: serde_json::Value) -> json::Extras {
    serde_json::value::to_raw_value(&v).ok()
}

fn sampler(root: &mut json::Root, wrap: [u32; 2]) -> Index<json::texture::Sampler> {
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
fn material(
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

fn primitive(
    bin: &mut Bin<'_>,
    pos: &[[f32; 3]],
    nrm: &[[f32; 3]],
    uv: &[[f32; 2]],
    idx: &[u32],
    morph: Option<&[[f32; 3]]>,
    material: Index<json::Material>,
) -> json::mesh::Primitive {
    use json::mesh::Semantic;
    let mut attributes = BTreeMap::new();
    attributes.insert(Valid(Semantic::Positions), bin.floats(pos, true));
    attributes.insert(Valid(Semantic::Normals), bin.floats(nrm, false));
    attributes.insert(Valid(Semantic::TexCoords(0)), bin.floats(uv, false));
    let targets = morph.map(|d| {
        vec![json::mesh::MorphTarget {
            positions: Some(bin.floats(d, true)),
            normals: None,
            tangents: None,
        }]
    });
    json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: None,
        indices: Some(bin.indices(idx)),
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets,
    }
}

/// Vertex streams of one primitive.
#[derive(Default)]
struct Quads {
    pos: Vec<[f32; 3]>,
    nrm: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
    morph: Vec<[f32; 3]>,
    idx: Vec<u32>,
}

impl Quads {
    /// One quad: corners in order (counter-clockwise as seen from the side it faces).
    fn push(&mut self, c: [[f32; 3]; 4], pc: [[f32; 3]; 4], n: [f32; 3], uv: [[f32; 2]; 4]) {
        let base = self.pos.len() as u32;
        for k in 0..4 {
            self.pos.push(c[k]);
            self.nrm.push(n);
            self.uv.push(uv[k]);
            self.morph
                .push([pc[k][0] - c[k][0], pc[k][1] - c[k][1], pc[k][2] - c[k][2]]);
        }
        self.idx
            .extend([0, 1, 2, 0, 2, 3].iter().map(|&i| base + i));
    }
}

/// The kept mesh as one glTF mesh (one primitive per material, shared vertex streams).
fn trunk_mesh(
    bin: &mut Bin<'_>,
    asset: &CloudAsset,
    mesh: &Mesh,
) -> Result<Option<Index<json::Mesh>>, String> {
    if mesh.triangles.is_empty() {
        return Ok(None);
    }
    let mut by_mat: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for (t, &m) in mesh.triangles.iter().zip(&mesh.materials) {
        by_mat.entry(m).or_default().extend(t);
    }
    let mut samplers = BTreeMap::new();
    let mut textures = BTreeMap::new();
    let pos: Vec<[f32; 3]> = mesh.vertices.iter().map(|v| v.position).collect();
    let nrm: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| {
            let n = glam::Vec3::from(v.normal).normalize_or(glam::Vec3::Y);
            n.to_array()
        })
        .collect();
    let uv: Vec<[f32; 2]> = mesh.vertices.iter().map(|v| v.uv).collect();
    let a_pos = bin.floats(&pos, true);
    let a_nrm = bin.floats(&nrm, false);
    let a_uv = bin.floats(&uv, false);
    let mut prims = Vec::new();
    for (m, idx) in by_mat {
        let mm = &asset.materials[m as usize];
        let tex = match mm.texture {
            None => None,
            Some(t) => Some(match textures.get(&t) {
                Some(&i) => i,
                None => {
                    let tx = &asset.textures[t as usize];
                    let s = *samplers
                        .entry(tx.wrap)
                        .or_insert_with(|| sampler(bin.root, tx.wrap));
                    let png = straight::encode_png(tx.width, tx.height, &tx.texels)?;
                    let i = bin.png_texture(&png, format!("texture{t}"), s);
                    textures.insert(t, i);
                    i
                }
            }),
        };
        let alpha = match mm.alpha_mode {
            1 => (json::material::AlphaMode::Mask, mm.alpha_cutoff),
            2 => (json::material::AlphaMode::Blend, 0.5),
            _ => (json::material::AlphaMode::Opaque, 0.5),
        };
        let mat = material(
            bin.root,
            format!("trunk/material{m}"),
            mm.base_color_factor,
            tex,
            alpha,
            mm.double_sided,
            false,
        );
        let indices = bin.indices(&idx);
        let mut attributes = BTreeMap::new();
        use json::mesh::Semantic;
        attributes.insert(Valid(Semantic::Positions), a_pos);
        attributes.insert(Valid(Semantic::Normals), a_nrm);
        attributes.insert(Valid(Semantic::TexCoords(0)), a_uv);
        prims.push(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(indices),
            material: Some(mat),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        });
    }
    Ok(Some(bin.root.push(json::Mesh {
        extensions: None,
        extras: None,
        name: Some("trunk".into()),
        primitives: prims,
        weights: None,
    })))
}

/// The `.glb` bytes of `asset` (validated first).
pub fn cloud_glb_bytes(asset: &CloudAsset, opts: &GltfOptions) -> Result<Vec<u8>, GltfError> {
    let encode = |message: String| GltfError::Encode {
        path: PathBuf::new(),
        message,
    };
    asset.validate().map_err(|source| GltfError::InvalidAsset {
        path: PathBuf::new(),
        source,
    })?;
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(asset.header.tool.clone()),
            ..Default::default()
        },
        extensions_used: vec!["KHR_materials_unlit".into()],
        ..Default::default()
    };
    let mut bin = Bin {
        root: &mut root,
        data: Vec::new(),
    };
    let alpha = match opts.alpha {
        GltfAlpha::Mask { cutoff } => (json::material::AlphaMode::Mask, cutoff),
        GltfAlpha::Blend => (json::material::AlphaMode::Blend, 0.5),
    };
    let clamp = sampler(bin.root, [1, 1]);
    // Atlases: one texture each, and a front and a back material.
    let pngs: Vec<Vec<u8>> = {
        use rayon::prelude::*;
        asset
            .atlases
            .par_iter()
            .map(straight::atlas_png)
            .collect::<Result<_, _>>()
            .map_err(encode)?
    };
    let mut atlas_mats = Vec::new();
    for (l, lv) in asset.levels.iter().enumerate() {
        for k in 0..lv.atlas_count as usize {
            let a = lv.first_atlas as usize + k;
            let tex = bin.png_texture(&pngs[a], format!("lod{l}/atlas{k}"), clamp);
            let side = |bin: &mut Bin<'_>, s: &str| {
                material(
                    bin.root,
                    format!("lod{l}/atlas{k}/{s}"),
                    [1.0; 4],
                    Some(tex),
                    alpha,
                    false,
                    true,
                )
            };
            atlas_mats.push([side(&mut bin, "front"), side(&mut bin, "back")]);
        }
    }
    let trunk = trunk_mesh(&mut bin, asset, &asset.trunk).map_err(encode)?;
    let mut lod_nodes = Vec::new();
    for (l, lv) in asset.levels.iter().enumerate() {
        // (atlas, side) → quads, in billboard order.
        let mut groups: BTreeMap<(u32, usize), Quads> = BTreeMap::new();
        let range = lv.first_billboard as usize..(lv.first_billboard + lv.billboard_count) as usize;
        for b in &asset.billboards[range] {
            let n = [b.plane[0], b.plane[1], b.plane[2]];
            let c = b.corners;
            let pc = b.parent_corners;
            let uv = |r: &billow_format::AtlasRect| {
                let [u0, v0, u1, v1] = r.uv;
                [[u0, v0], [u1, v0], [u1, v1], [u0, v1]]
            };
            let f = uv(&b.front);
            groups
                .entry((b.front.atlas, 0))
                .or_default()
                .push(c, pc, n, f);
            // Back: reversed order (0, 3, 2, 1) faces −n; same UV per corner.
            let bk = uv(&b.back);
            let r = [0, 3, 2, 1];
            groups.entry((b.back.atlas, 1)).or_default().push(
                r.map(|i| c[i]),
                r.map(|i| pc[i]),
                [-n[0], -n[1], -n[2]],
                r.map(|i| bk[i]),
            );
        }
        let mut prims = Vec::new();
        for ((a, side), q) in &groups {
            let mat = atlas_mats[*a as usize][*side];
            prims.push(primitive(
                &mut bin,
                &q.pos,
                &q.nrm,
                &q.uv,
                &q.idx,
                Some(&q.morph),
                mat,
            ));
        }
        let mesh = bin.root.push(json::Mesh {
            extensions: None,
            extras: extras(serde_json::json!({ "targetNames": ["parent"] })),
            name: Some(format!("lod{l}")),
            primitives: prims,
            weights: Some(vec![0.0]),
        });
        lod_nodes.push(bin.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(format!("lod{l}")),
            extras: extras(serde_json::json!({
                "lod": l,
                "billboards": lv.billboard_count,
                "epsilon": lv.epsilon,
                "texel_density": lv.texel_density,
            })),
            ..Default::default()
        }));
    }
    let trunk_node = trunk.map(|m| {
        bin.root.push(json::Node {
            mesh: Some(m),
            name: Some("trunk".into()),
            ..Default::default()
        })
    });
    for (l, &n) in lod_nodes.iter().enumerate() {
        let nodes = trunk_node.into_iter().chain([n]).collect();
        bin.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some(format!("lod{l}")),
            nodes,
        });
    }
    while !bin.data.len().is_multiple_of(4) {
        bin.data.push(0);
    }
    let data = std::mem::take(&mut bin.data);
    root.scene = Some(Index::new(0));
    root.push(json::Buffer {
        byte_length: USize64(data.len() as u64),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    let mut text = root.to_vec().map_err(|e| encode(e.to_string()))?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let length = 12 + 8 + text.len() + 8 + data.len();
    let length = u32::try_from(length).map_err(|_| {
        encode(format!(
            "{length} bytes is more than a GLB can hold (4 GiB)"
        ))
    })?;
    let glb = ::gltf::binary::Glb {
        header: ::gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length,
        },
        json: std::borrow::Cow::Owned(text),
        bin: Some(std::borrow::Cow::Owned(data)),
    };
    glb.to_vec().map_err(|e| encode(e.to_string()))
}
