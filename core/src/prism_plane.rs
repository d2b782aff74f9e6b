//! Prism/plane intersection, Volumetric Billboards (Decaudin & Neyret 2009) §3.3.2 and
//! Appendix A — the CPU reference a WGSL port is tested against. Pure, allocation-free,
//! self-contained (plain `[f32; 3]` arrays, no other module used).
//!
//! Input: the six vertices of a prism cell already in **camera space** (vertices 0,1,2
//! bottom, 3,4,5 top, `k+3` above `k`) with their 3D texture coordinates, and the slicing
//! plane `z = z_slice`. Output: the section polygon, 0 or 3..=5 vertices with
//! interpolated uvw, **counter-clockwise seen from +z** (from the camera's side).
//!
//! # The algorithm (Appendix A, with exact classification instead of jitter)
//!
//! The paper computes `s_k = (z_slice − z_k)/(z_{k+3} − z_k)` for the three vertical
//! lines, rejects the prism if all `s_k < 0` or all `> 1`, and then, for k = 0, 1, 2:
//! if `s_k ∈ [0,1]` emits the point on the vertical edge (k, k+3); if `s_k < 0` emits
//! the points on the bottom edges (k, k_L), (k, k_R) whose other line has `s ≥ 0`; if
//! `s_k > 1` the top edges (k+3, k_L+3), (k+3, k_R+3) whose other line has `s ≤ 1`.
//! It jitters the plane normal so that `z_{k+3} = z_k` never divides by zero.
//!
//! Jitter only makes the division *unlikely* to be by zero; it does not make the case
//! analysis consistent. A plane exactly through a vertex gives `s = 0` on one line and
//! `s = 1` on another (the same point emitted twice, or by the `[0,1]` inclusive tests
//! both on a vertical and on a cap edge), an edge lying in the plane emits both of its
//! end points twice, and a near-zero denominator produces huge `s` whose sign is noise.
//! Here instead:
//!
//! 1. **Every vertex is classified exactly once** by an exact comparison,
//!    `above_k = z_k ≥ z_slice`. This is symbolic perturbation: the plane is treated as
//!    lying infinitesimally *below* `z_slice`, so no vertex is ever *on* it. An edge
//!    crosses the plane iff its two end points are classified differently — each
//!    crossing is found exactly once, and shared edges of neighbouring prisms agree.
//! 2. **The case analysis of Appendix A is expressed with those classes**:
//!    `s_k ∈ [0,1]` ⇔ the vertical edge crosses; otherwise the line is entirely on one
//!    side and "`s_k < 0`" (emit bottom edges) vs "`s_k > 1`" (emit top edges) is decided
//!    without dividing: a cap edge (k, j) is emitted by line k when line j crosses
//!    (exactly one of the bottom/top edges then crosses, and that one is emitted) or,
//!    when both bottom and top edges between k and j cross, the bottom one by the line
//!    on the "bottom side" and the top one by the other line. The bottom side is taken
//!    from the orientation of a crossing vertical edge (the side its top vertex lies on,
//!    which is what `s_k < 0` means for prisms whose vertical edges point the same way),
//!    or, when no vertical edge crosses, from the sign of `Σ (z_{k+3} − z_k)` (ties:
//!    "above"; either choice is correct there). For every prism whose side faces are not
//!    twisted (see below) this emits each crossing edge exactly once, in polygon order —
//!    including vertical edges with `z_{k+3} = z_k`, mixed slope signs of splayed shell
//!    prisms, and inverted prisms.
//! 3. **Divisions only on crossing edges**, from the below end `a` to the above end `b`:
//!    `s = (z_slice − z_a)/(z_b − z_a)` with `z_a < z_slice ≤ z_b`, so the denominator is
//!    strictly positive and, rounding being monotone, `s ∈ (0, 1]` exactly. The point is
//!    `(1−s)·a + s·b` (exactly `b` when `s = 1`) with z set to `z_slice`. The computation
//!    depends only on the two end points, so the edge shared by two prisms gives
//!    bit-identical points in both (no cracks, no double coverage downstream).
//! 4. **No double-counted points**: when the plane passes exactly through a vertex `v`
//!    (classified above), every crossing edge at `v` yields exactly `v`; such exact
//!    duplicates are merged. Fewer than 3 distinct points (the plane touches a vertex or
//!    an edge only) give an empty polygon. A face lying exactly in the plane is emitted
//!    by the prism on its *below* side only — half-open, like a rasterizer's fill rule —
//!    so two stacked prisms never both draw it.
//! 5. **Consistent winding**: the signed area in xy decides whether to reverse the order,
//!    so inverted prisms (top below bottom, mirrored) also come out counter-clockwise.
//!
//! Limits: a generalized prism whose side face is *twisted* (non-planar, its 4 corners
//! alternately above and below the plane) has no convex section; there the emitted
//! points (still at most 5, each on a distinct crossing edge, inside the prism's hull)
//! may not be in convex order. Prisms with planar side faces never hit this.

