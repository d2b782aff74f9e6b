//! glTF 2.0 (`.gltf` / `.glb`) import.
//!
//! The document is parsed with the `gltf` crate (`json` only, no validation: its
//! validator indexes arrays unchecked and can panic on hostile files), and everything
//! else — buffers, accessors, images, node hierarchy — is resolved and bounds-checked
//! here, so that a missing image is a warning, not a failed import.
//!
//! Scene selection: the default `scene` if set, else every root node; a file with
//! meshes but no nodes at all imports each mesh untransformed. The hierarchy must be a
//! tree (a cycle, or a node with two parents, is an error rather than a hang or an
//! exponential expansion). Only the base colour texture is loaded (the report's textures
//! are only base colour images); `KHR_texture_transform` on it is baked into the vertex
//! UVs, and its `texCoord` picks which `TEXCOORD_n` becomes the vertex UV.

use std::collections::HashMap;
use std::path::Path;

use ::gltf::json;
use glam::{Mat2, Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use json::accessor::Type;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;

use super::accessor::{Accessors, Buffers};
use super::{face_normal, reserve, Ctx, ImportError};
use crate::scene::{SceneBuilder, Triangle, Vertex};
use glb::{split_glb, GlbError};

mod glb;
mod material;

/// `extensionsRequired` entries this importer honours. Anything else is refused.
pub const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "KHR_materials_unlit",
];

pub(super) fn load(path: &Path, ctx: &mut Ctx) -> Result<SceneBuilder, ImportError> {
    let bytes = crate::import::read_input(path).map_err(|e| ctx.io(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        let (j, b) = split_glb(&bytes).map_err(|e| match e {
            GlbError::Version(v) => {
                ctx.unsupported(format!("GLB container version {v} (only 2 is supported)"))
            }
            GlbError::Malformed(m) => ctx.parse(format!("malformed GLB: {m}")),
        })?;
        (j, b.map(<[u8]>::to_vec))
    } else {
        (&bytes[..], None)
    };
    let root = parse_json(json_bytes).map_err(|e| match e {
        JsonProblem::Json(e) => ctx.parse(format!("glTF JSON: {e}")),
        JsonProblem::Version(v) => ctx.unsupported(format!(
            "glTF version {v} (only glTF 2.0 is supported; convert older files, e.g. with \
             the Khronos glTF 1.0 to 2.0 converter or Blender)"
        )),
    })?;
    drop(bytes);
    for ext in &root.extensions_required {
        if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(ctx.unsupported(format!("required extension {ext} is not supported")));
        }
    }
    let mut imp = Importer {
        root: &root,
        base,
        acc: Accessors {
            root: &root,
            buffers: Buffers::new(&root, blob, base),
        },
        b: SceneBuilder::new(),
        materials: HashMap::new(),
        default_material: None,
        images: HashMap::new(),
        meshes: HashMap::new(),
    };
    imp.walk(ctx)?;
    Ok(imp.b)
}

/// What a glTF material became in the scene, plus how to compute its UVs.
#[derive(Clone, Copy)]
struct MatInfo {
    index: u32,
    tex_coord: u32,
    uv_transform: Option<(Mat2, Vec2)>,
}

struct Importer<'a> {
    root: &'a json::Root,
    base: &'a Path,
    acc: Accessors<'a>,
    b: SceneBuilder,
    materials: HashMap<usize, MatInfo>,
    default_material: Option<u32>,
    /// (image, wrap_u, wrap_v) → scene texture index (None: failed to load).
    images: HashMap<(usize, u8, u8), Option<u32>>,
    /// (mesh, primitive) → scene mesh index.
    meshes: HashMap<(usize, usize), u32>,
}

fn name_or(name: &Option<String>, kind: &str, i: usize) -> String {
    match name {
        Some(n) if !n.is_empty() => format!("{kind} {i} '{n}'"),
        _ => format!("{kind} {i}"),
    }
}

