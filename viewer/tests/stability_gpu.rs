//! Issue 25, item 5, on the viewer (GPU): the stability cases of the CPU suite
//! (tests/eval_slicer.rs, tests/eval_prism_plane.rs) rendered by billow-view.
//!
//! - 500 slices at α ≈ 1e-3 accumulated in the Rgba16Float target against f64;
//! - a camera inside a volume;
//! - a unit cell at a 1e5 offset;
//! - NaN / ∞ prism input: no section, no fragments, no NaN pixels.
//!
//! Each renders at most 32² pixels; the file runs in about 10 s on lavapipe on two shared
//! cores, mostly pipeline compilation (each `Renderer` builds its own).

mod common;

use billow_core::slicing::Spacing;
use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, VolumeAsset};
use billow_view::prism_plane_gpu::intersect_on_gpu;
use billow_view::{Renderer, SliceParams, ViewCamera};
use glam::{Mat4, Vec3};

const FOV: f32 = std::f32::consts::FRAC_PI_4;
const RES: u32 = 16;

/// The unit cube as a `RES³` volume, every level-0 voxel of opacity `alpha` (8-bit) and
/// premultiplied linear colour `colour · α`; level `l` composites `2^l` voxels, as
/// tests/eval_slicer.rs's `cube_volume` (linear instead of sRGB colour).
fn cube_volume(alpha: f32, colour: [f32; 3]) -> VolumeAsset {
    let dims = [RES; 3];
    let mips = full_mip_count(dims);
    let q = |v: f32| (v * 255.0).round() as u8;
    let levels = (0..mips)
        .map(|l| {
            let a = 1.0 - (1.0 - alpha).powi(1 << l);
            let texel = [q(colour[0] * a), q(colour[1] * a), q(colour[2] * a), q(a)];
            let d = mip_dims(dims, l);
            texel.repeat((d[0] * d[1] * d[2]) as usize)
        })
        .collect();
    VolumeAsset {
        header: Header::volume("test", ColourSpace::LinearPremultiplied, dims, mips, false),
        levels,
        normals: None,
        bands: Vec::new(),
        cells: common::box_prisms([0.0; 3], [1.0; 3], |p| p),
    }
}

/// A look-at camera (up +y) of `size²` pixels.
fn camera(eye: Vec3, target: Vec3, fov: f32, size: u32, near: f32) -> ViewCamera {
    ViewCamera::look_at(eye, target, Vec3::Y, fov, size, size, near, 1000.0)
}

fn renderer(gpu: billow_view::Gpu, asset: &VolumeAsset, spacing: Spacing) -> Renderer {
    let mut r = Renderer::new(gpu);
    r.params = SliceParams {
        spacing,
        ..Default::default()
    };
    r.add_volume(asset, vec![Mat4::IDENTITY]).expect("upload");
    r
}

