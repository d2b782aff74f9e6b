//! The directional shadow map, built only when a scene asks for shadows.
//!
//! Cascaded: the camera's depth range (where its frustum meets the scene's bounds) is
//! split into up to [`CASCADES`] slabs, one per factor [`CASCADE_RATIO`] of its depth
//! ratio (the practical split scheme: log and uniform splits mixed by
//! [`SPLIT_LAMBDA`]), and each slab gets its own orthographic light camera,
//! fitted to the receivers in that slab ([`fit_light_camera`]): across the light, to the
//! part of the scene's bounds inside the slab's frustum ([`frustum_scene_points`]);
//! along it, to the whole scene's bounds, so casters outside the view still cast. Each
//! window is texel-snapped (its centre moves in whole texels, its size in quarter-octave
//! steps), so the shadows do not shimmer as the camera moves. The cascades are the tiles
//! of one depth atlas ([`ATLAS_TILES`]² tiles of [`SHADOW_MAP_SIZE`]²) and share the
//! light's orientation and depth range, so a receiver needs one matrix (the *base*
//! camera's, fitted to the whole view, [`light_camera_for_view`]) and a per-cascade
//! scale and offset from the base map's NDC to the cascade's ([`CascadeUniform`]); the
//! lookup takes the finest cascade whose window holds the point (`shadow_lookup.wgsl`). Into its depth map go the meshes (depth
//! only), the billboard clouds (alpha-tested) and the volumes, sliced from the light
//! with [`SHADOW_SPACING_BIAS`]× the viewer's spacing — fewer slices whose opacity is
//! corrected for the larger spacing, the paper's opacity scaling (§4, Optimizations) —
//! each slice occluding where its opacity reaches [`SHADOW_ALPHA_CUTOFF`]. Receivers
//! (meshes, clouds, volume slices) look the map up with 3×3 PCF, taken as four bilinear
//! taps (`shaders/shadow_lookup.wgsl`), and scale the light by
//! `ambient + (1 − ambient)·vis`.

// NaN-safe range checks (`!(a <= b)` is true for NaN) are meant.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::layout::{comparison_sampler, depth_texture, entry, shader, uniform, Pipeline};
use crate::target::DEPTH_FORMAT;
use crate::texture::desc_2d;
use crate::{Gpu, ViewCamera};

