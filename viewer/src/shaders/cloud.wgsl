// Billboard clouds (Lacewell et al. 2006): instanced quads (or the foliage base mesh)
// whose vertices slide toward their parent billboard by the instance's morph factor (in
// this vertex shader: the per-asset vertex buffers never change); alpha-tested,
// depth-writing, opaque (the foliage base mesh's test hashed where its texture is
// minified, as the mesh pass's). shadow_lookup.wgsl, shading.wgsl and alpha_hash.wgsl are
// prepended.

struct Frame {
    view_proj: mat4x4<f32>,
    world_to_shadow: mat4x4<f32>,
    // xyz: direction towards the light, w: ambient
    light: vec4<f32>,
    // x: 1 = receive shadows, y: 1 = textures at MIP level 0 only (reference frames),
    // z: depth bias
    flags: vec4<f32>,
}

struct Draw {
    // x: alpha cut-off, y: 1 = premultiplied, z: 1 = lit at runtime from the normal map
    // (billboards; the foliage mesh is always lit), w: 1 = textured
    params: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var<uniform> dr: Draw;
@group(1) @binding(1) var tex: texture_2d<f32>;
@group(1) @binding(2) var smp: sampler;
// Tangent-space normal map (linear RGBA8, SPEC §9.4); a flat 1×1 where there is none.
@group(1) @binding(3) var nrm: texture_2d<f32>;
@group(1) @binding(4) var alpha_smp: sampler;

struct VIn {
    @location(0) pos: vec3<f32>,
    @location(1) target_pos: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    // xyz: T (the billboard's U), w: sign with B = w · cross(N, T) (glTF's convention)
    @location(4) tangent: vec4<f32>,
    @location(5) m0: vec4<f32>,
    @location(6) m1: vec4<f32>,
    @location(7) m2: vec4<f32>,
    @location(8) m3: vec4<f32>,
    // x: morph factor, y: dissolve t (0: none), z: 1 = the incoming level
    @location(9) morph: vec4<f32>,
}

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) shadow_clip: vec4<f32>,
    @location(3) tangent: vec4<f32>,
    // x: dissolve t, y: 1 = incoming level (cloud_pass module docs, "Dissolve")
    @location(4) @interpolate(flat) dissolve: vec2<f32>,
    @location(5) world: vec3<f32>,
}

// A vertex's world position: slid toward its parent billboard by the instance's morph
// factor, placed by the instance's transform.
fn world_of(v: VIn) -> vec4<f32> {
    let model = mat4x4<f32>(v.m0, v.m1, v.m2, v.m3);
    return model * vec4<f32>(mix(v.pos, v.target_pos, v.morph.x), 1.0);
}

