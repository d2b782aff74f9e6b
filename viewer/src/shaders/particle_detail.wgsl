// The detail noise (particles.wgsl's binding 3), for scenes whose particles have
// `detail > 0` or heat shimmer.
@group(0) @binding(3) var detail_tex: texture_3d<f32>;

fn detail_noise(p: Particle, local: vec3<f32>) -> f32 {
    let uvw = vec3<f32>(local.xy * 0.5 + p.detail.xy, pf.clip.z * 0.4 + p.detail.z);
    return textureSampleLevel(detail_tex, smp_repeat, uvw, 0.0).r;
}
