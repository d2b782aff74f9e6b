// Spherical billboards (Umenhoffer et al., ShaderX5): one instanced quad per particle,
// its fragment computing the ray's path through the particle sphere, clipped by the near
// plane and the opaque scene's depth; α = 1 − exp(−τ(1 − d/r)Δs). The port of
// viewer/src/particles/opacity.rs (the CPU reference the tests check). Rays are the
// exact perspective rays through each pixel. `planar` mode draws classic flat
// billboards at the particle centre for comparison.

struct PFrame {
    proj: mat4x4<f32>,
    // xyz: direction towards the light in view space, w: ambient
    light: vec4<f32>,
    // rgb: light colour (radiance of isotropic scattering at albedo 1)
    light_colour: vec4<f32>,
    // x, y: layer size in pixels; z, w: full-resolution size
    screen: vec4<f32>,
    // x: near, y: far, z: time (s), w: shimmer strength (layer pixels)
    clip: vec4<f32>,
}

struct Particle {
    // xyz: view-space centre, w: radius
    centre: vec4<f32>,
    // x: τ, y: albedo, z: g, w: kind (0 dust, 1 smoke, 2 fire)
    params: vec4<f32>,
    // x: T0, y: T1, z: emission, w: detail strength
    fire: vec4<f32>,
    // xyz: detail offset, w: 1 = planar mode
    detail: vec4<f32>,
}

@group(0) @binding(0) var<uniform> pf: PFrame;
@group(0) @binding(1) var<storage, read> parts: array<Particle>;
@group(0) @binding(2) var scene_depth: texture_depth_2d;
// Binding 3, the detail noise, and `detail_noise` are in particle_detail.wgsl (or its
// stand-in particle_no_detail.wgsl, which samples nothing).
@group(0) @binding(4) var phase_lut: texture_2d<f32>;
@group(0) @binding(5) var bb_lut: texture_2d<f32>;
@group(0) @binding(6) var smp_repeat: sampler;
@group(0) @binding(7) var smp_clamp: sampler;

// Keep in step with particles/phase.rs and particles/blackbody.rs.
const PHASE_MU: f32 = 128.0;
const PHASE_G: f32 = 64.0;
const PHASE_G_MAX: f32 = 0.98;
const BB_N: f32 = 256.0;
const BB_T_MAX: f32 = 10000.0;
const FOUR_PI: f32 = 12.566371;

struct VOut {
    @builtin(position) clip: vec4<f32>,
    // The view-space point of the quad under the fragment (its ray direction).
    @location(0) q: vec3<f32>,
    @location(1) @interpolate(flat) index: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @builtin(instance_index) ii: u32) -> VOut {
    let p = parts[ii];
    let c = p.centre.xyz;
    let r = p.centre.w;
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let k = corners[vi];
    var out: VOut;
    out.index = ii;
    if p.detail.w > 0.5 {
        // Planar: a flat quad at the centre's depth, facing the view axis; the hardware
        // clips it against the near plane as a whole (the popping artefact).
        let q = c + vec3<f32>(k * r, 0.0);
        out.q = q;
        out.clip = pf.proj * vec4<f32>(q, 1.0);
        return out;
    }
    let dist = length(c);
    let near = pf.clip.x;
    if dist <= r * 1.02 + near {
        // The eye is inside (or at) the sphere: cover the screen; each fragment finds its
        // own ray. The view-space point (x/P₀₀, y/P₁₁, −1) is linear in screen space.
        let ndc = k;
        out.q = vec3<f32>(ndc.x / pf.proj[0][0], ndc.y / pf.proj[1][1], -1.0);
        out.clip = vec4<f32>(ndc, 0.5, 1.0);
        return out;
    }
    // A quad perpendicular to the ray to the centre, on the sphere's far side, covering
    // the silhouette cone (half-angle asin(r/|c|)) with a margin.
    let w = c / dist;
    var up = vec3<f32>(0.0, 1.0, 0.0);
    if abs(w.y) > 0.99 {
        up = vec3<f32>(1.0, 0.0, 0.0);
    }
    let u = normalize(cross(w, up));
    let v = cross(u, w);
    let d = min(dist + 0.99 * r, pf.clip.y * 0.999);
    let s = 1.05 * d * r / sqrt(max(dist * dist - r * r, 1e-12));
    let q = w * d + (k.x * u + k.y * v) * s;
    out.q = q;
    out.clip = pf.proj * vec4<f32>(q, 1.0);
    return out;
}

// 1 − exp(−x) for x ≥ 0, accurate for small x (WGSL has no expm1).
fn one_minus_exp_neg(x: f32) -> f32 {
    if x < 1e-4 {
        return x * (1.0 - 0.5 * x);
    }
    return 1.0 - exp(-x);
}

