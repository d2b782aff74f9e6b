// Compute entry point that runs shading.wgsl's diffuse_factor on a list of cases, for the
// test against billow-core (viewer/tests/shading_gpu.rs). Prepended with shading.wgsl.

struct ShadingCase {
    // xyz: the unit normal, w: ambient
    n: vec4<f32>,
    // xyz: the unit direction towards the light, w: visibility
    light: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> cases: array<ShadingCase>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&cases) {
        return;
    }
    let k = cases[i];
    results[i] = vec4<f32>(diffuse_factor(k.n.xyz, k.light.xyz, k.n.w, k.light.w), 0.0, 0.0, 0.0);
}
