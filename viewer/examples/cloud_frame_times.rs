//! CPU and GPU time per frame of the cloud pass for 1, 100 and 1,000 instances of a cloud
//! asset (docs/performance.md, "Billboard-cloud frames"). Uses only the public renderer
//! API, so the same file builds against older revisions for before/after tables.
//!
//! `cargo run --release -p billow-view --example cloud_frame_times -- CLOUD.billow
//! [SIZE] [FRAMES] [shadows|noshadows] [LEVEL] [dissolve]` (run with `NODEVICE_SELECT=1` on Mesa). Per instance count: the
//! instances on a square grid 2.5 bounding-sphere radii apart, the camera fitting all of
//! them, LOD distances the viewer's default, shadows on unless `noshadows`, every instance at
//! billboard level `LEVEL` when given (the LOD distance forced just past its switch,
//! no morph; with `dissolve`, forced to the switch itself instead, where every instance
//! is half way through its dithered dissolve from level `LEVEL − 1`: both levels drawn, the
//! dissolve's worst case); 5 warm-up frames, then
//! `FRAMES` frames, each timed as CPU = `Renderer::render` (plan, encode, submit) and
//! GPU = the wait for the queue right after (submit→idle wall time: the adapter's
//! timestamp queries are not enabled by the viewer). The asset's kept mesh (trunk) is
//! left out. Prints medians, quads drawn, draw
//! calls, and (where the renderer reports it) bytes written per frame for the clouds.

use std::time::Instant;

use billow_format::CloudAsset;
use billow_view::target::Target;
use billow_view::{Gpu, Renderer, ViewCamera};
use glam::{Mat4, Vec3};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: cloud_frame_times CLOUD.billow [SIZE] [FRAMES]");
        std::process::exit(2);
    };
    let size: u32 = args.get(2).map_or(256, |s| s.parse().expect("SIZE"));
    let frames: usize = args.get(3).map_or(15, |s| s.parse().expect("FRAMES"));
    let shadows = args.get(4).is_none_or(|s| s != "noshadows");
    let level: Option<usize> = args.get(5).map(|s| s.parse().expect("LEVEL"));
    let dissolving = args.get(6).is_some_and(|s| s == "dissolve");
    let mut asset = CloudAsset::read(std::path::Path::new(path)).expect("read the cloud");
    // The kept mesh (trunk) is left out: `add_cloud` gives the mesh pass a copy of it, with
    // its textures, per instance (1,000 oak trunks exhaust 24 GB), and it is not the
    // cloud pass's work.
    asset.trunk = Default::default();
    let b = &asset.header.bounds;
    let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
    let (centre, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
    println!(
        "| instances | CPU ms/frame | GPU ms/frame | quads | draw calls | cloud bytes/frame |"
    );
    println!("|---:|---:|---:|---:|---:|---:|");
    let mut adapter = String::new();
    for count in [1usize, 100, 1000] {
        let gpu = Gpu::headless().expect("adapter");
        adapter = gpu.describe();
        let side = (count as f64).sqrt().ceil() as usize;
        let step = 2.5 * radius;
        let instances: Vec<Mat4> = (0..count)
            .map(|i| {
                let (x, z) = ((i % side) as f32, (i / side) as f32);
                let off = 0.5 * (side as f32 - 1.0);
                Mat4::from_translation(Vec3::new((x - off) * step, 0.0, (z - off) * step) - centre)
            })
            .collect();
        let mut r = Renderer::new(gpu);
        let fov = 0.8f32;
        r.add_cloud(&asset, instances, None, 0.25, fov)
            .expect("add the cloud");
        r.set_shadows(shadows);
        if let Some(k) = level {
            let d = billow_view::render::default_lod_distances(radius, fov, asset.levels.len() + 1);
            if dissolving {
                r.lod_distance_override = Some(d[k - 1]);
            } else {
                r.lod_distance_override = Some(1.01 * d[k - 1]);
                // One level at a time, not dissolving.
                r.dissolve_override = Some(0.0);
            }
        }
        // Seen from above at 45°, far enough for the whole grid.
        let extent = 0.5 * side as f32 * step + radius;
        let dist = 1.6 * extent / (0.5 * fov).tan();
        let eye = Vec3::new(0.0, 1.0, 1.0).normalize() * dist;
        let cam = ViewCamera::look_at(
            eye,
            Vec3::ZERO,
            Vec3::Y,
            fov,
            size,
            size,
            0.05 * dist,
            3.0 * dist,
        );
        let target = Target::new(&r.gpu, size, size);
        let (mut cpu, mut gpu_ms) = (Vec::new(), Vec::new());
        let mut last = None;
        for f in 0..5 + frames {
            let t0 = Instant::now();
            let stats = r.render(&target, &cam).expect("render");
            let t1 = Instant::now();
            r.gpu.wait().expect("wait");
            let t2 = Instant::now();
            if f >= 5 {
                cpu.push(1e3 * (t1 - t0).as_secs_f64());
                gpu_ms.push(1e3 * (t2 - t1).as_secs_f64());
            }
            last = Some(stats);
        }
        let s = last.expect("a frame");
        let ron = ron::to_string(&s).unwrap_or_default();
        let bytes = ron
            .split("cloud_bytes_uploaded:")
            .nth(1)
            .and_then(|t| t.split([',', ')']).next())
            .map_or("—".to_string(), |v| v.trim().to_string());
        println!(
            "| {count} | {:.2} | {:.2} | {} | {} | {bytes} |",
            median(cpu),
            median(gpu_ms),
            s.cloud_quads,
            s.draw_calls,
        );
        let lods = s.cloud_lods.iter().fold([0usize; 8], |mut a, (l, _)| {
            a[(*l).min(7)] += 1;
            a
        });
        eprintln!(
            "  {count} instances: levels {:?}",
            &lods[..asset.levels.len() + 1]
        );
    }
    println!(
        "\nadapter: {adapter}, {size}x{size}, {frames} frames after 5 warm-up, shadows {}",
        if shadows { "on" } else { "off" }
    );
    if let Some(k) = level {
        println!("every instance at billboard level {k}");
    }
}