@vertex
fn vs_main(v: VIn) -> VOut {
    let model = mat4x4<f32>(v.m0, v.m1, v.m2, v.m3);
    let w = world_of(v);
    var o: VOut;
    o.clip = frame.view_proj * w;
    o.shadow_clip = frame.world_to_shadow * w;
    o.uv = v.uv;
    o.normal = (model * vec4<f32>(v.normal, 0.0)).xyz;
    o.tangent = vec4<f32>((model * vec4<f32>(v.tangent.xyz, 0.0)).xyz, v.tangent.w);
    o.dissolve = v.morph.yz;
    o.world = w.xyz;
    return o;
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel threshold in [0, 1), fixed on
// screen, evenly spread over every small neighbourhood.
fn dither_threshold(p: vec2<f32>) -> f32 {
    let q = floor(p);
    return fract(52.9829189 * fract(0.06711056 * q.x + 0.00583715 * q.y));
}

// While an instance dissolves between two levels (t > 0), a pixel shows the incoming level
// where its threshold is below t and the outgoing one elsewhere: complementary masks.
fn dissolved(i: VOut) -> bool {
    return dissolved_at(i.dissolve, i.clip.xy);
}

// `dissolved` of a fragment at pixel `p` with the instance's `d` = (t, incoming).
fn dissolved_at(d: vec2<f32>, p: vec2<f32>) -> bool {
    let t = d.x;
    if t <= 0.0 {
        return false;
    }
    let below = dither_threshold(p) < t;
    if d.y > 0.5 {
        return !below;
    }
    return below;
}

fn texel(i: VOut) -> vec4<f32> {
    return texel_at(i.uv);
}

fn texel_at(uv: vec2<f32>) -> vec4<f32> {
    var c = dr.color;
    if dr.params.w > 0.5 {
        if frame.flags.y > 0.5 {
            c = c * textureSampleLevel(tex, smp, uv, 0.0);
        } else {
            c = c * textureSample(tex, smp, uv);
        }
    }
    return c;
}

fn visibility(i: VOut) -> f32 {
    return visibility_at(i.shadow_clip);
}

fn visibility_at(shadow_clip: vec4<f32>) -> f32 {
    if frame.flags.x > 0.5 {
        return shadow_visibility(shadow_clip, frame.flags.z);
    }
    return 1.0;
}

// Unlit foliage vertices (a zero normal): ambient + (1 − ambient)·vis of their colour.
fn shadow_factor(i: VOut) -> f32 {
    return frame.light.w + (1.0 - frame.light.w) * visibility(i);
}

// Baked lighting: a texel holds albedo·(ambient + (1 − ambient)·|N·L|), ambient and direct
// light together, and in shadow only the direct part goes. With |N·L| at its mean over
// the sphere, ½, the shadowed share is k = ambient / (ambient + (1 − ambient)/2), and the
// texel is scaled by k + (1 − k)·vis. (Scaling it by ambient + (1 − ambient)·vis, as
// before 2026-12-06, took the ambient share of the baked colour, not of the albedo: the
// oak's shadowed cloud read 18 % darker than the mesh under its own bake light.)
fn baked_shadow_factor(shadow_clip: vec4<f32>) -> f32 {
    let a = frame.light.w;
    let k = a / max(a + 0.5 * (1.0 - a), 1e-6);
    return k + (1.0 - k) * visibility_at(shadow_clip);
}

// The mesh pass's light factor (mesh.wgsl fs_main, shading.wgsl's diffuse_factor):
// ambient + (1 − ambient)·|N·L|·vis; a zero normal is lit as if it faced the light.
fn lambert_factor(n: vec3<f32>, i: VOut) -> f32 {
    let len = length(n);
    if len > 0.0 {
        return diffuse_factor(n / len, frame.light.xyz, frame.light.w, visibility(i));
    }
    return shadow_factor(i);
}

// The alpha test's threshold: billboards (premultiplied atlases, whose MIPs keep level 0's
// drawn coverage) test against the cut-off; the foliage base mesh's straight textures (plain
// MIPs) against alpha_threshold's hash where minified.
fn cut(i: VOut) -> f32 {
    return cut_at(i.uv, i.world);
}

fn cut_at(uv: vec2<f32>, world: vec3<f32>) -> f32 {
    // A uniform branch: billboards, untextured and opaque materials skip the hash and its
    // derivatives.
    if dr.params.y > 0.5 || dr.params.w < 0.5 || dr.params.x <= 0.0 {
        return dr.params.x;
    }
    let size = vec2<f32>(textureDimensions(tex));
    return alpha_threshold(dr.params.x, uv, size, world);
}

// The foliage base mesh: alpha-tested, lit like meshes (two-sided Lambert + ambient).
@fragment
fn fs_foliage(i: VOut) -> @location(0) vec4<f32> {
    let threshold = cut(i);
    let c = texel(i);
    if c.a < threshold || dissolved(i) {
        discard;
    }
    return vec4<f32>(c.rgb * lambert_factor(i.normal, i), 1.0);
}

// Billboards: alpha-tested on the premultiplied texel, opaque output of its straight
// colour. Baked lighting (the default, the pipeline of vs_baked / fs_baked below): only
// the shadow scales it (baked_shadow_factor). Baked unlit with a normal map (this one):
// lit here like meshes, N from the tangent-space normal map.
@fragment
fn fs_billboard(i: VOut) -> @location(0) vec4<f32> {
    let c = texel(i);
    let t = textureSample(nrm, smp, i.uv).xyz * 2.0 - 1.0;
    if c.a < dr.params.x || dissolved(i) {
        discard;
    }
    let nn = normalize(i.normal);
    let tt = normalize(i.tangent.xyz);
    let bb = i.tangent.w * cross(nn, tt);
    return vec4<f32>(c.rgb / c.a * lambert_factor(t.x * tt + t.y * bb + t.z * nn, i), 1.0);
}

// Billboards with baked lighting: only what their colour needs is passed on (no normal,
// tangent or world position), for on a software rasteriser every varying costs per
// fragment, and no normal map is sampled.
struct BakedOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) shadow_clip: vec4<f32>,
    @location(2) @interpolate(flat) dissolve: vec2<f32>,
}

@vertex
fn vs_baked(v: VIn) -> BakedOut {
    let w = world_of(v);
    var o: BakedOut;
    o.clip = frame.view_proj * w;
    o.shadow_clip = frame.world_to_shadow * w;
    o.uv = v.uv;
    o.dissolve = v.morph.yz;
    return o;
}

@fragment
fn fs_baked(i: BakedOut) -> @location(0) vec4<f32> {
    let c = texel_at(i.uv);
    if c.a < dr.params.x || dissolved_at(i.dissolve, i.clip.xy) {
        discard;
    }
    return vec4<f32>(c.rgb / c.a * baked_shadow_factor(i.shadow_clip), 1.0);
}

// The billboards of the shadow pass (its main fill): only what their alpha test reads is
// passed on, for on a software rasteriser every varying costs per fragment.
struct ShadowOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) dissolve: vec2<f32>,
}

@vertex
fn vs_billboard_shadow(v: VIn) -> ShadowOut {
    let w = world_of(v);
    var o: ShadowOut;
    o.clip = frame.view_proj * w;
    o.uv = v.uv;
    o.dissolve = v.morph.yz;
    return o;
}

// fs_shadow for billboards: premultiplied, textured, white (their cut-off is params.x).
@fragment
fn fs_billboard_shadow(i: ShadowOut) {
    if textureSample(tex, alpha_smp, i.uv).a < dr.params.x || dissolved_at(i.dissolve, i.clip.xy) {
        discard;
    }
}

// The foliage mesh in the shadow pass: what its (hashed) alpha test reads.
struct FoliageShadowOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) @interpolate(flat) dissolve: vec2<f32>,
    @location(2) world: vec3<f32>,
}

@vertex
fn vs_foliage_shadow(v: VIn) -> FoliageShadowOut {
    let w = world_of(v);
    var o: FoliageShadowOut;
    o.clip = frame.view_proj * w;
    o.uv = v.uv;
    o.dissolve = v.morph.yz;
    o.world = w.xyz;
    return o;
}

@fragment
fn fs_shadow(i: FoliageShadowOut) {
    let threshold = cut_at(i.uv, i.world);
    var a = dr.color.a;
    if dr.params.w > 0.5 {
        a = a * textureSample(tex, alpha_smp, i.uv).a;
    }
    if a < threshold || dissolved_at(i.dissolve, i.clip.xy) {
        discard;
    }
}