/// Side of one cascade's map (a tile of the atlas) in texels.
pub const SHADOW_MAP_SIZE: u32 = 1024;
/// Cascades (tiles of the atlas).
pub const CASCADES: usize = 4;
/// The atlas is `ATLAS_TILES` × `ATLAS_TILES` tiles.
pub const ATLAS_TILES: u32 = 2;
/// Practical split scheme: the split depths are `λ·log + (1 − λ)·uniform`.
pub const SPLIT_LAMBDA: f32 = 0.75;
/// A view whose depth range (inside the scene) spans a ratio `far / near` gets
/// `⌈log_CASCADE_RATIO(far / near)⌉` cascades (at least 1, at most [`CASCADES`]): a
/// compact view keeps one map (and the shadow pass its cost), a deep one splits.
pub const CASCADE_RATIO: f32 = 8.0;
/// Shadow slices are this many times farther apart than the viewer's.
pub const SHADOW_SPACING_BIAS: f32 = 4.0;
/// Opacity at which a shadow slice occludes. A depth map cannot composite, so each
/// slab (of [`SHADOW_SPACING_BIAS`]× the viewer's spacing) occludes on its own where its
/// opacity reaches this. Calibrated against the meshes' own shadows:
/// - 2026-12-05, once the volumes' levels kept the mesh's coverage (`make demo`'s scene,
///   ground pixels in shadow): the oak volume 1,729 at 0.5 and 4,152 at 0.3 against the
///   mesh's 4,459; the generated tree 2,843 and 4,776 against 5,285. (0.5 had matched the
///   volumes of before, which were 10–50 % too dense at the shadow slices' MIP levels.)
/// - 2026-12-06, once the volumes' albedo and cosine matched the mesh's (docs/relight.md):
///   0.25. The ground's shadow mass (Σ of 1 − shadowed / unshadowed over the ground, seen
///   from above) against the mesh's under the lights (1, 0.6, 0) and (0.3, 1, 0.5): the
///   oak 0.975 / 0.749 at 0.3, 1.002 / 0.837 at 0.25, 1.026 / 0.909 at 0.2; the tree
///   0.975 / 0.854 at 0.3, 0.980 / 0.896 at 0.25. The oak's canopy against the mesh's
///   from `+x-y-z` under the four standard lights: +8.4, +8.5, −0.8, +3.3 % at 0.3;
///   +2.3, +1.3, −8.2, −1.9 % at 0.25; −3.3, −5.5, −15.4, −6.2 % at 0.2.
/// - 2026-12-06 (later): 0.3 again. The mesh these were calibrated against was itself
///   wrong: its alpha MIPs drew its leaves 10 % thin at that distance and its shadow maps
///   too dense, so its shadowed canopy was about 12 % darker than the ray-traced mesh's.
///   With the hashed alpha test the viewer's shadowed oak is within 0.5 % of `billow eval
///   --shadows`'s reference (0.0683 against 0.0684 overhead, 0.0878 against 0.0881 under
///   the western sun). The volume's canopy against it, shadows on, under the four lights
///   (unshadowed: −2.6, −6.1, −4.3, −2.6 %): −9.6, −10.5, −13.7, −10.3 % at 0.25; −4.1,
///   −4.3, −5.9, −5.6 % at 0.3; +1.7, +2.9, +2.1, +0.1 % at 0.35. 0.3 puts the shadow's
///   own share within 3 %. The ground's shadow mass against the mesh's (seen from above,
///   256²): 0.990 / 0.682 at 0.25, 0.977 / 0.611 at 0.3 under (1, 0.6, 0) / (0.3, 1, 0.5)
///   (the second is the thin rim the canopy does not hide, 172 pixels' worth).
pub const SHADOW_ALPHA_CUTOFF: f32 = 0.3;

/// Who reads the shadow receiver's bindings: the passes' fragment shaders, and the
/// compute check of the lookup (`shadow_gpu`, a test support module).
const RECEIVERS: wgpu::ShaderStages =
    wgpu::ShaderStages::FRAGMENT.union(wgpu::ShaderStages::COMPUTE);

/// Group 2 of every receiving pipeline: the depth atlas, its comparison sampler and the
/// cascades' [`CascadeUniform`].
pub fn receiver_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadow receiver"),
        entries: &[
            entry(0, RECEIVERS, depth_texture()),
            entry(1, RECEIVERS, comparison_sampler()),
            entry(2, RECEIVERS, uniform(false)),
        ],
    })
}

/// What a receiver needs besides the base camera's matrix: per cascade (finest first)
/// the map from the base map's NDC to the cascade's (`ndc_k = ndc·map.xy + map.zw`; the
/// depth is shared) and its tile in the atlas (uv origin `xy`, size `zw`); `info.x`:
/// the cascades in use (0: no lookup).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CascadeUniform {
    pub map: [[f32; 4]; CASCADES],
    pub tile: [[f32; 4]; CASCADES],
    pub info: [f32; 4],
}

/// A frame's shadow cameras: the base (fitted to the whole view; receivers project with
/// it) and the cascades (finest first, each rendered into its tile).
#[derive(Clone, Debug)]
pub struct Cascades {
    pub base: ViewCamera,
    pub cameras: Vec<ViewCamera>,
    pub uniform: CascadeUniform,
    /// Per cascade: the receivers its window was fitted to (world points; empty where
    /// the cascade is the base camera).
    pub receivers: Vec<Vec<Vec3>>,
}

/// The atlas tile of cascade `k` in texels: (x, y, side).
pub fn tile_rect(k: usize, size: u32) -> (u32, u32, u32) {
    let k = k as u32;
    ((k % ATLAS_TILES) * size, (k / ATLAS_TILES) * size, size)
}

