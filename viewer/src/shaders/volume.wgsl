// Volumetric billboards, the paper's GPU slicing (§3.3): one instance per cell × slice,
// a fixed budget of 9 vertices (a fan of 3 triangles covers the ≤ 5-gon); the vertex
// shader intersects its cell with its slice plane (prism_plane.wgsl, prepended).
// Opacity correction and MIP choice as src/eval/slicer.rs.

struct Frame {
    proj: mat4x4<f32>,
    // x: total cells in the cell buffer (instance = slice · n + cell)
    counts: vec4<u32>,
}

struct Slice {
    // x: view-space z of the plane (−depth), y: spacing d
    zd: vec4<f32>,
}

struct Group {
    // x: v0 (level-0 voxel size), y: max lod (levels − 1)
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> cells: array<Cell>;
@group(0) @binding(2) var<storage, read> slices: array<Slice>;
@group(1) @binding(0) var<uniform> group_params: Group;
@group(1) @binding(1) var vol_tex: texture_3d<f32>;
@group(1) @binding(2) var vol_smp: sampler;

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uvw: vec3<f32>,
    @location(1) @interpolate(flat) lod_ratio: vec2<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOut {
    var out: VOut;
    let n = frame.counts.x;
    let slice = slices[ii / n];
    var c = cells[ii % n];
    var poly = intersect_prism_plane(&c, slice.zd.x);
    let tri = vi / 3u;
    let corner = vi % 3u;
    if poly.count < tri + 3u {
        // Unused vertex of the budget: a degenerate triangle outside the clip volume.
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        out.uvw = vec3<f32>(0.0);
        out.lod_ratio = vec2<f32>(0.0);
        return out;
    }
    let k = select(tri + corner, 0u, corner == 0u);
    out.clip = frame.proj * vec4<f32>(poly.pos[k], 1.0);
    out.uvw = poly.uvw[k];
    // MIP level from the spacing, opacity-correction ratio d / d0 (linear MIP filter).
    let d = slice.zd.y;
    let v0 = group_params.params.x;
    let lod = clamp(log2(d / v0), 0.0, group_params.params.y);
    let d0 = v0 * exp2(lod);
    out.lod_ratio = vec2<f32>(lod, d / d0);
    return out;
}

// ln(1 + x) and exp(x) − 1 with full relative precision for small |x| (WGSL has neither).
fn log1p_(x: f32) -> f32 {
    let u = 1.0 + x;
    if u == 1.0 {
        return x;
    }
    return log(u) * x / (u - 1.0);
}

fn expm1_(x: f32) -> f32 {
    let u = exp(x);
    if u == 1.0 {
        return x;
    }
    let um = u - 1.0;
    if um == -1.0 {
        return -1.0;
    }
    return um * x / log(u);
}

// α' = 1 − (1 − α)^ratio, premultiplied colour scaled by α'/α (src/eval/compositing.rs).
fn correct_premultiplied(c: vec4<f32>, ratio: f32) -> vec4<f32> {
    if ratio == 1.0 {
        return c;
    }
    let a = clamp(c.a, 0.0, 1.0);
    var a2 = 0.0;
    if ratio > 0.0 {
        if a >= 1.0 {
            a2 = 1.0;
        } else {
            a2 = clamp(-expm1_(ratio * log1p_(-a)), 0.0, 1.0);
        }
    }
    var scale = max(ratio, 0.0);
    if a > 0.0 {
        scale = a2 / a;
    }
    return vec4<f32>(c.rgb * scale, a2);
}

@fragment
fn fs_main(in: VOut) -> @location(0) vec4<f32> {
    let s = textureSampleLevel(vol_tex, vol_smp, in.uvw, in.lod_ratio.x);
    return correct_premultiplied(s, in.lod_ratio.y);
}
