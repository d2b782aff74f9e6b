//! Reference renderer correctness: scenes built in code render to analytically known
//! coverage and colour.
//!
//! Tolerances: coverage of the 16-spp render within 0.003 of the analytic fraction
//! (a ~40 px square has ~160 edge pixels, each off by at most ~1/8 with 4×4 stratified
//! samples); interior colour within 2e-3 (8-bit texture quantization is exact here, the
//! rest is f32 rounding); the 1-spp render counts exactly the pixel centres inside.

use billow::eval::reference::{raster_1spp, render_reference, Sampling};
use billow::scene::{AlphaMode, Material, Scene, SceneBuilder, Texture, Vertex, Wrap};
use billow_core::camera::Camera;
use glam::{Vec2, Vec3, Vec4};

const FOV: f32 = std::f32::consts::FRAC_PI_4;
const N: u32 = 64;

fn material(color: Vec4, texture: Option<u32>, mode: AlphaMode, double_sided: bool) -> Material {
    Material {
        name: "m".into(),
        base_color_factor: color,
        base_color_texture: texture,
        alpha_mode: mode,
        double_sided,
        unlit: false,
    }
}

/// Quad a-b-c-d (counter-clockwise = front), uv (0,1) (1,1) (1,0) (0,0) (glTF: v down).
fn quad(sb: &mut SceneBuilder, p: [Vec3; 4], mat: u32, mesh: u32) {
    let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let uv = [
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let v = |i: usize| Vertex {
        position: p[i],
        normal: n,
        uv: uv[i],
        color: Vec4::ONE,
    };
    sb.triangle([v(0), v(1), v(2)], mat, mesh);
    sb.triangle([v(0), v(2), v(3)], mat, mesh);
}

fn unit_quad(z: f32, half: f32, m: Material) -> Scene {
    let mut sb = SceneBuilder::new();
    let mat = sb.material(m);
    let mesh = sb.mesh("quad");
    quad(
        &mut sb,
        [
            Vec3::new(-half, -half, z),
            Vec3::new(half, -half, z),
            Vec3::new(half, half, z),
            Vec3::new(-half, half, z),
        ],
        mat,
        mesh,
    );
    sb.finish()
}

fn camera_at(z: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, z),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: FOV,
        width: N,
        height: N,
        near: 0.01,
        far: 100.0,
    }
}

/// Half side in pixels of a square of half side `h` at depth `d`.
fn half_px(h: f32, d: f32) -> f64 {
    f64::from(h / (d * (0.5 * FOV).tan())) * f64::from(N) / 2.0
}

/// Exact number of pixel centres inside `[c − h, c + h]²`, as a fraction.
fn centre_fraction(h: f64) -> f64 {
    let c = f64::from(N) / 2.0;
    let count = (0..N)
        .filter(|&x| (f64::from(x) + 0.5 - c).abs() <= h)
        .count() as f64;
    count * count / f64::from(N * N)
}

#[test]
fn unit_quad_coverage_colour_and_facing() {
    let color = Vec4::new(0.2, 0.4, 0.6, 1.0);
    let scene = unit_quad(0.0, 0.5, material(color, None, AlphaMode::Opaque, false));
    let d = 3.1;
    let h = half_px(0.5, d);
    let want = (2.0 * h / f64::from(N)).powi(2);
    let img = render_reference(&scene, &camera_at(d), Sampling::default()).unwrap();
    assert!(
        (img.coverage() - want).abs() < 0.003,
        "coverage {} vs {want}",
        img.coverage()
    );
    let c = img.get(N / 2, N / 2);
    assert!((c - color).abs().max_element() < 2e-3, "{c}");
    assert_eq!(img.get(0, 0), Vec4::ZERO);
    // 1 spp at centres: exactly the centres inside.
    let one = raster_1spp(&scene, &camera_at(d)).unwrap();
    assert!(
        (one.coverage() - centre_fraction(h)).abs() < 1e-9,
        "{} vs {}",
        one.coverage(),
        centre_fraction(h)
    );
    // Seen from behind: single-sided → invisible; double-sided → same coverage.
    let back = render_reference(&scene, &camera_at(-d), Sampling::default()).unwrap();
    assert_eq!(back.coverage(), 0.0);
    let ds = unit_quad(0.0, 0.5, material(color, None, AlphaMode::Opaque, true));
    let back2 = render_reference(&ds, &camera_at(-d), Sampling::default()).unwrap();
    assert!((back2.coverage() - want).abs() < 0.003);
    // Deterministic.
    let again = render_reference(&scene, &camera_at(d), Sampling::default()).unwrap();
    assert_eq!(img, again);
}

fn solid_texture(rgba: [u8; 4]) -> Texture {
    Texture {
        name: "t".into(),
        width: 2,
        height: 2,
        texels: vec![rgba; 4],
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
        encoded: None,
    }
}

