// Layer composition (Umenhoffer et al. §4): the particle layer (premultiplied, possibly
// at a fraction of the resolution, bilinearly upsampled) over the opaque + volume image,
// which the heat-shimmer offsets (when present) distort. Also the motion-blur
// accumulation: a layer added with a constant weight.

struct Comp {
    // x: 1 = apply shimmer offsets, y: layer-pixel → uv scale x, z: … y
    flags: vec4<f32>,
}

@group(0) @binding(0) var<uniform> cu: Comp;
@group(0) @binding(1) var scene_tex: texture_2d<f32>;
@group(0) @binding(2) var layer_tex: texture_2d<f32>;
@group(0) @binding(3) var shimmer_tex: texture_2d<f32>;
@group(0) @binding(4) var smp: sampler;

// VOut and vs_full: fullscreen.wgsl, prepended.

@fragment
fn fs_composite(i: VOut) -> @location(0) vec4<f32> {
    let layer = textureSampleLevel(layer_tex, smp, i.uv, 0.0);
    var uv = i.uv;
    if cu.flags.x > 0.5 {
        uv = uv + textureSampleLevel(shimmer_tex, smp, i.uv, 0.0).xy * cu.flags.yz;
    }
    let dims = vec2<f32>(textureDimensions(scene_tex));
    let px = vec2<i32>(clamp(uv * dims, vec2<f32>(0.0), dims - 1.0));
    let scene = textureLoad(scene_tex, px, 0);
    return layer + scene * (1.0 - clamp(layer.a, 0.0, 1.0));
}

// Motion blur: one time sample's layer, added with the blend constant as its weight.
@fragment
fn fs_accumulate(i: VOut) -> @location(0) vec4<f32> {
    return textureSampleLevel(layer_tex, smp, i.uv, 0.0);
}