/// 500 slices at α ≈ 1e-3 over one pixel, composited "over" in the Rgba16Float target,
/// against the same sum in f64.
///
/// The case: the unit cube, voxel α₈ = 8/255, white (premultiplied rgb = α), seen face-on
/// from 2.5 with a 15° field of view (the cube fills the view at every depth), uniform
/// spacing `d = 1/500`: `N = 500` slices, each of opacity `α = 1 − (1 − α₈)^(d/v₀) =
/// 1.0195e-3` (`v₀ = 1/16`, level 0). The exact result is `V = Σₖ α(1 − α)ᵏ =
/// 1 − (1 − α)^N = 0.3995` in all four channels.
///
/// The bound. Each blend `vₖ = s + (1 − α)·vₖ₋₁` is stored as f16, whose 10-bit
/// mantissa rounds it with relative error ≤ `u`: `u = 2⁻¹¹` rounding to nearest, `2⁻¹⁰`
/// rounding toward zero, which Vulkan permits for conversions to f16 and lavapipe does
/// (so `u = 2⁻¹⁰` is asserted). With `vₖ = (s + (1 − α)vₖ₋₁)(1 + δₖ)`, `|δₖ| ≤ u`, the
/// error `eₖ = vₖ − Vₖ` obeys `eₖ = (1 − α)eₖ₋₁ + δₖ·Vₖ` (to first order): an error made
/// at step k is damped by `(1 − α)^(N−k)` afterwards and, the partial sums only growing,
/// `|e_N| ≤ u·V·S` with `S = Σ_{j<N}(1 − α)^j = (1 − (1 − α)^N)/α = 391.9` — 0.383·V
/// (0.191·V to nearest; the undamped `N·u` would be 0.488). A blender that also rounds
/// its inputs to f16 (hardware fp16 blending; lavapipe blends in f32) adds `u` for the
/// source and, for the factor `1 − α` off by < 2⁻¹¹ (the f16 spacing below 1), `2⁻¹¹·T/S`
/// with `T = Σ_{j<N} j(1 − α)^(j−1)` (the sensitivity of `V = s·S` to the factor; `T/S =
/// 228.6`): 0.112. The bound asserted, relative, per channel: `u·S + u + 2⁻¹¹·T/S =
/// 0.495`. The shader's f32 opacity correction (≈ 1e-6 relative) is far below it.
/// lavapipe measures 0.359619 = −9.98 %, bit for bit the f32-blend, f16-store recurrence
/// rounded toward zero (to nearest it would be +1.8 %).
///
/// Seen failing on a broken build: with the target (`target::COLOR_FORMAT`) made
/// Rgba8Unorm, each slice's 1e-3 rounds to 0 of 1/255 and the pixel stays 0.
#[test]
fn five_hundred_faint_slices_accumulate_in_f16_within_the_mantissa_bound() {
    let name = "five_hundred_faint_slices_accumulate_in_f16_within_the_mantissa_bound";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let a8 = 8.0f32 / 255.0;
    let asset = cube_volume(a8, [1.0; 3]);
    // Level 0 holds exactly 8/255.
    assert_eq!(asset.levels[0][3], 8);
    let d = 1.0 / 500.0;
    let r = renderer(gpu, &asset, Spacing::Uniform { spacing: d });
    let size = 32;
    let cam = camera(
        Vec3::new(0.5, 0.5, 3.0),
        Vec3::splat(0.5),
        15f32.to_radians(),
        size,
        0.01,
    );
    let (img, stats) = r.render_image(&cam).expect("render");
    let n = stats.slices;
    assert_eq!(n, 500, "slices");
    let v0 = f64::from(stats.voxel_size);
    assert!((v0 - 1.0 / 16.0).abs() < 1e-6, "v0 {v0}");
    let alpha = 1.0 - (1.0 - f64::from(a8)).powf(f64::from(d) / v0);
    assert!((alpha - 1e-3).abs() < 3e-5, "per-slice α {alpha}");
    let want = 1.0 - (1.0 - alpha).powi(n as i32);
    let u = 2f64.powi(-10);
    let beta = 1.0 - alpha;
    let s_sum: f64 = (0..n).map(|j| beta.powi(j as i32)).sum();
    let t_sum: f64 = (1..n).map(|j| j as f64 * beta.powi(j as i32 - 1)).sum();
    let damped = u * s_sum;
    let bound = damped + u + 2f64.powi(-11) * t_sum / s_sum;
    let mut worst = 0.0f64;
    for (i, p) in img.data.iter().enumerate() {
        for (c, v) in p.iter().enumerate() {
            let v = f64::from(*v);
            assert!(v.is_finite(), "pixel {i} channel {c}: {v}");
            worst = worst.max((v - want).abs() / want);
        }
    }
    println!(
        "{n} slices of α {alpha:.4e}: f64 {want:.5}, centre {:?}, worst relative error {worst:.4} \
         (bound {bound:.4}; the f16 stores' share {damped:.4})",
        img.data[(size * size / 2 + size / 2) as usize]
    );
    assert!(
        worst <= bound,
        "relative error {worst} above the f16 bound {bound}"
    );
}

