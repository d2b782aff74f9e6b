//! The mesh and cloud passes' light model (`shaders/shading.wgsl`'s `diffuse_factor`),
//! run in a compute pass on the headless device and read back, against the Rust it
//! copies (shaders cannot call it): [`billow_core::shading::diffuse_factor`], the
//! two-sided Lambert plus ambient of the billboard bake, the reference and the mesh pass,
//! within `1e-6` (the GPU's dot product may fuse its multiply-adds). Unshadowed
//! (visibility 1) it is the core function itself; shadowed, the shader scales the
//! diffuse term `|n·light|` (the core's factor at zero ambient) by the visibility.
//!
//! `moments_cosine_of` ↔ [`billow_core::shading::moments_diffuse_factor`] at ambient 0 and
//! visibility 1 (the volume pass multiplies the rest in): moments from one axis to an even
//! spread, lights and view axes over the sphere, within `2e-5` (the GPU's `acos`, `sin`
//! and `sqrt` are not correctly rounded).

mod common;

use billow_core::shading::{
    diffuse_factor, moments_diffuse_factor, DEFAULT_AMBIENT, DEFAULT_LIGHT,
};
use billow_view::shading_gpu::{
    diffuse_factor_on_gpu, moments_cosine_on_gpu, MomentsCase, ShadingCase,
};
use glam::Vec3;

/// `n` unit directions spread over the sphere (a Fibonacci lattice).
fn sphere(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f32;
            Vec3::new(r * a.cos(), y, r * a.sin()).normalize()
        })
        .collect()
}

fn cases() -> Vec<ShadingCase> {
    let lights = [
        DEFAULT_LIGHT.normalize(),
        Vec3::Y,
        -Vec3::X,
        Vec3::new(0.3, 1.0, 0.2).normalize(),
        Vec3::new(-0.8, 0.1, -0.6).normalize(),
    ];
    let normals: Vec<Vec3> = sphere(96)
        .into_iter()
        .chain([Vec3::X, Vec3::Y, Vec3::Z, -Vec3::Y])
        .collect();
    let mut out = Vec::new();
    for light in lights {
        for ambient in [0.0, DEFAULT_AMBIENT, 0.35, 0.7, 1.0] {
            for visibility in [1.0, 0.0, 0.25, 0.618] {
                for n in &normals {
                    out.push(ShadingCase {
                        n: [n.x, n.y, n.z, ambient],
                        light: [light.x, light.y, light.z, visibility],
                    });
                }
            }
        }
    }
    out
}

#[test]
fn wgsl_diffuse_factor_matches_billow_core() {
    let Some((cases, out)) = common::check_on_gpu(
        "wgsl_diffuse_factor_matches_billow_core",
        cases(),
        diffuse_factor_on_gpu,
    ) else {
        return;
    };
    let results = cases.iter().zip(&out).map(|(k, &got)| {
        let (n, ambient) = (Vec3::from_slice(&k.n[..3]), k.n[3]);
        let (light, visibility) = (Vec3::from_slice(&k.light[..3]), k.light[3]);
        let want = if visibility == 1.0 {
            diffuse_factor(n, light, ambient)
        } else {
            ambient + (1.0 - ambient) * (diffuse_factor(n, light, 0.0) * visibility)
        };
        let call = format!("diffuse_factor({n}, {light}, {ambient}, {visibility})");
        (call, got, want)
    });
    assert_within(results, 1e-6);
}

/// Each `(call, gpu, core)` within `tol`: the worst difference printed, the first
/// mismatches listed when any.
fn assert_within(results: impl Iterator<Item = (String, f32, f32)>, tol: f32) {
    let (mut bad, mut worst, mut n) = (Vec::new(), 0f32, 0);
    for (call, got, want) in results {
        n += 1;
        worst = worst.max((got - want).abs());
        if (got - want).abs() > tol || (got - want).is_nan() {
            bad.push(format!("{call}: gpu {got}, core {want}"));
        }
    }
    eprintln!("{n} cases; worst |Δ| {worst:e}");
    assert!(
        bad.is_empty(),
        "{} mismatches, the first:\n{}",
        bad.len(),
        bad[..bad.len().min(20)].join("\n")
    );
}

fn moments_cases() -> Vec<MomentsCase> {
    let dirs = sphere(24);
    let mut ms = vec![
        Vec3::X,
        Vec3::Y,
        Vec3::splat(1.0 / 3.0),
        Vec3::new(0.5, 0.5, 0.0),
        Vec3::new(0.1, 0.8, 0.1),
        Vec3::new(0.0, 0.0, 0.0),
        // Filtered against empty texels: a trace below 1.
        Vec3::new(0.05, 0.2, 0.1),
    ];
    ms.extend(dirs.iter().step_by(3).map(|d| *d * *d));
    let mut out = Vec::new();
    for m in &ms {
        for light in &dirs {
            for axis in dirs.iter().step_by(2).chain([&(Vec3::Z * 3.0)]) {
                out.push(MomentsCase {
                    m: m.extend(0.0).to_array(),
                    light: light.extend(0.0).to_array(),
                    axis: axis.extend(0.0).to_array(),
                });
            }
        }
    }
    out
}

#[test]
fn wgsl_moments_cosine_matches_billow_core() {
    let Some((cases, out)) = common::check_on_gpu(
        "wgsl_moments_cosine_matches_billow_core",
        moments_cases(),
        moments_cosine_on_gpu,
    ) else {
        return;
    };
    let results = cases.iter().zip(&out).map(|(k, &got)| {
        let m = Vec3::from_slice(&k.m[..3]);
        let light = Vec3::from_slice(&k.light[..3]);
        let view = Vec3::from_slice(&k.axis[..3]).normalize();
        let want = moments_diffuse_factor(m, light, view, 0.0, 1.0);
        (
            format!("moments_cosine_of({m}, {light}, {view})"),
            got,
            want,
        )
    });
    assert_within(results, 2e-5);
}
