//! Wavefront OBJ + MTL import (via `tobj`, triangulated, single index).
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

use super::{face_normal, images, reserve, resolve_relative, Ctx, ImportError};
use crate::scene::{AlphaMode, Material, SceneBuilder, Texture, Triangle, Vertex};

pub(super) fn load(path: &Path, ctx: &mut Ctx) -> Result<SceneBuilder, ImportError> {
    let raw = super::read_input(path).map_err(|e| ctx.io(path, e))?;
    // Real exporters write bytes that are not UTF-8 (a Latin-1 `©` in a 3ds Max comment or
    // group name) and statements tobj refuses although they are harmless (a bare `usemtl`):
    // both are made acceptable here; what is still refused is reported with its line.
    let bytes = tolerate_obj(&String::from_utf8_lossy(&raw)).into_bytes();
    drop(raw);
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    // The index check runs before tobj's parse, not beside it: tobj overflows on some
    // out-of-range indices (`vt * 2` on a negative index past the start, a panic with
    // overflow checks; found by the obj_import fuzzer), and only the check reports them.
    check_face_indices(&String::from_utf8_lossy(&bytes), ctx)?;
    let parsed = {
        // Load MTL files ourselves to learn their folders and report missing ones.
        let mtl_dirs: RefCell<HashMap<String, PathBuf>> = RefCell::new(HashMap::new());
        let mtl_failures: RefCell<Vec<(PathBuf, String)>> = RefCell::new(Vec::new());
        let r = tobj::load_obj_buf(&mut Cursor::new(&bytes), &OBJ_OPTIONS, |mtl: &Path| {
            let p = resolve_relative(&dir, &mtl.to_string_lossy());
            let (r, failure) = load_mtl(&p);
            match &r {
                Ok((mats, _)) => {
                    ctx.read_from(&p);
                    let d = p.parent().unwrap_or(Path::new(".")).to_path_buf();
                    for m in mats {
                        mtl_dirs
                            .borrow_mut()
                            .entry(m.name.clone())
                            .or_insert_with(|| d.clone());
                    }
                }
                Err(e) => mtl_failures
                    .borrow_mut()
                    .push((p, failure.unwrap_or_else(|| e.to_string()))),
            }
            r
        });
        (r, mtl_dirs.into_inner(), mtl_failures.into_inner())
    };
    let (parsed, mtl_dirs, mtl_failures) = parsed;
    let (models, _materials_result) = parsed.map_err(|e| {
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
    for (p, e) in mtl_failures {
        ctx.warn(format!(
            "material library {} not loaded ({e}); using default materials",
            p.display()
        ))?;
    }
    // Re-read the materials that did load (tobj merges them and drops the folder).
    let mut b = SceneBuilder::new();
    let mut tex_cache: HashMap<(Option<PathBuf>, Option<PathBuf>), Option<u32>> = HashMap::new();
    let mut mat_map: HashMap<usize, u32> = HashMap::new();
    let materials = _materials_result.unwrap_or_default();
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
                    let dir = mtl_dirs
                        .get(&materials[i].name)
                        .cloned()
                        .unwrap_or_else(|| dir.clone());
                    let mat = convert_material(&materials[i], &dir, &mut b, &mut tex_cache, ctx)?;
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
    Ok(b)
}

fn convert_material(
    m: &tobj::Material,
    dir: &Path,
    b: &mut SceneBuilder,
    cache: &mut HashMap<(Option<PathBuf>, Option<PathBuf>), Option<u32>>,
    ctx: &mut Ctx,
) -> Result<Material, ImportError> {
    let kd = m.diffuse.unwrap_or([1.0; 3]);
    let tr = m
        .unknown_param
        .get("Tr")
        .and_then(|s| s.split_whitespace().next()?.parse::<f32>().ok());
    let d = m.dissolve.or(tr.map(|t| 1.0 - t)).unwrap_or(1.0);
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
    let (kd_name, d_name) = (map(&m.diffuse_texture), map(&m.dissolve_texture));
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

/// `tobj::load_mtl` without its panic: tobj 4.0.5 unwraps when a `Ka`, `Kd`, `Ks` or `Ke`
/// line has fewer than three numbers (found by fuzzing, `fuzz/regressions/obj_import/`).
/// Such a file is refused as a material parse error instead, like any other bad MTL.
/// A colour statement (`Ka`, `Kd`, `Ks`, `Ke`) with fewer than three values.
fn short_colour_line(line: &[u8]) -> bool {
    let line = String::from_utf8_lossy(line);
    let mut words = line.split_whitespace();
    matches!(words.next(), Some("Ka" | "Kd" | "Ks" | "Ke")) && words.count() < 3
}

/// Loads and decodes one MTL texture; a failure is a warning and `None`.
fn load_texture(
    name: &str,
    path: &Path,
    label: &str,
    slot: &str,
    ctx: &mut Ctx,
) -> Result<Option<Texture>, ImportError> {
    let r = super::read_input(path)
        .inspect(|_| ctx.read_from(path))
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

/// Name given to an unnamed material (a bare `newmtl`, as Blender 2.61 writes for a
/// material without a name); a bare `usemtl` selects it.
const UNNAMED_MATERIAL: &str = "(unnamed)";

/// The OBJ text with the harmless statements tobj would refuse rewritten: a bare
/// `usemtl` selects [`UNNAMED_MATERIAL`] (tobj requires a name).
fn tolerate_obj(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\n', '\r']);
        if body.trim() == "usemtl" {
            out.push_str("usemtl ");
            out.push_str(UNNAMED_MATERIAL);
            out.push_str(&line[body.len()..]);
        } else {
            out.push_str(line);
        }
    }
    out
}

/// The MTL text with the harmless statements tobj would refuse rewritten or dropped: a
/// bare `newmtl` names [`UNNAMED_MATERIAL`]; a texture statement (`map_Kd`, `bump`, ...)
/// without a file name and an `illum` without a number are dropped (they say nothing).
fn tolerate_mtl(text: &str) -> String {
    const MAPS: [&str; 11] = [
        "map_Ka", "map_Kd", "map_Ks", "map_Bump", "map_bump", "map_Ns", "map_ns", "map_NS", "bump",
        "map_d", "illum",
    ];
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\n', '\r']);
        let t = body.trim();
        if t == "newmtl" {
            out.push_str("newmtl ");
            out.push_str(UNNAMED_MATERIAL);
            out.push_str(&line[body.len()..]);
        } else if MAPS.contains(&t) {
            out.push_str(&line[body.len()..]);
        } else {
            out.push_str(line);
        }
    }
    out
}

/// Reads and parses one MTL library; an error is one line naming the line number and the
/// problem (the caller names the file).
fn load_mtl(p: &Path) -> (tobj::MTLLoadResult, Option<String>) {
    let raw = match super::read_input(p) {
        Ok(raw) => raw,
        Err(e) => return (Err(tobj::LoadError::OpenFileFailed), Some(e.to_string())),
    };
    let text = tolerate_mtl(&String::from_utf8_lossy(&raw)).into_bytes();
    // tobj panics on a colour statement with fewer than three values (found by the
    // obj_import fuzzer): refuse it here, naming the line.
    if let Some((n, line)) = text
        .split(|&b| b == b'\n')
        .enumerate()
        .find(|(_, l)| short_colour_line(l))
    {
        let shown = String::from_utf8_lossy(line);
        return (
            Err(tobj::LoadError::MaterialParseError),
            Some(format!(
                "line {}: '{}': a colour needs three values: {}",
                n + 1,
                shown.trim(),
                tobj::LoadError::MaterialParseError
            )),
        );
    }
    match tobj::load_mtl_buf(&mut Cursor::new(&text)) {
        Ok(r) => (Ok(r), None),
        Err(e) => {
            let at = failing_line(&text, |prefix| {
                tobj::load_mtl_buf(&mut Cursor::new(prefix)).err()
            });
            (Err(e), Some(format!("{at}{e}")))
        }
    }
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