/// The CPU case `camera_inside_the_volume_sees_the_part_in_front` on the viewer: the eye
/// at the centre of the α = 0.1 cube, near plane 0.1, looking down −z. The GPU plans the
/// same slices (billow-core's slice_depths from `max(z_min, near)`): 6 of them, one voxel
/// apart, from the near plane to the back face, the farthest standing for the slab to the
/// back face (`far_slab`), so together they stand for the whole path: every pixel is
/// finite with the path-length α = 1 − (1 − α₈)^6.4 (1e-3: the f16 target's rounding
/// over 6 blends; before the far slab it was 1 − (1 − α₈)⁶, 0.022 less).
///
/// Seen failing on a broken build: without the volume plan's near clamp (`z_min.max(
/// camera.near)`) 16 slices are planned instead of 6, half of them behind the eye (the
/// rasterizer clips at the near plane anyway, so the slice count is what shows it).
#[test]
fn camera_inside_the_volume_sees_the_part_in_front_on_the_gpu() {
    let name = "camera_inside_the_volume_sees_the_part_in_front_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let alpha = 0.1f32;
    let asset = cube_volume(alpha, [0.2, 0.5, 0.8]);
    let r = renderer(gpu, &asset, Spacing::Adaptive { bias: 1.0 });
    let cam = camera(Vec3::splat(0.5), Vec3::new(0.5, 0.5, -1.0), FOV, 32, 0.1);
    let (img, stats) = r.render_image(&cam).expect("render");
    let a8 = f64::from((alpha * 255.0).round() / 255.0);
    let n = 6;
    assert_eq!(
        stats.slices, n,
        "slices between the near plane and the back face only"
    );
    let want_path = 1.0 - (1.0 - a8).powf(0.4 * 16.0);
    let want = want_path;
    assert!((want - (1.0 - (1.0 - a8).powi(n as i32))).abs() > 0.01);
    for (i, p) in img.data.iter().enumerate() {
        assert!(p.iter().all(|c| c.is_finite()), "pixel {i}: {p:?}");
        assert!((0.0..=1.0).contains(&p[3]), "pixel {i}: α {}", p[3]);
        assert!(
            (f64::from(p[3]) - want).abs() < 1e-3,
            "pixel {i}: α {} vs {want} ({n} slices; path-length {want_path:.4})",
            p[3]
        );
    }
}

/// Renders the cube (α per voxel `alpha`) from 1.5 in front, at the origin and with the
/// cube and the camera moved by `off`.
fn at_origin_and_moved(
    gpu: billow_view::Gpu,
    alpha: f32,
    off: Vec3,
) -> (
    (billow_view::RgbaImage, billow_view::FrameStats),
    (
        (billow_view::RgbaImage, billow_view::Gpu),
        billow_view::FrameStats,
    ),
) {
    let asset = cube_volume(alpha, [0.2, 0.5, 0.8]);
    let mut far = asset.clone();
    for c in &mut far.cells {
        for p in &mut c.pos {
            *p = (Vec3::from(*p) + off).to_array();
        }
    }
    let mut r = Renderer::new(gpu);
    r.add_volume(&asset, vec![Mat4::IDENTITY]).expect("upload");
    let eye = Vec3::splat(0.5) + 1.5 * Vec3::new(0.45, 0.3, 0.84).normalize();
    let cam = camera(eye, Vec3::splat(0.5), FOV, 32, 0.01);
    let origin = r.render_image(&cam).expect("render");
    let mut r = Renderer::new(r.gpu);
    r.add_volume(&far, vec![Mat4::IDENTITY]).expect("upload");
    let fcam = camera(eye + off, Vec3::splat(0.5) + off, FOV, 32, 0.01);
    let (img, stats) = r.render_image(&fcam).expect("render");
    (origin, ((img, r.gpu), stats))
}

