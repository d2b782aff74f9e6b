// The check of shading.wgsl's diffuse_factor against billow-core
// (viewer/tests/shading_gpu.rs): prepended with shading.wgsl, followed by
// compute_check.wgsl's entry point.

struct Case {
    // xyz: the unit normal, w: ambient
    n: vec4<f32>,
    // xyz: the unit direction towards the light, w: visibility
    light: vec4<f32>,
}

struct Out {
    // x: diffuse_factor
    v: vec4<f32>,
}

fn check(k: Case) -> Out {
    return Out(vec4<f32>(diffuse_factor(k.n.xyz, k.light.xyz, k.n.w, k.light.w), 0.0, 0.0, 0.0));
}
