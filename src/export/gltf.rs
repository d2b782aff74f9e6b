//! Exporting a billboard cloud ([`CloudAsset`]) as standard glTF 2.0: binary (`.glb`) or
//! one self-contained JSON file (`.gltf`), [`GltfContainer`].
//!
//! The document is built with `gltf-json` (re-exported as `gltf::json`). A `.glb` is
//! packed with `::gltf::binary::Glb`, every image a buffer view of its binary chunk; a
//! `.gltf` is the same document with its one buffer as a base64 `data:` URI.
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
//!   fringes ([`super::straight`]); sampler linear / linear-mipmap-linear, clamp.
//! - **Normal maps** (assets baked with `--normal-map`): each atlas's normal map (level 0,
//!   RGB PNG, linear) is the materials' `normalTexture`; every quad vertex carries a
//!   `TANGENT` = (U, w) with U the billboard's u direction and w = −1 on the front quad,
//!   +1 on the back quad, so glTF's bitangent `cross(N, T)·w` is −V (image up) on both
//!   sides — the tangent frame the normals were baked in (SPEC §9.4). Those materials are
//!   lit (no `KHR_materials_unlit`): a normal map only matters to a viewer that lights the
//!   billboards, so such assets are best baked `--unlit` (albedo).
//! - **Morph**: each LOD mesh has one morph target (`extras.targetNames = ["parent"]`,
//!   weight 0): the displacement of each corner to its projection onto the parent
//!   billboard in the next level, so a renderer can morph between levels (Lacewell §3).
//! - **Trunk**: the kept mesh with its materials (base colour factor and texture, alpha
//!   mode, double-sided) and textures as authored (straight alpha, wrap modes). With the
//!   source scene ([`GltfOptions::source`]) they keep their names, and a texture whose
//!   texels are its source image's embeds that image's bytes unchanged (JPEG or PNG, with
//!   its `mimeType`); any other texture is PNG-encoded from the texels.
//!
//! Deterministic: the same asset gives the same bytes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use ::gltf::json;
use billow_format::{CloudAsset, CloudError, FormatError, Mesh, MeshTexture};
use json::validation::{Checked::Valid, USize64};
use json::Index;

use super::straight;

mod build;
use build::{base64, extras, material, sampler, Bin};

use crate::scene::{EncodedImage, Scene, Texture};

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

/// How the document and its binary data are packed into the one output file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GltfContainer {
    /// Binary glTF (`.glb`): the JSON chunk and one binary chunk with every buffer view.
    #[default]
    Glb,
    /// JSON glTF (`.gltf`), self-contained in one file: the same document, its one buffer a
    /// base64 `data:application/octet-stream` URI (images stay buffer views of it).
    Embedded,
}