#[test]
fn textured_cube_coverage_and_colour() {
    let mut sb = SceneBuilder::new();
    let factor = Vec4::new(1.0, 0.5, 0.25, 1.0);
    let mat = sb.material(material(factor, Some(0), AlphaMode::Opaque, false));
    let mesh = sb.mesh("cube");
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * 0.5;
    // Outward counter-clockwise faces.
    let faces = [
        [
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ],
        [
            c(1., -1., -1.),
            c(-1., -1., -1.),
            c(-1., 1., -1.),
            c(1., 1., -1.),
        ],
        [
            c(1., -1., 1.),
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(1., 1., 1.),
        ],
        [
            c(-1., -1., -1.),
            c(-1., -1., 1.),
            c(-1., 1., 1.),
            c(-1., 1., -1.),
        ],
        [
            c(-1., 1., 1.),
            c(1., 1., 1.),
            c(1., 1., -1.),
            c(-1., 1., -1.),
        ],
        [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., -1., 1.),
            c(-1., -1., 1.),
        ],
    ];
    for f in faces {
        quad(&mut sb, f, mat, mesh);
    }
    let mut scene = sb.finish();
    scene.textures.push(solid_texture([188, 188, 188, 255]));
    let d = 3.0;
    let h = half_px(0.5, d - 0.5); // the front face, at depth d − 0.5
    let want = (2.0 * h / f64::from(N)).powi(2);
    let img = render_reference(&scene, &camera_at(d), Sampling::default()).unwrap();
    assert!(
        (img.coverage() - want).abs() < 0.003,
        "coverage {} vs {want}",
        img.coverage()
    );
    let tex = 0.502_886_5f32; // sRGB 188 → linear
    let expect = Vec4::new(tex, 0.5 * tex, 0.25 * tex, 1.0);
    let px = img.get(N / 2 + 3, N / 2 - 5);
    assert!((px - expect).abs().max_element() < 2e-3, "{px} vs {expect}");
    // From the diagonal, three faces: the silhouette is a hexagon; all covered pixels opaque.
    let diag = Camera {
        eye: Vec3::splat(3.0),
        ..camera_at(3.0)
    };
    let img = render_reference(&scene, &diag, Sampling::Centre).unwrap();
    assert!(img.data.iter().all(|p| p.w == 0.0 || p.w == 1.0));
    assert!(img.coverage() > 0.05);
}

/// 4×4 texels, every one a different colour (red grows with u, green with v), repeat.
fn gradient_texture() -> Texture {
    let mut texels = Vec::new();
    for j in 0..4u8 {
        for i in 0..4u8 {
            texels.push([30 + 60 * i, 30 + 60 * j, 220 - 50 * i, 255]);
        }
    }
    Texture {
        name: "gradient".into(),
        width: 4,
        height: 4,
        texels,
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
        encoded: None,
    }
}

#[test]
fn textured_cube_follows_the_uv_mapping() {
    // The cube of `textured_cube_coverage_and_colour` with a texture whose every texel
    // differs: at each pixel centre the colour must be the texture at the uv of the point
    // the ray hits, computed here analytically from the face's corner uvs (a swapped,
    // mirrored or mis-interpolated uv fails).
    let mut sb = SceneBuilder::new();
    let factor = Vec4::new(1.0, 0.8, 0.6, 1.0);
    let mat = sb.material(material(factor, Some(0), AlphaMode::Opaque, false));
    let mesh = sb.mesh("cube");
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * 0.5;
    // Front (+z) and right (+x) faces, corners a b c d with uv (0,1) (1,1) (1,0) (0,0).
    quad(
        &mut sb,
        [
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ],
        mat,
        mesh,
    );
    quad(
        &mut sb,
        [
            c(1., -1., 1.),
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(1., 1., 1.),
        ],
        mat,
        mesh,
    );
    let mut scene = sb.finish();
    let tex = gradient_texture();
    scene.textures.push(tex.clone());
    // (camera, axis of the face, uv of a point on it)
    type Uv = fn(Vec3) -> Vec2;
    let views: [(Camera, usize, Uv); 2] = [
        (camera_at(3.0), 2, |p| Vec2::new(p.x + 0.5, 0.5 - p.y)),
        (
            Camera {
                eye: Vec3::new(3.0, 0.0, 0.0),
                ..camera_at(3.0)
            },
            0,
            |p| Vec2::new(0.5 - p.z, 0.5 - p.y),
        ),
    ];
    for (cam, axis, uv_of) in views {
        let img = render_reference(&scene, &cam, Sampling::Centre).unwrap();
        let (mut checked, mut discriminating) = (0, 0);
        for y in 0..N {
            for x in 0..N {
                let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
                let t = (0.5 - r.origin[axis]) / r.dir[axis];
                let p = r.origin + r.dir * t;
                let inside = (0..3).filter(|&a| a != axis).all(|a| p[a].abs() < 0.45);
                if !inside {
                    continue;
                }
                let uv = uv_of(p);
                let want = factor * tex.sample_bilinear(uv);
                let got = img.get(x, y);
                assert!(
                    (got - want).abs().max_element() < 2e-3,
                    "axis {axis} pixel ({x},{y}) uv {uv}: {got} vs {want}"
                );
                let swapped = factor * tex.sample_bilinear(Vec2::new(uv.y, uv.x));
                if (swapped - want).abs().max_element() > 0.05 {
                    discriminating += 1;
                }
                checked += 1;
            }
        }
        assert!(checked > 400, "{checked} pixels checked");
        assert!(
            discriminating > checked / 2,
            "the texture would not catch swapped uvs"
        );
    }
}

