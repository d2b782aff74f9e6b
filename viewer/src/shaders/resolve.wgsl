// Resolve: the premultiplied linear Rgba16Float frame over an opaque background colour,
// to an 8-bit output (sRGB-encoded here when the output format does not encode it).
// Overlay: a straight-alpha texture blended into a rectangle (the stats line).

struct Resolve {
    background: vec4<f32>,
    // x: 1 = encode sRGB in the shader
    flags: vec4<f32>,
    // overlay rectangle in NDC: x0, y0, x1, y1
    rect: vec4<f32>,
}

@group(0) @binding(0) var<uniform> u: Resolve;
@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var smp: sampler;

// VOut and vs_full: fullscreen.wgsl, prepended.

@vertex
fn vs_rect(@builtin(vertex_index) i: u32) -> VOut {
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    );
    let c = corners[i];
    var o: VOut;
    o.clip = vec4<f32>(mix(u.rect.x, u.rect.z, c.x), mix(u.rect.w, u.rect.y, c.y), 0.0, 1.0);
    o.uv = c;
    return o;
}

fn encode(c: vec3<f32>) -> vec3<f32> {
    if u.flags.x < 0.5 {
        return c;
    }
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_resolve(i: VOut) -> @location(0) vec4<f32> {
    let dims = vec2<f32>(textureDimensions(src));
    let c = textureLoad(src, vec2<i32>(i.uv * dims), 0);
    let rgb = c.rgb + u.background.rgb * (1.0 - clamp(c.a, 0.0, 1.0));
    return vec4<f32>(encode(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0))), 1.0);
}

@fragment
fn fs_overlay(i: VOut) -> @location(0) vec4<f32> {
    let c = textureSampleLevel(src, smp, i.uv, 0.0);
    return vec4<f32>(encode(c.rgb), c.a);
}
