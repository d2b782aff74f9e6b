//! The oak before a wall (fixtures/scenes/oak_wall.ron), drawn by the CPU slicer's depth
//! fade test (tests/eval_depth_fade.rs) and the GPU's (viewer/tests/oak_wall_fade.rs):
//! the bundled oak as a volume, the scene's camera and the wall's colour.

use std::collections::BTreeMap;

use glam::Vec3;

use crate::import::{import, ImportOptions};
use crate::voxelize::{voxelize, CombineFn, Preset, Resolution, VoxelizeOptions};
use billow_core::camera::Camera;
use billow_format::VolumeAsset;

/// The wall's colour (linear RGBA, opaque).
pub const WALL: [f32; 4] = [0.5, 0.45, 0.4, 1.0];

/// The bundled oak as a `res`³ `opaque` volume named `name` (32: the committed
/// fixtures/scenes/oak32.billow; other sizes baked here).
pub fn oak(res: u32, name: &str) -> VolumeAsset {
    let repo = super::repo();
    if res == 32 {
        return VolumeAsset::read(&repo.join("fixtures/scenes/oak32.billow")).expect("oak32");
    }
    let scene = import(
        &repo.join("fixtures/oak/eztree_oak_medium.gltf"),
        &ImportOptions::default(),
    )
    .expect("import the oak")
    .scene;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(res),
        combine: CombineFn::Preset(Preset::Opaque),
        ..VoxelizeOptions::default()
    };
    voxelize(&scene, &opts, &|_, _| {})
        .expect("voxelize")
        .into_asset(name, None, BTreeMap::new())
}

/// The camera of `oak_wall.ron`, `size`² pixels.
pub fn camera(size: u32) -> Camera {
    Camera {
        eye: Vec3::new(110.0, 60.0, 70.0),
        target: Vec3::new(0.0, 30.0, 0.0),
        up: Vec3::Y,
        fov_y: 45f32.to_radians(),
        width: size,
        height: size,
        near: 1.0,
        far: 400.0,
    }
}