/// The depth atlas, its cascade uniform and the bind group that lets receivers read
/// them.
pub struct ShadowMap {
    /// Side of one cascade's tile.
    pub size: u32,
    pub view: wgpu::TextureView,
    pub cascades: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
}

impl ShadowMap {
    /// An atlas of [`ATLAS_TILES`]² tiles of `size`² (`size = 1`: the stand-in bound when
    /// a scene has no shadows).
    pub fn new(gpu: &Gpu, layout: &wgpu::BindGroupLayout, size: u32) -> ShadowMap {
        let side = if size > 1 { size * ATLAS_TILES } else { 1 };
        let tex = gpu.device.create_texture(&desc_2d(
            "shadow map",
            side,
            side,
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        ));
        let view = tex.create_view(&Default::default());
        let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow compare"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let cascades = gpu.buffer(
            "shadow cascades",
            bytemuck::bytes_of(&CascadeUniform::default()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = gpu.bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow receiver"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: cascades.as_entire_binding(),
                },
            ],
        });
        ShadowMap {
            size,
            view,
            cascades,
            bind_group,
        }
    }
}

/// A triangle over the viewport at the far plane, written whatever the depth there.
const TILE_CLEAR_WGSL: &str = "
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 1.0, 1.0);
}

@fragment
fn fs_main() {}
";

/// The depth-only pipeline that clears one tile of the atlas (drawn over the tile's
/// viewport: a load op would clear every tile, and a frame may keep some of them).
pub fn tile_clear_pipeline(gpu: &Gpu) -> wgpu::RenderPipeline {
    let module = shader(&gpu.device, "shadow tile clear", &[TILE_CLEAR_WGSL]);
    let layout = gpu
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow tile clear"),
            bind_group_layouts: &[],
            immediate_size: 0,
        });
    gpu.note_built("pipeline:shadow-tile-clear");
    Pipeline {
        depth: Some((true, wgpu::CompareFunction::Always)),
        ..Pipeline::new("shadow tile clear", &layout, &module)
    }
    .build(&gpu.device)
}

/// The frame's shadow cameras for `camera`: the base ([`light_camera_for_view`]) and
/// up to [`CASCADES`] cascades of `size`² ([`CASCADE_RATIO`]) over the camera's depth
/// range inside the scene's bounds `scene`, split by the practical scheme
/// ([`SPLIT_LAMBDA`]).
pub fn cascades(
    towards_light: Vec3,
    camera: &ViewCamera,
    scene: (Vec3, Vec3),
    size: u32,
) -> Cascades {
    let base = light_camera_for_view(towards_light, camera, scene, size);
    // The depth range where the frustum meets the scene.
    let pts = frustum_scene_points(camera, scene);
    let (mut d0, mut d1) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in &pts {
        let d = -camera.to_view(*p).z;
        d0 = d0.min(d);
        d1 = d1.max(d);
    }
    let mut cameras = Vec::with_capacity(CASCADES);
    let mut receivers = Vec::with_capacity(CASCADES);
    let (n, f) = (d0.max(camera.near), d1.min(camera.far));
    if n < f {
        // As many cascades as the depth ratio needs: one per factor of CASCADE_RATIO.
        let count = ((f / n).ln() / CASCADE_RATIO.ln()).ceil() as usize;
        let count = count.clamp(1, CASCADES);
        let mut prev = n;
        for i in 1..=count {
            let t = i as f32 / count as f32;
            let split = if i == count {
                f
            } else {
                SPLIT_LAMBDA * n * (f / n).powf(t) + (1.0 - SPLIT_LAMBDA) * (n + (f - n) * t)
            };
            let slab = ViewCamera {
                near: prev,
                far: split.max(prev * (1.0 + 1e-5)),
                ..*camera
            };
            let pts = frustum_scene_points(&slab, scene);
            if let Some(c) = fit_light_camera(towards_light, &pts, scene, size) {
                cameras.push(c);
                receivers.push(pts);
            }
            prev = split;
        }
    }
    if cameras.is_empty() {
        cameras.push(base);
        receivers.push(Vec::new());
    }
    Cascades {
        base,
        uniform: cascade_uniform(&base, &cameras),
        cameras,
        receivers,
    }
}

