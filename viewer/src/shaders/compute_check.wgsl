// The entry point of every WGSL-against-core check (compute_check.rs appends it to the
// check's sources): one invocation per case, in workgroups of 64. The check shader before
// it declares the structs Case (one set of arguments) and Out (what it computed) and
// fn check(k: Case) -> Out.

@group(0) @binding(0) var<storage, read> cases: array<Case>;
@group(0) @binding(1) var<storage, read_write> results: array<Out>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= arrayLength(&cases) {
        return;
    }
    results[i] = check(cases[i]);
}
