//! Procedural test shapes for the hard cases no bundled asset covers.
//!
//! - [`truss`]: an Eiffel-like lattice tower of beams much thinner than a voxel at
//!   typical bake resolutions — the case where volumetric billboards must keep partial
//!   opacity instead of aliasing (VB paper, Figure 7's Eiffel tower).
//! - [`furry_torus`]: strands of fur growing out of a torus (VB paper, Figure 11), as
//!   explicit geometry: thousands of thin double-sided triangles with vertex colours.
//! - [`torus`] and [`fur_tile`]: the surface and the tileable fur volume source used to
//!   build the same torus as a *shell* of prisms (volumetric texture).
//! - [`leafy_tree`]: a broadleaf tree — an opaque trunk and branches, and alpha-masked
//!   leaf cards with a generated leaf texture (MASK 0.5) in a crown — the second foliage
//!   mesh of the billboard-cloud tests beside the bundled oak.
//! - [`bench_tree`]: the 200,000-triangle textured "tree" of the voxelize benchmark
//!   (`make bench`, docs/benchmarks.md): an icosphere canopy core and leaf quads, one
//!   opaque single-sided material with a 512² bark/leaf atlas, written as an indexed OBJ.
//!
//! Everything is deterministic for a given seed (see [`crate::rng`]). The shapes are built
//! with [`SceneBuilder`], the importers' builder, so they drop degenerate triangles by the
//! same rule.

use std::f32::consts::TAU;
use std::io::Write;
use std::path::Path;

use glam::{Vec2, Vec3, Vec4};

use crate::rng::Pcg32;
use crate::scene::{AlphaMode, Material, Scene, SceneBuilder, Texture, Vertex, Wrap};

fn vertex(position: Vec3, normal: Vec3, uv: Vec2, color: Vec4) -> Vertex {
    Vertex {
        position,
        normal,
        uv,
        color,
    }
}

fn opaque(name: &str, rgb: Vec3, double_sided: bool) -> Material {
    Material {
        name: name.into(),
        base_color_factor: rgb.extend(1.0),
        base_color_texture: None,
        alpha_mode: AlphaMode::Opaque,
        double_sided,
        unlit: false,
    }
}

/// A closed box beam from `a` to `b` with square cross-section of side `width`.
pub fn beam(sb: &mut SceneBuilder, a: Vec3, b: Vec3, width: f32, material: u32, mesh: u32) {
    let axis = (b - a).normalize_or_zero();
    if axis == Vec3::ZERO {
        return;
    }
    let u = axis.any_orthonormal_vector() * (0.5 * width);
    let v = axis.cross(u.normalize()) * (0.5 * width);
    let corners = |c: Vec3| [c - u - v, c + u - v, c + u + v, c - u + v];
    let (ca, cb) = (corners(a), corners(b));
    let white = Vec4::ONE;
    for i in 0..4 {
        let j = (i + 1) % 4;
        sb.quad([ca[i], ca[j], cb[j], cb[i]], white, material, mesh);
    }
    sb.quad([ca[3], ca[2], ca[1], ca[0]], white, material, mesh);
    sb.quad([cb[0], cb[1], cb[2], cb[3]], white, material, mesh);
}

/// A lattice tower (+Y up) `height` tall with `levels` storeys, legs tapering from
/// `base` to `base / 4`, braced by horizontals and crossing diagonals, every beam
/// `beam_width` thick (choose it well below a voxel: e.g. height/1000).
pub fn truss(height: f32, base: f32, levels: u32, beam_width: f32) -> Scene {
    let mut sb = SceneBuilder::new();
    let m = sb.material(opaque("steel", Vec3::new(0.45, 0.33, 0.25), false));
    let mesh = sb.mesh("truss");
    let levels = levels.max(1);
    let corner = |lvl: u32, k: usize| {
        let t = lvl as f32 / levels as f32;
        let half = 0.5 * base * (1.0 - 0.75 * t);
        let s = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)][k];
        Vec3::new(s.0 * half, t * height, s.1 * half)
    };
    for lvl in 0..levels {
        for k in 0..4 {
            let j = (k + 1) % 4;
            beam(
                &mut sb,
                corner(lvl, k),
                corner(lvl + 1, k),
                beam_width,
                m,
                mesh,
            );
            beam(
                &mut sb,
                corner(lvl + 1, k),
                corner(lvl + 1, j),
                beam_width,
                m,
                mesh,
            );
            beam(
                &mut sb,
                corner(lvl, k),
                corner(lvl + 1, j),
                beam_width,
                m,
                mesh,
            );
            beam(
                &mut sb,
                corner(lvl, j),
                corner(lvl + 1, k),
                beam_width,
                m,
                mesh,
            );
        }
    }
    sb.finish()
}

