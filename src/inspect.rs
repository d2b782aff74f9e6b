//! A summary of an imported scene and its import report ([`Imported`]): what `billow
//! inspect` shows an artist as a first sanity check (and prints as JSON with `--json`).

use std::fmt;
use std::path::Path;

use serde::Serialize;

use crate::import::Imported;
use crate::scene::AlphaMode;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InspectReport {
    pub file: String,
    pub triangles: usize,
    pub dropped_triangles: usize,
    pub meshes: Vec<MeshSummary>,
    pub materials: Vec<MaterialSummary>,
    pub textures: Vec<TextureSummary>,
    /// `None` when the scene has no triangles.
    pub bounds: Option<BoundsSummary>,
    pub warnings: Vec<String>,
    /// The files read beside the mesh file ([`crate::import::ImportReport::files`]), as the
    /// import resolved them.
    pub files: Vec<String>,
    /// The files the import looked for and could not read
    /// ([`crate::import::ImportReport::missing`]): a missing texture, MTL library or image.
    pub missing_files: Vec<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshSummary {
    pub name: String,
    pub triangles: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialSummary {
    pub name: String,
    /// `"opaque"`, `"mask"` or `"blend"`.
    pub alpha_mode: &'static str,
    /// The MASK cutoff, when `alpha_mode` is `"mask"`.
    pub alpha_cutoff: Option<f32>,
    pub double_sided: bool,
    pub has_texture: bool,
    /// Linear RGBA.
    pub base_color_factor: [f32; 4],
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureSummary {
    pub name: String,
    pub found: bool,
    /// Decoded size; `None` when not found.
    pub width: Option<u32>,
    pub height: Option<u32>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoundsSummary {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub size: [f32; 3],
}

pub fn inspect(imported: &Imported, path: &Path) -> InspectReport {
    let Imported { scene, report } = imported;
    let materials = scene
        .materials
        .iter()
        .map(|m| {
            let (alpha_mode, alpha_cutoff) = match m.alpha_mode {
                AlphaMode::Opaque => ("opaque", None),
                AlphaMode::Mask { cutoff } => ("mask", Some(cutoff)),
                AlphaMode::Blend => ("blend", None),
            };
            MaterialSummary {
                name: m.name.clone(),
                alpha_mode,
                alpha_cutoff,
                double_sided: m.double_sided,
                has_texture: m.base_color_texture.is_some(),
                base_color_factor: m.base_color_factor.to_array(),
            }
        })
        .collect();
    let textures = report
        .textures
        .iter()
        .map(|r| {
            // A combined OBJ texture is named "<map_Kd> (alpha: <map_d>)".
            let prefix = format!("{} (alpha: ", r.name);
            let tex = r.found.then(|| {
                scene
                    .textures
                    .iter()
                    .find(|t| t.name == r.name || t.name.starts_with(&prefix))
            });
            let tex = tex.flatten();
            TextureSummary {
                name: r.name.clone(),
                found: r.found,
                width: tex.map(|t| t.width),
                height: tex.map(|t| t.height),
            }
        })
        .collect();
    let bounds = (!scene.bounds.is_empty()).then(|| BoundsSummary {
        min: scene.bounds.min.to_array(),
        max: scene.bounds.max.to_array(),
        size: scene.bounds.size().to_array(),
    });
    InspectReport {
        file: path.display().to_string(),
        triangles: scene.triangles.len(),
        dropped_triangles: report.dropped_triangles,
        meshes: scene
            .meshes
            .iter()
            .map(|m| MeshSummary {
                name: m.name.clone(),
                triangles: m.triangles,
            })
            .collect(),
        materials,
        textures,
        bounds,
        warnings: report.messages(),
        files: report
            .files
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        missing_files: report
            .missing
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
    }
}

fn v3(v: [f32; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", v[0], v[1], v[2])
}

impl fmt::Display for InspectReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{:<10} {}", "file", self.file)?;
        writeln!(
            f,
            "{:<10} {} ({} zero-area dropped)",
            "triangles", self.triangles, self.dropped_triangles
        )?;
        match &self.bounds {
            Some(b) => writeln!(
                f,
                "{:<10} {} .. {}  size {}",
                "bounds",
                v3(b.min),
                v3(b.max),
                v3(b.size)
            )?,
            None => writeln!(f, "{:<10} empty", "bounds")?,
        }
        let w = |names: &mut dyn Iterator<Item = usize>| names.max().unwrap_or(0).min(40);
        writeln!(f, "meshes     {}", self.meshes.len())?;
        let mw = w(&mut self.meshes.iter().map(|m| m.name.chars().count()));
        for m in &self.meshes {
            writeln!(f, "  {:<mw$}  {:>9} triangles", m.name, m.triangles)?;
        }
        writeln!(f, "materials  {}", self.materials.len())?;
        let mw = w(&mut self.materials.iter().map(|m| m.name.chars().count()));
        for m in &self.materials {
            let mode = match m.alpha_cutoff {
                Some(c) => format!("mask {c}"),
                None => m.alpha_mode.to_string(),
            };
            let sided = if m.double_sided {
                "double-sided"
            } else {
                "single-sided"
            };
            let tex = if m.has_texture {
                "textured"
            } else {
                "no texture"
            };
            writeln!(f, "  {:<mw$}  {:<8}  {}  {}", m.name, mode, sided, tex)?;
        }
        writeln!(f, "textures   {}", self.textures.len())?;
        let tw = w(&mut self.textures.iter().map(|t| t.name.chars().count()));
        for t in &self.textures {
            match (t.found, t.width, t.height) {
                (true, Some(w), Some(h)) => writeln!(f, "  {:<tw$}  {w}x{h}", t.name)?,
                (true, _, _) => writeln!(f, "  {:<tw$}  found", t.name)?,
                (false, _, _) => writeln!(f, "  {:<tw$}  MISSING", t.name)?,
            }
        }
        writeln!(f, "files read {}", self.files.len())?;
        for p in &self.files {
            writeln!(f, "  {p}")?;
        }
        if !self.missing_files.is_empty() {
            writeln!(f, "files missing {}", self.missing_files.len())?;
            for p in &self.missing_files {
                writeln!(f, "  {p}")?;
            }
        }
        write!(f, "warnings   {}", self.warnings.len())?;
        for w in &self.warnings {
            write!(f, "\n  {w}")?;
        }
        Ok(())
    }
}
