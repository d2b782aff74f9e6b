//! Block-compressed assets (format 1.2, SPEC §12) on the GPU, both upload paths:
//! - **blocks**: a device with the BC features (`Gpu::headless_with(true)`) uploads a
//!   compressed volume as a `Bc7RgbaUnormSrgb` 3D texture (needs
//!   `TEXTURE_COMPRESSION_BC_SLICED_3D`) and a cloud's atlases and normal maps as BC7 2D
//!   textures (`TEXTURE_COMPRESSION_BC`);
//! - **decode**: a device without them (`Gpu::headless_with(false)`, what
//!   `BILLOW_VIEW_BC=decode` selects) uploads the texels the reader decoded.
//!
//! The decode path must upload no block texture; the blocks path must upload every
//! texture as blocks exactly when the adapter has the features (the test prints which
//! path the adapter takes: lavapipe, the software Vulkan of the test machines, reports
//! `TEXTURE_COMPRESSION_BC` and the sliced-3D feature or not — see the SKIP/PATH line).
//! Both paths draw the same picture: BC7 decoding is exact, so the GPU's texels equal the
//! reader's. Tolerances: volume max |Δ| ≤ 2/255 per channel; the alpha-tested cloud
//! RMSE ≤ 0.01 (the decode path rescales the atlas MIPs' alpha for coverage, the blocks
//! path draws the stored MIPs, which the baker already made coverage-preserving).

mod common;

use billow::compress::{compress_cloud, compress_volume};
use billow::eval::image::write_comparison_png;
use billow::eval::metrics::compare;
use billow::test_support::max_abs_diff as max_abs;
use billow_format::{CloudAsset, Mesh};
use billow_view::{Gpu, Renderer, RgbaImage, ViewCamera};
use common::image_f32;
use glam::{Mat4, Vec3};

/// Two devices: with the BC features requested (when the adapter has them, and blocks
/// kept even on a software adapter, which by default uploads compressed textures decoded:
/// `Gpu::sample_blocks`) and without.
fn devices(name: &str) -> Option<(Gpu, Gpu)> {
    common::gpu_or_skip(name)?;
    let mut with = Gpu::headless_with(true).expect("adapter");
    with.sample_blocks = true;
    let without = Gpu::headless_with(false).expect("adapter");
    Some((with, without))
}

/// A software adapter (lavapipe) decodes a BC7 block at every texel fetch, so by default
/// it uploads compressed assets decoded — volumes in extinction space (one filtered sample
/// per fragment), cloud atlases as RGBA8 — and no block texture; a hardware adapter with
/// the BC features keeps the blocks.
#[test]
fn software_adapters_upload_compressed_assets_decoded() {
    let name = "software_adapters_upload_compressed_assets_decoded";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    drop(gpu);
    let gpu = Gpu::headless_with(true).expect("adapter");
    let software = gpu.info.device_type == wgpu::DeviceType::Cpu;
    assert_eq!(gpu.sample_blocks, !software, "{}", gpu.describe());
    let mut asset = common::ball_asset(false);
    let blocks = compress_volume(&mut asset);
    let direct = gpu.block_upload(asset.level_dims(0), true);
    if software {
        assert!(!direct && !gpu.block_upload([64, 64, 1], false));
    }
    let mut r = Renderer::new(gpu);
    r.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    assert_eq!(r.block_textures, u32::from(direct));
    println!(
        "PATH: {}: compressed assets {}",
        r.gpu.describe(),
        if r.block_textures > 0 {
            "kept as blocks"
        } else {
            "uploaded decoded"
        }
    );
}