#[test]
fn mask_and_blend() {
    // Mask: left texel opaque, right transparent, clamp: alpha crosses 0.5 at u = 0.5.
    let mut scene = unit_quad(
        0.0,
        0.5,
        material(Vec4::ONE, Some(0), AlphaMode::Mask { cutoff: 0.5 }, false),
    );
    scene.textures.push(Texture {
        name: "mask".into(),
        width: 2,
        height: 1,
        texels: vec![[255, 255, 255, 255], [255, 255, 255, 0]],
        wrap_u: Wrap::ClampToEdge,
        wrap_v: Wrap::ClampToEdge,
        encoded: None,
    });
    let d = 3.1;
    let h = half_px(0.5, d);
    let full = (2.0 * h / f64::from(N)).powi(2);
    let img = render_reference(&scene, &camera_at(d), Sampling::default()).unwrap();
    assert!(
        (img.coverage() - 0.5 * full).abs() < 0.003,
        "{} vs {}",
        img.coverage(),
        0.5 * full
    );
    // Real values: white premultiplied (rgb = α); α a multiple of 1/16 (16 samples, each
    // kept whole or cut); fully opaque left of the cut (screen x < N/2, where u < 0.5) and
    // fully transparent right of it, inside the quad away from its edges.
    let edge = (f64::from(N) / 2.0 - h).ceil() as u32 + 1;
    for y in 0..N {
        for x in 0..N {
            let p = img.get(x, y);
            assert!(
                (p.truncate() - Vec3::splat(p.w)).abs().max_element() < 1e-6,
                "{p}"
            );
            let k = p.w * 16.0;
            assert!((k - k.round()).abs() < 1e-4, "({x},{y}) α {} not k/16", p.w);
            let interior = (edge..N - edge).contains(&x) && (edge..N - edge).contains(&y);
            if interior && x < N / 2 - 1 {
                assert_eq!(p.w, 1.0, "({x},{y}) left of the cut");
            }
            if (interior && x > N / 2) || x > N - edge {
                assert_eq!(p.w, 0.0, "({x},{y}) right of the cut");
            }
        }
    }

    // Blend: red α 0.5 in front of blue α 0.5 → α 0.75, rgb (0.5, 0, 0.25).
    let mut sb = SceneBuilder::new();
    let red = sb.material(material(
        Vec4::new(1.0, 0.0, 0.0, 0.5),
        None,
        AlphaMode::Blend,
        false,
    ));
    let blue = sb.material(material(
        Vec4::new(0.0, 0.0, 1.0, 0.5),
        None,
        AlphaMode::Blend,
        false,
    ));
    let mesh = sb.mesh("layers");
    let sq = |z: f32| {
        [
            Vec3::new(-0.5, -0.5, z),
            Vec3::new(0.5, -0.5, z),
            Vec3::new(0.5, 0.5, z),
            Vec3::new(-0.5, 0.5, z),
        ]
    };
    quad(&mut sb, sq(-0.2), blue, mesh);
    quad(&mut sb, sq(0.2), red, mesh);
    let scene = sb.finish();
    let img = render_reference(&scene, &camera_at(d), Sampling::Centre).unwrap();
    let px = img.get(N / 2, N / 2);
    assert!(
        (px - Vec4::new(0.5, 0.0, 0.25, 0.75)).abs().max_element() < 1e-5,
        "{px}"
    );
    // The diagonal of each quad passes through pixel centres: no double compositing.
    let diag_px = img.get(N / 2 + 4, N / 2 - 4);
    assert!(
        (diag_px - Vec4::new(0.5, 0.0, 0.25, 0.75))
            .abs()
            .max_element()
            < 1e-5,
        "{diag_px}"
    );
    // An opaque surface behind blended ones.
    let mut sb = SceneBuilder::new();
    let red = sb.material(material(
        Vec4::new(1.0, 0.0, 0.0, 0.25),
        None,
        AlphaMode::Blend,
        false,
    ));
    let green = sb.material(material(
        Vec4::new(0.0, 1.0, 0.0, 1.0),
        None,
        AlphaMode::Opaque,
        false,
    ));
    let mesh = sb.mesh("l");
    quad(&mut sb, sq(0.2), red, mesh);
    quad(&mut sb, sq(-0.2), green, mesh);
    let img = render_reference(&sb.finish(), &camera_at(d), Sampling::Centre).unwrap();
    let px = img.get(N / 2, N / 2);
    assert!(
        (px - Vec4::new(0.25, 0.75, 0.0, 1.0)).abs().max_element() < 1e-5,
        "{px}"
    );
}
