//! `billow view`: TARGET (scene file, asset or mesh) → the viewer's CPU-side content.

use std::path::{Path, PathBuf};

use billow::import::{import, ImportOptions};
use billow::scene::{AlphaMode, Scene};
use billow_format::{read_file, AssetKind, CloudAsset, VolumeAsset};
use billow_view::content::{CloudContent, Content, VolumeContent};
use billow_view::mesh_pass::{MeshData, MeshMaterial, MeshVertex};
use billow_view::scene::{CloudDesc, MeshDesc, SceneFile, Transform, VolumeDesc};
use billow_view::texture::TextureData;
use glam::{Mat4, Quat, Vec3};

use crate::exit::{CliError, Code};

fn extension_is(p: &Path, ext: &str) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

/// TARGET as a scene (a lone asset or mesh becomes a one-item scene).
pub fn load_scene(target: &Path) -> Result<SceneFile, CliError> {
    if extension_is(target, "ron") {
        return SceneFile::load(target).map_err(|e| CliError::new(Code::from(&e), e));
    }
    if !target.is_file() {
        return Err(CliError::new(
            Code::InputIo,
            format!("{}: no such file", target.display()),
        ));
    }
    let mut s = SceneFile::default();
    if extension_is(target, "billow") {
        let c = read_file(target).map_err(|e| CliError::new(Code::from(&e), e))?;
        match c.header.kind {
            AssetKind::Cloud => s.clouds.push(CloudDesc {
                asset: target.to_path_buf(),
                instances: vec![Transform::default()],
                lod_distances: None,
                transition: 0.25,
                dissolve: billow_view::cloud_pass::DEFAULT_DISSOLVE,
            }),
            _ => s.volumes.push(VolumeDesc {
                asset: target.to_path_buf(),
                instances: vec![Transform::default()],
                animation: None,
            }),
        }
    } else {
        s.meshes.push(MeshDesc {
            path: target.to_path_buf(),
            transform: Default::default(),
        });
    }
    Ok(s)
}

/// An imported scene as mesh-pass data, transformed by `t`.
pub fn mesh_data(s: &Scene, t: &Transform) -> MeshData {
    let mat = t.matrix();
    let nmat = Mat4::from_quat(Quat::from_rotation_y(t.rotate_y_deg.to_radians()));
    let mut data = MeshData {
        textures: s
            .textures
            .iter()
            .map(|x| TextureData::straight(x.width, x.height, x.texels.concat()))
            .collect(),
        materials: s
            .materials
            .iter()
            .map(|m| MeshMaterial {
                texture: m.base_color_texture,
                alpha_cutoff: match m.alpha_mode {
                    AlphaMode::Opaque => None,
                    AlphaMode::Mask { cutoff } => Some(cutoff),
                    AlphaMode::Blend => Some(0.5),
                },
            })
            .collect(),
        ..Default::default()
    };
    for tri in &s.triangles {
        let m = &s.materials[tri.material as usize];
        for v in &tri.v {
            data.vertices.push(MeshVertex {
                pos: mat.transform_point3(v.position).to_array(),
                // The mesh pass draws zero-normal vertices unlit (KHR_materials_unlit).
                normal: if m.unlit {
                    [0.0; 3]
                } else {
                    nmat.transform_vector3(v.normal).to_array()
                },
                uv: v.uv.to_array(),
                color: (m.base_color_factor * v.color).to_array(),
            });
        }
        data.triangle_materials.push(tri.material);
    }
    data
}

/// Reads every asset and mesh of `scene`; `read` receives every file read (the scene's
/// assets and meshes, and the files the meshes refer to).
pub fn load_content(scene: &SceneFile, read: &mut Vec<PathBuf>) -> Result<Content, CliError> {
    let mut c = Content {
        light_dir: Vec3::from(scene.light.direction),
        ambient: scene.light.ambient,
        shadows: scene.shadows,
        particles: scene.particles.clone(),
        particle_layer: scene.particle_layer,
        ..Default::default()
    };
    for v in &scene.volumes {
        read.push(v.asset.clone());
        let (asset, blocks) = VolumeAsset::read_with_blocks(&v.asset)
            .map_err(|e| CliError::new(Code::from(&e), e))?;
        c.volumes.push(VolumeContent {
            asset,
            blocks: blocks.map(std::sync::Arc::new),
            instances: v.instances.iter().map(|t| t.matrix()).collect(),
            animation: v.animation,
        });
    }
    for d in &scene.clouds {
        read.push(d.asset.clone());
        let (asset, blocks) = CloudAsset::read_with_blocks(&d.asset)
            .map_err(|e| CliError::new(Code::from(&e), format!("{}: {e}", d.asset.display())))?;
        let levels = asset.levels.len();
        if let Some(dist) = &d.lod_distances {
            if dist.len() != levels {
                return Err(CliError::new(
                    Code::InvalidInput,
                    format!(
                        "{}: lod_distances has {} entries; this cloud has the foliage mesh and \
                         {levels} billboard levels, so {levels} distances are needed",
                        d.asset.display(),
                        dist.len()
                    ),
                ));
            }
        }
        c.clouds.push(CloudContent {
            asset,
            blocks: blocks.map(std::sync::Arc::new),
            instances: d.instances.iter().map(|t| t.matrix()).collect(),
            lod_distances: d.lod_distances.clone(),
            transition: d.transition,
            dissolve: d.dissolve,
        });
    }
    for m in &scene.meshes {
        let s = import(&m.path, &ImportOptions::default())
            .map_err(|e| CliError::new(Code::from(&e), &e))?;
        read.push(m.path.clone());
        read.extend(s.report.files);
        c.meshes.push(mesh_data(&s.scene, &m.transform));
    }
    if let Some(g) = &scene.ground {
        let h = 0.5 * g.size;
        let corner = Vec3::new(g.centre[0] - h, g.height, g.centre[1] - h);
        c.meshes.push(MeshData::quad(
            corner,
            Vec3::new(0.0, 0.0, g.size),
            Vec3::new(g.size, 0.0, 0.0),
            [g.color[0], g.color[1], g.color[2], 1.0],
        ));
    }
    Ok(c)
}
