// Volumetric billboards, the paper's GPU slicing (§3.3): one instance per slice × cell
// of a draw, a fixed budget of 9 vertices (a fan of 3 triangles covers the ≤ 5-gon);
// the vertex shader intersects its cell with its slice plane (prism_plane.wgsl,
// prepended, with shadow_lookup.wgsl, volume_math.wgsl and the texture-slot switch
// `sample_volume`). Opacity correction, MIP choice (slice_lod), extinction-space
// filtering (slab_sample) and the depth fade (depth_fade) as src/eval/slicer.rs and
// src/eval/volume_sampler.rs: those three are volume_math.wgsl's copies of billow-core's
// functions, tested against them (viewer/tests/volume_math_gpu.rs). Volumes with normals
// are shaded at runtime (VB §3.2): albedo × (ambient + (1 − ambient) · shadow ·
// max(n̄·L, 0)) with n̄ the Toksvig normal (billow_core::shading::volume_diffuse_factor).

struct Frame {
    proj: mat4x4<f32>,
    view_to_shadow: mat4x4<f32>,
    // x: 1 = receive shadows, y: alpha cut-off of the shadow pipeline, z: shadow bias
    flags: vec4<f32>,
    // xyz: unit direction towards the light (view space), w: ambient
    light: vec4<f32>,
}

struct Slice {
    // x: view-space z of the plane (−depth), y: spacing d, z: the thickness of the slab
    // the slice stands for (d; more for the farthest, billow_core::slicing::far_slab)
    zd: vec4<f32>,
}

struct VolumeParams {
    // The band's: x: v0 · 2^first_level, y: its max lod, z: texture slot,
    // w: flags (1 = repeat, + 2 = shaded from normals, + 4 = BC7 blocks filtered by loads,
    // + 8 = the normals are moments, + 16 = moments as BC7 blocks)
    p: vec4<f32>,
    // The asset's: x: v0, y: largest LOD L, z..w: slice-LOD range [f_b, f_{b+1}) of the band
    q: vec4<f32>,
    // x: the world size of a level-0 texel of the band's texture
    r: vec4<f32>,
}