impl Importer<'_> {
    fn walk(&mut self, ctx: &mut Ctx) -> Result<(), ImportError> {
        let nodes = &self.root.nodes;
        if nodes.is_empty() {
            // No node hierarchy at all: import every mesh untransformed rather than nothing.
            for mi in 0..self.root.meshes.len() {
                self.mesh(mi, Mat4::IDENTITY, ctx)?;
            }
            return Ok(());
        }
        // Hierarchy checks: valid child indices, at most one parent, no cycles.
        let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            for c in n.children.iter().flatten() {
                let c = c.value();
                if c >= nodes.len() {
                    return Err(ctx.invalid(format!(
                        "{}: child {c} does not exist",
                        name_or(&n.name, "node", i)
                    )));
                }
                if c == i {
                    return Err(ctx.invalid(format!(
                        "node hierarchy has a loop: node {i} is its own child"
                    )));
                }
                if let Some(p) = parent[c] {
                    return Err(ctx.invalid(format!(
                        "node {c} has two parents ({p} and {i}); the hierarchy must be a tree"
                    )));
                }
                parent[c] = Some(i);
            }
        }
        for start in 0..nodes.len() {
            // With one parent each, following parents either ends at a root or cycles.
            let (mut cur, mut steps) = (start, 0usize);
            while let Some(p) = parent[cur] {
                cur = p;
                steps += 1;
                if cur == start || steps > nodes.len() {
                    return Err(
                        ctx.invalid(format!("node hierarchy has a loop through node {start}"))
                    );
                }
            }
        }
        let roots: Vec<usize> = match self.root.scene {
            Some(s) => {
                let scene = self.root.scenes.get(s.value()).ok_or_else(|| {
                    ctx.invalid(format!("default scene {} does not exist", s.value()))
                })?;
                scene.nodes.iter().map(|n| n.value()).collect()
            }
            None => (0..nodes.len()).filter(|&i| parent[i].is_none()).collect(),
        };
        let mut visited = vec![false; nodes.len()];
        let mut stack: Vec<(usize, Mat4)> =
            roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
        while let Some((i, parent_world)) = stack.pop() {
            let node = nodes
                .get(i)
                .ok_or_else(|| ctx.invalid(format!("scene node {i} does not exist")))?;
            if std::mem::replace(&mut visited[i], true) {
                return Err(ctx.invalid(format!(
                    "node {i} is reached twice from the scene (listed as a root and as a child?)"
                )));
            }
            let world = parent_world
                * local_transform(node).ok_or_else(|| {
                    ctx.invalid(format!(
                        "{}: non-finite transform",
                        name_or(&node.name, "node", i)
                    ))
                })?;
            if !world.is_finite() {
                return Err(ctx.invalid(format!(
                    "{}: world transform is not finite",
                    name_or(&node.name, "node", i)
                )));
            }
            if let Some(m) = node.mesh {
                self.mesh(m.value(), world, ctx)?;
            }
            for c in node.children.iter().flatten().rev() {
                stack.push((c.value(), world));
            }
        }
        Ok(())
    }

    fn mesh(&mut self, mi: usize, world: Mat4, ctx: &mut Ctx) -> Result<(), ImportError> {
        let mesh = self
            .root
            .meshes
            .get(mi)
            .ok_or_else(|| ctx.invalid(format!("mesh {mi} does not exist")))?;
        let mesh_name = name_or(&mesh.name, "mesh", mi);
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            let what = format!("{mesh_name} primitive {pi}");
            let mode = match prim.mode {
                Checked::Valid(m) => m,
                Checked::Invalid => return Err(ctx.invalid(format!("{what}: invalid mode"))),
            };
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                ctx.warn(format!(
                    "{what}: {mode:?} primitive skipped (only triangles are imported)"
                ))?;
                continue;
            }
            self.primitive(mi, pi, &what, prim, mode, world, ctx)?;
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn primitive(
        &mut self,
        mi: usize,
        pi: usize,
        what: &str,
        prim: &json::mesh::Primitive,
        mode: Mode,
        world: Mat4,
        ctx: &mut Ctx,
    ) -> Result<(), ImportError> {
        let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|i| i.value());
        let Some(pos_acc) = attr(Semantic::Positions) else {
            // Allowed by the spec; such a primitive is not rendered.
            return ctx.warn(format!("{what}: no POSITION attribute, skipped"));
        };
        let mat = self.material(prim.material.map(|m| m.value()), ctx)?;
        let positions = self
            .acc
            .read(pos_acc, &[Type::Vec3], ctx, what, "POSITION")?;
        let n = positions.len();
        if let Some((k, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(ctx.invalid(format!(
                "{what}: non-finite vertex position {} at vertex {k}",
                p.truncate()
            )));
        }
        let mut read_attr = |s: Semantic,
                             types: &[Type],
                             label: &str,
                             ctx: &mut Ctx|
         -> Result<Option<Vec<Vec4>>, ImportError> {
            let Some(a) = attr(s) else { return Ok(None) };
            let v = self.acc.read(a, types, ctx, what, label)?;
            if v.len() != n {
                return Err(ctx.invalid(format!(
                    "{what}: {label} has {} elements but POSITION has {n}",
                    v.len()
                )));
            }
            Ok(Some(v))
        };
        let normals = read_attr(Semantic::Normals, &[Type::Vec3], "NORMAL", ctx)?;
        let colors = read_attr(
            Semantic::Colors(0),
            &[Type::Vec3, Type::Vec4],
            "COLOR_0",
            ctx,
        )?;
        let uvs = read_attr(
            Semantic::TexCoords(mat.tex_coord),
            &[Type::Vec2],
            "TEXCOORD",
            ctx,
        )?;
        let indices: Vec<u32> = match prim.indices {
            Some(ia) => {
                let idx = self.acc.read_indices(ia.value(), ctx, what)?;
                if let Some((k, &bad)) = idx.iter().enumerate().find(|(_, &v)| v as usize >= n) {
                    return Err(ctx.invalid(format!(
                        "{what}: index {bad} at position {k} is out of range ({n} vertices)"
                    )));
                }
                idx
            }
            None => (0..n as u32).collect(),
        };
        let m = indices.len();
        let tris: Vec<[u32; 3]> = match mode {
            Mode::Triangles => indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            Mode::TriangleStrip => (0..m.saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    }
                })
                .collect(),
            _ => (1..m.saturating_sub(1))
                .map(|i| [indices[i], indices[i + 1], indices[0]])
                .collect(),
        };
        drop(indices);
        let mesh_id = match self.meshes.get(&(mi, pi)) {
            Some(&id) => id,
            None => {
                let mesh = &self.root.meshes[mi];
                let base = mesh
                    .name
                    .clone()
                    .filter(|s| !s.is_empty())
                    .unwrap_or_else(|| format!("mesh {mi}"));
                let name = if mesh.primitives.len() > 1 {
                    format!("{base}/{pi}")
                } else {
                    base
                };
                let id = self.b.mesh(name);
                self.meshes.insert((mi, pi), id);
                id
            }
        };
        reserve(&mut self.b, tris.len(), ctx)?;
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let flip = world.determinant() < 0.0;
        for t in tris {
            let order = if flip { [t[0], t[2], t[1]] } else { t };
            let p = order.map(|i| world.transform_point3(positions[i as usize].truncate()));
            let fallback = face_normal(p[0], p[1], p[2]);
            let v = [0, 1, 2].map(|k| {
                let i = order[k] as usize;
                let normal = normals
                    .as_ref()
                    .and_then(|ns| (normal_matrix * ns[i].truncate()).try_normalize())
                    .unwrap_or(fallback);
                let mut uv = uvs
                    .as_ref()
                    .map_or(Vec2::ZERO, |u| u[i].truncate().truncate());
                if let Some((r, off)) = mat.uv_transform {
                    uv = r * uv + off;
                }
                let color = colors.as_ref().map_or(Vec4::ONE, |c| c[i]);
                Vertex {
                    position: p[k],
                    normal,
                    uv,
                    color,
                }
            });
            self.b.push(Triangle {
                v,
                material: mat.index,
                mesh: mesh_id,
            });
        }
        Ok(())
    }
}

