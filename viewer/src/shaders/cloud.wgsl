// Billboard clouds (Lacewell et al. 2006): instanced quads (or the foliage base mesh)
// whose vertices slide toward their parent billboard by the instance's morph factor;
// alpha-tested, depth-writing. shadow_lookup.wgsl is prepended.

struct Frame {
    view_proj: mat4x4<f32>,
    world_to_shadow: mat4x4<f32>,
    // xyz: direction towards the light, w: ambient
    light: vec4<f32>,
    // x: 1 = receive shadows, z: depth bias
    flags: vec4<f32>,
}

struct Draw {
    // x: alpha cut-off, y: 1 = premultiplied, z: 1 = lit, w: 1 = textured
    params: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var<uniform> dr: Draw;
@group(1) @binding(1) var tex: texture_2d<f32>;
@group(1) @binding(2) var smp: sampler;

struct VIn {
    @location(0) pos: vec3<f32>,
    @location(1) target_pos: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
    @location(4) m0: vec4<f32>,
    @location(5) m1: vec4<f32>,
    @location(6) m2: vec4<f32>,
    @location(7) m3: vec4<f32>,
    @location(8) morph: vec4<f32>,
}

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) shadow_clip: vec4<f32>,
}

@vertex
fn vs_main(v: VIn) -> VOut {
    let model = mat4x4<f32>(v.m0, v.m1, v.m2, v.m3);
    let p = mix(v.pos, v.target_pos, v.morph.x);
    let w = model * vec4<f32>(p, 1.0);
    var o: VOut;
    o.clip = frame.view_proj * w;
    o.shadow_clip = frame.world_to_shadow * w;
    o.uv = v.uv;
    o.normal = (model * vec4<f32>(v.normal, 0.0)).xyz;
    return o;
}

fn texel(i: VOut) -> vec4<f32> {
    var c = dr.color;
    if dr.params.w > 0.5 {
        c = c * textureSample(tex, smp, i.uv);
    }
    return c;
}

fn visibility(i: VOut) -> f32 {
    if frame.flags.x > 0.5 {
        return shadow_visibility(i.shadow_clip, frame.flags.z);
    }
    return 1.0;
}

// The foliage base mesh: alpha-tested, lit like meshes (two-sided Lambert + ambient).
@fragment
fn fs_foliage(i: VOut) -> @location(0) vec4<f32> {
    let c = texel(i);
    if c.a < dr.params.x {
        discard;
    }
    var lambert = 1.0;
    let len = length(i.normal);
    if len > 0.0 {
        lambert = abs(dot(i.normal / len, frame.light.xyz));
    }
    let k = frame.light.w + (1.0 - frame.light.w) * lambert * visibility(i);
    return vec4<f32>(c.rgb * k, 1.0);
}

// Billboards, depth pre-pass: only texels at least as opaque as the cut-off write depth.
@fragment
fn fs_depth(i: VOut) -> @location(0) vec4<f32> {
    if texel(i).a < dr.params.x {
        discard;
    }
    return vec4<f32>(0.0);
}

// Billboards, sorted blend: premultiplied texels (lighting baked in; shadows scale it).
@fragment
fn fs_blend(i: VOut) -> @location(0) vec4<f32> {
    let c = texel(i);
    let k = frame.light.w + (1.0 - frame.light.w) * visibility(i);
    return vec4<f32>(c.rgb * k, c.a);
}

@fragment
fn fs_shadow(i: VOut) {
    if texel(i).a < dr.params.x {
        discard;
    }
}
