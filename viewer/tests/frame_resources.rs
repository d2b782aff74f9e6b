//! A frame makes no GPU resources once the first frames have sized the persistent ones
//! (issue 22, item 6). Counted by the `Gpu` wrapper (`Gpu::resources_created`: buffers,
//! bind groups and textures made through it) plus the cloud pass's own count.
//!
//! The scene is gallery-like: two volume assets (three instances), a ground mesh,
//! shadows on (so the volumes are planned twice per frame: from the light and from the
//! camera), the cell wireframe on, and dust and fire particles with motion blur and heat
//! shimmer (one
//! particle draw per shutter sample). After two warm-up frames (one per camera), eight
//! more frames alternating between the two cameras must make nothing. The window's
//! resolve pass (frame + stats line) drawn offscreen: the same text again makes nothing;
//! new text of the same size is written into the same texture.
//!
//! Before the change, each frame made 6 buffers and a bind group per volume plan (×2 with
//! shadows), a frame buffer and bind group per mesh view, 2 buffers and a bind group for
//! the wireframe, 2 buffers and a bind group per particle sample plus the composite's,
//! and the resolve pass a texture, two buffers and two bind groups.

mod common;

use billow_view::mesh_pass::MeshData;
use billow_view::overlay::Resolve;
use billow_view::particle_pass::{MotionBlur, ParticleLayerDesc};
use billow_view::particles::{BillboardMode, EmitterDesc, ParticleKind, ParticleSystemDesc};
use billow_view::target::Target;
use billow_view::{Renderer, ViewCamera};
use glam::{Mat4, Vec3};

fn dust() -> ParticleSystemDesc {
    ParticleSystemDesc {
        kind: ParticleKind::Dust,
        emitter: EmitterDesc {
            position: [0.5, 0.5, 0.5],
            count: 12,
            radius: (0.2, 0.4),
            lifetime: (10.0, 10.0),
            seed: 3,
            spread: 0.5,
            rise: 0.1,
            start: -1.0,
        },
        density: Some(0.5),
        albedo: Some(0.8),
        g: None,
        t0: None,
        t1: None,
        emission: 1.0,
        detail: 0.5,
        mode: BillboardMode::Spherical,
    }
}

fn renderer(gpu: billow_view::Gpu) -> Renderer {
    let mut r = Renderer::new(gpu);
    r.add_volume(
        &common::ball_asset(false),
        vec![
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(1.2, 0.0, -0.5)),
        ],
    )
    .expect("volume");
    r.add_volume(
        &common::ball_asset(true),
        vec![Mat4::from_translation(Vec3::new(-1.2, 0.0, 0.3))],
    )
    .expect("volume");
    r.add_mesh(&MeshData::quad(
        Vec3::new(-4.0, -0.05, -4.0),
        Vec3::new(0.0, 0.0, 8.0),
        Vec3::new(8.0, 0.0, 0.0),
        [0.3, 0.36, 0.22, 1.0],
    ))
    .expect("ground");
    let layer = ParticleLayerDesc {
        motion_blur: Some(MotionBlur {
            shutter: 0.1,
            samples: 3,
        }),
        shimmer: Some(0.5),
        ..Default::default()
    };
    let fire = ParticleSystemDesc {
        kind: ParticleKind::Fire,
        ..dust()
    };
    r.set_particles(vec![dust(), fire], layer)
        .expect("particles");
    r.set_shadows(true);
    r.set_wireframe(true);
    r.time = 1.0;
    r
}

fn made(r: &Renderer) -> u64 {
    r.gpu.resources_created() + r.cloud_resources_created()
}

#[test]
fn frames_make_no_gpu_resources_after_the_first() {
    let name = "frames_make_no_gpu_resources_after_the_first";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let r = renderer(gpu);
    let (w, h) = (96, 64);
    let cams = [
        ViewCamera::look_at(
            Vec3::new(1.0, 2.0, 4.0),
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::Y,
            0.9,
            w,
            h,
            0.1,
            50.0,
        ),
        ViewCamera::look_at(
            Vec3::new(-3.0, 1.5, 3.0),
            Vec3::new(0.2, 0.5, 0.0),
            Vec3::Y,
            0.9,
            w,
            h,
            0.1,
            50.0,
        ),
    ];
    let target = Target::new(&r.gpu, w, h);
    for cam in &cams {
        let s = r.render(&target, cam).expect("render");
        assert!(
            s.slices > 0 && s.shadow_slices > 0 && s.particles > 0,
            "{s:?}"
        );
    }
    r.gpu.wait().expect("wait");
    let warm = made(&r);
    let mut per_frame = Vec::new();
    for f in 0..8 {
        let before = made(&r);
        r.render(&target, &cams[f % 2]).expect("render");
        per_frame.push(made(&r) - before);
    }
    r.gpu.wait().expect("wait");
    assert!(
        per_frame.iter().all(|&n| n == 0),
        "buffers, bind groups or textures made per frame after the warm-up: {per_frame:?} \
         ({} in all after {warm} for the upload and the first two frames)",
        made(&r) - warm
    );
}

#[test]
fn the_resolve_pass_reuses_its_stats_texture_until_the_text_changes() {
    let name = "the_resolve_pass_reuses_its_stats_texture_until_the_text_changes";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let resolve = Resolve::new(&gpu, format);
    let (w, h) = (160, 48);
    let frame = Target::new(&gpu, w, h);
    let out = gpu
        .texture(&wgpu::TextureDescriptor {
            label: Some("window stand-in"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default());
    let draw = |text: &str| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        resolve.draw(
            &gpu,
            &mut enc,
            &frame.color_view,
            &out,
            (w, h),
            true,
            [0.5, 0.6, 0.7],
            Some(text),
        );
        gpu.queue.submit([enc.finish()]);
    };
    draw("12.5 ms  slices 40");
    let first = gpu.resources_created();
    for _ in 0..4 {
        draw("12.5 ms  slices 40");
    }
    // The same size of text (one line, as many columns): written into the same texture.
    draw("13.0 ms  slices 41");
    gpu.wait().expect("wait");
    assert_eq!(
        gpu.resources_created() - first,
        0,
        "the resolve pass made resources for frames whose stats texture could be reused"
    );
}