#[test]
fn compressed_volumes_draw_the_same_from_blocks_and_decoded() {
    let name = "compressed_volumes_draw_the_same_from_blocks_and_decoded";
    let Some((with, without)) = devices(name) else {
        return;
    };
    let mut asset = common::ball_asset(false);
    let raw = asset.clone();
    let blocks = compress_volume(&mut asset);
    let dims = asset.level_dims(0);
    let direct = with.block_upload(dims, true);
    println!(
        "PATH: {}: 3D BC7 volume {}",
        with.describe(),
        if direct {
            "uploaded as blocks"
        } else {
            "decoded on load (no TEXTURE_COMPRESSION_BC_SLICED_3D)"
        }
    );
    assert!(!without.block_upload(dims, true));
    let mut rb = Renderer::new(with);
    rb.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    let mut rd = Renderer::new(without);
    rd.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    assert_eq!(rd.block_textures, 0, "the decode path uploads no blocks");
    assert_eq!(rb.block_textures, u32::from(direct));
    let mut rr = Renderer::new(common::gpu_or_skip(name).expect("adapter"));
    rr.add_volume(&raw, vec![Mat4::IDENTITY]).unwrap();
    let cam = ViewCamera::look_at(
        Vec3::new(0.5, 0.6, 2.2),
        Vec3::splat(0.5),
        Vec3::Y,
        0.8,
        64,
        64,
        0.1,
        10.0,
    );
    let b = image_f32(&rb.render_image(&cam).unwrap().0);
    let d = image_f32(&rd.render_image(&cam).unwrap().0);
    let r = image_f32(&rr.render_image(&cam).unwrap().0);
    let diff = max_abs(&b, &d);
    let lossy = compare(&r, &d).unwrap().rmse;
    println!("blocks vs decoded max |Δ| {diff:.5}; compressed vs raw RMSE {lossy:.5}");
    if diff > 2.0 / 255.0 {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&d, &b, 4.0, &p).unwrap();
        panic!("blocks vs decoded max |Δ| {diff}; {}", p.display());
    }
    assert!(d.coverage() > 1e-3, "the ball is drawn");
    // Compression is lossy, but a little: the picture stays the ball's.
    assert!(lossy < 0.02, "compressed vs raw RMSE {lossy}");
}

/// A volume of normal moments (format 1.4, lit two-sided): its `VMB7` blocks are sampled
/// as they are where the colour's are (the shader maps the unorm of the XOR-ed bytes back),
/// and draw what the decoded moments draw.
#[test]
fn compressed_moments_draw_the_same_from_blocks_and_decoded() {
    let name = "compressed_moments_draw_the_same_from_blocks_and_decoded";
    let Some((with, without)) = devices(name) else {
        return;
    };
    let mut asset = common::as_moments(billow::noise_volume::sphere(32, Vec3::new(0.6, 0.5, 0.4)));
    let blocks = compress_volume(&mut asset);
    assert!(blocks.normals.is_some(), "the moments are compressed too");
    let direct = with.block_upload(asset.level_dims(0), true);
    let mut rb = Renderer::new(with);
    rb.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    let mut rd = Renderer::new(without);
    rd.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    assert_eq!(rd.block_textures, 0, "the decode path uploads no blocks");
    // Colour and moments.
    assert_eq!(rb.block_textures, 2 * u32::from(direct));
    let cam = ViewCamera::look_at(
        Vec3::new(1.8, 1.2, 2.6),
        Vec3::ZERO,
        Vec3::Y,
        0.8,
        64,
        64,
        0.1,
        10.0,
    );
    let b = image_f32(&rb.render_image(&cam).unwrap().0);
    let d = image_f32(&rd.render_image(&cam).unwrap().0);
    let diff = max_abs(&b, &d);
    println!("moments: blocks vs decoded max |Δ| {diff:.5}");
    if diff > 2.0 / 255.0 {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&d, &b, 4.0, &p).unwrap();
        panic!("blocks vs decoded max |Δ| {diff}; {}", p.display());
    }
    assert!(d.coverage() > 1e-3, "the ball is drawn");
}

