//! CPU and GPU time per frame of whole scenes (docs/performance.md, "Frames without
//! allocations"): the gallery scenes, headless. Uses only the public renderer API that
//! existed before issue 22, so the same file builds against older revisions for
//! before/after tables.
//!
//! `cargo run --release -p billow-view --example scene_frame_times -- [--size WxH]
//! [--frames N] SCENE.ron...` (run with `NODEVICE_SELECT=1` on Mesa). Per scene: loaded
//! like `billow view` loads it (volumes, clouds, meshes, ground, light, shadows), the
//! scene's camera (near/far from the content's bounding sphere as `billow view` makes
//! them), one warm-up frame, then `N` frames into one target, each timed as CPU =
//! `Renderer::render` (plan, encode, submit) and GPU = the wait for the queue right after
//! (submit → idle wall time: the viewer enables no timestamp queries). Prints medians.

use std::path::PathBuf;
use std::time::Instant;

use billow::import::{import, ImportOptions};
use billow::scene::AlphaMode;
use billow_format::{CloudAsset, VolumeAsset};
use billow_view::content::{CloudContent, Content, VolumeContent};
use billow_view::mesh_pass::{MeshData, MeshMaterial, MeshVertex};
use billow_view::scene::SceneFile;
use billow_view::target::Target;
use billow_view::texture::TextureData;
use billow_view::{Gpu, SliceParams, ViewCamera};
use glam::{Mat4, Quat, Vec3};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The scene's content, as `billow view` loads it (bin/billow/view_load.rs).
fn content(scene: &SceneFile) -> Content {
    let mut c = Content {
        light_dir: Vec3::from(scene.light.direction),
        ambient: scene.light.ambient,
        shadows: scene.shadows,
        particles: scene.particles.clone(),
        particle_layer: scene.particle_layer,
        ..Default::default()
    };
    for v in &scene.volumes {
        let (asset, blocks) = VolumeAsset::read_with_blocks(&v.asset).expect("volume asset");
        c.volumes.push(VolumeContent {
            asset,
            instances: v.instances.iter().map(|t| t.matrix()).collect(),
            animation: v.animation,
            blocks: blocks.map(std::sync::Arc::new),
        });
    }
    for d in &scene.clouds {
        let (asset, blocks) = CloudAsset::read_with_blocks(&d.asset).expect("cloud asset");
        c.clouds.push(CloudContent {
            asset,
            instances: d.instances.iter().map(|t| t.matrix()).collect(),
            lod_distances: d.lod_distances.clone(),
            transition: d.transition,
            dissolve: d.dissolve,
            blocks: blocks.map(std::sync::Arc::new),
        });
    }
    for m in &scene.meshes {
        let s = import(&m.path, &ImportOptions::default())
            .expect("mesh")
            .scene;
        let t = &m.transform;
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
        c.meshes.push(data);
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
    c
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut w, mut h, mut frames) = (320u32, 240u32, 5usize);
    let mut scenes: Vec<PathBuf> = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--size" => {
                let s = args.next().expect("--size WxH");
                let (a, b) = s.split_once('x').expect("--size WxH");
                (w, h) = (a.parse().expect("width"), b.parse().expect("height"));
            }
            "--frames" => frames = args.next().expect("--frames N").parse().expect("N"),
            _ => scenes.push(PathBuf::from(a)),
        }
    }
    println!("| scene | CPU ms/frame | GPU ms/frame | slices | shadow slices | draws |");
    println!("|---|---:|---:|---:|---:|---:|");
    let mut adapter = String::new();
    for path in &scenes {
        let scene = SceneFile::load(path).expect("scene");
        let c = content(&scene);
        let (lo, hi) = c.bounds().expect("content");
        let (centre, radius) = (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-6));
        let sc = scene.camera.as_ref().expect("the scene's camera");
        let fov = sc.fov_deg.to_radians();
        let eye = Vec3::from(sc.eye);
        let dist = (eye - centre).length();
        let near = sc
            .near
            .unwrap_or(((dist - radius) * 0.5).max(radius * 1e-3));
        let far = sc.far.unwrap_or((dist + radius) * 2.0);
        let cam = ViewCamera::look_at(
            eye,
            Vec3::from(sc.target),
            Vec3::from(sc.up),
            fov,
            w,
            h,
            near,
            far,
        );
        let gpu = Gpu::headless().expect("adapter");
        adapter = gpu.describe();
        let r = c.build(gpu, SliceParams::default(), fov).expect("build");
        let target = Target::new(&r.gpu, w, h);
        let (mut cpu, mut gpu_ms) = (Vec::new(), Vec::new());
        let mut last = None;
        for f in 0..1 + frames {
            let t0 = Instant::now();
            let stats = r.render(&target, &cam).expect("render");
            let t1 = Instant::now();
            r.gpu.wait().expect("wait");
            let t2 = Instant::now();
            if f >= 1 {
                cpu.push(1e3 * (t1 - t0).as_secs_f64());
                gpu_ms.push(1e3 * (t2 - t1).as_secs_f64());
            }
            last = Some(stats);
        }
        let s = last.expect("a frame");
        let name = path
            .file_stem()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        println!(
            "| {name} | {:.2} | {:.0} | {} | {} | {} |",
            median(cpu),
            median(gpu_ms),
            s.slices,
            s.shadow_slices,
            s.draw_calls
        );
    }
    println!("\nadapter: {adapter}, {w}x{h}, median of {frames} frames after 1 warm-up");
}
