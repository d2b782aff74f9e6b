// The check of volume_math.wgsl's functions (and volume_loads.wgsl's to_extinction)
// against billow-core (viewer/tests/volume_math_gpu.rs): prepended with volume_math.wgsl
// and volume_loads.wgsl, followed by compute_check.wgsl's entry point.

struct Case {
    // slice_lod(x, y, z); w: the ratio of slab_sample and to_extinction
    lod: vec4<f32>,
    // depth_fade(x, y, z)
    fade: vec4<f32>,
    // slab_sample's filtered extinction-space sample
    e: vec4<f32>,
    // to_extinction's premultiplied texel
    c: vec4<f32>,
    // band_holds(xy, z)
    band: vec4<f32>,
}

struct Out {
    // x: slice_lod, y: depth_fade, z: MAX_OPTICAL_DEPTH, w: OPAQUE_OPTICAL_DEPTH
    scalars: vec4<f32>,
    slab: vec4<f32>,
    extinction: vec4<f32>,
    // x: band_holds (1 or 0)
    band: vec4<f32>,
}

fn check(k: Case) -> Out {
    var o: Out;
    o.scalars = vec4<f32>(
        slice_lod(k.lod.x, k.lod.y, k.lod.z),
        depth_fade(k.fade.x, k.fade.y, k.fade.z),
        MAX_OPTICAL_DEPTH,
        OPAQUE_OPTICAL_DEPTH,
    );
    o.slab = slab_sample(k.e, k.lod.w);
    o.extinction = to_extinction(k.c, k.lod.w);
    o.band = vec4<f32>(select(0.0, 1.0, band_holds(k.band.xy, k.band.z)), 0.0, 0.0, 0.0);
    return o;
}
