//! Wavefront OBJ + MTL import (OBJ statements via `tobj`, triangulated, single index; MTL
//! libraries parsed here).
//!
//! Text: UTF-8 (a byte-order mark is skipped; bytes that are not UTF-8 become U+FFFD) or
//! UTF-16 LE/BE, with a byte-order mark or recognised by its NUL bytes; the same for MTL
//! libraries. Only faces (`f` with three or more vertices) are imported: `p` and `l`
//! statements (and `f` with fewer vertices) are counted in one warning per file. An
//! import without a single triangle is a warning that says why (no face; or statements
//! that are not OBJ, naming the first), and so are an MTL library that defines no material
//! and a `usemtl` that names a material no library defines.
//!
//! MTL statements are parsed one by one: one whose values do not parse is ignored with a
//! warning naming its line (the rest of the library is kept). Colours take one value
//! (grey: g = b = r, as the MTL specification says and Blender writes `Ks 0`), three, or
//! `xyz` and CIE XYZ values; `d -halo f` is read as `d f`.
//!
//! Material mapping (MTL → [`Material`]):
//! - `Kd` → base colour factor RGB, taken as **linear** (as Blender's importer does);
//!   `d` (or `1 - Tr` when `d` is absent) → factor alpha;
//! - `map_Kd` (RGB) and `map_d` (its alpha channel if it has one, else its luminance)
//!   are combined into one RGBA texture; texture paths may contain spaces or `\`
//!   and are resolved relative to the MTL file's folder; leading options (`-s 1 1 1`,
//!   `-bm 0.5`, ...) are skipped;
//! - alpha mode: `map_d` present → `Mask { cutoff: 0.5 }` (foliage cut-outs), else
//!   `d < 1` → `Blend`, else `Opaque`;
//! - double-sided: OBJ has no such flag, so materials with `map_d` or `d < 1` (cut-outs
//!   and see-through surfaces, whose back faces are visible) are double-sided and all
//!   others single-sided.
//!
//! UV `v` is flipped (OBJ's origin is bottom-left, the scene's top-left). Vertex
//! colours (`v x y z r g b`) are taken as linear.

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::mtl::{parse_mtl, MtlMaterial, MtlNotes, UNNAMED_MATERIAL};
use super::text::{decode_text, shown};
use super::{face_normal, images, reserve, resolve_relative, Ctx, ImportError};
use crate::scene::{AlphaMode, Material, SceneBuilder, Texture, Triangle, Vertex};