/// The CPU case `a_cell_at_a_1e5_offset_matches_the_cell_at_the_origin` on the viewer (the
/// same oblique view, cubes and offset): every pixel finite with α in [0, 1], the same
/// slice count and voxel size, the centre covered.
///
/// The tolerance is the CPU's (mean |Δα| < 0.004, ≤ 16 pixels off by > 0.05): the volume
/// plan transforms cells camera-relative (`ViewCamera::to_view`, `R·(p − eye)`).
///
/// Seen failing on a broken build: with the view matrix instead (`view·p = R·p + t`,
/// `|t| ≈ 1.7e5`, each vertex moving by its own f32 rounding) the viewer measured mean
/// |Δα| 0.0103 and 50 pixels (α = 0.3), 0.0074 and 47 (α = 0.05).
#[test]
fn a_cell_at_a_1e5_offset_matches_the_cell_at_the_origin_on_the_gpu() {
    let name = "a_cell_at_a_1e5_offset_matches_the_cell_at_the_origin_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let mut gpu = Some(gpu);
    let off = Vec3::new(100_000.3, -100_000.7, 100_000.1);
    let mut results = Vec::new();
    for alpha in [0.3f32, 0.05] {
        let ((a, sa), (b, sb)) = at_origin_and_moved(gpu.take().expect("device"), alpha, off);
        gpu = Some(b.1);
        let (a, b) = (a, b.0);
        let (mut sum, mut big) = (0.0f64, 0usize);
        for (p, q) in a.data.iter().zip(&b.data) {
            assert!(
                q.iter().all(|c| c.is_finite()) && (0.0..=1.0).contains(&q[3]),
                "{q:?}"
            );
            let d = f64::from((p[3] - q[3]).abs());
            sum += d;
            big += usize::from(d > 0.05);
        }
        let mean = sum / 1024.0;
        println!(
            "α {alpha}: mean |Δα| {mean:.5}, {big} pixels > 0.05, slices {} / {}, v0 {} / {}",
            sa.slices, sb.slices, sa.voxel_size, sb.voxel_size
        );
        assert!(a.data[16 * 32 + 16][3] > 0.5);
        assert_eq!(sa.slices, sb.slices, "α {alpha}");
        assert!((sa.voxel_size - sb.voxel_size).abs() < 1e-4, "α {alpha}");
        results.push((alpha, mean, big));
    }
    for (alpha, mean, big) in results {
        assert!(
            mean < 0.004 && big <= 16,
            "α {alpha}: mean |Δα| {mean}, {big} pixels > 0.05"
        );
    }
}

/// The prisms of a NaN / ∞ case: a finite box prism with one coordinate replaced.
fn poisoned(which: usize, value: f32) -> ([[f32; 3]; 6], [[f32; 3]; 6]) {
    let cell = &common::box_prisms([-1.0, -1.0, -3.0], [1.0, 1.0, -1.0], |p| {
        [(p[0] + 1.0) / 2.0, (p[1] + 1.0) / 2.0, (p[2] + 3.0) / 2.0]
    })[0];
    let (mut pos, mut uvw) = (cell.pos, cell.uvw);
    match which {
        0 => pos[1][0] = value, // x of a bottom vertex
        1 => pos[4][2] = value, // z of a top vertex (its vertical edge crosses the plane)
        _ => uvw[2][1] = value, // a texture coordinate
    }
    (pos, uvw)
}

/// NaN and ∞ prism input has no section on the GPU either (billow-core's guard, ported
/// to prism_plane.wgsl): the compute check returns the empty polygon for every case
/// (the finite prism has a triangle there), as the CPU does.
///
/// Seen failing on a broken build: without the WGSL guard the first case (a NaN x)
/// returns a triangle with a NaN vertex.
#[test]
fn nan_and_infinite_prisms_have_no_section_on_the_gpu() {
    let name = "nan_and_infinite_prisms_have_no_section_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    let mut cases = Vec::new();
    for which in 0..3 {
        for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let (pos, uvw) = poisoned(which, v);
            cases.push((pos, uvw, -2.0));
        }
    }
    // The finite prism and a NaN plane.
    let (pos, uvw) = poisoned(0, 1.0);
    cases.push((pos, uvw, -2.0));
    cases.push((pos, uvw, f32::NAN));
    let got = intersect_on_gpu(&gpu, &cases).expect("GPU intersection");
    for (i, (g, (p, t, z))) in got.iter().zip(&cases).enumerate() {
        let cpu = billow_core::prism_plane::intersect_prism_plane(p, t, *z);
        if i == cases.len() - 2 {
            assert!(
                g.count >= 3 && cpu.count == g.count,
                "the finite prism is cut"
            );
        } else {
            assert_eq!(
                (g.count, cpu.count),
                (0, 0),
                "case {i}: {p:?} {t:?} z {z}: GPU {:?}",
                &g.pos[..g.count]
            );
        }
    }
}

