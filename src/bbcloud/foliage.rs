//! Foliage vs the rest: which triangles go into the cloud, and the meshes the asset keeps.
//!
//! By default a triangle is foliage when its material is alpha-tested or blended (glTF
//! `MASK`/`BLEND`: leaf cards); with explicit material names, exactly those materials are.
//! Everything else (trunk, branches) is kept as an ordinary indexed mesh.

use std::collections::HashMap;

use billow_format::{Mesh, MeshMaterial, MeshTexture, MeshVertex};

use super::BbcloudError;
use crate::scene::{AlphaMode, Scene, Triangle, Wrap};

/// Which triangles are foliage (`true`) by the rule above. Unknown names are an error.
pub fn classify(scene: &Scene, names: &[String]) -> Result<Vec<bool>, BbcloudError> {
    for n in names {
        if !scene.materials.iter().any(|m| &m.name == n) {
            let have: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
            return Err(BbcloudError::UnknownMaterial(n.clone(), have.join(", ")));
        }
    }
    let is_leaf: Vec<bool> = scene
        .materials
        .iter()
        .map(|m| {
            if names.is_empty() {
                !matches!(m.alpha_mode, AlphaMode::Opaque)
            } else {
                names.contains(&m.name)
            }
        })
        .collect();
    Ok(scene
        .triangles
        .iter()
        .map(|t| is_leaf[t.material as usize])
        .collect())
}

/// The scene's materials in the asset's encoding (indices preserved).
pub fn materials(scene: &Scene) -> Vec<MeshMaterial> {
    scene
        .materials
        .iter()
        .map(|m| {
            let (mode, cutoff) = match m.alpha_mode {
                AlphaMode::Opaque => (0, 0.5),
                AlphaMode::Mask { cutoff } => (1, cutoff),
                AlphaMode::Blend => (2, 0.5),
            };
            MeshMaterial {
                base_color_factor: m.base_color_factor.to_array(),
                alpha_cutoff: cutoff,
                texture: m.base_color_texture,
                alpha_mode: mode,
                double_sided: m.double_sided,
            }
        })
        .collect()
}

/// The scene's textures as authored (indices preserved).
pub fn textures(scene: &Scene) -> Vec<MeshTexture> {
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => 0,
        Wrap::ClampToEdge => 1,
        Wrap::MirroredRepeat => 2,
    };
    scene
        .textures
        .iter()
        .map(|t| MeshTexture {
            width: t.width,
            height: t.height,
            wrap: [wrap(t.wrap_u), wrap(t.wrap_v)],
            texels: t.texels.iter().flatten().copied().collect(),
        })
        .collect()
}

/// Indexed mesh builder: identical vertices (bit for bit, and same `key`) are shared.
#[derive(Default)]
pub struct MeshBuilder {
    mesh: Mesh,
    map: HashMap<([u32; 8], u32), u32>,
}

impl MeshBuilder {
    /// Add a triangle; `key` separates vertices that must not be shared (e.g. the billboard a
    /// foliage triangle morphs to), `morph` the per-vertex morph targets if any.
    pub fn push(&mut self, t: &Triangle, key: u32, morph: Option<[glam::Vec3; 3]>) {
        let mut idx = [0u32; 3];
        for (k, v) in t.v.iter().enumerate() {
            let mv = MeshVertex {
                position: v.position.to_array(),
                normal: v.normal.to_array(),
                uv: v.uv.to_array(),
            };
            let bits: Vec<u32> = mv
                .position
                .iter()
                .chain(&mv.normal)
                .chain(&mv.uv)
                .map(|f| f.to_bits())
                .collect();
            let bits: [u32; 8] = bits.try_into().expect("8 floats");
            let next = self.mesh.vertices.len() as u32;
            let i = *self.map.entry((bits, key)).or_insert(next);
            if i == next {
                self.mesh.vertices.push(mv);
                if let Some(m) = morph {
                    self.mesh.morph.push(m[k].to_array());
                }
            }
            idx[k] = i;
        }
        self.mesh.triangles.push(idx);
        self.mesh.materials.push(t.material);
        if morph.is_some() {
            self.mesh.billboard.push(key);
        }
    }

    pub fn finish(self) -> Mesh {
        self.mesh
    }
}

/// The kept (non-foliage) mesh.
pub fn trunk_mesh(scene: &Scene, foliage: &[bool]) -> Mesh {
    let mut b = MeshBuilder::default();
    for (t, _) in scene.triangles.iter().zip(foliage).filter(|(_, &f)| !f) {
        b.push(t, 0, None);
    }
    b.finish()
}
