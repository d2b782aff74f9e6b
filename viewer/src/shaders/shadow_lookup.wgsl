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
// the filter inside its tile), 3×3 percentage-closer filtering (as 4 bilinear taps), the bias scaled to that
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
        // Nine bilinear taps one texel apart weigh the 4×4 texels around the point by
        // [1 − f, 1, 1, f] ⊗ [1 − f, 1, 1, f] / 9 (f: the point's fraction between texel
        // centres). Taken as four bilinear taps, each placed on a pair of texels where the
        // ratio of their weights puts it and weighted by the pair's sum: the same filter
        // with 4 lookups instead of 9.
        let x = uv / texel - 0.5;
        let i0 = floor(x);
        let f = x - i0;
        let wa = 2.0 - f;
        let wb = 1.0 + f;
        let pa = (i0 - 0.5 + 1.0 / wa) * texel;
        let pb = (i0 + 1.5 + f / wb) * texel;
        let s = wa.x * wa.y * textureSampleCompareLevel(shadow_map, shadow_smp, pa, depth)
            + wb.x * wa.y * textureSampleCompareLevel(shadow_map, shadow_smp, vec2<f32>(pb.x, pa.y), depth)
            + wa.x * wb.y * textureSampleCompareLevel(shadow_map, shadow_smp, vec2<f32>(pa.x, pb.y), depth)
            + wb.x * wb.y * textureSampleCompareLevel(shadow_map, shadow_smp, pb, depth);
        return s / 9.0;
    }
    return 1.0;
}