/// Position and outward normal on a torus around +Y (major radius `r_major`, tube `r_minor`)
/// at angles (u, v) in [0, 1)².
pub fn torus_point(r_major: f32, r_minor: f32, u: f32, v: f32) -> (Vec3, Vec3) {
    let (su, cu) = (u * TAU).sin_cos();
    let (sv, cv) = (v * TAU).sin_cos();
    let n = Vec3::new(cu * cv, sv, su * cv);
    let centre = Vec3::new(cu * r_major, 0.0, su * r_major);
    (centre + n * r_minor, n)
}

/// A torus surface with UVs (u around the ring, v around the tube), outward normals.
pub fn torus(r_major: f32, r_minor: f32, segments: u32, sides: u32) -> Scene {
    let mut sb = SceneBuilder::new();
    let m = sb.material(opaque("skin", Vec3::new(0.30, 0.18, 0.10), false));
    let mesh = sb.mesh("torus");
    let (segments, sides) = (segments.max(3), sides.max(3));
    let vert = |i: u32, j: u32| {
        let (u, v) = (i as f32 / segments as f32, j as f32 / sides as f32);
        let (p, n) = torus_point(r_major, r_minor, u, v);
        vertex(p, n, Vec2::new(u, v), Vec4::ONE)
    };
    for i in 0..segments {
        for j in 0..sides {
            let (a, b, c, d) = (
                vert(i, j),
                vert(i + 1, j),
                vert(i + 1, j + 1),
                vert(i, j + 1),
            );
            // Counter-clockwise seen from outside.
            sb.triangle([a, c, b], m, mesh);
            sb.triangle([a, d, c], m, mesh);
        }
    }
    sb.finish()
}

/// One strand: a thin double-sided ribbon from `root` along `dir` with a gentle curl,
/// `segments` pieces, tapering to a point; colour from dark root to light tip.
#[allow(clippy::too_many_arguments)]
fn strand(
    sb: &mut SceneBuilder,
    root: Vec3,
    dir: Vec3,
    side: Vec3,
    curl: Vec3,
    length: f32,
    width: f32,
    segments: u32,
    material: u32,
    mesh: u32,
) {
    let root_c = Vec4::new(0.20, 0.12, 0.06, 1.0);
    let tip_c = Vec4::new(0.85, 0.70, 0.45, 1.0);
    let point = |t: f32| root + (dir * t + curl * (t * t)) * length;
    let normal = dir.cross(side).normalize_or_zero();
    for s in 0..segments {
        let (t0, t1) = (s as f32 / segments as f32, (s + 1) as f32 / segments as f32);
        let (w0, w1) = (0.5 * width * (1.0 - t0), 0.5 * width * (1.0 - t1));
        let (c0, c1) = (root_c.lerp(tip_c, t0), root_c.lerp(tip_c, t1));
        let (p0, p1) = (point(t0), point(t1));
        let v = |p: Vec3, c: Vec4, v: f32| vertex(p, normal, Vec2::new(0.5, v), c);
        let a = v(p0 - side * w0, c0, 1.0 - t0);
        let b = v(p0 + side * w0, c0, 1.0 - t0);
        let c = v(p1 + side * w1, c1, 1.0 - t1);
        let d = v(p1 - side * w1, c1, 1.0 - t1);
        sb.triangle([a, b, c], material, mesh);
        if s + 1 < segments {
            sb.triangle([a, c, d], material, mesh);
        }
    }
}

/// A torus with `count` strands of fur (explicit geometry; VB paper Figure 11).
pub fn furry_torus(count: u32, seed: u64) -> Scene {
    let (r_major, r_minor) = (1.0, 0.35);
    let mut sb = SceneBuilder::new();
    let skin = sb.material(opaque("skin", Vec3::new(0.30, 0.18, 0.10), false));
    let fur = sb.material(opaque("fur", Vec3::ONE, true));
    let torus_mesh = sb.mesh("torus");
    let fur_mesh = sb.mesh("fur");
    for t in torus(r_major, r_minor, 48, 24).triangles {
        sb.triangle(t.v, skin, torus_mesh);
    }
    let mut rng = Pcg32::seeded(seed, 1);
    for _ in 0..count {
        let (p, n) = torus_point(r_major, r_minor, rng.next_f32(), rng.next_f32());
        let side = n.any_orthonormal_vector();
        let side = Quat2::rotate(side, n, rng.range_f32(0.0, TAU));
        let curl = Quat2::rotate(side, n, 1.0) * 0.35;
        let length = rng.range_f32(0.10, 0.16);
        strand(&mut sb, p, n, side, curl, length, 0.008, 3, fur, fur_mesh);
    }
    sb.finish()
}