/// What receivers projecting with `base` need to look up the cascades `cameras`
/// (finest first, cascade k in tile k).
pub fn cascade_uniform(base: &ViewCamera, cameras: &[ViewCamera]) -> CascadeUniform {
    let mut u = CascadeUniform {
        info: [cameras.len() as f32, 0.0, 0.0, 0.0],
        ..Default::default()
    };
    let hb = base.ortho_half_height.unwrap_or(1.0);
    let eb = base.eye();
    let frac = 1.0 / ATLAS_TILES as f32;
    for (k, c) in cameras.iter().enumerate() {
        let hk = c.ortho_half_height.unwrap_or(1.0);
        // The base eye in cascade k's light space: its offset across the light.
        let q = c.to_view(eb);
        u.map[k] = [hb / hk, hb / hk, q.x / hk, q.y / hk];
        let (x, y, _) = tile_rect(k, 1);
        u.tile[k] = [x as f32 * frac, y as f32 * frac, frac, frac];
    }
    u
}

/// Whether the cascade `light` (drawn for an earlier frame) still serves `receivers`
/// as well as a cascade fitted to them: an orthographic window of the same size as
/// `fitted` (so the same texels) that holds every receiver a texel inside its edge, as
/// the fit leaves room for the 3×3 filter. The light's orientation and depth range
/// are the same for every cascade of one light and one scene.
pub fn window_holds(light: &ViewCamera, fitted: &ViewCamera, receivers: &[Vec3]) -> bool {
    let (Some(hh), Some(fh)) = (light.ortho_half_height, fitted.ortho_half_height) else {
        return false;
    };
    if hh != fh
        || (light.width, light.near, light.far) != (fitted.width, fitted.near, fitted.far)
        || receivers.is_empty()
    {
        return false;
    }
    let inner = hh - light.pixel_size_at(1.0);
    receivers.iter().all(|p| {
        let q = light.to_view(*p);
        q.x.abs() <= inner * light.aspect() && q.y.abs() <= inner
    })
}

/// Whether a caster inside the sphere (`centre`, `radius`) can reach `light`'s window
/// (an orthographic cascade; a perspective camera holds everything). Only the window
/// across the light is tested: every cascade's depth range covers all casters.
pub fn sphere_in_window(light: &ViewCamera, centre: Vec3, radius: f32) -> bool {
    let Some(hh) = light.ortho_half_height else {
        return true;
    };
    let q = light.to_view(centre);
    q.x.abs() <= hh * light.aspect() + radius && q.y.abs() <= hh + radius
}

/// Texels per world unit at `p` with `cascades`: those of the finest cascade whose map
/// holds `p` (what the lookup uses), 0 outside every one.
pub fn texel_density_at(cascades: &Cascades, p: Vec3) -> f32 {
    for c in &cascades.cameras {
        let q = (c.projection() * c.view).project_point3(p);
        if q.x.abs() <= 1.0 && q.y.abs() <= 1.0 {
            return texel_density(c);
        }
    }
    0.0
}

/// The light's orthographic camera covering the sphere (`centre`, `radius`), looking
/// along `-towards_light` (the fit before [`light_camera_for_view`]; kept as the
/// fallback and the comparison of `docs/viewer.md`).
pub fn light_camera(towards_light: Vec3, centre: Vec3, radius: f32, size: u32) -> ViewCamera {
    let l = towards_light.normalize_or(Vec3::Y);
    let r = radius.max(1e-6);
    let eye = centre + l * (2.0 * r);
    let up = if l.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    ViewCamera::orthographic(eye, -l, up, r, size, size, r * 0.5, r * 3.5)
}

/// The light's rotation (world → light space about the origin) for `towards_light`: the
/// basis every fitted light camera shares, so snapping to its texel grid is stable.
fn light_basis(towards_light: Vec3) -> Mat4 {
    let l = towards_light.normalize_or(Vec3::Y);
    let up = if l.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    ViewCamera::look_at(Vec3::ZERO, -l, up, 1.0, 1, 1, 0.1, 1.0).view
}