// Opaque depth under the fragment, as a view distance along −z (infinite = none).
fn scene_distance(frag: vec2<f32>) -> f32 {
    let scale = pf.screen.zw / pf.screen.xy;
    let px = vec2<i32>(clamp(frag * scale, vec2<f32>(0.0), pf.screen.zw - 1.0));
    let z = textureLoad(scene_depth, px, 0);
    if z >= 1.0 {
        return 3.0e38;
    }
    let near = pf.clip.x;
    let far = pf.clip.y;
    return near / (1.0 - z * (far - near) / far);
}

struct Shaded {
    colour: vec4<f32>,
    noise: f32,
}

fn shade(in: VOut) -> Shaded {
    let p = parts[in.index];
    let c = p.centre.xyz;
    let r = p.centre.w;
    let near = pf.clip.x;
    let scene = scene_distance(in.clip.xy);
    var alpha_in = 0.0;
    var d = 0.0;
    var path = 0.0;
    var local = vec3<f32>(0.0);
    if p.detail.w > 0.5 {
        // Planar billboard: the sphere's full chord at the quad point, hidden where the
        // scene is in front of the quad plane (the clipping artefact).
        d = length(in.q.xy - c.xy);
        if d >= r || -c.z > scene {
            return Shaded(vec4<f32>(0.0), 0.0);
        }
        path = 2.0 * sqrt(r * r - d * d);
        local = (in.q - c) / r;
    } else {
        let dir = normalize(in.q);
        let b = dot(dir, c);
        let d2 = max(dot(c, c) - b * b, 0.0);
        if d2 >= r * r {
            return Shaded(vec4<f32>(0.0), 0.0);
        }
        let w = sqrt(r * r - d2);
        let dz = -dir.z;
        var t_near = 0.0;
        var t_scene = 3.0e38;
        if dz > 1e-12 {
            t_near = near / dz;
            t_scene = scene / dz;
        }
        let enter = max(max(b - w, t_near), 0.0);
        let exit = min(b + w, t_scene);
        path = max(exit - enter, 0.0);
        d = sqrt(d2);
        local = (dir * b - c) / r;
    }
    let n = detail_noise(p, local);
    let kind = u32(p.params.w + 0.5);
    var tau = p.params.x;
    if kind != 2u {
        // Dust and smoke: the detail perturbs the opacity.
        tau = tau * max(1.0 + p.fire.w * (2.0 * n - 1.0), 0.0);
    }
    let alpha = one_minus_exp_neg(tau * max(1.0 - d / r, 0.0) * path);
    if kind == 2u {
        // Fire: black-body emission at T = T0 + T1 · noise.
        let t = p.fire.x + p.fire.y * mix(0.5, n, p.fire.w * 2.0);
        let x = (clamp(t / BB_T_MAX, 0.0, 1.0) * (BB_N - 1.0) + 0.5) / BB_N;
        let le = textureSampleLevel(bb_lut, smp_clamp, vec2<f32>(x, 0.5), 0.0).rgb * p.fire.z;
        return Shaded(vec4<f32>(le * alpha, alpha), n);
    }
    // Dust and smoke: in-scattering of the light with the phase function (ω′ towards the
    // light, ω towards the viewer), plus ambient.
    let dir = normalize(in.q);
    let mu = dot(pf.light.xyz, -dir);
    let gx = (clamp((mu + 1.0) * 0.5, 0.0, 1.0) * (PHASE_MU - 1.0) + 0.5) / PHASE_MU;
    let gy = (clamp((p.params.z + PHASE_G_MAX) / (2.0 * PHASE_G_MAX), 0.0, 1.0) * (PHASE_G - 1.0) + 0.5) / PHASE_G;
    let phase = textureSampleLevel(phase_lut, smp_clamp, vec2<f32>(gx, gy), 0.0).r;
    let inscatter = pf.light_colour.rgb * (FOUR_PI * phase) + vec3<f32>(pf.light.w);
    return Shaded(vec4<f32>(inscatter * (p.params.y * alpha), alpha), n);
}

@fragment
fn fs_main(in: VOut) -> @location(0) vec4<f32> {
    return shade(in).colour;
}

// Heat shimmer: fire particles write a noise offset (layer pixels), weighted by their
// opacity; the composite shifts what lies behind them by it.
@fragment
fn fs_shimmer(in: VOut) -> @location(0) vec4<f32> {
    let s = shade(in);
    let p = parts[in.index];
    if u32(p.params.w + 0.5) != 2u {
        return vec4<f32>(0.0);
    }
    let local = vec3<f32>(in.clip.xy * 0.013, 0.0);
    let n2 = detail_noise(p, local + vec3<f32>(0.37, 0.71, 0.0));
    let off = vec2<f32>(s.noise - 0.5, n2 - 0.5) * (2.0 * pf.clip.w * s.colour.a);
    return vec4<f32>(off, 0.0, 0.0);
}
