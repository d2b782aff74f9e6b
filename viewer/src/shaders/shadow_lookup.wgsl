// Shadow-map lookup shared by the passes that receive shadows (meshes, volume slices,
// billboard clouds). Group 2: the light's depth atlas (one tile per cascade), a
// comparison sampler and the cascades (shadow.rs, CascadeUniform); without shadows a 1×1
// map is bound and callers skip the lookup.

struct ShadowCascades {
    // Per cascade, finest first: base NDC → the cascade's NDC (xy scale, zw offset).
    map: array<vec4<f32>, 4>,
    // Per cascade: its tile in the atlas (uv origin xy, uv size zw).
    tile: array<vec4<f32>, 4>,
    // x: cascades in use.
    info: vec4<f32>,
}

@group(2) @binding(0) var shadow_map: texture_depth_2d;
@group(2) @binding(1) var shadow_smp: sampler_comparison;
@group(2) @binding(2) var<uniform> shadow_cascades: ShadowCascades;

// Fraction of the light reaching a point given in the base shadow camera's clip space
// (orthographic: w = 1): the finest cascade whose window holds the point (with room for
// the filter inside its tile), 3×3 percentage-closer filtering, the bias scaled to that
// cascade's texel; 1 outside every cascade.
fn shadow_visibility(clip: vec4<f32>, bias: f32) -> f32 {
    let ndc = clip.xyz / clip.w;
    if ndc.z > 1.0 || ndc.z < 0.0 {
        return 1.0;
    }
    let texel = 1.0 / vec2<f32>(textureDimensions(shadow_map));
    let n = u32(shadow_cascades.info.x);
    for (var k = 0u; k < n; k++) {
        let m = shadow_cascades.map[k];
        let t = shadow_cascades.tile[k];
        let c = ndc.xy * m.xy + m.zw;
        // 1.5 texels of the tile, in its NDC (2 units across).
        let margin = 3.0 * texel / t.zw;
        if any(abs(c) > vec2<f32>(1.0) - margin) {
            continue;
        }
        let uv = t.xy + vec2<f32>(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * t.zw;
        let depth = ndc.z - bias / m.x;
        var s = 0.0;
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let o = vec2<f32>(f32(dx), f32(dy)) * texel;
                s += textureSampleCompareLevel(shadow_map, shadow_smp, uv + o, depth);
            }
        }
        return s / 9.0;
    }
    return 1.0;
}
