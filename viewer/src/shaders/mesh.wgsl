// Opaque meshes: one directional light (two-sided Lambert) plus ambient, linear colour.

struct MeshFrame {
    view_proj: mat4x4<f32>,
    // xyz: direction towards the light (unit), w: ambient
    light: vec4<f32>,
}

@group(0) @binding(0) var<uniform> mf: MeshFrame;

struct VIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
}

struct VOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
}

@vertex
fn vs_main(v: VIn) -> VOut {
    var o: VOut;
    o.clip = mf.view_proj * vec4<f32>(v.pos, 1.0);
    o.normal = v.normal;
    o.color = v.color;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let len = length(i.normal);
    var lambert = 1.0;
    if len > 0.0 {
        lambert = abs(dot(i.normal / len, mf.light.xyz));
    }
    let k = mf.light.w + (1.0 - mf.light.w) * lambert;
    return vec4<f32>(i.color.rgb * k, 1.0);
}