/// A volume with an LOD band (format 1.3, as `billow emptyspace` writes): every band's blocks take the
/// same path as the base texture, and both paths draw the same picture.
#[test]
fn compressed_bands_draw_the_same_from_blocks_and_decoded() {
    let name = "compressed_bands_draw_the_same_from_blocks_and_decoded";
    let Some((with, without)) = devices(name) else {
        return;
    };
    // The ball with its level 1.. as a tail band (what `billow emptyspace` writes last).
    let mut asset = common::ball_asset(false);
    asset.bands.push(billow_format::LodBand {
        first_level: 1,
        dims: asset.level_dims(1),
        levels: asset.levels[1..].to_vec(),
        normals: None,
        cells: asset.cells.clone(),
    });
    asset.validate().unwrap();
    let blocks = compress_volume(&mut asset);
    assert_eq!(blocks.bands.len(), asset.bands.len());
    let direct = with.block_upload(asset.level_dims(0), true);
    let mut rb = Renderer::new(with);
    rb.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    let mut rd = Renderer::new(without);
    rd.add_volume_blocks(&asset, Some(&blocks), vec![Mat4::IDENTITY], None)
        .unwrap();
    assert_eq!(rd.block_textures, 0, "the decode path uploads no blocks");
    if direct {
        assert_eq!(rb.block_textures as usize, 1 + asset.bands.len());
    }
    println!("PATH: bands: {} block textures", rb.block_textures);
    let cam = ViewCamera::look_at(
        Vec3::new(0.5, 0.6, 2.2),
        Vec3::splat(0.5),
        Vec3::Y,
        0.8,
        64,
        64,
        0.1,
        10.0,
    );
    let b = image_f32(&rb.render_image(&cam).unwrap().0);
    let d = image_f32(&rd.render_image(&cam).unwrap().0);
    let diff = max_abs(&b, &d);
    assert!(diff <= 2.0 / 255.0, "blocks vs decoded max |Δ| {diff}");
    assert!(d.coverage() > 1e-3, "the ball is drawn");
}

#[test]
fn compressed_clouds_draw_the_same_from_blocks_and_decoded() {
    use billow::bbcloud::bake::Shading;
    use billow::bbcloud::{bake, BbcloudOptions};
    use billow::import::{import, ImportOptions};
    let name = "compressed_clouds_draw_the_same_from_blocks_and_decoded";
    let Some((with, without)) = devices(name) else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/oak/eztree_oak_medium.gltf");
    let scene = import(&path, &ImportOptions::default()).expect("oak").scene;
    let opts = BbcloudOptions {
        samples: 30,
        lods: 1,
        atlas_size: 512,
        supersample: 1,
        normal_map: true,
        shading: Shading {
            light: None,
            ambient: 0.3,
        },
        ..Default::default()
    };
    let (mut asset, _) = bake(&scene, &opts, "test", None, &|_, _| {}).expect("bake");
    asset.trunk = Mesh::default();
    let blocks = compress_cloud(&mut asset);
    let a0 = &asset.atlases[0];
    let direct = with.block_upload([a0.width, a0.height, 1], false);
    println!(
        "PATH: {}: BC7 atlases {}",
        with.describe(),
        if direct {
            "uploaded as blocks"
        } else {
            "decoded on load (no TEXTURE_COMPRESSION_BC)"
        }
    );
    let frame = |gpu: Gpu, cloud: &CloudAsset| -> (RgbaImage, u32) {
        let mut r = Renderer::new(gpu);
        r.add_cloud_blocks(
            cloud,
            Some(&blocks),
            vec![Mat4::IDENTITY],
            Some(vec![1.0]),
            0.0,
            0.8,
        )
        .expect("upload");
        r.lod_distance_override = Some(10.0);
        let b = &cloud.header.bounds;
        let c = 0.5 * (Vec3::from(b.min) + Vec3::from(b.max));
        let rad = 0.5 * (Vec3::from(b.max) - Vec3::from(b.min)).length();
        let eye = c + Vec3::new(1.0, 0.2, 0.6).normalize() * 2.5 * rad;
        let cam = ViewCamera::look_at(eye, c, Vec3::Y, 0.8, 96, 96, 0.1 * rad, 10.0 * rad);
        (r.render_image(&cam).expect("render").0, r.block_textures)
    };
    let (b, nb) = frame(with, &asset);
    let (d, nd) = frame(without, &asset);
    assert_eq!(nd, 0, "the decode path uploads no blocks");
    // Atlases and (runtime-lit) normal maps.
    let want = if direct {
        2 * asset.atlases.len() as u32
    } else {
        0
    };
    assert_eq!(nb, want);
    let (b, d) = (image_f32(&b), image_f32(&d));
    let err = compare(&d, &b).unwrap().rmse;
    println!(
        "cloud blocks vs decoded RMSE {err:.5}, max |Δ| {:.4}, coverage {:.4} {:.4}",
        max_abs(&b, &d),
        b.coverage(),
        d.coverage()
    );
    if err > 0.01 {
        let p = common::out_dir().join(format!("{name}.diff.png"));
        write_comparison_png(&d, &b, 4.0, &p).unwrap();
        panic!("cloud blocks vs decoded RMSE {err}; {}", p.display());
    }
    assert!(d.coverage() > 1e-3, "the oak's billboards are drawn");
}
