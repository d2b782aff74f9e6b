// Shadow-map lookup shared by the passes that receive shadows (meshes, volume slices,
// billboard clouds). Group 2: the light's depth map and a comparison sampler; without
// shadows a 1×1 map is bound and callers skip the lookup.

@group(2) @binding(0) var shadow_map: texture_depth_2d;
@group(2) @binding(1) var shadow_smp: sampler_comparison;

// Fraction of the light reaching a point given in the shadow map's clip space
// (orthographic: w = 1): 3×3 percentage-closer filtering; 1 outside the map.
fn shadow_visibility(clip: vec4<f32>, bias: f32) -> f32 {
    let ndc = clip.xyz / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || ndc.z > 1.0 || ndc.z < 0.0 {
        return 1.0;
    }
    let texel = 1.0 / vec2<f32>(textureDimensions(shadow_map));
    var s = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let o = vec2<f32>(f32(dx), f32(dy)) * texel;
            s += textureSampleCompareLevel(shadow_map, shadow_smp, uv + o, ndc.z - bias);
        }
    }
    return s / 9.0;
}
