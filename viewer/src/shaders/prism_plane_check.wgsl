// Compute entry point that runs intersect_prism_plane on a list of cases, for the test
// against the Rust reference. Prepended with prism_plane.wgsl.

struct Case {
    cell: Cell,
    z: vec4<f32>,
}

struct OutPoly {
    count: vec4<u32>,
    pos: array<vec4<f32>, 5>,
    uvw: array<vec4<f32>, 5>,
}

@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> results: array<OutPoly>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&cases) {
        return;
    }
    var c = cases[i].cell;
    var p = intersect_prism_plane(&c, cases[i].z.x);
    var o: OutPoly;
    o.count = vec4<u32>(p.count, 0u, 0u, 0u);
    for (var k = 0u; k < 5u; k++) {
        o.pos[k] = vec4<f32>(p.pos[k], 0.0);
        o.uvw[k] = vec4<f32>(p.uvw[k], 0.0);
    }
    results[i] = o;
}
