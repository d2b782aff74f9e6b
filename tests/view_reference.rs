//! The explosion scene (`fixtures/scenes/explosion.ron`: 16 dust, 115 fire, 28 smoke
//! particles next to a wall, the ground and a swaying oak volume) rendered headless by the
//! real binary at two times, compared with stored reference images
//! (`fixtures/scenes/reference/`, made on lavapipe).
//!
//! Tolerance: RMSE over the sRGB channels ≤ [`MAX_RMSE`] and at most [`MAX_BAD`] of the
//! pixels off by more than [`BAD_DELTA`] in some channel — loose enough for another
//! driver's rounding, tight enough that the frame 1.2 s later (the same scene, its
//! particles moved on) fails it, which the test checks too. On failure a comparison image
//! (reference | render | heatmap × 4) is written and named in the message.
//!
//! `BILLOW_BLESS=1` rewrites the references from the current renderer. Without a GPU
//! adapter the test says it skips, except under CI (env `CI`), where it fails.

mod common;

use std::path::{Path, PathBuf};

use billow::eval::image::{write_comparison_png, ImageF32};
use common::{repo, run};

const SIZE: &str = "160x112";
const TIMES: [&str; 2] = ["0.8", "2.0"];
const MAX_RMSE: f64 = 0.02;
const BAD_DELTA: f32 = 0.1;
const MAX_BAD: f64 = 0.01;

fn reference(t: &str) -> PathBuf {
    repo().join(format!("fixtures/scenes/reference/explosion_t{t}.png"))
}

fn load(p: &Path) -> image::RgbaImage {
    image::open(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .to_rgba8()
}

/// RMSE over sRGB channels in [0, 1] and the fraction of pixels off by > BAD_DELTA.
fn compare(a: &image::RgbaImage, b: &image::RgbaImage) -> (f64, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let (mut se, mut bad) = (0.0f64, 0usize);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let mut worst = 0.0f32;
        for c in 0..4 {
            let d = (p[c] as f32 - q[c] as f32) / 255.0;
            se += (d * d) as f64;
            worst = worst.max(d.abs());
        }
        bad += (worst > BAD_DELTA) as usize;
    }
    let n = (a.width() * a.height()) as f64;
    ((se / (4.0 * n)).sqrt(), bad as f64 / n)
}

fn linear(img: &image::RgbaImage) -> ImageF32 {
    ImageF32::from_image(&image::DynamicImage::ImageRgba8(img.clone()))
}

/// Renders the scene at `t` into `dir`; `None` (after saying why) without an adapter.
fn render(t: &str, dir: &Path) -> Option<image::RgbaImage> {
    let scene = repo().join("fixtures/scenes/explosion.ron");
    let shot = format!("t{t}.png");
    let r = run(
        &[
            "view",
            scene.to_str().unwrap(),
            "--headless",
            "--time",
            t,
            "--size",
            SIZE,
            "--screenshot",
            &shot,
        ],
        dir,
    );
    if r.code != Some(0) && r.stderr.contains("no GPU adapter") {
        common::skip("the explosion reference test", r.stderr.trim());
        return None;
    }
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    Some(load(&dir.join(shot)))
}

#[test]
fn explosion_matches_its_reference_images() {
    let dir = tempfile::tempdir().unwrap();
    let bless = std::env::var_os("BILLOW_BLESS").is_some();
    let mut renders = Vec::new();
    for t in TIMES {
        let Some(img) = render(t, dir.path()) else {
            return;
        };
        if bless {
            let p = reference(t);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            img.save(&p).unwrap();
            println!("blessed {}", p.display());
        }
        renders.push(img);
    }
    let mut failures = Vec::new();
    for (t, img) in TIMES.iter().zip(&renders) {
        let want = load(&reference(t));
        let (rmse, bad) = compare(&want, img);
        println!(
            "t = {t} s: RMSE {rmse:.4}, {:.2}% of pixels off by > {BAD_DELTA}",
            bad * 100.0
        );
        if rmse > MAX_RMSE || bad > MAX_BAD {
            let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("view-reference");
            std::fs::create_dir_all(&out).unwrap();
            let p = out.join(format!("explosion_t{t}.diff.png"));
            write_comparison_png(&linear(&want), &linear(img), 4.0, &p).unwrap();
            failures.push(format!(
                "t = {t} s: RMSE {rmse:.4} (max {MAX_RMSE}), {:.2}% bad pixels (max {:.0}%); \
                 comparison image {}",
                bad * 100.0,
                MAX_BAD * 100.0,
                p.display()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The tolerance tells frames apart: the later reference does not pass for the earlier.
    let (rmse, bad) = compare(&load(&reference(TIMES[1])), &renders[0]);
    assert!(
        rmse > MAX_RMSE || bad > MAX_BAD,
        "the tolerance is too loose: frames {} s and {} s pass as equal (RMSE {rmse:.4}, {:.2}% bad)",
        TIMES[0],
        TIMES[1],
        bad * 100.0
    );
}