/// The render half of the case above: a volume whose cells include prisms that turn
/// non-finite in view space draws nothing but its finite cells, and no NaN pixel.
///
/// Seen failing on a broken build: without the WGSL guard the poisoned prisms' finite
/// triangles are drawn (498 of the 1024 pixels outside the finite cube, lavapipe).
#[test]
fn nan_and_infinite_prisms_draw_nothing_on_the_gpu() {
    let name = "nan_and_infinite_prisms_draw_nothing_on_the_gpu";
    let Some(gpu) = common::gpu_or_skip(name) else {
        return;
    };
    // Rendering. Assets are checked on upload (a non-finite CELL is an error), so the
    // poison comes from the instance transform: x and y scaled by 1e10, cells given at
    // 1e-10 of their size, one vertex of each poisoned prism at ±1e30 (finite) → ±∞ in
    // world space, NaN in view space. `clean`: a cube in the view's lower left; `dirty`:
    // the same plus poisoned copies of a view-filling box (the camera looks down −z).
    let tiny = |p: [f32; 3]| [p[0] * 1e-10, p[1] * 1e-10, p[2]];
    let asset = cube_volume(0.3, [0.2, 0.5, 0.8]);
    let mut clean = asset.clone();
    clean.cells = common::box_prisms([0.0, 0.0, 0.0], [0.4, 0.4, 1.0], |p| p);
    for c in &mut clean.cells {
        c.pos = c.pos.map(tiny);
    }
    let mut dirty = clean.clone();
    // Each vertex in turn (x or y, either sign), seen obliquely: the slices cut quads and
    // pentagons whose finite triangles a missing guard would draw (a triangle with a NaN
    // vertex the rasterizer drops by itself).
    for k in 0..6 {
        for mut c in common::box_prisms([-2.0, -2.0, 0.0], [3.0, 3.0, 1.0], |p| {
            [p[0].clamp(0.0, 1.0), p[1].clamp(0.0, 1.0), p[2]]
        }) {
            c.pos = c.pos.map(tiny);
            c.pos[k][k % 2] = if k < 3 { 1e30 } else { -1e30 };
            dirty.cells.push(c);
        }
    }
    let m = Mat4::from_scale(Vec3::new(1e10, 1e10, 1.0));
    let eye = Vec3::splat(0.5) + 3.0 * Vec3::new(0.3, 0.2, 1.0).normalize();
    let cam = camera(eye, Vec3::splat(0.5), FOV, 32, 0.01);
    let mut r = Renderer::new(gpu);
    r.add_volume(&clean, vec![m]).expect("upload");
    let (want, ws) = r.render_image(&cam).expect("render");
    let mut r = Renderer::new(r.gpu);
    r.add_volume(&dirty, vec![m]).expect("upload");
    let (got, gs) = r.render_image(&cam).expect("render");
    assert_eq!(gs.cells, ws.cells + 12, "the poisoned cells are drawn");
    // The poisoned prisms' finite vertices widen the depth range (more slices), so the
    // finite cube's pixels may differ; the view-filling poisoned prisms may draw nowhere.
    let covered = want.data.iter().filter(|p| p[3] > 0.5).count();
    assert!(covered > 20, "the finite cells show ({covered} pixels)");
    // Outside: no pixel within 2 of it drawn in `want` (the finite cube's outline may
    // move with the slices).
    let near_cube = |i: usize| {
        let (x, y) = ((i % 32) as i32, (i / 32) as i32);
        (-2..=2).any(|dy| {
            (-2..=2).any(|dx| {
                let (u, v) = (x + dx, y + dy);
                (0..32).contains(&u)
                    && (0..32).contains(&v)
                    && want.data[(v * 32 + u) as usize][3] > 0.0
            })
        })
    };
    let mut stray = 0;
    for (i, p) in got.data.iter().enumerate() {
        assert!(p.iter().all(|c| c.is_finite()), "pixel {i}: {p:?}");
        stray += usize::from(!near_cube(i) && *p != [0.0; 4]);
    }
    println!(
        "slices {} / {}, {covered} pixels covered, {stray} drawn outside the finite cells",
        ws.slices, gs.slices
    );
    assert_eq!(stray, 0, "pixels drawn by the poisoned prisms");
}
