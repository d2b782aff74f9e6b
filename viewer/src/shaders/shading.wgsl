// The light models, prepended to mesh.wgsl (mesh_pass.rs), cloud.wgsl (cloud_pass),
// volume.wgsl (volume_pass) and shading_check.wgsl (shading_gpu.rs, which runs them in a
// compute pass for viewer/tests/shading_gpu.rs): the WGSL copy of billow_core::shading
// (shaders cannot call Rust), tested against it there.

// Two-sided Lambert plus ambient, ambient + (1 − ambient)·(|n·light|·visibility), n and
// light unit: billow_core::shading::diffuse_factor with its diffuse term scaled by the
// shadow map's visibility (1 without shadows).
fn diffuse_factor(n: vec3<f32>, light: vec3<f32>, ambient: f32, visibility: f32) -> f32 {
    return ambient + (1.0 - ambient) * (abs(dot(n, light)) * visibility);
}

// The two-sided cosine of a volume texel storing normal moments (SPEC §8.4a):
// billow_core::shading::moments_diffuse_factor at ambient 0, visibility 1. `m`: the
// filtered moments (E[n∘n], any trace: divided by it), `light`: unit, towards the light,
// `axis`: the camera's view axis (any length), both in the volume's own axes. √q where the
// normals share an axis, E|n·L| band-limited to the second moment where they spread (as a
// viewer sees spread normals: moments_view_factor), blended by the concentration.
fn moments_cosine_of(m: vec3<f32>, light: vec3<f32>, axis: vec3<f32>) -> f32 {
    let tr = m.x + m.y + m.z;
    if !(tr > 1e-6) {
        return 0.0;
    }
    let u = m / tr;
    let q = clamp(dot(u, light * light), 0.0, 1.0);
    let w = clamp((3.0 * dot(u, u) - 1.0) * 0.5, 0.0, 1.0);
    let spread = min(3.0 / 16.0 + 15.0 / 16.0 * q, 1.0) * moments_view_factor(u, light, axis, q);
    return w * sqrt(q) + (1.0 - w) * min(spread, 1.0);
}

// billow_core::shading's view_factor: spread_view_factor(cos γ), cos γ the correlation of
// n·V and n·L under the normalised moments u (q = u·(L∘L)); 1 where it is undefined.
fn moments_view_factor(u: vec3<f32>, light: vec3<f32>, axis: vec3<f32>, q: f32) -> f32 {
    let al = length(axis);
    if !(al > 0.0) {
        return 1.0;
    }
    let v = axis / al;
    let d = sqrt(dot(u, v * v) * q);
    if !(d > 1e-12) {
        return 1.0;
    }
    let c = min(abs(dot(u, v * light)) / d, 1.0);
    // billow_core::shading::spread_view_factor: 8/(3π)·(√(1 − c²) + c·asin c) as a
    // polynomial in c², exact at c = 1.
    let c2 = c * c;
    let k8 = 1.57079633 - (1.0 + 1.0 / 2.0 + 1.0 / 24.0 + 1.0 / 80.0);
    let s = 1.0 + c2 * (1.0 / 2.0 + c2 * (1.0 / 24.0 + c2 * (1.0 / 80.0 + c2 * k8)));
    return 8.0 / (3.0 * 3.14159265) * s;
}
