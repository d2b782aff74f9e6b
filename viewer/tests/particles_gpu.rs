//! Spherical billboards on the GPU against their CPU reference
//! (`billow_view::particles::opacity`), and the paper's Figure 1 artefact measured.
//!
//! One particle (no detail noise, albedo 1, ambient 1 so a pixel's colour equals its
//! opacity) is drawn:
//! - in front of a far background, framed: every pixel's alpha matches
//!   `opacity::spherical` along that pixel's ray within 0.01 (f16 target, f32 shader);
//! - with the camera inside the particle (the near plane cuts it): matches too;
//! - cut by an opaque wall through its centre: spherical billboards change smoothly
//!   across the wall line (largest step between neighbouring pixels < 0.1 of the
//!   planar one), planar billboards jump (the clipping artefact) — measured on the GPU.

mod common;

use billow_view::mesh_pass::MeshData;
use billow_view::particle_pass::ParticleLayerDesc;
use billow_view::particles::{
    opacity, particles_at, BillboardMode, EmitterDesc, ParticleKind, ParticleSystemDesc,
};
use billow_view::{Renderer, RgbaImage, ViewCamera};
use glam::Vec3;

const W: u32 = 64;
const H: u32 = 48;

fn system(mode: BillboardMode) -> ParticleSystemDesc {
    ParticleSystemDesc {
        kind: ParticleKind::Dust,
        emitter: EmitterDesc {
            position: [0.0, 0.0, 0.0],
            count: 1,
            radius: (2.0, 2.0),
            lifetime: (10.0, 10.0),
            seed: 0,
            spread: 0.0,
            rise: 0.0,
            // Born between t = −1 and 0 (the draws stagger starts by up to 10 % of the
            // lifetime): alive and fully formed at t = 1.
            start: -1.0,
        },
        density: Some(0.8),
        albedo: Some(1.0),
        g: None,
        t0: None,
        t1: None,
        emission: 1.0,
        detail: 0.0,
        mode,
    }
}

fn camera(eye: Vec3, near: f32) -> ViewCamera {
    ViewCamera::look_at(eye, Vec3::ZERO, Vec3::Y, 0.9, W, H, near, 100.0)
}

/// The view-space direction of pixel (x, y)'s centre ray.
fn ray(cam: &ViewCamera, x: u32, y: u32) -> Vec3 {
    let ndc = Vec3::new(
        (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / H as f32 * 2.0,
        0.0,
    );
    let p = cam.projection();
    Vec3::new(ndc.x / p.col(0).x, ndc.y / p.col(1).y, -1.0).normalize()
}

fn render(mode: BillboardMode, cam: &ViewCamera, wall: bool) -> (RgbaImage, ParticleSystemDesc) {
    let gpu = common::gpu_or_skip("particles_gpu").expect("adapter");
    let mut r = Renderer::new(gpu);
    r.ambient = 1.0;
    let s = system(mode);
    r.set_particles(vec![s.clone()], ParticleLayerDesc::default())
        .unwrap();
    if wall {
        // An opaque wall in the plane x = 0 (through the particle's centre), behind
        // which the particle's right half lies.
        r.add_mesh(&MeshData::quad(
            Vec3::new(0.0, -10.0, 10.0),
            Vec3::new(0.0, 20.0, 0.0),
            Vec3::new(0.0, 0.0, -20.0),
            [0.0, 0.0, 0.0, 1.0],
        ))
        .unwrap();
    }
    r.time = 1.0;
    let (img, stats) = r.render_image(cam).unwrap();
    assert_eq!(stats.particles, 1);
    (img, s)
}

#[test]
fn gpu_opacity_matches_the_cpu_reference() {
    if common::gpu_or_skip("gpu_opacity_matches_the_cpu_reference").is_none() {
        return;
    }
    for (eye, near, what) in [
        (Vec3::new(1.0, 1.5, 9.0), 0.1, "framed"),
        (Vec3::new(0.3, 0.2, 1.0), 0.3, "camera inside the particle"),
    ] {
        let cam = camera(eye, near);
        let (img, s) = render(BillboardMode::Spherical, &cam, false);
        let p = particles_at(&s, 1.0)[0];
        let c = cam.to_view(p.centre);
        let mut worst = 0.0f32;
        let mut covered = 0;
        for y in 0..H {
            for x in 0..W {
                let want = opacity::spherical(
                    c,
                    p.radius,
                    p.density,
                    ray(&cam, x, y),
                    near,
                    f32::INFINITY,
                );
                let got = img.data[(y * W + x) as usize];
                worst = worst.max((got[3] - want).abs()).max((got[0] - want).abs());
                covered += usize::from(want > 0.05);
            }
        }
        println!("{what}: max |GPU − CPU| = {worst:.4}, {covered} covered pixels");
        assert!(covered > 50, "{what}: the particle must be on screen");
        assert!(
            worst < 0.01,
            "{what}: GPU vs CPU opacity differs by {worst}"
        );
    }
}

#[test]
fn an_opaque_wall_cuts_planar_billboards_hard_and_spherical_ones_softly() {
    if common::gpu_or_skip("an_opaque_wall_cuts").is_none() {
        return;
    }
    // Looking along −z at the particle; the wall x = 0 runs along the view axis, so the
    // pixels right of the centre see the wall in front of the particle's far half.
    let cam = ViewCamera::look_at(
        Vec3::new(-3.0, 0.0, 8.0),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::Y,
        0.9,
        W,
        H,
        0.1,
        100.0,
    );
    let step = |img: &RgbaImage| {
        // Largest alpha change between horizontal neighbours on the centre row, where the
        // particle is in front of the wall (alpha below the wall's 1).
        let y = H / 2;
        let a = |x: u32| img.data[(y * W + x) as usize];
        (1..W)
            .map(|x| {
                let (p, q) = (a(x - 1), a(x));
                // The wall is black and opaque: the particle's own contribution is rgb.
                (p[0] - q[0]).abs()
            })
            .fold(0.0f32, f32::max)
    };
    let (spherical, _) = render(BillboardMode::Spherical, &cam, true);
    let (planar, _) = render(BillboardMode::Planar, &cam, true);
    let (s, p) = (step(&spherical), step(&planar));
    println!("largest neighbour step on the centre row: spherical {s:.3}, planar {p:.3}");
    assert!(
        p > 0.2,
        "planar billboards must show the hard clipping line ({p})"
    );
    assert!(
        s < 0.5 * p,
        "spherical billboards must fade across the wall ({s} vs {p})"
    );
}
