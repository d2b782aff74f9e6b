// The check of shading.wgsl's moments_cosine_of against billow-core
// (viewer/tests/shading_gpu.rs): prepended with shading.wgsl, followed by
// compute_check.wgsl's entry point.

struct Case {
    // xyz: the filtered moments (any trace)
    m: vec4<f32>,
    // xyz: the unit direction towards the light
    light: vec4<f32>,
    // xyz: the view axis (any length)
    axis: vec4<f32>,
}

struct Out {
    // x: moments_cosine_of
    v: vec4<f32>,
}

fn check(k: Case) -> Out {
    return Out(vec4<f32>(moments_cosine_of(k.m.xyz, k.light.xyz, k.axis.xyz), 0.0, 0.0, 0.0));
}
