// Hashed alpha testing (Wyman and McGuire, "Hashed Alpha Testing", I3D 2017) for
// alpha-masked mesh textures. Their MIP levels are plain averages, so a level's alpha is the
// share of the area it covers; a fixed cut-off cannot draw that share once a leaf is
// smaller than a pixel (it draws all of it or nothing), a threshold uniform in [0, 1) does
// in expectation. Where the texture is magnified the material's own cut-off keeps edges
// crisp; from one texel per two pixels on the threshold is the hash; between them a blend.

// PCG-style integer hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", 2020).
fn pcg3d(v0: vec3<u32>) -> vec3<u32> {
    var v = v0 * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v = v ^ (v >> vec3<u32>(16u));
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return v;
}

// The threshold `alpha` is tested against (pass: alpha >= threshold). `uv` in [0, 1]
// texture space, `size` the texture's level-0 size, `world` the fragment's position: the
// hash is of the world cell about one pixel wide that holds it, so it stays on the surface
// while the camera moves. Call in uniform control flow (derivatives).
fn alpha_threshold(cutoff: f32, uv: vec2<f32>, size: vec2<f32>, world: vec3<f32>) -> f32 {
    let t = uv * size;
    let texels = max(length(dpdx(t)), length(dpdy(t)));
    // 0 at one texel per pixel or fewer, 1 from two texels per pixel on.
    let w = clamp(log2(max(texels, 1e-8)), 0.0, 1.0);
    let footprint = max(max(length(dpdx(world)), length(dpdy(world))), 1e-20);
    let cell = exp2(ceil(log2(footprint)));
    let q = vec3<i32>(floor(world / cell));
    let h = f32(pcg3d(bitcast<vec3<u32>>(q)).x >> 8u) * (1.0 / 16777216.0);
    return mix(cutoff, h, w);
}