/// Parses the glTF JSON, first smoothing over what the `gltf-json` schema is stricter
/// about than the glTF spec in parts billow does not use: animations are dropped
/// (never imported), a scene without `nodes` gets an empty list, and integral numbers
/// written as floats (`1.0`) become integers.
/// Why the document could not be read as glTF 2.0.
enum JsonProblem {
    Json(serde_json::Error),
    /// `asset.version` says another major version (glTF 1.0 has a different schema).
    Version(String),
}

fn parse_json(bytes: &[u8]) -> Result<json::Root, JsonProblem> {
    fn integral(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Number(n) if !n.is_i64() && !n.is_u64() => {
                if let Some(f) = n.as_f64().filter(|f| f.fract() == 0.0 && f.abs() < 9.0e15) {
                    *v = serde_json::Value::from(f as i64);
                }
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(integral),
            serde_json::Value::Object(o) => o.values_mut().for_each(integral),
            _ => {}
        }
    }
    // A UTF-8 byte-order mark is not JSON, but editors on Windows write one.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut v: serde_json::Value = serde_json::from_slice(bytes).map_err(JsonProblem::Json)?;
    let version = match v.pointer("/asset/version") {
        Some(serde_json::Value::String(s)) => Some(s.clone()),
        Some(n @ serde_json::Value::Number(_)) => Some(n.to_string()),
        _ => None,
    };
    if let Some(version) = version {
        if version.split('.').next().map(str::trim) != Some("2") {
            return Err(JsonProblem::Version(version));
        }
    }
    if let Some(o) = v.as_object_mut() {
        o.remove("animations");
        if let Some(scenes) = o.get_mut("scenes").and_then(|s| s.as_array_mut()) {
            for s in scenes.iter_mut().filter_map(|s| s.as_object_mut()) {
                s.entry("nodes")
                    .or_insert_with(|| serde_json::Value::Array(Vec::new()));
            }
        }
    }
    integral(&mut v);
    serde_json::from_value(v).map_err(JsonProblem::Json)
}

/// The node's local transform, `None` when not finite.
fn local_transform(node: &json::scene::Node) -> Option<Mat4> {
    let m = if let Some(m) = node.matrix {
        Mat4::from_cols_array(&m)
    } else {
        let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
        let r = Quat::from_array(node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |q| q.0));
        let r = if r.length_squared() > 0.0 {
            r.normalize()
        } else {
            Quat::IDENTITY
        };
        let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
        Mat4::from_scale_rotation_translation(s, r, t)
    };
    m.is_finite().then_some(m)
}
