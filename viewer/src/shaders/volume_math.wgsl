// The volume pass's pure functions, prepended to volume.wgsl (and volume_loads.wgsl) by
// volume_pass/mod.rs and to volume_math_check.wgsl by volume_math_gpu.rs, which runs them in
// a compute pass for viewer/tests/volume_math_gpu.rs: each is the WGSL copy of a
// billow-core function (shaders cannot call Rust), tested against it there.

// The MIP level λ a slice of spacing d samples (SPEC §8.6):
// billow_core::slicing::slice_lod.
fn slice_lod(d: f32, v0: f32, max_lod: f32) -> f32 {
    return clamp(log2(d / v0), 0.0, max_lod);
}

// Whether a slice of LOD lambda draws the band whose slice-LOD range is
// [range.x, range.y) (billow_core::slicing::band_lod_range, SPEC §8.6):
// billow_core::slicing::band_holds.
fn band_holds(range: vec2<f32>, lambda: f32) -> bool {
    return lambda >= range.x && lambda < range.y;
}

// ln(1 + x) and exp(x) − 1 with full relative precision for small |x| (WGSL has neither).
fn log1p_(x: f32) -> f32 {
    let u = 1.0 + x;
    if u == 1.0 {
        return x;
    }
    return log(u) * x / (u - 1.0);
}

fn expm1_(x: f32) -> f32 {
    let u = exp(x);
    if u == 1.0 {
        return x;
    }
    let um = u - 1.0;
    if um == -1.0 {
        return -1.0;
    }
    return um * x / log(u);
}

// Extinction-space filtering (billow_core::extinction, src/eval/volume_sampler.rs): a
// texel is (σ·c, σ), σ = −ln(1 − α) capped at ln 510, c its straight colour, its optical
// depth divided by the texel's size in level-0 voxels (a density; opaque texels hold
// ln 510 at every level), filtered trilinearly within a level and linearly between
// levels, and turned back into premultiplied RGBA for the slab the slice stands for
// (slab_sample). `sample_volume` (volume_pass/mod.rs) returns the filtered sample: the
// texture unit's trilinear sample of a texture stored in extinction space (Rgba16Float),
// or for BC7 block textures eight converted loads per level (volume_loads.wgsl).
// Filtering α instead gives a one-voxel opaque layer an optical depth of only 2: thin
// layers turn see-through.
// billow_core::extinction::MAX_OPTICAL_DEPTH.
const MAX_OPTICAL_DEPTH: f32 = 6.234411;
// σ at or above this is opaque (α = 1): billow_core::extinction::OPAQUE_F16_OPTICAL_DEPTH,
// the CPU's MAX_OPTICAL_DEPTH − 1e-4 lowered by one f16 step (2^-8 at 6.2) so that a
// footprint of opaque texels stored as f16 (6.234375) and filtered with the hardware's
// weights still gives α = 1.
const OPAQUE_OPTICAL_DEPTH: f32 = 6.2304;

// The filtered density e over a slab `ratio` level-0 voxels thick: α = 1 − e^(−σ·ratio),
// colour (σ·c)/σ · α; opaque (α = 1) where every texel under the filter is
// (billow_core::extinction::slab_from_extinction of e · ratio, opaque at
// OPAQUE_OPTICAL_DEPTH · ratio).
fn slab_sample(e: vec4<f32>, ratio: f32) -> vec4<f32> {
    let s = e.a;
    if !(s > 0.0) || !(ratio > 0.0) {
        return vec4<f32>(0.0);
    }
    var a = 1.0;
    if s < OPAQUE_OPTICAL_DEPTH {
        a = -expm1_(-s * ratio);
    }
    return vec4<f32>(e.rgb * (a / s), a);
}

// The part of the slice's slab, from view distance slab0 and `thickness` deep, in front
// of the surface at distance z (3e38: none): billow_core::slicing::slab_fade.
fn depth_fade(z: f32, slab0: f32, thickness: f32) -> f32 {
    if z >= 3.0e38 {
        return 1.0;
    }
    if !(thickness > 0.0) {
        return select(0.0, 1.0, slab0 < z);
    }
    return clamp((z - slab0) / thickness, 0.0, 1.0);
}