pub(super) fn load(path: &Path, ctx: &mut Ctx) -> Result<SceneBuilder, ImportError> {
    let raw = super::read_input(path).map_err(|e| ctx.io(path, e))?;
    // Real exporters write bytes that are not UTF-8 (a Latin-1 `©` in a 3ds Max comment or
    // group name), UTF-16 (Windows tools) and statements tobj refuses although they are
    // harmless (a bare `usemtl`): all are made acceptable here; what is still refused is
    // reported with its line.
    let (text, scan) = tolerate_obj(&decode_text(&raw));
    drop(raw);
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    // The index check runs before tobj's parse, not beside it: tobj overflows on some
    // out-of-range indices (`vt * 2` on a negative index past the start, a panic with
    // overflow checks; found by the obj_import fuzzer), and only the check reports them.
    check_face_indices(&text, ctx)?;
    let bytes = text.into_bytes();
    // MTL libraries are read and parsed here (tobj's MTL parser drops a whole library over
    // one statement it does not expect); tobj gets their material names, to resolve
    // `usemtl`, and `materials` the same list in the same order with what billow uses.
    let materials: RefCell<Vec<MtlMaterial>> = RefCell::new(Vec::new());
    let libraries: RefCell<Vec<(PathBuf, Result<MtlNotes, String>)>> = RefCell::new(Vec::new());
    let parsed = tobj::load_obj_buf(&mut Cursor::new(&bytes), &OBJ_OPTIONS, |mtl: &Path| {
        let p = resolve_relative(&dir, &mtl.to_string_lossy());
        let raw = match ctx.read_referenced(&p) {
            Ok(raw) => raw,
            Err(e) => {
                libraries.borrow_mut().push((p, Err(e.to_string())));
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        let folder = p.parent().unwrap_or(Path::new(".")).to_path_buf();
        let (mats, notes) = parse_mtl(&decode_text(&raw), &folder);
        let list = mats
            .iter()
            .map(|m| tobj::Material {
                name: m.name.clone(),
                ..Default::default()
            })
            .collect();
        // A later material of the same name wins, as in tobj.
        let names = mats
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), i))
            .collect();
        materials.borrow_mut().extend(mats);
        libraries.borrow_mut().push((p, Ok(notes)));
        Ok((list, names))
    });
    let (materials, libraries) = (materials.into_inner(), libraries.into_inner());
    let (models, _) = parsed.map_err(|e| {
        let at = failing_line(&bytes, |prefix| {
            tobj::load_obj_buf(&mut Cursor::new(prefix), &OBJ_OPTIONS, |_| {
                Ok((Vec::new(), Default::default()))
            })
            .err()
        });
        match e {
            tobj::LoadError::FaceVertexOutOfBounds
            | tobj::LoadError::FaceTexCoordOutOfBounds
            | tobj::LoadError::FaceNormalOutOfBounds
            | tobj::LoadError::FaceColorOutOfBounds
            | tobj::LoadError::InvalidPolygon => ctx.invalid(format!("{at}{e}")),
            _ => ctx.parse(format!("{at}{e}")),
        }
    })?;
    let mut all_loaded = true;
    for (p, r) in &libraries {
        match r {
            Err(e) => {
                all_loaded = false;
                ctx.warn(format!(
                    "material library {} not loaded ({e}); using default materials",
                    p.display()
                ))?;
            }
            Ok(notes) => {
                for w in notes.warnings(p) {
                    ctx.warn(w)?;
                }
            }
        }
    }
    // A `usemtl` that names no material is drawn with the default material: said, unless
    // a library that was not loaded already explains it. A bare `usemtl` (no name) means
    // the default material and is not reported.
    let undefined: Vec<&String> = scan
        .usemtl
        .iter()
        .filter(|n| *n != UNNAMED_MATERIAL && !materials.iter().any(|m| &m.name == *n))
        .collect();
    if all_loaded && !undefined.is_empty() {
        let shown: Vec<String> = undefined.iter().take(5).map(|n| format!("'{n}'")).collect();
        let more = if undefined.len() > 5 { ", …" } else { "" };
        let what = if undefined.len() == 1 {
            "a material".to_string()
        } else {
            format!("{} materials", undefined.len())
        };
        ctx.warn(format!(
            "usemtl names {what} that no material library defines ({}{more}); their faces use \
             the default material",
            shown.join(", ")
        ))?;
    }
    if let Some(w) = scan.skipped_warning() {
        ctx.warn(w)?;
    }
    let mut b = SceneBuilder::new();
    let mut tex_cache: HashMap<(Option<PathBuf>, Option<PathBuf>), Option<u32>> = HashMap::new();
    let mut mat_map: HashMap<usize, u32> = HashMap::new();
    let mut default_material = None;

    for (oi, model) in models.iter().enumerate() {
        let name = if model.name.is_empty() {
            format!("object {oi}")
        } else {
            model.name.clone()
        };
        let m = &model.mesh;
        let n = m.positions.len() / 3;
        if let Some(k) = m.positions.iter().position(|x| !x.is_finite()) {
            let p = &m.positions[k / 3 * 3..k / 3 * 3 + 3];
            return Err(ctx.invalid(format!(
                "object '{name}': non-finite vertex position ({}, {}, {})",
                p[0], p[1], p[2]
            )));
        }
        if let Some(&bad) = m.indices.iter().find(|&&i| i as usize >= n) {
            return Err(ctx.invalid(format!(
                "object '{name}': vertex index {bad} out of range ({n} vertices)"
            )));
        }
        let material = match m.material_id.filter(|&i| i < materials.len()) {
            Some(i) => match mat_map.get(&i) {
                Some(&s) => s,
                None => {
                    let mat = convert_material(&materials[i], &mut b, &mut tex_cache, ctx)?;
                    let idx = b.material(mat);
                    mat_map.insert(i, idx);
                    idx
                }
            },
            None => *default_material.get_or_insert_with(|| b.material(Material::default())),
        };
        let mesh_id = b.mesh(name);
        let ntri = m.indices.len() / 3;
        reserve(&mut b, ntri, ctx)?;
        let pos = |i: usize| {
            Vec3::new(
                m.positions[3 * i],
                m.positions[3 * i + 1],
                m.positions[3 * i + 2],
            )
        };
        let has_normals = m.normals.len() == m.positions.len();
        let has_uv = m.texcoords.len() == 2 * n;
        let has_color = m.vertex_color.len() == m.positions.len();
        for t in m.indices.chunks_exact(3) {
            let p = [pos(t[0] as usize), pos(t[1] as usize), pos(t[2] as usize)];
            let fallback = face_normal(p[0], p[1], p[2]);
            let v = [0, 1, 2].map(|k| {
                let i = t[k] as usize;
                let normal = if has_normals {
                    Vec3::new(m.normals[3 * i], m.normals[3 * i + 1], m.normals[3 * i + 2])
                        .try_normalize()
                        .unwrap_or(fallback)
                } else {
                    fallback
                };
                let uv = if has_uv {
                    Vec2::new(m.texcoords[2 * i], 1.0 - m.texcoords[2 * i + 1])
                } else {
                    Vec2::ZERO
                };
                let color = if has_color {
                    Vec4::new(
                        m.vertex_color[3 * i],
                        m.vertex_color[3 * i + 1],
                        m.vertex_color[3 * i + 2],
                        1.0,
                    )
                } else {
                    Vec4::ONE
                };
                Vertex {
                    position: p[k],
                    normal,
                    uv,
                    color,
                }
            });
            b.push(Triangle {
                v,
                material,
                mesh: mesh_id,
            });
        }
    }
    if b.offered() == 0 {
        ctx.warn(scan.no_triangles())?;
    }
    Ok(b)
}

