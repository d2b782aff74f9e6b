//! Pruned volumes (`billow emptyspace`, format 1.1 LOD bands, SPEC §8.6) on the GPU:
//! the oak baked at 80³ (`--align 8`) and pruned with default options, drawn from three
//! eval directions at the framed distance, 4× and 16× (so every band is used):
//! - GPU vs the CPU slicer on the pruned asset: RMSE ≤ 0.005, max |Δ| ≤ 0.05 (the
//!   tolerance of gpu_vs_cpu.rs), identical slice counts;
//! - GPU pruned vs GPU unpruned: max |Δ| ≤ 0.02 (the pruned asset samples exactly what
//!   the source samples; the GPU's fixed-point filter weights differ between textures
//!   of different sizes by a few 8-bit steps at most).
//!
//! Diff images on failure.

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow::emptyspace::{prune, EmptySpaceOptions};
use billow::eval::image::write_comparison_png;
use billow::eval::metrics::compare;
use billow::eval::slicer::{render_volume, SlicerParams};
use billow::import::{import, ImportOptions};
use billow::test_support::max_abs_diff as max_abs;
use billow::voxelize::{voxelize, Resolution, VoxelizeOptions};
use billow_core::camera::Camera;
use billow_core::Aabb;
use billow_format::VolumeAsset;
use billow_view::Renderer;
use common::image_f32;
use glam::{Mat4, Vec3};

#[test]
fn pruned_volumes_with_lod_bands_draw_like_the_cpu_and_like_the_source() {
    let name = "pruned_volumes_with_lod_bands";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).unwrap().scene;
    let opts = VoxelizeOptions {
        resolution: Resolution::Longest(80),
        align: 8,
        ..VoxelizeOptions::default()
    };
    let src: VolumeAsset =
        voxelize(&scene, &opts, &|_, _| {})
            .unwrap()
            .into_asset("test", None, BTreeMap::new());
    let pruned = prune(&src, &EmptySpaceOptions::default()).unwrap().asset;
    assert!(!pruned.bands.is_empty(), "the test needs a banded asset");
    let mut rp = Renderer::new(gpu);
    rp.add_volume(&pruned, vec![Mat4::IDENTITY]).unwrap();
    let mut rs = Renderer::new(common::gpu_or_skip(name).expect("a second device"));
    rs.add_volume(&src, vec![Mat4::IDENTITY]).unwrap();
    let b = &src.header.bounds;
    let bounds = Aabb {
        min: Vec3::from(b.min),
        max: Vec3::from(b.max),
    };
    let out = common::out_dir();
    for (i, (dir, dist)) in [
        (Vec3::new(1.0, -0.6, -0.8), 1.0),
        (Vec3::new(-1.0, 0.0, 0.0), 4.0),
        (Vec3::new(0.3, -1.0, 0.5), 16.0),
    ]
    .into_iter()
    .enumerate()
    {
        let c = Camera::framed(&bounds, dir, std::f32::consts::FRAC_PI_4, 64, 64, dist);
        let cam = common::view_camera(&c);
        let cpu = render_volume(&pruned, &c, &SlicerParams::default()).expect("CPU render");
        let (g, stats) = rp.render_image(&cam).expect("GPU render");
        let (s, _) = rs.render_image(&cam).expect("GPU render");
        let (g, s) = (image_f32(&g), image_f32(&s));
        let err = compare(&cpu.image, &g).unwrap();
        let d_cpu = max_abs(&cpu.image, &g);
        let d_src = max_abs(&s, &g);
        println!(
            "view {i}: slices gpu {} cpu {}, rmse {:.5}, max |Δ| vs CPU {d_cpu:.4}, vs source {d_src:.4}",
            stats.slices, cpu.stats.slices, err.rmse
        );
        if err.rmse > 0.005 || d_cpu > 0.05 || stats.slices != cpu.stats.slices {
            let p = out.join(format!("{name}.{i}.cpu.diff.png"));
            write_comparison_png(&cpu.image, &g, 4.0, &p).unwrap();
            panic!(
                "view {i}: GPU vs CPU rmse {} max {d_cpu}, slices {} vs {}; {}",
                err.rmse,
                stats.slices,
                cpu.stats.slices,
                p.display()
            );
        }
        if d_src > 0.02 {
            let p = out.join(format!("{name}.{i}.source.diff.png"));
            write_comparison_png(&s, &g, 4.0, &p).unwrap();
            panic!(
                "view {i}: pruned vs source max |Δ| {d_src}; {}",
                p.display()
            );
        }
        assert!(g.coverage() > 1e-4, "view {i} shows the oak");
    }
}
