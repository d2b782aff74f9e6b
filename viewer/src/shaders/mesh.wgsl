// Opaque meshes: base colour × vertex colour × texture, alpha-masked materials discard
// (hashed where the texture is minified: alpha_hash.wgsl);
// one directional light (two-sided Lambert, shading.wgsl's diffuse_factor) plus ambient,
// linear colour, shadowed when the frame has a shadow map (shadow_lookup.wgsl,
// shading.wgsl and alpha_hash.wgsl are prepended). A zero normal marks an unlit vertex: its base colour is
// drawn as it is, no Lambert, no shadow.

struct MeshFrame {
    view_proj: mat4x4<f32>,
    world_to_shadow: mat4x4<f32>,
    // xyz: direction towards the light (unit), w: ambient
    light: vec4<f32>,
    // x: 1 = receive shadows, y: 1 = textures at MIP level 0 only (reference frames),
    // z: depth bias
    flags: vec4<f32>,
}

struct Material {
    // x: alpha cut-off (0 = opaque), y: 1 = textured
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> mf: MeshFrame;
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_tex: texture_2d<f32>;
@group(1) @binding(2) var base_smp: sampler;

struct VIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) color: vec4<f32>,
}

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) shadow_clip: vec4<f32>,
    @location(4) world: vec3<f32>,
}

@vertex
fn vs_main(v: VIn) -> VOut {
    var o: VOut;
    o.clip = mf.view_proj * vec4<f32>(v.pos, 1.0);
    o.shadow_clip = mf.world_to_shadow * vec4<f32>(v.pos, 1.0);
    o.normal = v.normal;
    o.color = v.color;
    o.uv = v.uv;
    o.world = v.pos;
    return o;
}

fn base_colour(i: VOut) -> vec4<f32> {
    var c = i.color;
    if material.params.y > 0.5 {
        if mf.flags.y > 0.5 {
            c = c * textureSampleLevel(base_tex, base_smp, i.uv, 0.0);
        } else {
            c = c * textureSample(base_tex, base_smp, i.uv);
        }
    }
    return c;
}

// The threshold of the alpha test (0: opaque, never discarded).
fn cut(i: VOut) -> f32 {
    // A uniform branch: opaque materials skip the hash and its derivatives.
    if material.params.x <= 0.0 {
        return 0.0;
    }
    let size = vec2<f32>(textureDimensions(base_tex));
    return alpha_threshold(material.params.x, i.uv, size, i.world);
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let threshold = cut(i);
    let c = base_colour(i);
    if c.a < threshold {
        discard;
    }
    let len = length(i.normal);
    if len == 0.0 {
        // Unlit (e.g. glTF KHR_materials_unlit, lighting baked in): neither Lambert nor
        // shadow, the base colour is the final colour.
        return vec4<f32>(c.rgb, 1.0);
    }
    var vis = 1.0;
    if mf.flags.x > 0.5 {
        vis = shadow_visibility(i.shadow_clip, mf.flags.z);
    }
    let k = diffuse_factor(i.normal / len, mf.light.xyz, mf.light.w, vis);
    return vec4<f32>(c.rgb * k, 1.0);
}

@fragment
fn fs_shadow(i: VOut) {
    let threshold = cut(i);
    if base_colour(i).a < threshold {
        discard;
    }
}
