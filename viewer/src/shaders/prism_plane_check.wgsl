// The check of prism_plane.wgsl's intersect_prism_plane against the Rust reference
// (viewer/tests/prism_plane_gpu.rs): prepended with prism_plane.wgsl, followed by
// compute_check.wgsl's entry point.

struct Case {
    cell: Cell,
    z: vec4<f32>,
}

struct Out {
    count: vec4<u32>,
    pos: array<vec4<f32>, 5>,
    uvw: array<vec4<f32>, 5>,
}

fn check(k: Case) -> Out {
    var c = k.cell;
    var p = intersect_prism_plane(&c, k.z.x);
    var o: Out;
    o.count = vec4<u32>(p.count, 0u, 0u, 0u);
    for (var j = 0u; j < 5u; j++) {
        o.pos[j] = vec4<f32>(p.pos[j], 0.0);
        o.uvw[j] = vec4<f32>(p.uvw[j], 0.0);
    }
    return o;
}