/// A tileable patch of fur for shell texturing: strands rooted in the unit square of the
/// x–z plane growing along +Y up to height 1; strands near an edge wrap to the opposite
/// edge, so tiles join seamlessly.
pub fn fur_tile(count: u32, seed: u64) -> Scene {
    let mut sb = SceneBuilder::new();
    let fur = sb.material(opaque("fur", Vec3::ONE, true));
    let mesh = sb.mesh("fur_tile");
    let mut rng = Pcg32::seeded(seed, 2);
    for _ in 0..count {
        let root = Vec3::new(rng.next_f32(), 0.0, rng.next_f32());
        let side = Quat2::rotate(Vec3::X, Vec3::Y, rng.range_f32(0.0, TAU));
        let lean = Quat2::rotate(Vec3::X, Vec3::Y, rng.range_f32(0.0, TAU)) * 0.25;
        let length = rng.range_f32(0.75, 0.98);
        // Draw the strand and its copies shifted by ±1 in x and z; keep only what lies in the tile.
        for dx in [-1.0f32, 0.0, 1.0] {
            for dz in [-1.0f32, 0.0, 1.0] {
                let r = root + Vec3::new(dx, 0.0, dz);
                let reach = 0.3;
                if r.x < -reach || r.x > 1.0 + reach || r.z < -reach || r.z > 1.0 + reach {
                    continue;
                }
                strand(&mut sb, r, Vec3::Y, side, lean, length, 0.03, 3, fur, mesh);
            }
        }
    }
    sb.finish()
}

/// Rotation of a vector about a unit axis (Rodrigues), kept local to avoid a quaternion import.
struct Quat2;
impl Quat2 {
    fn rotate(v: Vec3, axis: Vec3, angle: f32) -> Vec3 {
        let (s, c) = angle.sin_cos();
        v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
    }
}

/// The leaf texture of [`leafy_tree`]: `size`² RGBA, a pointed oval leaf (alpha 255
/// inside, 0 outside) with a lighter midrib, green shades in sRGB.
pub fn leaf_texture(size: u32) -> Texture {
    let mut texels = Vec::with_capacity((size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            // u across the leaf, v along it (stem at v = 1).
            let u = (x as f32 + 0.5) / size as f32 * 2.0 - 1.0;
            let v = (y as f32 + 0.5) / size as f32;
            // Half-width of a pointed oval along v.
            let half = 0.9 * (std::f32::consts::PI * v).sin().powf(0.8) * (1.0 - 0.3 * v);
            let inside = u.abs() <= half && v < 0.96;
            let rib = (u.abs() < 0.06) as u8;
            let shade = (1.0 - 0.4 * u.abs() / half.max(1e-3)).clamp(0.5, 1.0);
            let g = (150.0 * shade) as u8;
            texels.push(if inside {
                [40 + 40 * rib, g + 30 * rib, 30, 255]
            } else {
                [40, 90, 30, 0]
            });
        }
    }
    Texture {
        name: "leaf.png".into(),
        width: size,
        height: size,
        texels,
        wrap_u: Wrap::ClampToEdge,
        wrap_v: Wrap::ClampToEdge,
        encoded: None,
    }
}

