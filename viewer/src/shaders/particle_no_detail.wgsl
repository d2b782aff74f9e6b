// Without detail (every system's `detail` is 0, no shimmer): no noise texture is bound
// and nothing is sampled. 0.5 is the noise's neutral value; with a detail strength of 0
// the shader's results do not depend on it (dust/smoke: τ·max(1 + 0·(2n − 1), 0) = τ;
// fire: mix(0.5, n, 0) = 0.5).
fn detail_noise(p: Particle, local: vec3<f32>) -> f32 {
    return 0.5;
}
