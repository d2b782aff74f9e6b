//! The reference of `billow eval --light` lights the mesh as the viewer's mesh pass does
//! (issue 38): a smooth sphere drawn headless by the real binary and ray traced by the
//! reference ([`Lighting::Scene`], which states the model itself, not through
//! `billow_core::shading`) under the viewer's default light agree pixel for pixel, within
//! a tolerance that the one-sided model (what volumes use) misses by far. So a change of
//! the lighting model on either side alone fails here. Without a GPU adapter the test says
//! it skips (a failure under CI).

mod common;

use billow::eval::image::{write_comparison_png, ImageF32};
use billow::eval::lighting::Lighting;
use billow::eval::metrics::compare;
use billow::eval::reference::{ReferenceRenderer, Sampling};
use billow::import::{import, ImportOptions};
use billow_core::camera::Camera;
use billow_core::shading::{DEFAULT_AMBIENT, DEFAULT_LIGHT};
use billow_core::Aabb;
use common::headless_shot;
use glam::Vec3;

/// A UV sphere of radius 1 with smooth normals, `n` segments around.
fn sphere_obj(n: usize) -> String {
    let rings = n / 2;
    let mut s = String::new();
    for r in 0..=rings {
        let th = std::f32::consts::PI * r as f32 / rings as f32;
        for k in 0..n {
            let ph = std::f32::consts::TAU * k as f32 / n as f32;
            let p = Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
            s += &format!("v {} {} {}\nvn {} {} {}\n", p.x, p.y, p.z, p.x, p.y, p.z);
        }
    }
    let id = |r: usize, k: usize| r * n + k % n + 1;
    for r in 0..rings {
        for k in 0..n {
            let (a, b, c, d) = (id(r, k), id(r, k + 1), id(r + 1, k + 1), id(r + 1, k));
            s += &format!("f {a}//{a} {b}//{b} {c}//{c}\nf {a}//{a} {c}//{c} {d}//{d}\n");
        }
    }
    s
}

#[test]
fn the_reference_lights_a_mesh_as_the_viewer_does() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("sphere.obj"), sphere_obj(96)).unwrap();
    let size = 96;
    let args = ["--size", "96x96", "--view", "-z"];
    if headless_shot(
        "the_reference_lights_a_mesh_as_the_viewer_does",
        "sphere.obj",
        "gpu.png",
        &args,
        d,
    )
    .is_none()
    {
        return;
    }
    let gpu = ImageF32::from_image(&image::open(d.join("gpu.png")).unwrap());

    let scene = import(&d.join("sphere.obj"), &ImportOptions::default())
        .unwrap()
        .scene;
    let b = Aabb {
        min: scene.bounds.min,
        max: scene.bounds.max,
    };
    let cam = Camera::framed(&b, -Vec3::Z, 45f32.to_radians(), size, size, 1.0);
    let render = |lighting: Lighting| {
        ReferenceRenderer::new(&scene)
            .with_lighting(lighting)
            .unwrap()
            .render(&cam, Sampling::Centre)
            .unwrap()
    };
    let light = DEFAULT_LIGHT.normalize();
    let two_sided = render(Lighting::Scene {
        light,
        ambient: DEFAULT_AMBIENT,
        shadows: false,
    });
    let e = compare(&two_sided, &gpu).unwrap();
    let one_sided = compare(
        &render(Lighting::Volume {
            light,
            ambient: DEFAULT_AMBIENT,
        }),
        &gpu,
    )
    .unwrap();
    eprintln!(
        "viewer vs reference: RMSE {:.5} (two-sided), {:.5} (one-sided)",
        e.rmse, one_sided.rmse
    );
    if e.rmse > 0.005 {
        let p = d.join("comparison.png");
        write_comparison_png(&two_sided, &gpu, 4.0, &p).unwrap();
        let keep = std::env::temp_dir().join("billow_view_lighting.png");
        let _ = std::fs::copy(&p, &keep);
        panic!(
            "viewer vs reference: RMSE {:.4} > 0.005 (reference | viewer | diff ×4: {})",
            e.rmse,
            keep.display()
        );
    }
    // The tolerance tells the models apart: the one-sided model is far outside it.
    assert!(
        one_sided.rmse > 3.0 * e.rmse.max(0.005),
        "{} vs {}",
        one_sided.rmse,
        e.rmse
    );
}
