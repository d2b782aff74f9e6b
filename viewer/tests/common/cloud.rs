//! The synthetic billboard clouds of the cloud-pass tests (`cloud_pass.rs`,
//! `cloud_shadows.rs`): a one-level cloud whose 2×2 quad faces +z, the renderer and camera
//! that show it, and the colour it stores.

use std::collections::BTreeMap;

use billow_format::{
    Atlas, AtlasRect, Billboard, Bounds, CloudAsset, CloudLevel, ColourSpace, Header, Mesh,
};
use billow_view::{Renderer, RgbaImage, ViewCamera};
use glam::{Mat4, Vec3};

/// Side of the synthetic atlas.
pub const N: u32 = 16;
/// The atlas's straight linear colour.
pub const ALBEDO: [f32; 3] = [0.8, 0.4, 0.2];

pub fn srgb(v: f32) -> u8 {
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The albedo channel `c` as stored (8-bit sRGB) and decoded by the sampler.
pub fn stored(c: usize) -> f32 {
    let v = f32::from(srgb(ALBEDO[c])) / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A cloud asset with one billboard level: the quad `[-1,1]² × {0}` (U = +x, V = +y,
/// normal +z), both sides showing a 16² atlas whose alpha is `alpha(x, y)` (texel
/// column, row), colour [`ALBEDO`] premultiplied. `normal`: a tangent-space normal map
/// of one constant normal; `unlit`: the header says the bake left lighting out.
pub fn asset(alpha: impl Fn(u32, u32) -> f32, normal: Option<[f32; 3]>, unlit: bool) -> CloudAsset {
    let mut texels = Vec::new();
    for y in 0..N {
        for x in 0..N {
            let a = alpha(x, y);
            texels.extend_from_slice(&[
                srgb(ALBEDO[0] * a),
                srgb(ALBEDO[1] * a),
                srgb(ALBEDO[2] * a),
                (a * 255.0).round() as u8,
            ]);
        }
    }
    let normals = normal.map(|n| {
        let e = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
        let t = [e(n[0]), e(n[1]), e(n[2]), 255];
        vec![t.repeat((N * N) as usize)]
    });
    let mut params = BTreeMap::new();
    params.insert(
        "light".to_string(),
        if unlit { "unlit" } else { "0.3,1,0.2" }.to_string(),
    );
    let rect = AtlasRect {
        atlas: 0,
        uv: [0.0, 0.0, 1.0, 1.0],
    };
    let corners = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    CloudAsset {
        header: Header {
            kind: billow_format::AssetKind::Cloud,
            tool: "test".into(),
            source: None,
            bounds: Bounds {
                min: [-1.0, -1.0, -0.1],
                max: [1.0, 1.0, 0.1],
            },
            colour_space: ColourSpace::SrgbPremultiplied,
            seed: None,
            params,
            volume: None,
        },
        levels: vec![CloudLevel {
            first_billboard: 0,
            billboard_count: 1,
            first_atlas: 0,
            atlas_count: 1,
            epsilon: 0.01,
            texel_density: 8.0,
        }],
        billboards: vec![Billboard {
            plane: [0.0, 0.0, 1.0, 0.0],
            corners,
            parent_corners: corners,
            front: rect,
            back: rect,
            parent: None,
            elements: 1,
        }],
        atlases: vec![Atlas {
            width: N,
            height: N,
            mips: vec![texels],
            normals,
        }],
        materials: Vec::new(),
        textures: Vec::new(),
        trunk: Mesh::default(),
        foliage: Mesh::default(),
    }
}

/// Alpha bands along x: 0, 0.25 (below the cut-off), 0.75, 1.
pub fn banded(x: u32, _y: u32) -> f32 {
    [0.0, 0.25, 0.75, 1.0][(x / 4) as usize]
}

/// A renderer showing `cloud` once per transform, at its billboard level.
pub fn renderer(gpu: billow_view::Gpu, cloud: &CloudAsset, instances: Vec<Mat4>) -> Renderer {
    let mut r = Renderer::new(gpu);
    r.add_cloud(cloud, instances, Some(vec![1.0]), 0.0, 0.8)
        .expect("upload");
    r.lod_distance_override = Some(10.0);
    r
}

/// Looking at the origin from `+z·dist` (or `−z·dist` when `back`).
pub fn camera(size: u32, dist: f32, back: bool) -> ViewCamera {
    let eye = Vec3::new(0.0, 0.0, if back { -dist } else { dist });
    ViewCamera::look_at(eye, Vec3::ZERO, Vec3::Y, 0.8, size, size, 0.1, 100.0)
}

pub fn pixel(img: &RgbaImage, x: u32, y: u32) -> [f32; 4] {
    img.data[(y * img.width + x) as usize]
}

/// Mean colour over the `k`×`k` block centred on the frame's centre.
pub fn centre_mean(img: &RgbaImage, k: u32) -> [f32; 4] {
    let (cx, cy) = (img.width / 2, img.height / 2);
    let mut s = [0.0f32; 4];
    for y in cy - k / 2..cy + k / 2 {
        for x in cx - k / 2..cx + k / 2 {
            let p = pixel(img, x, y);
            for c in 0..4 {
                s[c] += p[c];
            }
        }
    }
    s.map(|v| v / (k * k) as f32)
}