/// The orthographic light camera of a `size`² map whose window (across the light)
/// covers `receivers` (world points, inside `casters`) and whose depth range (along the
/// light) covers the box `casters`. The window's side is rounded up to a quarter-octave step (2^(k/4))
/// with a texel of margin each side for the 3×3 filter, and its centre to a whole texel
/// of the light's fixed basis: moving the camera moves the window by whole texels.
/// `None` without receivers.
pub fn fit_light_camera(
    towards_light: Vec3,
    receivers: &[Vec3],
    casters: (Vec3, Vec3),
    size: u32,
) -> Option<ViewCamera> {
    let rot = light_basis(towards_light);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in receivers {
        let q = rot.transform_point3(*p);
        lo = lo.min(q);
        hi = hi.max(q);
    }
    if !(lo.x <= hi.x && lo.y <= hi.y && lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let size = size.max(2);
    let side = (hi.x - lo.x).max(hi.y - lo.y).max(1e-4) * size as f32 / (size - 2) as f32;
    let side = (side.log2() * 4.0).ceil() * 0.25;
    let side = side.exp2();
    let texel = side / size as f32;
    let snap = |v: f32| (v / texel).round() * texel;
    let (cx, cy) = (snap(0.5 * (lo.x + hi.x)), snap(0.5 * (lo.y + hi.y)));
    // Depth: the casters' box along the light (view space looks down −z).
    // (The receivers lie inside the casters' box: every cascade gets the same range.)
    let (cl, ch) = casters;
    let (mut z_lo, mut z_hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { cl.x } else { ch.x },
            if i & 2 == 0 { cl.y } else { ch.y },
            if i & 4 == 0 { cl.z } else { ch.z },
        );
        let z = rot.transform_point3(c).z;
        if z.is_finite() {
            z_lo = z_lo.min(z);
            z_hi = z_hi.max(z);
        }
    }
    if !(z_lo <= z_hi) {
        (z_lo, z_hi) = (lo.z, hi.z);
    }
    let margin = 0.05 * (z_hi - z_lo).max(1e-3) + 1e-3;
    let ez = z_hi + margin;
    let near = 0.5 * margin;
    let far = ez - z_lo + margin;
    // The view built from the shared rotation (not from the eye: `look_at` would
    // recompute the direction from a far-away eye and lose bits), so every cascade has
    // exactly the base's orientation and depth.
    let view = Mat4::from_translation(-Vec3::new(cx, cy, ez)) * rot;
    let mut cam = ViewCamera::from_parts(view, 1.0, size, size, near, far);
    cam.ortho_half_height = Some(0.5 * side);
    Some(cam)
}

/// Texels of `light`'s map per world unit across the light (what the receivers get).
pub fn texel_density(light: &ViewCamera) -> f32 {
    1.0 / light.pixel_size_at(1.0)
}

/// The corners of `camera`'s frustum in world space: near then far plane, each (−x −y),
/// (+x −y), (+x +y), (−x +y).
pub fn frustum_corners(camera: &ViewCamera) -> [Vec3; 8] {
    let inv = camera.view.inverse();
    let mut out = [Vec3::ZERO; 8];
    for (i, d) in [camera.near, camera.far].into_iter().enumerate() {
        let hh = match camera.ortho_half_height {
            Some(h) => h,
            None => d * (0.5 * camera.fov_y).tan(),
        };
        let hw = hh * camera.aspect();
        for (j, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            out[4 * i + j] = inv.transform_point3(Vec3::new(sx * hw, sy * hh, -d));
        }
    }
    out
}

/// Keeps the part of the convex polygon `poly` where `n·p + d ≥ 0`.
fn clip_polygon(poly: &[Vec3], n: Vec3, d: f32) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (n.dot(a) + d, n.dot(b) + d);
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            out.push(a + (b - a) * t);
        }
    }
    out
}

