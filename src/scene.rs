//! The imported scene: what every baker consumes.
//!
//! Import runs once and produces world-space triangles with per-vertex attributes
//! and a per-triangle material. Conventions (all importers follow them):
//! - positions in world space (node transforms applied), metres as authored;
//! - UVs in glTF convention: origin at the top-left of the image, v grows downwards
//!   (OBJ's v is flipped on import);
//! - colours (vertex colours, factors) are **linear**, straight (not premultiplied) alpha;
//! - texture texels are stored as authored: RGB sRGB-encoded, alpha linear, straight alpha.

use std::path::PathBuf;

use glam::{Vec2, Vec3, Vec4};

/// One vertex of a world-space triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub position: Vec3,
    /// Unit normal; when the source has none, the face normal.
    pub normal: Vec3,
    pub uv: Vec2,
    /// Linear RGBA vertex colour, (1,1,1,1) when absent.
    pub color: Vec4,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v: [Vertex; 3],
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Index into [`Scene::meshes`] (which source mesh/primitive or OBJ object it came from).
    pub mesh: u32,
}

impl Triangle {
    /// Geometric (counter-clockwise) face normal, not normalised; length = 2 × area.
    pub fn cross(&self) -> Vec3 {
        (self.v[1].position - self.v[0].position).cross(self.v[2].position - self.v[0].position)
    }
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Alpha-tested: visible where alpha >= cutoff.
    Mask {
        cutoff: f32,
    },
    Blend,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGBA, straight alpha.
    pub base_color_factor: Vec4,
    /// Index into [`Scene::textures`]; `None` also when the texture was missing (see warnings).
    pub base_color_texture: Option<u32>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// Shade without lighting (glTF `KHR_materials_unlit`: base colour × texture is the
    /// final colour, e.g. billboards whose lighting is baked in). Only glTF sets it.
    pub unlit: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            unlit: false,
        }
    }
}

/// A decoded texture. RGB are sRGB-encoded, A linear, straight alpha.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// URI or name as the source file gives it (for messages and `inspect`).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
}

/// What the source calls a mesh (glTF mesh primitive, OBJ object/group).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshInfo {
    pub name: String,
    pub triangles: usize,
}

/// The axis-aligned box: moved to the shared rendering core, re-exported here.
pub use billow_core::Aabb;

/// A non-fatal problem found during import. With `--strict` each becomes an error.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub message: String,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureReport {
    pub name: String,
    pub found: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub meshes: Vec<MeshInfo>,
    /// Every texture the source referenced, found or not (for `inspect`).
    pub texture_report: Vec<TextureReport>,
    pub warnings: Vec<Warning>,
    /// Zero-area (or non-finite-area) triangles dropped during import.
    pub dropped_triangles: usize,
    pub bounds: Aabb,
    /// The files the import read besides the mesh file itself (glTF buffers and images,
    /// MTL libraries, OBJ textures), in first-read order; empty for generated scenes.
    /// Callers that write files use it never to write over an input.
    pub files: Vec<PathBuf>,
}

impl Scene {
    pub fn material(&self, t: &Triangle) -> &Material {
        &self.materials[t.material as usize]
    }
}
