//! The scene: what every baker consumes, and the one [`SceneBuilder`] that makes it.
//!
//! Import runs once and produces world-space triangles with per-vertex attributes
//! and a per-triangle material; the procedural shapes (`procgen`, a test generator) build the
//! same kind of scene. A `Scene` is geometry only: what an import noticed on the way
//! (warnings, textures found or missing, dropped triangles, files read) is in the
//! separate [`crate::import::ImportReport`]. Conventions (all importers follow them):
//! - positions in world space (node transforms applied), metres as authored;
//! - UVs in glTF convention: origin at the top-left of the image, v grows downwards
//!   (OBJ's v is flipped on import);
//! - colours (vertex colours, factors) are **linear**, straight (not premultiplied) alpha;
//! - texture texels are stored as authored: RGB sRGB-encoded, alpha linear, straight alpha.

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
    /// Index into [`Scene::textures`]; `None` also when the texture was missing (see the
    /// import report's warnings).
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
    /// URI or name as the source file gives it (for messages, `inspect` and the names of
    /// exported images).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    /// The source's encoded image when [`Texture::texels`] are exactly its decoding and it
    /// is a format glTF carries (JPEG, PNG), so that an export can embed the author's bytes
    /// instead of encoding the texels again (a JPEG stays a JPEG). `None` for other formats
    /// (TGA, BMP, …), generated textures, and textures the import changed (an OBJ `map_Kd`
    /// combined with its `map_d`). Whoever changes the texels must clear it.
    pub encoded: Option<EncodedImage>,
}

/// An image file's bytes as the source held them ([`Texture::encoded`]). Cloning shares
/// the bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EncodedImage {
    pub format: EncodedFormat,
    pub bytes: std::sync::Arc<[u8]>,
}

/// The formats [`EncodedImage`] holds: those glTF 2.0 embeds without an extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EncodedFormat {
    Png,
    Jpeg,
}

impl EncodedFormat {
    /// The MIME type glTF names the format with (`image/png`, `image/jpeg`).
    pub fn mime_type(self) -> &'static str {
        match self {
            EncodedFormat::Png => "image/png",
            EncodedFormat::Jpeg => "image/jpeg",
        }
    }
}

/// What the source calls a mesh (glTF mesh primitive, OBJ object/group).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshInfo {
    pub name: String,
    pub triangles: usize,
}

use billow_core::Aabb;

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub meshes: Vec<MeshInfo>,
    /// The box around every vertex of [`Scene::triangles`].
    pub bounds: Aabb,
}

impl Scene {
    pub fn material(&self, t: &Triangle) -> &Material {
        &self.materials[t.material as usize]
    }
}

/// Accumulates a [`Scene`]: materials, textures, meshes and triangles. The one builder of
/// the importers and the procedural shapes, so both follow one rule: a triangle whose area
/// is zero or not finite is dropped (and counted, [`SceneBuilder::dropped`]); every kept
/// one grows the bounds and its mesh's triangle count.
#[derive(Debug)]
pub struct SceneBuilder {
    scene: Scene,
    dropped: usize,
}

impl SceneBuilder {
    pub fn new() -> Self {
        SceneBuilder {
            scene: Scene {
                triangles: Vec::new(),
                materials: Vec::new(),
                textures: Vec::new(),
                meshes: Vec::new(),
                bounds: Aabb::EMPTY,
            },
            dropped: 0,
        }
    }

    /// Adds a material and returns its index.
    pub fn material(&mut self, m: Material) -> u32 {
        self.scene.materials.push(m);
        (self.scene.materials.len() - 1) as u32
    }

    /// Adds a texture and returns its index.
    pub fn texture(&mut self, t: Texture) -> u32 {
        self.scene.textures.push(t);
        (self.scene.textures.len() - 1) as u32
    }

    /// Adds a mesh entry (no triangles yet) and returns its index.
    pub fn mesh(&mut self, name: impl Into<String>) -> u32 {
        self.scene.meshes.push(MeshInfo {
            name: name.into(),
            triangles: 0,
        });
        (self.scene.meshes.len() - 1) as u32
    }

    /// Adds a triangle unless its area is zero or not finite (then it is counted as
    /// dropped). `t.mesh` must be an index [`SceneBuilder::mesh`] returned.
    pub fn push(&mut self, t: Triangle) {
        let area = t.area();
        if !(area > 0.0 && area.is_finite()) {
            self.dropped += 1;
            return;
        }
        for v in &t.v {
            self.scene.bounds.grow(v.position);
        }
        self.scene.meshes[t.mesh as usize].triangles += 1;
        self.scene.triangles.push(t);
    }

    /// Adds the triangle `v` (counter-clockwise front face), as [`SceneBuilder::push`].
    pub fn triangle(&mut self, v: [Vertex; 3], material: u32, mesh: u32) {
        self.push(Triangle { v, material, mesh });
    }

    /// Adds the quad a-b-c-d (counter-clockwise) as two triangles with flat normal and
    /// UVs spanning the unit square (glTF convention: a bottom-left, b bottom-right,
    /// c top-right).
    pub fn quad(&mut self, p: [Vec3; 4], color: Vec4, material: u32, mesh: u32) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let uv = [
            Vec2::new(0.0, 1.0),
            Vec2::ONE,
            Vec2::new(1.0, 0.0),
            Vec2::ZERO,
        ];
        let v = |i: usize| Vertex {
            position: p[i],
            normal: n,
            uv: uv[i],
            color,
        };
        self.triangle([v(0), v(1), v(2)], material, mesh);
        self.triangle([v(0), v(2), v(3)], material, mesh);
    }

    /// Reserves room for `additional` more triangles.
    pub fn reserve(&mut self, additional: usize) {
        self.scene.triangles.reserve(additional);
    }

    /// Every triangle offered so far, kept or dropped.
    pub fn offered(&self) -> usize {
        self.scene.triangles.len().saturating_add(self.dropped)
    }

    /// The triangles dropped so far (zero or non-finite area).
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// The scene built (the dropped count, if wanted, is [`SceneBuilder::dropped`] before).
    pub fn finish(self) -> Scene {
        self.scene
    }
}

impl Default for SceneBuilder {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32) -> Vertex {
        Vertex {
            position: Vec3::new(x, y, 0.0),
            normal: Vec3::Z,
            uv: Vec2::ZERO,
            color: Vec4::ONE,
        }
    }

    /// One rule for importers and generators: zero, NaN and infinite areas are dropped and
    /// counted; kept triangles grow the bounds and their mesh's count.
    #[test]
    fn builder_drops_zero_and_non_finite_areas() {
        let mut b = SceneBuilder::new();
        let m = b.material(Material::default());
        let mesh = b.mesh("m");
        b.triangle([v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)], m, mesh);
        b.triangle([v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0)], m, mesh);
        b.triangle([v(0.0, 0.0), v(f32::NAN, 0.0), v(0.0, 1.0)], m, mesh);
        // Finite corners whose cross product overflows: infinite area.
        b.triangle([v(0.0, 0.0), v(3e38, 0.0), v(0.0, 3e38)], m, mesh);
        assert_eq!((b.offered(), b.dropped()), (4, 3));
        let s = b.finish();
        assert_eq!(s.triangles.len(), 1);
        assert_eq!(s.meshes[0].triangles, 1);
        assert_eq!(s.bounds.max, Vec3::new(1.0, 1.0, 0.0));
    }
}
