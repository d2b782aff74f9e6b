//! The renderer builds only the pipelines its passes need (issue 37, item 6): the shadow
//! pipelines of the meshes, clouds and volumes only when a frame has a `shadow` pass, and
//! each pipeline once. Read from the renderer's record of what it built
//! (`RenderRecord::built`, what `billow view --json` prints), for a scene holding a
//! volume, a ground mesh and a billboard cloud, with shadows off and on.
//!
//! Also: volume textures are stored in extinction space (`Rgba16Float`, one hardware
//! sample per fragment) unless a hardware adapter keeps an asset's BC7 blocks.

mod common;

use std::path::Path;

use billow_format::CloudAsset;
use billow_view::content::{BuildProgress, BuildStep, CloudContent, Content, VolumeContent};
use billow_view::mesh_pass::MeshData;
use billow_view::volume_pass::{VolumePass, VolumeStorage, EXTINCTION_FORMAT};
use billow_view::{SliceParams, ViewCamera};
use glam::{Mat4, Vec3};

const SHADOW_PIPELINES: [&str; 3] = [
    "pipeline:volume-shadow",
    "pipeline:mesh-shadow",
    "pipeline:cloud-shadow",
];

fn content(shadows: bool) -> Content {
    let cloud =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/format/v1_cloud_tiny.billow");
    let cloud = CloudAsset::read(&cloud).expect("the tiny cloud fixture");
    Content {
        volumes: vec![VolumeContent {
            asset: common::ball_asset(false),
            blocks: None,
            instances: vec![Mat4::IDENTITY],
            animation: None,
        }],
        clouds: vec![CloudContent {
            asset: cloud,
            blocks: None,
            instances: vec![Mat4::from_translation(Vec3::new(1.5, 0.0, 0.0))],
            lod_distances: None,
            transition: 0.2,
            dissolve: 0.0,
        }],
        meshes: vec![MeshData::quad(
            Vec3::new(-2.0, -0.01, 2.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -4.0),
            [0.3, 0.4, 0.2, 1.0],
        )],
        shadows,
        ..Default::default()
    }
}

fn camera() -> ViewCamera {
    ViewCamera::look_at(
        Vec3::new(0.5, 1.5, 4.0),
        Vec3::new(0.5, 0.3, 0.0),
        Vec3::Y,
        0.8,
        32,
        32,
        0.1,
        20.0,
    )
}

fn count(built: &[&str], what: &str) -> usize {
    built.iter().filter(|b| **b == what).count()
}

#[test]
fn shadow_pipelines_are_built_only_with_shadows_and_each_pipeline_once() {
    let name = "shadow_pipelines_are_built_only_with_shadows_and_each_pipeline_once";
    for shadows in [false, true] {
        let Some(gpu) = common::gpu_or_skip(name) else {
            return;
        };
        let c = content(shadows);
        assert_eq!(c.passes().contains(&"shadow"), shadows);
        let mut steps = Vec::new();
        let r = c
            .build_with(gpu, SliceParams::default(), 0.8, &mut |p| steps.push(p))
            .expect("build");
        // The build tells its steps in order, each started then finished.
        let order: Vec<String> = steps
            .iter()
            .map(|p| match p {
                BuildProgress::Started(s) => format!("start {s:?}"),
                BuildProgress::Finished(s, _) => format!("end {s:?}"),
            })
            .collect();
        assert_eq!(
            order,
            [
                "start Upload",
                "end Upload",
                "start Pipelines",
                "end Pipelines"
            ]
        );
        assert_eq!(BuildStep::Pipelines.describe(), "building the pipelines");
        // Built before the first frame: what the passes need.
        let built = r.record().built;
        for p in ["pipeline:volume", "pipeline:mesh", "pipeline:cloud"] {
            assert_eq!(count(&built, p), 1, "shadows {shadows}: {built:?}");
        }
        for p in SHADOW_PIPELINES {
            assert_eq!(
                count(&built, p),
                usize::from(shadows),
                "shadows {shadows}: {p} in {built:?}"
            );
        }
        // Two frames build nothing more (the shadow map is made by the first frame).
        let (img, stats) = r.render_image(&camera()).expect("frame");
        r.render_image(&camera()).expect("frame");
        assert!(img.data.iter().any(|p| p[3] > 0.0), "something is drawn");
        assert_eq!(stats.shadow_slices > 0, shadows);
        let after = r.record().built;
        let mut expected = built.clone();
        if shadows {
            expected.push("texture:shadow-map");
        }
        assert_eq!(after, expected, "shadows {shadows}");
    }
}

/// Turning shadows on later (the window's `S`) builds the shadow pipelines then, once.
#[test]
fn shadows_turned_on_later_build_their_pipelines_on_first_use() {
    let name = "shadows_turned_on_later_build_their_pipelines_on_first_use";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let mut r = content(false)
        .build(gpu, SliceParams::default(), 0.8)
        .expect("build");
    r.render_image(&camera()).expect("frame");
    assert!(SHADOW_PIPELINES
        .iter()
        .all(|p| count(&r.record().built, p) == 0));
    r.set_shadows(true);
    r.render_image(&camera()).expect("frame");
    r.render_image(&camera()).expect("frame");
    let built = r.record().built;
    for p in SHADOW_PIPELINES {
        assert_eq!(count(&built, p), 1, "{p}: {built:?}");
    }
}

#[test]
fn volume_textures_are_stored_in_extinction_space() {
    let name = "volume_textures_are_stored_in_extinction_space";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let layout = billow_view::shadow::receiver_layout(&gpu.device);
    let pass = VolumePass::new(&gpu, &layout, 1);
    let asset = common::ball_asset(false);
    let textures = pass.upload(&gpu, &asset).expect("upload");
    assert_eq!(textures.len(), 1);
    assert_eq!(textures[0].storage, VolumeStorage::Extinction);
    assert_eq!(textures[0].texture.format(), EXTINCTION_FORMAT);
    assert_eq!(textures[0].levels as usize, asset.levels.len());
}

/// A software adapter runs every case of the shader's texture-slot switch, so it binds one
/// volume texture per batch; a hardware adapter binds as many as the content has (at most
/// the batch maximum), and the shader switches over no unused slot.
#[test]
fn texture_batches_fit_the_adapter_and_the_content() {
    let name = "texture_batches_fit_the_adapter_and_the_content";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let software = gpu.info.device_type == wgpu::DeviceType::Cpu;
    let preferred = billow_view::volume_pass::preferred_batch(&gpu);
    assert_eq!(
        preferred,
        if software {
            1
        } else {
            billow_view::volume_pass::MAX_TEXTURES_PER_BATCH
        }
    );
    assert_eq!(billow_view::Renderer::new(gpu).texture_batch, preferred);
    let gpu = common::gpu_or_skip(name).expect("adapter");
    let mut c = content(false);
    c.volumes.push(c.volumes[0].clone());
    assert_eq!(c.volume_textures(), 2);
    let r = c.build(gpu, SliceParams::default(), 0.8).expect("build");
    assert_eq!(r.texture_batch, preferred.min(2));
}