/// A broadleaf tree about 8 units tall (+Y up, base at the origin): a tapering trunk and
/// `branches` branches (opaque bark beams) and `leaves` leaf cards (double-sided, MASK 0.5,
/// [`leaf_texture`], tinted per card by vertex colour) clustered around the branch tips in
/// an ellipsoidal crown. Deterministic for a seed.
pub fn leafy_tree(leaves: u32, branches: u32, seed: u64) -> Scene {
    let mut rng = Pcg32::seeded(seed, 11);
    let mut sb = SceneBuilder::new();
    sb.texture(leaf_texture(64));
    let bark = sb.material(opaque("bark", Vec3::new(0.28, 0.18, 0.10), false));
    let leaf = sb.material(Material {
        name: "leaf".into(),
        base_color_factor: Vec4::ONE,
        base_color_texture: Some(0),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        unlit: false,
    });
    let trunk_mesh = sb.mesh("trunk");
    let leaf_mesh = sb.mesh("leaves");
    let top = Vec3::new(0.0, 3.2, 0.0);
    beam(&mut sb, Vec3::ZERO, top, 0.35, bark, trunk_mesh);
    let crown = Vec3::new(0.0, 5.0, 0.0);
    let radii = Vec3::new(2.6, 2.0, 2.6);
    let mut tips = Vec::new();
    for b in 0..branches.max(1) {
        let angle = TAU * (b as f32 + 0.3 * rng.next_f32()) / branches.max(1) as f32;
        let rise = 0.2 + 0.8 * rng.next_f32();
        let dir = Vec3::new(angle.cos(), rise, angle.sin()).normalize();
        let start = Vec3::new(0.0, 2.4 + 0.8 * rng.next_f32(), 0.0);
        let tip = crown + dir * radii * (0.55 + 0.35 * rng.next_f32());
        beam(&mut sb, start, tip, 0.12, bark, trunk_mesh);
        tips.push(tip);
    }
    for i in 0..leaves {
        let tip = tips[i as usize % tips.len()];
        // A point in a ball around the branch tip, kept inside the crown.
        let off = loop {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if p.length_squared() <= 1.0 {
                break p;
            }
        };
        let c = tip + off * Vec3::new(1.1, 0.8, 1.1);
        let n = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.2,
            rng.next_f32() - 0.5,
        )
        .normalize_or(Vec3::Y);
        let along = n.any_orthonormal_vector();
        let side = n.cross(along);
        let (len, wid) = (0.55 + 0.25 * rng.next_f32(), 0.35);
        let a = along * len * 0.5;
        let w = side * wid * 0.5;
        // a: bottom-left (stem end), counter-clockwise seen from +n.
        let p = [c - a - w, c - a + w, c + a + w, c + a - w];
        let tint = 0.75 + 0.25 * rng.next_f32();
        let colour = Vec4::new(tint, tint, 0.8 + 0.2 * rng.next_f32(), 1.0);
        sb.quad(p, colour, leaf, leaf_mesh);
    }
    sb.finish()
}

/// Writes a scene as Wavefront OBJ + MTL (positions, normals, UVs; vertex colours as the
/// common `v x y z r g b` extension; a material's base-colour texture as a PNG beside the
/// OBJ named after the texture, `map_Kd` + `map_d`). Used to ship the procedural shapes as
/// fixture files.
pub fn write_obj(scene: &Scene, obj_path: &Path) -> std::io::Result<()> {
    let mtl_path = obj_path.with_extension("mtl");
    let mtl_name = mtl_path
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("out.mtl");
    let mut mtl = Vec::new();
    let dir = obj_path.parent().unwrap_or(Path::new("."));
    for m in &scene.materials {
        let c = m.base_color_factor;
        writeln!(
            mtl,
            "newmtl {}\nKd {} {} {}\nd {}",
            m.name, c.x, c.y, c.z, c.w
        )?;
        if let Some(t) = m
            .base_color_texture
            .and_then(|i| scene.textures.get(i as usize))
        {
            // The texture beside the OBJ; its alpha is the material's cut-out (map_d).
            let bytes: Vec<u8> = t.texels.iter().flatten().copied().collect();
            image::save_buffer(
                dir.join(&t.name),
                &bytes,
                t.width,
                t.height,
                image::ExtendedColorType::Rgba8,
            )
            .map_err(std::io::Error::other)?;
            writeln!(mtl, "map_Kd {}", t.name)?;
            if m.alpha_mode != AlphaMode::Opaque {
                writeln!(mtl, "map_d {}", t.name)?;
            }
        }
        writeln!(mtl)?;
    }
    let mut obj = Vec::new();
    writeln!(obj, "# generated by billow::procgen\nmtllib {mtl_name}")?;
    let mut current: Option<(u32, u32)> = None;
    for (i, t) in scene.triangles.iter().enumerate() {
        if current != Some((t.mesh, t.material)) {
            let mesh = &scene.meshes[t.mesh as usize].name;
            writeln!(
                obj,
                "o {mesh}\nusemtl {}",
                scene.materials[t.material as usize].name
            )?;
            current = Some((t.mesh, t.material));
        }
        for v in &t.v {
            let (p, c) = (v.position, v.color);
            writeln!(obj, "v {} {} {} {} {} {}", p.x, p.y, p.z, c.x, c.y, c.z)?;
            writeln!(obj, "vn {} {} {}", v.normal.x, v.normal.y, v.normal.z)?;
            // OBJ's v axis points up; the scene's (glTF's) points down.
            writeln!(obj, "vt {} {}", v.uv.x, 1.0 - v.uv.y)?;
        }
        let b = 3 * i + 1;
        writeln!(obj, "f {b}/{b}/{b} {0}/{0}/{0} {1}/{1}/{1}", b + 1, b + 2)?;
    }
    std::fs::write(&mtl_path, mtl)?;
    std::fs::write(obj_path, obj)
}