fn convert_material(
    m: &MtlMaterial,
    b: &mut SceneBuilder,
    cache: &mut HashMap<(Option<PathBuf>, Option<PathBuf>), Option<u32>>,
    ctx: &mut Ctx,
) -> Result<Material, ImportError> {
    let kd = m.kd.unwrap_or([1.0; 3]);
    let d = m.d.or(m.tr.map(|t| 1.0 - t)).unwrap_or(1.0);
    let d = if d.is_finite() {
        d.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let factor = Vec4::new(kd[0], kd[1], kd[2], d);
    if !factor.is_finite() {
        return Err(ctx.invalid(format!("material '{}': non-finite Kd", m.name)));
    }
    let map = |s: &Option<String>| {
        s.as_deref()
            .map(strip_map_options)
            .filter(|s| !s.is_empty())
            .map(|s| s.replace('\\', "/"))
    };
    let (kd_name, d_name) = (map(&m.map_kd), map(&m.map_d));
    let dir = m.dir.as_path();
    let (alpha_mode, double_sided) = if d_name.is_some() {
        (AlphaMode::Mask { cutoff: 0.5 }, true)
    } else if d < 1.0 {
        (AlphaMode::Blend, true)
    } else {
        (AlphaMode::Opaque, false)
    };
    let kd_path = kd_name.as_ref().map(|n| resolve_relative(dir, n));
    let d_path = d_name.as_ref().map(|n| resolve_relative(dir, n));
    let key = (kd_path.clone(), d_path.clone());
    let texture = match cache.get(&key) {
        Some(&t) => t,
        None => {
            let label = format!("material '{}'", m.name);
            let color = match (&kd_name, &kd_path) {
                (Some(n), Some(p)) => load_texture(n, p, &label, "map_Kd", ctx)?,
                _ => None,
            };
            let alpha = match (&d_name, &d_path) {
                (Some(n), Some(p)) if d_path != kd_path => {
                    load_texture(n, p, &label, "map_d", ctx)?
                }
                (Some(_), _) => color.clone(),
                _ => None,
            };
            let combined = match (color, alpha) {
                (Some(mut c), Some(a)) => {
                    images::combine_alpha(&mut c, &a);
                    if kd_path != d_path {
                        c.name = format!("{} (alpha: {})", c.name, a.name);
                    }
                    Some(c)
                }
                (Some(c), None) => Some(c),
                (None, Some(a)) => {
                    let mut w = images::white_like(&a, &a.name);
                    images::combine_alpha(&mut w, &a);
                    Some(w)
                }
                (None, None) => None,
            };
            let idx = combined.map(|t| b.texture(t));
            cache.insert(key, idx);
            idx
        }
    };
    Ok(Material {
        name: m.name.clone(),
        base_color_factor: factor,
        base_color_texture: texture,
        alpha_mode,
        double_sided,
        unlit: false,
    })
}

/// Loads and decodes one MTL texture; a failure is a warning and `None`.
fn load_texture(
    name: &str,
    path: &Path,
    label: &str,
    slot: &str,
    ctx: &mut Ctx,
) -> Result<Option<Texture>, ImportError> {
    let r = ctx
        .read_referenced(path)
        .map_err(|e| format!("{}: {e}", path.display()))
        .and_then(|bytes| images::decode(&bytes, name, None));
    ctx.texture(name, r.is_ok());
    match r {
        Ok(t) => Ok(Some(t)),
        Err(e) => {
            ctx.warn(format!(
                "{label}: {slot} '{name}' not loaded ({e}); using the factor colour"
            ))?;
            Ok(None)
        }
    }
}

/// Skips leading MTL texture options (`-o u v w`, `-bm 0.5`, `-clamp on`, ...) and
/// returns the file name, which may contain spaces.
fn strip_map_options(s: &str) -> &str {
    let mut rest = s.trim();
    while rest.starts_with('-') {
        let (opt, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
        rest = after.trim_start();
        let max_args = match opt {
            "-o" | "-s" | "-t" => 3,
            "-mm" => 2,
            _ => 1,
        };
        let numeric = matches!(
            opt,
            "-o" | "-s" | "-t" | "-mm" | "-bm" | "-boost" | "-texres"
        );
        for _ in 0..max_args {
            let (tok, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
            if tok.is_empty() || after.trim().is_empty() || (numeric && tok.parse::<f32>().is_err())
            {
                break;
            }
            rest = after.trim_start();
        }
    }
    rest
}

const OBJ_OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    triangulate: true,
    single_index: true,
    ignore_points: true,
    ignore_lines: true,
};

/// Statement keywords of the OBJ format (including free-form geometry, which billow does
/// not import): a line starting with anything else is not understood.
const OBJ_KEYWORDS: &[&str] = &[
    "v",
    "vt",
    "vn",
    "vp",
    "f",
    "fo",
    "l",
    "p",
    "o",
    "g",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "trace_obj",
    "shadow_obj",
    "ctech",
    "stech",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "call",
    "csh",
];

/// What [`tolerate_obj`] saw: the statements, those skipped and those not understood.
#[derive(Debug, Default)]
struct ObjScan {
    /// Non-blank lines that are not comments.
    statements: usize,
    vertices: usize,
    /// `f` statements with at least three vertices.
    faces: usize,
    /// `f` statements with one or two vertices (tobj drops them).
    short_faces: usize,
    points: usize,
    lines: usize,
    /// Statements whose keyword is not OBJ, and the first of them (line number, text).
    unknown: usize,
    first_unknown: Option<(usize, String)>,
    /// The material names `usemtl` selects, each once, in order.
    usemtl: Vec<String>,
}

impl ObjScan {
    /// The warning for the `p`, `l` and short `f` statements skipped, if any.
    fn skipped_warning(&self) -> Option<String> {
        let plural =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let mut kinds = Vec::new();
        if self.points > 0 {
            kinds.push(format!("{} point (`p`)", self.points));
        }
        if self.lines > 0 {
            kinds.push(format!("{} line (`l`)", self.lines));
        }
        let mut parts = Vec::new();
        if !kinds.is_empty() {
            let n = self.points + self.lines;
            let noun = if n == 1 { "statement" } else { "statements" };
            parts.push(format!("{} {noun}", kinds.join(" and ")));
        }
        if self.short_faces > 0 {
            parts.push(format!(
                "{} (`f`) with fewer than three vertices",
                plural(self.short_faces, "face", "faces")
            ));
        }
        (!parts.is_empty()).then(|| {
            format!(
                "{} skipped (only faces of three or more vertices are imported)",
                parts.join(" and ")
            )
        })
    }

    /// The warning for an import without a single triangle: why there is none.
    fn no_triangles(&self) -> String {
        if let Some((line, text)) = &self.first_unknown {
            format!(
                "no triangles: {} of its {} statements are not OBJ (the first, line {line}: \
                 '{}'); is it a text OBJ file (UTF-8 or UTF-16)?",
                self.unknown,
                self.statements,
                shown(text)
            )
        } else if self.statements == 0 {
            "no triangles: the file holds no statements".to_string()
        } else {
            format!(
                "no triangles: no face (`f` with three or more vertices) among its {} \
                 statements ({} vertices)",
                self.statements, self.vertices
            )
        }
    }
}

/// The OBJ text with the statements tobj would mishandle rewritten, and what it holds
/// ([`ObjScan`]): a bare `usemtl` selects [`UNNAMED_MATERIAL`] (tobj requires a name); `p`
/// and `l` statements are blanked (billow imports faces only, and tobj would make a
/// triangle of a three-vertex `l`). Line numbers are kept.
fn tolerate_obj(text: &str) -> (String, ObjScan) {
    let mut scan = ObjScan::default();
    let mut out = String::with_capacity(text.len() + 16);
    for (n, line) in text.split_inclusive('\n').enumerate() {
        let body = line.trim_end_matches(['\n', '\r']);
        let ending = &line[body.len()..];
        let t = body.trim();
        if t.is_empty() || t.starts_with('#') {
            out.push_str(line);
            continue;
        }
        scan.statements += 1;
        let mut words = t.split_whitespace();
        let keyword = words.next().unwrap_or_default();
        match keyword {
            "usemtl" => {
                let name = t["usemtl".len()..].trim();
                let name = if name.is_empty() {
                    out.push_str("usemtl ");
                    out.push_str(UNNAMED_MATERIAL);
                    out.push_str(ending);
                    UNNAMED_MATERIAL
                } else {
                    out.push_str(line);
                    name
                };
                if !scan.usemtl.iter().any(|u| u == name) {
                    scan.usemtl.push(name.to_string());
                }
                continue;
            }
            "p" | "l" => {
                if keyword == "p" {
                    scan.points += 1;
                } else {
                    scan.lines += 1;
                }
                out.push_str(ending);
                continue;
            }
            "f" if words.by_ref().count() >= 3 => scan.faces += 1,
            "f" => scan.short_faces += 1,
            "v" => scan.vertices += 1,
            k if OBJ_KEYWORDS.contains(&k) => {}
            _ => {
                scan.unknown += 1;
                if scan.first_unknown.is_none() {
                    scan.first_unknown = Some((n + 1, t.to_string()));
                }
            }
        }
        out.push_str(line);
    }
    (out, scan)
}

/// `"line N: '<text>': "` for the first line of `text` at which `parse` (run on a prefix
/// of whole lines) fails, found by bisection over the line count; empty if no prefix
/// fails (an error found only at the end of the file). Only run on the error path.
fn failing_line<E>(text: &[u8], parse: impl Fn(&[u8]) -> Option<E>) -> String {
    let ends: Vec<usize> = text
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .map(|(i, _)| i + 1)
        .chain((text.last() != Some(&b'\n')).then_some(text.len()))
        .collect();
    // Smallest k such that the first k lines fail.
    let (mut lo, mut hi) = (1usize, ends.len());
    if ends.is_empty() || parse(&text[..ends[hi - 1]]).is_none() {
        return String::new();
    }
    while lo < hi {
        let mid = (lo + hi) / 2;
        if parse(&text[..ends[mid - 1]]).is_some() {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let start = if lo >= 2 { ends[lo - 2] } else { 0 };
    let line = String::from_utf8_lossy(&text[start..ends[lo - 1]]);
    let line = line.trim();
    let shown: String = line.chars().take(60).collect();
    let more = if line.chars().count() > 60 { "…" } else { "" };
    format!("line {lo}: '{shown}{more}': ")
}

/// Checks every face index before `tobj` sees it: 0, negative indices that resolve
/// before the first element, and positive indices past the end are errors naming the
/// object and line.
fn check_face_indices(text: &str, ctx: &Ctx) -> Result<(), ImportError> {
    let mut totals = [0i64; 3];
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let mut seen = [0i64; 3];
    let mut object = String::from("(unnamed)");
    const KIND: [&str; 3] = ["vertex", "texcoord", "normal"];
    for (ln, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => seen[0] += 1,
            Some("vt") => seen[1] += 1,
            Some("vn") => seen[2] += 1,
            Some("o") | Some("g") => object = words.collect::<Vec<_>>().join(" "),
            Some("f") => {
                for w in words {
                    for (k, part) in w.split('/').enumerate().take(3) {
                        if part.is_empty() {
                            continue;
                        }
                        let Ok(x) = part.parse::<i64>() else {
                            return Err(ctx.parse(format!(
                                "object '{object}', line {}: bad face index {part:?}",
                                ln + 1
                            )));
                        };
                        let ok = if x < 0 {
                            seen[k] + x >= 0
                        } else {
                            x >= 1 && x <= totals[k]
                        };
                        if !ok {
                            return Err(ctx.invalid(format!(
                                "object '{object}', line {}: face {} index {x} out of range ({} defined)",
                                ln + 1,
                                KIND[k],
                                if x < 0 { seen[k] } else { totals[k] }
                            )));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::strip_map_options;

    #[test]
    fn map_options() {
        assert_eq!(strip_map_options("leaf.png"), "leaf.png");
        assert_eq!(strip_map_options("  my leaf.png "), "my leaf.png");
        assert_eq!(
            strip_map_options("-s 1 1 1 -bm 0.5 tex dir\\a b.png"),
            "tex dir\\a b.png"
        );
        assert_eq!(strip_map_options("-clamp on a.png"), "a.png");
        assert_eq!(strip_map_options("-o 0.5 x.png"), "x.png");
    }
}
