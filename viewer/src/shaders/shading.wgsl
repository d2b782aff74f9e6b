// The mesh pass's light model, prepended to mesh.wgsl (mesh_pass.rs), cloud.wgsl
// (cloud_pass) and shading_check.wgsl (shading_gpu.rs, which runs it in a compute pass
// for viewer/tests/shading_gpu.rs): the WGSL copy of billow_core::shading (shaders
// cannot call Rust), tested against it there.

// Two-sided Lambert plus ambient, ambient + (1 − ambient)·(|n·light|·visibility), n and
// light unit: billow_core::shading::diffuse_factor with its diffuse term scaled by the
// shadow map's visibility (1 without shadows).
fn diffuse_factor(n: vec3<f32>, light: vec3<f32>, ambient: f32, visibility: f32) -> f32 {
    return ambient + (1.0 - ambient) * (abs(dot(n, light)) * visibility);
}