// `!(a < b)` comparisons are deliberate: they also catch NaN. Non-finite input gives the
// empty polygon (checked first).
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// Section polygon: `count` is 0 or 3..=5; entries beyond `count` are zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlicePolygon {
    pub count: usize,
    /// Camera-space positions; `z` is exactly `z_slice`.
    pub pos: [[f32; 3]; 5],
    pub uvw: [[f32; 3]; 5],
}

impl SlicePolygon {
    pub const EMPTY: SlicePolygon = SlicePolygon {
        count: 0,
        pos: [[0.0; 3]; 5],
        uvw: [[0.0; 3]; 5],
    };

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// Intersects the prism (`pos`, `uvw` in camera space, vertex numbering as above) with
/// the plane `z = z_slice`. See the module docs for the guarantees.
pub fn intersect_prism_plane(
    pos: &[[f32; 3]; 6],
    uvw: &[[f32; 3]; 6],
    z_slice: f32,
) -> SlicePolygon {
    // Non-finite input (a NaN or infinite coordinate, a NaN plane) has no section: the
    // defined result is the empty polygon, never a NaN vertex.
    let finite = |v: &[f32; 3]| v.iter().all(|c| c.is_finite());
    if !(z_slice.is_finite() && pos.iter().all(finite) && uvw.iter().all(finite)) {
        return SlicePolygon::EMPTY;
    }
    let mut above = [false; 6];
    for i in 0..6 {
        above[i] = pos[i][2] >= z_slice;
    }
    let n_above = above.iter().filter(|&&a| a).count();
    // Trivial rejection (all s_k < 0 or all s_k > 1). NaN z counts as below.
    if n_above == 0 || n_above == 6 {
        return SlicePolygon::EMPTY;
    }
    let crosses = |k: usize| above[k] != above[k + 3];
    // Side whose non-crossing vertical lines emit their *bottom* cap edges.
    let bottom_side = match (0..3).find(|&k| crosses(k)) {
        Some(k) => above[k + 3],
        None => {
            let sum: f32 = (0..3).map(|k| pos[k + 3][2] - pos[k][2]).sum();
            !(sum < 0.0)
        }
    };

    let mut out = SlicePolygon::EMPTY;
    let mut push = |a: usize, b: usize| {
        let (lo, hi) = if above[a] { (b, a) } else { (a, b) };
        let (p, t) = edge_point(&pos[lo], &pos[hi], &uvw[lo], &uvw[hi], z_slice);
        // Merge exact duplicates (plane through a vertex).
        if (0..out.count).any(|i| out.pos[i] == p) || out.count == 5 {
            return;
        }
        out.pos[out.count] = p;
        out.uvw[out.count] = t;
        out.count += 1;
    };
    for k in 0..3 {
        let k_r = (k + 1) % 3;
        let k_l = (k + 2) % 3;
        if crosses(k) {
            push(k, k + 3);
            continue;
        }
        let side = above[k];
        for j in [k_l, k_r] {
            let bottom = above[j] != side;
            let top = above[j + 3] != side;
            match (bottom, top) {
                (true, false) => push(k, j),
                (false, true) => push(k + 3, j + 3),
                (true, true) => {
                    if side == bottom_side {
                        push(k, j)
                    } else {
                        push(k + 3, j + 3)
                    }
                }
                (false, false) => {}
            }
        }
    }
    if out.count < 3 {
        return SlicePolygon::EMPTY;
    }
    if signed_area_xy(&out) < 0.0 {
        out.pos[..out.count].reverse();
        out.uvw[..out.count].reverse();
    }
    out
}

/// Point and uvw where the plane crosses the edge from `a` (below, `z_a < z`) to `b`
/// (above, `z_b ≥ z`).
#[inline]
fn edge_point(
    a: &[f32; 3],
    b: &[f32; 3],
    ta: &[f32; 3],
    tb: &[f32; 3],
    z: f32,
) -> ([f32; 3], [f32; 3]) {
    let s = (z - a[2]) / (b[2] - a[2]);
    let s = if s > 1.0 { 1.0 } else { s }; // unreachable for finite input; NaN passes through
    let r = 1.0 - s;
    let lerp = |x: f32, y: f32| r * x + s * y;
    (
        [lerp(a[0], b[0]), lerp(a[1], b[1]), z],
        [lerp(ta[0], tb[0]), lerp(ta[1], tb[1]), lerp(ta[2], tb[2])],
    )
}

/// Twice the signed area of the polygon projected on xy (positive = counter-clockwise
/// seen from +z), relative to the first vertex to limit cancellation.
pub fn signed_area_xy(p: &SlicePolygon) -> f32 {
    if p.count < 3 {
        return 0.0;
    }
    let o = p.pos[0];
    let mut a = 0.0;
    for i in 1..p.count - 1 {
        let (u, v) = (p.pos[i], p.pos[i + 1]);
        a += (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0]);
    }
    a
}
