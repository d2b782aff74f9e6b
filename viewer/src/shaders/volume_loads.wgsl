// The filter by loads of the volume pass (prepended by volume_pass/mod.rs only when some
// texture is BC7 blocks of premultiplied texels, flag 4): eight texel loads per level,
// each taken to extinction space, weighted with the CPU's texel addressing
// (src/eval/volume_sampler.rs, sample_level_extinction), linear between levels; each
// level's optical depth divided by its texels' size in level-0 voxels, opaque texels at
// ln 510 (volume_pass/textures.rs, extinction_levels, does the same on upload).
// MAX_OPTICAL_DEPTH and log1p_ come from volume_math.wgsl. to_extinction is
// billow_core::extinction::to_density (viewer/tests/volume_math_gpu.rs).

fn to_extinction(c: vec4<f32>, ratio: f32) -> vec4<f32> {
    let a = min(c.a, 1.0);
    if !(a > 0.0) {
        return vec4<f32>(0.0);
    }
    var s = MAX_OPTICAL_DEPTH;
    if a < 1.0 {
        let own = -log1p_(-a);
        if own < MAX_OPTICAL_DEPTH {
            s = own / ratio;
        }
    }
    return vec4<f32>(c.rgb * (s / a), s);
}

struct TexelPair {
    i0: i32,
    i1: i32,
    t: f32,
}

// Texels and weight of a linear filter along an axis of n texels (centres at (i + ½)/n);
// repeat wraps each index, clamp-to-edge clamps.
fn texel_pair(u_in: f32, n: i32, rep: bool) -> TexelPair {
    var u = u_in;
    if rep {
        u = u - floor(u);
    }
    let x = u * f32(n) - 0.5;
    let x0 = floor(x);
    var p: TexelPair;
    p.t = x - x0;
    let i = i32(x0);
    if rep {
        p.i0 = ((i % n) + n) % n;
        p.i1 = (((i + 1) % n) + n) % n;
    } else {
        p.i0 = clamp(i, 0, n - 1);
        p.i1 = clamp(i + 1, 0, n - 1);
    }
    return p;
}

fn extinction_level(t: texture_3d<f32>, rep: bool, uvw: vec3<f32>, level: i32) -> vec4<f32> {
    let n = vec3<i32>(textureDimensions(t, level));
    // The texels' size in level-0 texels (billow_core::slicing::level_size_ratio).
    let n0 = vec3<f32>(textureDimensions(t, 0));
    let r = exp2(log2(n0.x * n0.y * n0.z / (f32(n.x) * f32(n.y) * f32(n.z))) / 3.0);
    let px = texel_pair(uvw.x, n.x, rep);
    let py = texel_pair(uvw.y, n.y, false);
    let pz = texel_pair(uvw.z, n.z, rep);
    let e000 = to_extinction(textureLoad(t, vec3<i32>(px.i0, py.i0, pz.i0), level), r);
    let e100 = to_extinction(textureLoad(t, vec3<i32>(px.i1, py.i0, pz.i0), level), r);
    let e010 = to_extinction(textureLoad(t, vec3<i32>(px.i0, py.i1, pz.i0), level), r);
    let e110 = to_extinction(textureLoad(t, vec3<i32>(px.i1, py.i1, pz.i0), level), r);
    let e001 = to_extinction(textureLoad(t, vec3<i32>(px.i0, py.i0, pz.i1), level), r);
    let e101 = to_extinction(textureLoad(t, vec3<i32>(px.i1, py.i0, pz.i1), level), r);
    let e011 = to_extinction(textureLoad(t, vec3<i32>(px.i0, py.i1, pz.i1), level), r);
    let e111 = to_extinction(textureLoad(t, vec3<i32>(px.i1, py.i1, pz.i1), level), r);
    let c00 = e000 + (e100 - e000) * px.t;
    let c10 = e010 + (e110 - e010) * px.t;
    let c01 = e001 + (e101 - e001) * px.t;
    let c11 = e011 + (e111 - e011) * px.t;
    let c0 = c00 + (c10 - c00) * py.t;
    let c1 = c01 + (c11 - c01) * py.t;
    return c0 + (c1 - c0) * pz.t;
}

// Extinction-space sample at fractional level lod (already clamped to the texture's).
fn sample_extinction(t: texture_3d<f32>, rep: bool, uvw: vec3<f32>, lod: f32) -> vec4<f32> {
    let l0 = floor(lod);
    let f = lod - l0;
    let a = extinction_level(t, rep, uvw, i32(l0));
    if f <= 0.0 {
        return a;
    }
    let b = extinction_level(t, rep, uvw, i32(l0) + 1);
    return a + (b - a) * f;
}