struct Draw {
    first_slice: u32,
    slice_count: u32,
    list_offset: u32,
    cell_count: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> cells: array<Cell>;
@group(0) @binding(2) var<storage, read> slices: array<Slice>;
@group(0) @binding(3) var<storage, read> list: array<u32>;
@group(0) @binding(4) var<storage, read> volumes: array<VolumeParams>;
@group(0) @binding(5) var<uniform> draw: Draw;
// The opaque meshes' depth (read-only attachment); only fs_main reads it.
@group(3) @binding(0) var scene_depth: texture_depth_2d;

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uvw: vec3<f32>,
    // x: lod, y: the slab's thickness in level-0 texels of the band's texture (the
    // opacity correction), z: the view distance where the slab starts (depth − d/2),
    // w: its thickness
    @location(1) @interpolate(flat) lod_ratio: vec4<f32>,
    // x: texture slot, y: flags (1 = repeat addressing, 2 = shaded from normals, 8 = moments,
    // 16 = moments as BC7 blocks,
    // 4 = BC7 blocks filtered by loads)
    @location(2) @interpolate(flat) slot: vec2<u32>,
    @location(3) shadow_clip: vec4<f32>,
    // Rows of the cell's normal matrix (stored normals → view space).
    @location(4) @interpolate(flat) n0: vec3<f32>,
    @location(5) @interpolate(flat) n1: vec3<f32>,
    @location(6) @interpolate(flat) n2: vec3<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOut {
    var out: VOut;
    let n = max(draw.cell_count, 1u);
    let slice = slices[draw.first_slice + ii / n];
    var c = cells[list[draw.list_offset + ii % n]];
    let params = volumes[bitcast<u32>(c.pos[0].w)];
    let vol = params.p;
    // The slice's LOD λ (SPEC §8.6): a banded asset draws each slice with one band.
    let d = slice.zd.y;
    let lambda = slice_lod(d, params.q.x, params.q.y);
    let in_band = band_holds(params.q.zw, lambda);
    var poly = intersect_prism_plane(&c, slice.zd.x);
    let tri = vi / 3u;
    let corner = vi % 3u;
    if !in_band || poly.count < tri + 3u {
        // Unused vertex of the budget: a degenerate triangle outside the clip volume.
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        out.uvw = vec3<f32>(0.0);
        out.lod_ratio = vec4<f32>(0.0);
        out.slot = vec2<u32>(0u);
        out.shadow_clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        out.n0 = vec3<f32>(0.0);
        out.n1 = vec3<f32>(0.0);
        out.n2 = vec3<f32>(0.0);
        return out;
    }
    let k = select(tri + corner, 0u, corner == 0u);
    let p = vec4<f32>(poly.pos[k], 1.0);
    out.clip = frame.proj * p;
    out.shadow_clip = frame.view_to_shadow * p;
    out.uvw = poly.uvw[k];
    // MIP level from the spacing (the band's own LOD λ − f_b); the opacity correction:
    // the textures hold optical depths per level-0 texel (volume_pass/textures.rs,
    // extinction_levels), so the slab takes its thickness over that texel's size of them
    // (billow_core::slicing::level_weights).
    let v0 = vol.x;
    let lod = slice_lod(d, v0, vol.y);
    let thickness = slice.zd.z;
    out.lod_ratio = vec4<f32>(lod, thickness / params.r.x, -slice.zd.x - 0.5 * d, thickness);
    out.slot = vec2<u32>(u32(vol.z), u32(vol.w));
    // The normal matrix rows (volume_pass/gpu_types.rs, GpuCell::with_normal_matrix).
    out.n0 = vec3<f32>(c.uvw[0].w, c.uvw[1].w, c.uvw[2].w);
    out.n1 = vec3<f32>(c.uvw[3].w, c.uvw[4].w, c.uvw[5].w);
    out.n2 = vec3<f32>(c.pos[1].w, c.pos[2].w, c.pos[3].w);
    return out;
}

fn sample_corrected(in: VOut, ratio: f32) -> vec4<f32> {
    let e = sample_volume(in.slot.x, in.slot.y, in.uvw, in.lod_ratio.x);
    return slab_sample(e, ratio);
}

// View distance of the opaque surface under the fragment (3e38: none), inverting the
// camera's projection (perspective or orthographic) at the stored depth.
fn scene_distance(frag: vec2<f32>) -> f32 {
    let z = textureLoad(scene_depth, vec2<i32>(frag), 0);
    if z >= 1.0 {
        return 3.0e38;
    }
    let p = frame.proj;
    return (p[3][2] - z * p[3][3]) / (p[2][2] - z * p[2][3]);
}

// The Toksvig normal at the fragment in view space: the filtered (α·n̄, α) over α (the
// alpha-weighted mean, length ≤ 1; src/eval/volume_sampler.rs::normal_from_weighted),
// turned by the normal matrix, its length kept (src/eval/slicer.rs::shade_normal).
fn toksvig_normal(in: VOut) -> vec3<f32> {
    let s = sample_normals(in.slot.x, (in.slot.y & 1u) != 0u, in.uvw, in.lod_ratio.x);
    if !(s.w > 0.0) {
        return vec3<f32>(0.0);
    }
    var n = s.xyz / s.w;
    let len = length(n);
    if len > 1.0 {
        n = n / len;
    }
    let v = vec3<f32>(dot(in.n0, n), dot(in.n1, n), dot(in.n2, n));
    let lv = length(v);
    if !(lv > 0.0) {
        return vec3<f32>(0.0);
    }
    return v * (min(len, 1.0) / lv);
}

// The two-sided cosine of a volume storing normal moments (flag 8; SPEC §8.4a;
// core/src/shading.rs::moments_diffuse_factor) from m, the filtered moments as stored
// (E[n∘n]; flag 16: their BC7 blocks, unorm of the snorm bytes XOR 0x80, mapped back by
// v = (255·u − 128)/127), with L and the camera's view axis in the volume's own axes
// (Mᵀ·L and Mᵀ·z, M the normal matrix whose rows are n0, n1, n2).
fn moments_cosine(in: VOut) -> f32 {
    var s = sample_normals(in.slot.x, (in.slot.y & 1u) != 0u, in.uvw, in.lod_ratio.x);
    if (in.slot.y & 16u) != 0u {
        s = vec4<f32>(s.xyz * (255.0 / 127.0) - vec3<f32>(128.0 / 127.0), 0.0);
    }
    let l = frame.light.xyz;
    let ll = in.n0 * l.x + in.n1 * l.y + in.n2 * l.z;
    let len = length(ll);
    if !(len > 0.0) {
        return 0.0;
    }
    return moments_cosine_of(s.xyz, ll / len, in.n2);
}

@fragment
fn fs_main(in: VOut) -> @location(0) vec4<f32> {
    let fade = depth_fade(scene_distance(in.clip.xy), in.lod_ratio.z, in.lod_ratio.w);
    if !(fade > 0.0) {
        discard;
    }
    var c = sample_corrected(in, in.lod_ratio.y * fade);
    var vis = 1.0;
    if frame.flags.x > 0.5 {
        vis = shadow_visibility(in.shadow_clip, frame.flags.z);
    }
    if (in.slot.y & 10u) == 10u {
        // Normal moments: two-sided (core/src/shading.rs::moments_diffuse_factor).
        let k = frame.light.w + (1.0 - frame.light.w) * vis * moments_cosine(in);
        c = vec4<f32>(c.rgb * k, c.a);
    } else if (in.slot.y & 2u) != 0u {
        // Runtime shading (src/eval/lighting.rs::volume_diffuse_factor, one-sided).
        let d = max(dot(toksvig_normal(in), frame.light.xyz), 0.0);
        let k = frame.light.w + (1.0 - frame.light.w) * vis * d;
        c = vec4<f32>(c.rgb * k, c.a);
    } else if frame.flags.x > 0.5 {
        let k = frame.light.w + (1.0 - frame.light.w) * vis;
        c = vec4<f32>(c.rgb * k, c.a);
    }
    return c;
}

// Shadow map: an opacity-scaled slice (fewer slices, opacity corrected for the larger
// spacing) occludes where its opacity reaches the cut-off.
@fragment
fn fs_shadow(in: VOut) {
    if sample_corrected(in, in.lod_ratio.y).a < frame.flags.y {
        discard;
    }
}