/// The vertices of (`camera`'s frustum ∩ the box `bounds`): every face of each body
/// clipped by the other's half-spaces. Empty when they do not meet.
pub fn frustum_scene_points(camera: &ViewCamera, bounds: (Vec3, Vec3)) -> Vec<Vec3> {
    let (lo, hi) = bounds;
    if !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z) {
        return Vec::new();
    }
    let c = frustum_corners(camera);
    let quads = |c: &[Vec3; 8]| -> [[Vec3; 4]; 6] {
        [
            [c[0], c[1], c[2], c[3]],
            [c[4], c[5], c[6], c[7]],
            [c[0], c[1], c[5], c[4]],
            [c[1], c[2], c[6], c[5]],
            [c[2], c[3], c[7], c[6]],
            [c[3], c[0], c[4], c[7]],
        ]
    };
    let centre = c.iter().copied().sum::<Vec3>() / 8.0;
    // Inward half-spaces of the frustum's faces.
    let frustum_planes: Vec<(Vec3, f32)> = quads(&c)
        .iter()
        .map(|q| {
            let mut n = (q[1] - q[0]).cross(q[3] - q[0]);
            if n.length_squared() < 1e-20 {
                n = (q[2] - q[1]).cross(q[0] - q[1]);
            }
            let mut n = n.normalize_or_zero();
            if n.dot(centre - q[0]) < 0.0 {
                n = -n;
            }
            (n, -n.dot(q[0]))
        })
        .collect();
    let box_planes = [
        (Vec3::X, -lo.x),
        (Vec3::NEG_X, hi.x),
        (Vec3::Y, -lo.y),
        (Vec3::NEG_Y, hi.y),
        (Vec3::Z, -lo.z),
        (Vec3::NEG_Z, hi.z),
    ];
    // Grown by a hair so faces lying on the other body's planes are kept.
    let eps = 1e-4 * (hi - lo).length().max(1e-3);
    let b = [
        lo,
        Vec3::new(hi.x, lo.y, lo.z),
        Vec3::new(hi.x, hi.y, lo.z),
        Vec3::new(lo.x, hi.y, lo.z),
        Vec3::new(lo.x, lo.y, hi.z),
        Vec3::new(hi.x, lo.y, hi.z),
        hi,
        Vec3::new(lo.x, hi.y, hi.z),
    ];
    let mut out = Vec::new();
    let mut clip_all = |faces: [[Vec3; 4]; 6], planes: &[(Vec3, f32)]| {
        for f in faces {
            let mut poly = f.to_vec();
            for &(n, d) in planes {
                poly = clip_polygon(&poly, n, d + eps);
                if poly.is_empty() {
                    break;
                }
            }
            out.extend(poly);
        }
    };
    clip_all(quads(&c), &box_planes);
    clip_all(quads(&b), &frustum_planes);
    out
}

/// The light camera for a frame seen by `camera`: fitted ([`fit_light_camera`]) to the
/// part of the scene's bounds in view, and to the whole scene when none of it is.
pub fn light_camera_for_view(
    towards_light: Vec3,
    camera: &ViewCamera,
    scene: (Vec3, Vec3),
    size: u32,
) -> ViewCamera {
    let mut receivers = frustum_scene_points(camera, scene);
    if receivers.is_empty() {
        let (lo, hi) = scene;
        receivers = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
    }
    fit_light_camera(towards_light, &receivers, scene, size).unwrap_or_else(|| {
        let (lo, hi) = scene;
        light_camera(
            towards_light,
            0.5 * (lo + hi),
            0.5 * (hi - lo).length(),
            size,
        )
    })
}

/// Camera view space → the shadow map's clip space.
pub fn view_to_shadow(camera: &ViewCamera, light: &ViewCamera) -> Mat4 {
    light.projection() * light.view * camera.view.inverse()
}

/// Depth bias in the shadow map's depth units: about two texels of the map's extent.
pub fn depth_bias(light: &ViewCamera) -> f32 {
    let texel = light.pixel_size_at(1.0);
    2.0 * texel / (light.far - light.near)
}