impl GltfContainer {
    /// The container an output path asks for by its extension (any case): `.glb` →
    /// [`GltfContainer::Glb`], `.gltf` → [`GltfContainer::Embedded`]; `None` otherwise.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "glb" => Some(GltfContainer::Glb),
            "gltf" => Some(GltfContainer::Embedded),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GltfOptions<'a> {
    pub alpha: GltfAlpha,
    pub container: GltfContainer,
    /// The scene the cloud was baked from (its materials and textures are the asset's, in
    /// the same order). With it the trunk keeps the source's material names and texture
    /// and image names, and embeds a texture's source image unchanged (JPEG or PNG bytes,
    /// [`crate::scene::Texture::encoded`]) where its texels are the asset's; without it
    /// they are named `trunk/material{m}` and `texture{t}` and every image is PNG-encoded
    /// from the asset's texels.
    pub source: Option<&'a Scene>,
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

/// Writes `asset` as a `.glb` at `path`, atomically, whatever `opts.container` says.
pub fn write_cloud_glb(
    asset: &CloudAsset,
    path: &Path,
    opts: &GltfOptions,
) -> Result<(), GltfError> {
    let opts = GltfOptions {
        container: GltfContainer::Glb,
        ..*opts
    };
    write_cloud_gltf(asset, path, &opts)
}

/// Writes `asset` as glTF in `opts.container` at `path`, atomically.
pub fn write_cloud_gltf(
    asset: &CloudAsset,
    path: &Path,
    opts: &GltfOptions,
) -> Result<(), GltfError> {
    let bytes = cloud_gltf_bytes(asset, opts).map_err(|e| match e {
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

fn primitive(
    bin: &mut Bin<'_>,
    q: &Quads,
    tangents: bool,
    material: Index<json::Material>,
) -> json::mesh::Primitive {
    use json::mesh::Semantic;
    let mut attributes = BTreeMap::new();
    attributes.insert(Valid(Semantic::Positions), bin.floats(&q.pos, true));
    attributes.insert(Valid(Semantic::Normals), bin.floats(&q.nrm, false));
    if tangents {
        attributes.insert(Valid(Semantic::Tangents), bin.floats(&q.tan, false));
    }
    attributes.insert(Valid(Semantic::TexCoords(0)), bin.floats(&q.uv, false));
    let (idx, morph) = (&q.idx, Some(&q.morph));
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
    tan: Vec<[f32; 4]>,
    uv: Vec<[f32; 2]>,
    morph: Vec<[f32; 3]>,
    idx: Vec<u32>,
}

impl Quads {
    /// One quad: corners in order (counter-clockwise as seen from the side it faces), its
    /// normal and tangent (xyz, w).
    fn push(
        &mut self,
        c: [[f32; 3]; 4],
        pc: [[f32; 3]; 4],
        n: [f32; 3],
        t: [f32; 4],
        uv: [[f32; 2]; 4],
    ) {
        let base = self.pos.len() as u32;
        for k in 0..4 {
            self.pos.push(c[k]);
            self.nrm.push(n);
            self.tan.push(t);
            self.uv.push(uv[k]);
            self.morph
                .push([pc[k][0] - c[k][0], pc[k][1] - c[k][1], pc[k][2] - c[k][2]]);
        }
        self.idx
            .extend([0, 1, 2, 0, 2, 3].iter().map(|&i| base + i));
    }
}

/// The unit u direction of a billboard (corner 0 → corner 1), made exactly perpendicular to
/// its normal; any perpendicular unit vector for a zero-width billboard.
fn tangent(c: &[[f32; 3]; 4], n: glam::Vec3) -> glam::Vec3 {
    let n = n.normalize_or(glam::Vec3::Z);
    let e = glam::Vec3::from(c[1]) - glam::Vec3::from(c[0]);
    let e = e - e.dot(n) * n;
    e.try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector())
}

/// Whether `source`'s texels are exactly `texture`'s.
fn same_texels(source: &Texture, texture: &MeshTexture) -> bool {
    (source.width, source.height) == (texture.width, texture.height)
        && source.texels.len() * 4 == texture.texels.len()
        && source.texels.iter().flatten().eq(texture.texels.iter())
}

/// The kept mesh as one glTF mesh (one primitive per material, shared vertex streams),
/// named and with images as [`GltfOptions::source`] says.
fn trunk_mesh(
    bin: &mut Bin<'_>,
    asset: &CloudAsset,
    mesh: &Mesh,
    source: Option<&Scene>,
) -> Result<Option<Index<json::Mesh>>, String> {
    if let Some(s) = source {
        if (s.materials.len(), s.textures.len()) != (asset.materials.len(), asset.textures.len()) {
            return Err(format!(
                "the source scene is not the asset's: it has {} materials and {} textures, \
                 the asset {} and {}",
                s.materials.len(),
                s.textures.len(),
                asset.materials.len(),
                asset.textures.len()
            ));
        }
    }
    if mesh.triangles.is_empty() {
        return Ok(None);
    }
    // Source images already embedded, so that one image used with two samplers (two
    // textures) is stored once.
    let mut kept: Vec<(&EncodedImage, Index<json::Image>)> = Vec::new();
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
                    let src = source.map(|s| &s.textures[t as usize]);
                    let name = src.map_or_else(|| format!("texture{t}"), |s| s.name.clone());
                    let encoded = src
                        .filter(|s| same_texels(s, tx))
                        .and_then(|s| s.encoded.as_ref());
                    let image = match encoded {
                        Some(e) => match kept.iter().find(|(k, _)| *k == e) {
                            Some(&(_, image)) => image,
                            None => {
                                let image = bin.image(&e.bytes, e.format.mime_type(), name.clone());
                                kept.push((e, image));
                                image
                            }
                        },
                        None => {
                            let png = straight::encode_png(tx.width, tx.height, &tx.texels)?;
                            bin.image(&png, "image/png", name.clone())
                        }
                    };
                    let i = bin.texture(image, name, s);
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
        let name = source.map_or_else(
            || format!("trunk/material{m}"),
            |s| s.materials[m as usize].name.clone(),
        );
        let mat = material(
            bin.root,
            name,
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

/// The `.glb` bytes of `asset` (validated first), whatever `opts.container` says.
pub fn cloud_glb_bytes(asset: &CloudAsset, opts: &GltfOptions) -> Result<Vec<u8>, GltfError> {
    cloud_glb_bytes_with(asset, opts, None)
}

/// [`cloud_glb_bytes`] with the atlases' level-0 PNGs already encoded
/// ([`straight::atlas_pngs`], in atlas order), so a caller that also dumps them encodes
/// them once.
pub fn cloud_glb_bytes_with(
    asset: &CloudAsset,
    opts: &GltfOptions,
    atlas_pngs: Option<&[Vec<u8>]>,
) -> Result<Vec<u8>, GltfError> {
    let opts = GltfOptions {
        container: GltfContainer::Glb,
        ..*opts
    };
    cloud_gltf_bytes_with(asset, &opts, atlas_pngs)
}

/// The glTF bytes of `asset` (validated first) in `opts.container`: a `.glb`, or a
/// self-contained `.gltf`.
pub fn cloud_gltf_bytes(asset: &CloudAsset, opts: &GltfOptions) -> Result<Vec<u8>, GltfError> {
    cloud_gltf_bytes_with(asset, opts, None)
}

/// [`cloud_gltf_bytes`] with the atlases' level-0 PNGs already encoded
/// ([`straight::atlas_pngs`], in atlas order), so a caller that also dumps them encodes
/// them once.
pub fn cloud_gltf_bytes_with(
    asset: &CloudAsset,
    opts: &GltfOptions,
    atlas_pngs: Option<&[Vec<u8>]>,
) -> Result<Vec<u8>, GltfError> {
    let encode = |message: String| GltfError::Encode {
        path: PathBuf::new(),
        message,
    };
    if atlas_pngs.is_some_and(|p| p.len() != asset.atlases.len()) {
        return Err(encode("one PNG per atlas expected".into()));
    }
    asset.validate().map_err(|source| GltfError::InvalidAsset {
        path: PathBuf::new(),
        source,
    })?;
    let has_normals = asset.atlases.iter().all(|a| a.normals.is_some());
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(asset.header.tool.clone()),
            ..Default::default()
        },
        extensions_used: if has_normals {
            Vec::new()
        } else {
            vec!["KHR_materials_unlit".into()]
        },
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
    let own: Vec<Vec<u8>>;
    let pngs: &[Vec<u8>] = match atlas_pngs {
        Some(p) => p,
        None => {
            use rayon::prelude::*;
            own = asset
                .atlases
                .par_iter()
                .map(straight::atlas_png)
                .collect::<Result<_, _>>()
                .map_err(encode)?;
            &own
        }
    };
    let normal_pngs: Vec<Vec<u8>> = if has_normals {
        use rayon::prelude::*;
        asset
            .atlases
            .par_iter()
            .map(|a| {
                let n = &a.normals.as_ref().expect("checked")[0];
                let rgb: Vec<u8> = n.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
                straight::encode_png_rgb(a.width, a.height, &rgb)
            })
            .collect::<Result<_, _>>()
            .map_err(encode)?
    } else {
        Vec::new()
    };
    let mut atlas_mats = Vec::new();
    for (l, lv) in asset.levels.iter().enumerate() {
        for k in 0..lv.atlas_count as usize {
            let a = lv.first_atlas as usize + k;
            let tex = bin.png_texture(&pngs[a], format!("lod{l}/atlas{k}"), clamp);
            let ntex = normal_pngs
                .get(a)
                .map(|png| bin.png_texture(png, format!("lod{l}/atlas{k}/normal"), clamp));
            let side = |bin: &mut Bin<'_>, s: &str| {
                let m = material(
                    bin.root,
                    format!("lod{l}/atlas{k}/{s}"),
                    [1.0; 4],
                    Some(tex),
                    alpha,
                    false,
                    !has_normals,
                );
                if let Some(index) = ntex {
                    bin.root.materials[m.value()].normal_texture =
                        Some(json::material::NormalTexture {
                            index,
                            scale: 1.0,
                            tex_coord: 0,
                            extensions: None,
                            extras: None,
                        });
                }
                m
            };
            atlas_mats.push([side(&mut bin, "front"), side(&mut bin, "back")]);
        }
    }
    let trunk = trunk_mesh(&mut bin, asset, &asset.trunk, opts.source).map_err(encode)?;
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
            let u = tangent(&b.corners, glam::Vec3::from(n));
            groups
                .entry((b.front.atlas, 0))
                .or_default()
                .push(c, pc, n, [u.x, u.y, u.z, -1.0], f);
            // Back: reversed order (0, 3, 2, 1) faces −n; same UV per corner.
            let bk = uv(&b.back);
            let r = [0, 3, 2, 1];
            groups.entry((b.back.atlas, 1)).or_default().push(
                r.map(|i| c[i]),
                r.map(|i| pc[i]),
                [-n[0], -n[1], -n[2]],
                [u.x, u.y, u.z, 1.0],
                r.map(|i| bk[i]),
            );
        }
        let mut prims = Vec::new();
        for ((a, side), q) in &groups {
            let mat = atlas_mats[*a as usize][*side];
            prims.push(primitive(&mut bin, q, has_normals, mat));
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
    let embedded = opts.container == GltfContainer::Embedded;
    root.push(json::Buffer {
        byte_length: USize64(data.len() as u64),
        name: None,
        uri: embedded.then(|| format!("data:application/octet-stream;base64,{}", base64(&data))),
        extensions: None,
        extras: None,
    });
    if embedded {
        let mut text = root.to_vec_pretty().map_err(|e| encode(e.to_string()))?;
        text.push(b'\n');
        return Ok(text);
    }
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