/// An indexed, textured triangle mesh as the benchmark writes it (see [`bench_tree`]).
pub struct IndexedMesh {
    pub positions: Vec<Vec3>,
    /// OBJ texture coordinates (v up).
    pub uvs: Vec<Vec2>,
    /// Per triangle, indices into `positions` and `uvs` alike.
    pub faces: Vec<[u32; 3]>,
    pub texture: Texture,
}

/// The voxelize benchmark's tree (after `gen_tree.py` of earlier rounds, same construction
/// and counts, this crate's generator): exactly 200,000 triangles — an icosphere of
/// 81,920 (subdivided 6 times, radius 0.3 around (0, 0, 0.6), bark in the left half of a
/// 512 × 512 atlas) and 59,040 leaf quads of side 0.012–0.03 scattered in a shell up to
/// 0.52 around it, randomly oriented, textured with the atlas's right half (a leaf shape;
/// the material is opaque, so the quads are whole). Deterministic for a seed.
pub fn bench_tree(seed: u64) -> IndexedMesh {
    let mut rng = Pcg32::seeded(seed, 23);
    const W: u32 = 512;
    let mut texels = Vec::with_capacity((W * W) as usize);
    for y in 0..W {
        for x in 0..W {
            let (xf, yf) = (x as f32, y as f32);
            texels.push(if x < W / 2 {
                let s = 0.5 + 0.5 * (xf * 0.35 + 3.0 * (yf * 0.05).sin()).sin();
                [
                    (90.0 + 60.0 * s) as u8,
                    (55.0 + 35.0 * s) as u8,
                    (25.0 + 15.0 * s) as u8,
                    255,
                ]
            } else {
                let u = (xf - W as f32 * 0.75) / (W as f32 * 0.25);
                let v = (yf - W as f32 * 0.5) / (W as f32 * 0.5);
                let inside = u * u + v * v * 0.6 < 0.9;
                let g0 = 0.5 + 0.5 * (yf * 0.2).sin();
                let rgb = if u.abs() < 0.03 {
                    [150, 200, 90]
                } else {
                    [(40.0 + 40.0 * g0) as u8, (120.0 + 80.0 * g0) as u8, 30]
                };
                [rgb[0], rgb[1], rgb[2], if inside { 255 } else { 0 }]
            });
        }
    }
    let texture = Texture {
        name: "tree.png".into(),
        width: W,
        height: W,
        texels,
        wrap_u: Wrap::Repeat,
        wrap_v: Wrap::Repeat,
        encoded: None,
    };
    // Icosphere.
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..6 {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push(((verts[a as usize] + verts[b as usize]) / 2.0).normalize());
                verts.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for &[a, b, c] in &faces {
            let (ab, bc, ca) = (
                mid(a, b, &mut verts),
                mid(b, c, &mut verts),
                mid(c, a, &mut verts),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let (centre, r) = (Vec3::new(0.0, 0.0, 0.6), 0.30f32);
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for v in &verts {
        positions.push(centre + r * *v);
        let u = 0.5 + v.y.atan2(v.x) / TAU;
        let w = 0.5 + v.z.clamp(-1.0, 1.0).asin() / std::f32::consts::PI;
        uvs.push(Vec2::new(u * 0.5, w));
    }
    // Leaves.
    for _ in 0..59_040 {
        let (p, d) = loop {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let d = p.length();
            if 0.2 < d && d <= 1.0 {
                break (p, d);
            }
        };
        let c = centre + (r + 0.22 * d) * p / d;
        let n = loop {
            let n = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if n.length_squared() > 1e-4 && n.length_squared() <= 1.0 {
                break n.normalize();
            }
        };
        let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let t1 = n.cross(a).normalize();
        let t2 = n.cross(t1);
        let s = rng.range_f32(0.012, 0.03);
        let base = positions.len() as u32;
        for (su, sv, uu, vv) in [
            (-0.5, -1.0, 0.5, 0.0),
            (0.5, -1.0, 1.0, 0.0),
            (0.5, 1.0, 1.0, 1.0),
            (-0.5, 1.0, 0.5, 1.0),
        ] {
            positions.push(c + s * (su * t1 + sv * t2));
            uvs.push(Vec2::new(uu, vv));
        }
        faces.push([base, base + 1, base + 2]);
        faces.push([base, base + 2, base + 3]);
    }
    IndexedMesh {
        positions,
        uvs,
        faces,
        texture,
    }
}

impl IndexedMesh {
    /// Writes `obj_path` (v, vt, `f a/a b/b c/c`), its `.mtl` (one opaque material,
    /// `map_Kd`) and the texture as a PNG beside it.
    pub fn write_obj(&self, obj_path: &Path) -> std::io::Result<()> {
        let dir = obj_path.parent().unwrap_or(Path::new("."));
        let t = &self.texture;
        let bytes: Vec<u8> = t.texels.iter().flatten().copied().collect();
        image::save_buffer(
            dir.join(&t.name),
            &bytes,
            t.width,
            t.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(std::io::Error::other)?;
        let mtl_path = obj_path.with_extension("mtl");
        let mtl_name = mtl_path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("out.mtl");
        std::fs::write(
            &mtl_path,
            format!(
                "newmtl tree\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd {}\n",
                t.name
            ),
        )?;
        let mut obj = Vec::with_capacity(64 * self.positions.len());
        writeln!(
            obj,
            "# billow::procgen::bench_tree: {} vertices, {} triangles\nmtllib {mtl_name}",
            self.positions.len(),
            self.faces.len()
        )?;
        for p in &self.positions {
            writeln!(obj, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z)?;
        }
        for uv in &self.uvs {
            writeln!(obj, "vt {:.6} {:.6}", uv.x, uv.y)?;
        }
        writeln!(obj, "usemtl tree")?;
        for f in &self.faces {
            let [a, b, c] = f.map(|i| i + 1);
            writeln!(obj, "f {a}/{a} {b}/{b} {c}/{c}")?;
        }
        std::fs::write(obj_path, obj)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truss_beams_are_thin_and_closed() {
        let s = truss(10.0, 3.0, 6, 0.01);
        // 4 legs + 4 horizontals + 8 diagonals per level, 12 triangles per beam: none dropped.
        assert_eq!(s.triangles.len(), 6 * 16 * 12);
        assert!((s.bounds.size().y - 10.0).abs() < 0.02);
    }

    #[test]
    fn quad_uvs_span_the_unit_square() {
        let mut sb = SceneBuilder::new();
        let m = sb.material(Material::default());
        let mesh = sb.mesh("q");
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        sb.quad(p, Vec4::ONE, m, mesh);
        let s = sb.finish();
        for t in &s.triangles {
            let (a, b, c) = (t.v[0].uv, t.v[1].uv, t.v[2].uv);
            let uv_area = 0.5 * (b - a).perp_dot(c - a).abs();
            assert!((uv_area - 0.5).abs() < 1e-6, "{t:?}");
            for v in &t.v {
                // uv = (x, 1 - y): top-left origin.
                assert_eq!(v.uv, Vec2::new(v.position.x, 1.0 - v.position.y));
            }
        }
    }

    #[test]
    fn bench_tree_has_exactly_200k_triangles() {
        let t = bench_tree(1);
        assert_eq!(t.faces.len(), 200_000);
        assert_eq!(t.positions.len(), t.uvs.len());
        assert!(t
            .faces
            .iter()
            .flatten()
            .all(|&i| (i as usize) < t.positions.len()));
    }

    #[test]
    fn furry_torus_is_deterministic() {
        let a = furry_torus(200, 3);
        let b = furry_torus(200, 3);
        let c = furry_torus(200, 4);
        assert_eq!(a, b);
        assert_ne!(a.triangles, c.triangles);
        assert_eq!(a.meshes[1].triangles, 200 * 5);
    }

    #[test]
    fn fur_tile_stays_near_unit_tile() {
        let s = fur_tile(100, 1);
        assert!(s.bounds.min.y >= -1e-6 && s.bounds.max.y <= 1.0 + 1e-3);
        assert!(s.bounds.min.x > -0.6 && s.bounds.max.x < 1.6);
    }
}
