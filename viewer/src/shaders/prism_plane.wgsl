// Prism/plane intersection, Volumetric Billboards §3.3.2 and Appendix A: a line-by-line
// port of core/src/prism_plane.rs (the Rust reference; see its docs for the exact
// classification that replaces the paper's jitter). Input: a prism in camera space
// (vertices 0,1,2 bottom, 3,4,5 top, k+3 above k) with uvw; the plane z = z_slice.
// Output: 0 or 3..=5 vertices, counter-clockwise seen from +z; 0 for non-finite input.

struct Cell {
    pos: array<vec4<f32>, 6>,
    uvw: array<vec4<f32>, 6>,
}

struct Poly {
    count: u32,
    pos: array<vec3<f32>, 5>,
    uvw: array<vec3<f32>, 5>,
}

fn pp_bit(mask: u32, i: u32) -> bool {
    return ((mask >> i) & 1u) != 0u;
}

// Point and uvw where the plane crosses the edge (a, b); the end point with z < z_slice
// is the "low" one. Exact duplicates are merged, at most 5 points are kept.
fn pp_push(out: ptr<function, Poly>, c: ptr<function, Cell>, above: u32, a: u32, b: u32, z: f32) {
    var lo = a;
    var hi = b;
    if pp_bit(above, a) {
        lo = b;
        hi = a;
    }
    let pa = (*c).pos[lo].xyz;
    let pb = (*c).pos[hi].xyz;
    var s = (z - pa.z) / (pb.z - pa.z);
    if s > 1.0 {
        s = 1.0;
    }
    let r = 1.0 - s;
    let p = vec3<f32>(r * pa.x + s * pb.x, r * pa.y + s * pb.y, z);
    let ta = (*c).uvw[lo].xyz;
    let tb = (*c).uvw[hi].xyz;
    let t = vec3<f32>(r * ta.x + s * tb.x, r * ta.y + s * tb.y, r * ta.z + s * tb.z);
    let n = (*out).count;
    if n == 5u {
        return;
    }
    for (var i = 0u; i < n; i++) {
        if all((*out).pos[i] == p) {
            return;
        }
    }
    (*out).pos[n] = p;
    (*out).uvw[n] = t;
    (*out).count = n + 1u;
}

fn pp_signed_area(p: ptr<function, Poly>) -> f32 {
    let n = (*p).count;
    if n < 3u {
        return 0.0;
    }
    let o = (*p).pos[0];
    var a = 0.0;
    for (var i = 1u; i + 1u < n; i++) {
        let u = (*p).pos[i];
        let v = (*p).pos[i + 1u];
        a += (u.x - o.x) * (v.y - o.y) - (u.y - o.y) * (v.x - o.x);
    }
    return a;
}

// Whether `x` is a NaN or an infinity: all exponent bits set. Tested on the bits, not
// with `x != x` comparisons, which WGSL implementations may fold away (they may assume
// finite floats).
fn pp_non_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

fn pp_non_finite3(v: vec3<f32>) -> bool {
    return pp_non_finite(v.x) || pp_non_finite(v.y) || pp_non_finite(v.z);
}

fn intersect_prism_plane(c: ptr<function, Cell>, z: f32) -> Poly {
    var out: Poly;
    out.count = 0u;
    // Non-finite input (a NaN or infinite coordinate or uvw, a NaN plane) has no section:
    // the empty polygon, never a NaN vertex (billow-core's guard). Only xyz: w carries
    // the volume index and the normal matrix.
    var bad = pp_non_finite(z);
    for (var i = 0u; i < 6u; i++) {
        bad = bad || pp_non_finite3((*c).pos[i].xyz) || pp_non_finite3((*c).uvw[i].xyz);
    }
    if bad {
        return out;
    }
    var above = 0u;
    for (var i = 0u; i < 6u; i++) {
        if (*c).pos[i].z >= z {
            above |= 1u << i;
        }
    }
    let n_above = countOneBits(above);
    if n_above == 0u || n_above == 6u {
        return out;
    }
    var bottom_side = false;
    var found = false;
    for (var k = 0u; k < 3u; k++) {
        if pp_bit(above, k) != pp_bit(above, k + 3u) {
            bottom_side = pp_bit(above, k + 3u);
            found = true;
            break;
        }
    }
    if !found {
        var sum = 0.0;
        for (var k = 0u; k < 3u; k++) {
            sum += (*c).pos[k + 3u].z - (*c).pos[k].z;
        }
        bottom_side = !(sum < 0.0);
    }
    for (var k = 0u; k < 3u; k++) {
        if pp_bit(above, k) != pp_bit(above, k + 3u) {
            pp_push(&out, c, above, k, k + 3u, z);
            continue;
        }
        let side = pp_bit(above, k);
        for (var jj = 0u; jj < 2u; jj++) {
            // Left neighbour first, then right (k_L = k+2, k_R = k+1, mod 3).
            let j = select((k + 1u) % 3u, (k + 2u) % 3u, jj == 0u);
            let bottom = pp_bit(above, j) != side;
            let top = pp_bit(above, j + 3u) != side;
            if bottom && !top {
                pp_push(&out, c, above, k, j, z);
            } else if !bottom && top {
                pp_push(&out, c, above, k + 3u, j + 3u, z);
            } else if bottom && top {
                if side == bottom_side {
                    pp_push(&out, c, above, k, j, z);
                } else {
                    pp_push(&out, c, above, k + 3u, j + 3u, z);
                }
            }
        }
    }
    if out.count < 3u {
        out.count = 0u;
        return out;
    }
    if pp_signed_area(&out) < 0.0 {
        let n = out.count;
        for (var i = 0u; i < n / 2u; i++) {
            let j = n - 1u - i;
            let tp = out.pos[i];
            out.pos[i] = out.pos[j];
            out.pos[j] = tp;
            let tt = out.uvw[i];
            out.uvw[i] = out.uvw[j];
            out.uvw[j] = tt;
        }
    }
    return out;
}
