//! Shared test helpers: a GPU adapter or a documented skip, a small synthetic volume.
#![allow(dead_code)]

pub mod cloud;

use std::collections::BTreeMap;
use std::path::PathBuf;

use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, VolumeAsset};
use billow_view::Gpu;

/// A test that cannot run says so on stderr (`SKIP: <test>: <reason>`), and fails instead
/// under CI (`CI` set) or `BILLOW_REQUIRE=all`: [`billow::test_support::skip`], the one
/// rule every billow test and report generator follows.
pub fn skip(test: &str, reason: &str) {
    billow::test_support::skip(test, reason)
}

/// The headless device, or `None` after [`skip`] when no adapter exists (under CI or
/// `BILLOW_REQUIRE=all` a missing adapter fails the test instead: rendering must be
/// possible there; `.ci/ensure-vulkan` installs lavapipe).
pub fn gpu_or_skip(test: &str) -> Option<Gpu> {
    match Gpu::headless() {
        Ok(g) => Some(g),
        Err(e) => {
            skip(test, &e.to_string());
            None
        }
    }
}

/// The cases of a WGSL-against-core check with what the GPU computed for each (`run`,
/// one result a case), or `None` after [`skip`] when no adapter exists.
pub fn check_on_gpu<C, O>(
    test: &str,
    cases: Vec<C>,
    run: impl FnOnce(&Gpu, &[C]) -> Result<Vec<O>, billow_view::ViewError>,
) -> Option<(Vec<C>, Vec<O>)> {
    let gpu = gpu_or_skip(test)?;
    let out = run(&gpu, &cases).expect("run the check shader");
    assert_eq!(out.len(), cases.len(), "one result a case");
    Some((cases, out))
}

/// Where failing tests write their diff images.
pub fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("view-tests");
    std::fs::create_dir_all(&d).expect("create the test output folder");
    d
}

/// Two prisms (vertical edges along z) tiling the box `[a, b]`, uvw = position mapped
/// through `uvw_of` (the library's test support, shared with the root tests).
pub use billow::test_support::box_prisms_z as box_prisms;

/// A 16³ fuzzy, coloured ball in `[0,1]³` (sRGB premultiplied, full MIP chain built by
/// 2×2×2 averaging), cut into 2 × 2 boxes of 2 prisms each (8 cells, shared edges).
pub fn ball_asset(shell: bool) -> VolumeAsset {
    let n = 16u32;
    let dims = [n; 3];
    let mut level0 = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = [x, y, z].map(|i| (i as f32 + 0.5) / n as f32);
                let r = ((p[0] - 0.5).powi(2) + (p[1] - 0.5).powi(2) + (p[2] - 0.5).powi(2)).sqrt();
                let a = (1.0 - r / 0.45).clamp(0.0, 1.0).powf(0.7) * 0.6;
                let lin = [p[0], 0.3 + 0.5 * p[1], 1.0 - p[2]];
                let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                let srgb = |v: f32| {
                    if v <= 0.003_130_8 {
                        12.92 * v
                    } else {
                        1.055 * v.powf(1.0 / 2.4) - 0.055
                    }
                };
                level0.extend_from_slice(&[
                    q(srgb(lin[0] * a)),
                    q(srgb(lin[1] * a)),
                    q(srgb(lin[2] * a)),
                    q(a),
                ]);
            }
        }
    }
    let mips = full_mip_count(dims);
    let mut levels = vec![level0];
    for l in 1..mips {
        let (pd, d) = (mip_dims(dims, l - 1), mip_dims(dims, l));
        let prev = &levels[l as usize - 1];
        let mut out = Vec::new();
        for z in 0..d[2] {
            for y in 0..d[1] {
                for x in 0..d[0] {
                    for ch in 0..4 {
                        let mut s = 0u32;
                        for k in 0..8u32 {
                            let (xx, yy, zz) = (
                                (2 * x + (k & 1)).min(pd[0] - 1),
                                (2 * y + ((k >> 1) & 1)).min(pd[1] - 1),
                                (2 * z + (k >> 2)).min(pd[2] - 1),
                            );
                            s += u32::from(
                                prev[(4 * (xx + pd[0] * (yy + pd[1] * zz)) + ch) as usize],
                            );
                        }
                        out.push(((s + 4) / 8) as u8);
                    }
                }
            }
        }
        levels.push(out);
    }
    let mut cells = Vec::new();
    for (x0, x1) in [(0.0, 0.5), (0.5, 1.0)] {
        for (y0, y1) in [(0.0, 0.5), (0.5, 1.0)] {
            cells.extend(box_prisms([x0, y0, 0.0], [x1, y1, 1.0], |p| {
                if shell {
                    // Two periods in x and z: exercises repeat addressing.
                    [2.0 * p[0] - 0.25, p[1], 2.0 * p[2] + 0.1]
                } else {
                    p
                }
            }));
        }
    }
    let mut params = BTreeMap::new();
    if shell {
        params.insert("shell".to_string(), "test".to_string());
    }
    VolumeAsset {
        header: Header {
            params,
            ..Header::volume("test", ColourSpace::SrgbPremultiplied, dims, mips, false)
        },
        levels,
        normals: None,
        bands: Vec::new(),
        cells,
    }
}

/// `asset` with its mean normals turned into normal moments (SPEC §8.4a): each texel's
/// `(nx², ny², nz²)` of its stored normal, snorm8.
pub fn as_moments(mut asset: VolumeAsset) -> VolumeAsset {
    let sq = |b: u8| {
        let v = f32::from(b as i8).max(-127.0) / 127.0;
        (v * v * 127.0).round() as i8 as u8
    };
    for level in asset.normals.as_mut().expect("normals") {
        for t in level.chunks_exact_mut(4) {
            let m = [sq(t[0]), sq(t[1]), sq(t[2]), 0];
            t.copy_from_slice(&m);
        }
    }
    let v = asset.header.volume.as_mut().expect("volume");
    v.set_normal_kind(Some(billow_format::NormalKind::Moments));
    asset.validate().expect("a valid moments asset");
    asset
}

/// A GPU render read back ([`billow_view::RgbaImage`]) as the CPU renderers' image, to
/// compare the two (the same premultiplied linear RGBA, row 0 at the top).
pub fn image_f32(i: &billow_view::RgbaImage) -> billow::eval::ImageF32 {
    billow::eval::ImageF32 {
        width: i.width,
        height: i.height,
        data: i.data.iter().map(|p| glam::Vec4::from_array(*p)).collect(),
    }
}

/// The viewer's camera for an eval camera, built from its view matrix and projection
/// parameters (`ViewCamera::from_parts`, as the GPU/CPU pairs compare them).
pub fn view_camera(c: &billow_core::camera::Camera) -> billow_view::ViewCamera {
    billow_view::ViewCamera::from_parts(c.view(), c.fov_y, c.width, c.height, c.near, c.far)
}
