//! Stability suite for the prism/plane intersection (VB Appendix A).
//!
//! Every result is checked against an f64 reference computed from the same f32 inputs:
//! - `count` ∈ {0, 3, 4, 5}; vertices pairwise distinct; z exactly `z_slice`;
//! - each vertex lies on a prism edge that the plane crosses, at the f64 parameter
//!   `s = (z − z_a)/(z_b − z_a)`, and its uvw is the same interpolation, both within
//!   `TOL_REL` × the coordinate scale (so inside the prism's hull);
//! - convex and counter-clockwise seen from +z (turns ≥ −`TOL_REL`·scale²);
//! - its area equals the area of the convex hull of *all* f64 crossing points (no point
//!   lost), within `TOL_REL`·scale².

use billow::test_support::box_positions_z as boxed;
use billow_core::prism_plane::{intersect_prism_plane, SlicePolygon};
use proptest::prelude::*;

/// Relative tolerance (f32 has 6e-8; a lerp costs a few ulps).
const TOL_REL: f64 = 2e-6;

type P6 = [[f32; 3]; 6];

fn edges() -> [(usize, usize); 9] {
    [
        (0, 3),
        (1, 4),
        (2, 5),
        (0, 1),
        (1, 2),
        (2, 0),
        (3, 4),
        (4, 5),
        (5, 3),
    ]
}

fn scale_of(pos: &P6) -> f64 {
    pos.iter()
        .flatten()
        .map(|v| f64::from(v.abs()))
        .fold(1e-30, f64::max)
}

/// f64 crossing points (x, y) of all crossing edges, with the same exact classification.
fn crossings(pos: &P6, z: f32) -> Vec<(f64, f64, [f64; 3], usize)> {
    let mut out = Vec::new();
    for (ei, (a, b)) in edges().into_iter().enumerate() {
        let (ua, ub) = (pos[a][2] >= z, pos[b][2] >= z);
        if ua == ub {
            continue;
        }
        let (lo, hi) = if ua { (b, a) } else { (a, b) };
        let (za, zb) = (f64::from(pos[lo][2]), f64::from(pos[hi][2]));
        let s = (f64::from(z) - za) / (zb - za);
        let l = |p: f32, q: f32| f64::from(p) * (1.0 - s) + f64::from(q) * s;
        out.push((
            l(pos[lo][0], pos[hi][0]),
            l(pos[lo][1], pos[hi][1]),
            [s, lo as f64, hi as f64],
            ei,
        ));
    }
    out
}

fn hull_area(mut pts: Vec<(f64, f64)>) -> f64 {
    pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
    pts.dedup();
    if pts.len() < 3 {
        return 0.0;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut h: Vec<(f64, f64)> = Vec::new();
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in it {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    poly_area(&h)
}

fn poly_area(p: &[(f64, f64)]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| p[i].0 * p[(i + 1) % n].1 - p[(i + 1) % n].0 * p[i].1)
        .sum::<f64>()
        * 0.5
}

fn uvw_of(pos: &P6) -> P6 {
    // A distinct, non-degenerate uvw per vertex (the fixture's box mapping, skewed).
    let mut t = [[0.0; 3]; 6];
    for (k, v) in t.iter_mut().enumerate() {
        *v = [
            (k % 3) as f32 * 0.4 + 0.1,
            ((k * 7) % 5) as f32 * 0.2,
            if k >= 3 { 1.0 } else { 0.0 },
        ];
    }
    let _ = pos;
    t
}

/// Checks every invariant; returns the polygon.
fn check(pos: &P6, z: f32) -> SlicePolygon {
    check_with(pos, z, true)
}

/// Checks the invariants that hold for any prism; with `planar_sides` also convexity,
/// winding and area (a prism with a twisted side face has no convex section, see the
/// module docs of `prism_plane`).
fn check_with(pos: &P6, z: f32, planar_sides: bool) -> SlicePolygon {
    let uvw = uvw_of(pos);
    let poly = intersect_prism_plane(pos, &uvw, z);
    let n = poly.count;
    assert!(n == 0 || (3..=5).contains(&n), "count {n}");
    let scale = scale_of(pos);
    let tol = TOL_REL * scale;
    let cr = crossings(pos, z);
    for i in 0..n {
        let p = poly.pos[i];
        assert!(p.iter().all(|c| c.is_finite()) && poly.uvw[i].iter().all(|c| c.is_finite()));
        assert_eq!(p[2], z, "vertex {i} off the plane");
        for j in 0..i {
            assert_ne!(poly.pos[j], p, "duplicate vertex");
        }
        // On some crossing edge, with consistent uvw.
        let found = cr.iter().any(|&(x, y, [s, lo, hi], _)| {
            let (lo, hi) = (lo as usize, hi as usize);
            let uv_ok = (0..3).all(|c| {
                let e = f64::from(uvw[lo][c]) * (1.0 - s) + f64::from(uvw[hi][c]) * s;
                (e - f64::from(poly.uvw[i][c])).abs() <= 1e-5
            });
            (x - f64::from(p[0])).abs() <= tol && (y - f64::from(p[1])).abs() <= tol && uv_ok
        });
        assert!(
            found,
            "vertex {i} {p:?} not on a crossing edge (uvw {:?}); crossings {cr:?}",
            poly.uvw[i]
        );
    }
    // Each vertex on a distinct crossing edge: no crossing is used twice.
    assert!(n <= cr.len(), "{n} vertices from {} crossings", cr.len());
    if !planar_sides {
        return poly;
    }
    let pts: Vec<(f64, f64)> = (0..n)
        .map(|i| (f64::from(poly.pos[i][0]), f64::from(poly.pos[i][1])))
        .collect();
    if n >= 3 {
        let area = poly_area(&pts);
        assert!(area >= -tol * scale, "clockwise: area {area}");
        for i in 0..n {
            let (a, b, c) = (pts[i], pts[(i + 1) % n], pts[(i + 2) % n]);
            let turn = (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
            assert!(turn >= -4.0 * tol * scale, "not convex at {i}: {turn}");
        }
    }
    let ref_area = hull_area(cr.iter().map(|c| (c.0, c.1)).collect());
    let area = if n >= 3 { poly_area(&pts) } else { 0.0 };
    assert!(
        (area - ref_area).abs() <= 8.0 * tol * scale,
        "area {area} vs hull {ref_area}"
    );
    poly
}

/// Re-orders coordinates so the prism's vertical edges point along `axis` (0 = x, ...).
fn permute(p: &P6, perm: [usize; 3]) -> P6 {
    p.map(|v| [v[perm[0]], v[perm[1]], v[perm[2]]])
}

#[test]
fn box_along_view_axis() {
    let [p0, p1] = boxed([0.0, 0.0, 0.0], [1.5, 1.0, 0.5]);
    // Plane exactly on the bottom face: every vertex is "above": empty (half-open).
    assert_eq!(check(&p0, 0.0).count, 0);
    // On the top face: the top triangle, drawn once.
    let top = check(&p0, 0.5);
    assert_eq!(top.count, 3);
    assert!(top.uvw[..3].iter().all(|t| t[2] == 1.0));
    // In between: triangles; the two halves tile the rectangle.
    let (a, b) = (check(&p0, 0.25), check(&p1, 0.25));
    assert_eq!((a.count, b.count), (3, 3));
    // Shared diagonal: bit-identical end points in both prisms.
    for q in &a.pos[..3] {
        if q[0] != 0.0 || q[1] != 0.0 {
            continue;
        }
        assert!(b.pos[..3].contains(q));
    }
    assert_eq!(check(&p0, -1.0).count, 0);
    assert_eq!(check(&p0, 1.0).count, 0);
}

#[test]
fn vertical_edges_parallel_to_plane() {
    // Vertical edges along y: z_{k+3} == z_k on every line (the paper's division by zero).
    for prism in boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) {
        let p = permute(&prism, [0, 2, 1]);
        for z in [0.0, 0.25, 0.5, 0.999, 1.0] {
            check(&p, z);
        }
        let q = check(&p, 0.5);
        assert!(q.count == 4 || q.count == 0, "{}", q.count);
    }
    // Through the edge lying in the plane (z = 0 contains 0-3 and, for prism 0, 1-4).
    let p = permute(&boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])[0], [0, 2, 1]);
    check(&p, 0.0);
    check(&p, 1.0);
}

#[test]
fn plane_through_vertices_and_diagonals() {
    // Tilted cube: the plane passes exactly through vertices with various combinations.
    let prisms = boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
    let tilt = |p: &P6| p.map(|v| [v[0], v[1], v[0] + v[1] + v[2]]);
    for prism in &prisms {
        let t = tilt(prism);
        for z in [0.0, 1.0, 2.0, 3.0, 0.5, 1.5, 2.5] {
            check(&t, z);
        }
    }
    // z = x + y: plane x + y = 1 contains the diagonal face 0-2-5-3 of both prisms.
    for prism in &prisms {
        let t = prism.map(|v| [v[0], v[2], v[0] + v[1]]);
        for z in [0.0, 1.0, 2.0] {
            check(&t, z);
        }
    }
}

#[test]
fn degenerate_prisms() {
    let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.3], [0.0, 1.0, 0.7]];
    // Zero height: top == bottom.
    let flat: P6 = [tri[0], tri[1], tri[2], tri[0], tri[1], tri[2]];
    for z in [0.0, 0.1, 0.3, 0.5, 0.7] {
        check(&flat, z);
    }
    // Collinear bottom and top (zero-area caps).
    let line: P6 = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.5],
        [2.0, 0.0, 1.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
        [2.0, 1.0, 1.0],
    ];
    for z in [0.0, 0.25, 0.5, 1.0] {
        check(&line, z);
    }
    // Everything at one point.
    let point: P6 = [[0.5, 0.5, 0.5]; 6];
    for z in [0.0, 0.5, 1.0] {
        assert_eq!(check(&point, z).count, 0);
    }
    // Inverted (top below bottom): still counter-clockwise.
    let [p0, _] = boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
    let inv: P6 = [p0[3], p0[4], p0[5], p0[0], p0[1], p0[2]];
    assert_eq!(check(&inv, 0.5).count, 3);
}

#[test]
fn huge_and_tiny_coordinates() {
    for s in [1e-6f32, 1e6] {
        for prism in boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) {
            let p = prism.map(|v| [v[0] * s, v[1] * s, (v[0] * 0.3 + v[1] * 0.6 + v[2]) * s]);
            for z in [0.0, 0.2, 0.5, 0.9, 1.0, 1.3, 1.9] {
                check(&p, z * s);
            }
        }
    }
}

/// The sweep of `neighbouring_planes_sweep`: every vertex z and its f32 neighbours.
fn sweep(p: &P6) {
    sweep_with(p, true)
}

fn sweep_with(p: &P6, planar_sides: bool) {
    for v in p {
        for z in [
            v[2],
            f32::from_bits(v[2].to_bits().wrapping_add(1)),
            f32::from_bits(v[2].to_bits().wrapping_sub(1)),
        ] {
            if z.is_finite() {
                check_with(p, z, planar_sides);
            }
        }
    }
}

/// Whether side face (k, j, j+3, k+3) is non-planar: the f64 volume of its corners.
fn twisted(p: &P6) -> bool {
    let v = |i: usize| glam::DVec3::from(p[i].map(f64::from));
    let scale = scale_of(p);
    [(0, 1), (1, 2), (2, 0)].iter().any(|&(k, j)| {
        let (a, b, c, d) = (v(k), v(j), v(j + 3), v(k + 3));
        (b - a).cross(c - a).dot(d - a).abs() > 1e-3 * scale.powi(3)
    })
}

// The two cases in tests/eval_prism_plane.proptest-regressions were recorded before
// `arb_prism` generated only prisms with planar side faces; their seeds no longer
// reproduce them, so they are kept here as the printed (shrunk) inputs. Both prisms have
// twisted side faces, outside what the intersection promises convex sections for (the
// module docs' "Limits"): every vertex must still be finite, exactly on the plane, on a
// distinct crossing edge at the f64 parameter, with its uvw; convexity is not asserted
// (the sections are measurably non-convex, turns of −2 % of scale²).

/// Regression `cc 34735a3d…` (found by `neighbouring_planes_sweep`): a 1e-6-scale
/// twisted prism swept through its vertex depths.
#[test]
fn regression_34735a3d_tiny_prism_sweep() {
    let p: P6 = [
        [3.7781822e-7, -7.1439723e-7, 0.0],
        [5.361265e-7, -5.3509524e-7, 0.0],
        [0.0, 0.0, 7.1288e-7],
        [1.2515054e-6, -1.0349689e-6, -8.8988037e-7],
        [1.5801702e-6, -6.6271895e-7, -1.8546991e-6],
        [4.6711483e-7, 4.4819535e-7, 5.9013394e-7],
    ];
    assert!(twisted(&p));
    sweep_with(&p, false);
}

/// Regression `cc a6db94de…` (found by `random_prisms_random_planes` with `pick = 3`):
/// the plane through vertex 3 of a 1e-6-scale twisted prism.
#[test]
fn regression_a6db94de_plane_through_top_vertex() {
    let p: P6 = [
        [0.0, 9.110304e-7, 4.1852257e-7],
        [0.0, 5.3650524e-7, 4.1852257e-7],
        [0.0, -2.1474582e-7, 0.0],
        [-2.635566e-7, 5.1095003e-7, 1.9531053e-7],
        [-2.635566e-7, 4.3604499e-7, 1.1160601e-7],
        [-2.635566e-7, 2.8579475e-7, 1.1160601e-7],
    ];
    assert!(twisted(&p));
    let poly = check_with(&p, p[3][2], false);
    assert!(poly.count == 0 || poly.count >= 3);
    sweep_with(&p, false);
}

fn arb_prism() -> impl Strategy<Value = (P6, f64)> {
    let v3 = || prop::array::uniform3(-1.0f32..1.0);
    (
        prop::array::uniform3(v3()),
        v3(),
        0.2f32..2.5,
        prop::sample::select(vec![1e-6f32, 1e-3, 1.0, 1e3, 1e6]),
        prop::array::uniform3(prop::sample::select(vec![0usize, 1, 2])),
    )
        .prop_map(|(mut bot, mut t, mut lambda, s, snap)| {
            // Snaps keep the side faces planar: equal z on the bottom triangle (planes
            // through two vertices at once), or a pure translation parallel to the plane
            // (every vertical edge has z_{k+3} == z_k: the paper's division by zero).
            if snap[1] == 1 {
                bot[1][2] = bot[0][2];
            }
            if snap[0] == 1 {
                t[2] = 0.0;
                lambda = 1.0;
            }
            // Top = homothety of the bottom (+ translation): planar side faces.
            let c = [0, 1, 2].map(|i| (bot[0][i] + bot[1][i] + bot[2][i]) / 3.0);
            let mut p = [[0.0f32; 3]; 6];
            for k in 0..3 {
                p[k] = bot[k];
                p[k + 3] = if lambda == 1.0 {
                    [0, 1, 2].map(|i| bot[k][i] + t[i])
                } else {
                    [0, 1, 2].map(|i| c[i] + lambda * (bot[k][i] - c[i]) + t[i])
                };
            }
            (p.map(|v| v.map(|x| x * s)), f64::from(s))
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn random_prisms_random_planes((p, _s) in arb_prism(), f in 0.0f64..1.0, pick in 0usize..8) {
        let zs: Vec<f32> = p.iter().map(|v| v[2]).collect();
        let (lo, hi) = zs.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |a, &z| (a.0.min(z), a.1.max(z)));
        let z = if pick < 6 { zs[pick] } else { (f64::from(lo) + f * (f64::from(hi) - f64::from(lo))) as f32 };
        check(&p, z);
    }

    #[test]
    fn neighbouring_planes_sweep((p, _s) in arb_prism()) {
        // Sweep the plane across every vertex z and its f32 neighbours.
        sweep(&p);
    }
}

/// Issue 25, item 5: the twisted prisms of a real shell — the furry torus's (the gallery's
/// `billow shell` of procgen's torus, here 24 × 12 segments, 0.15 thick, as in
/// fixtures/scenes/gallery/furry_torus.ron) — seen from four cameras and cut by planes at
/// every vertex depth, its f32 neighbours and between them: each section against the f64
/// crossings of the same prism (`check_with`: every vertex finite, exactly on the plane,
/// on a distinct crossing edge at the f64 parameter within 2e-6 × scale, with its uvw;
/// prisms with planar sides also convex, counter-clockwise, of the f64 hull's area).
#[test]
fn furry_torus_shell_prisms_against_f64() {
    let surface = billow::procgen::torus(1.0, 0.35, 24, 12);
    let prisms = billow::shell::shell_prisms(&surface, 0.15, glam::Vec2::new(4.0, 2.0)).unwrap();
    assert_eq!(prisms.len(), 24 * 12 * 2);
    let eyes = [
        glam::Vec3::new(2.9, 2.3, 3.2),
        glam::Vec3::new(0.0, 4.0, 0.01),
        glam::Vec3::new(-3.5, 0.2, 0.4),
        glam::Vec3::new(0.3, -0.1, 0.2), // inside the ring
    ];
    let (mut sections, mut twisted_n, mut twisted_cut) = (0usize, 0usize, 0usize);
    for eye in eyes {
        // Right-handed look-at (camera looks down −z).
        let f = (-eye).normalize();
        let r = f.cross(glam::Vec3::Y).normalize();
        let u = r.cross(f);
        let view = glam::Mat4::from_cols(
            glam::Vec4::new(r.x, u.x, -f.x, 0.0),
            glam::Vec4::new(r.y, u.y, -f.y, 0.0),
            glam::Vec4::new(r.z, u.z, -f.z, 0.0),
            glam::Vec4::new(-r.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        );
        for pr in &prisms {
            let p: P6 = pr
                .pos
                .map(|v| view.transform_point3(glam::Vec3::from(v)).to_array());
            // Twisted: any side face whose corners are not coplanar beyond f32 rounding,
            // relative to the prism's own size (not the camera-space coordinates').
            let w = |i: usize| glam::DVec3::from(pr.pos[i].map(f64::from));
            let ext = (0..6)
                .flat_map(|i| (0..6).map(move |j| (i, j)))
                .map(|(i, j)| (w(i) - w(j)).length())
                .fold(0.0, f64::max);
            let tw = [(0, 1), (1, 2), (2, 0)].iter().any(|&(k, j)| {
                let (a, b, c, d) = (w(k), w(j), w(j + 3), w(k + 3));
                (b - a).cross(c - a).dot(d - a).abs() > 1e-6 * ext.powi(3)
            });
            twisted_n += usize::from(tw);
            let mut zs: Vec<f32> = p.iter().map(|v| v[2]).collect();
            zs.sort_by(f32::total_cmp);
            let mids: Vec<f32> = zs.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
            for z in mids {
                let poly = check_with(&p, z, !tw);
                sections += usize::from(poly.count >= 3);
                twisted_cut += usize::from(tw && poly.count >= 3);
            }
            sweep_with(&p, !tw);
        }
    }
    // The shell really has twisted prisms (its normals are not coplanar along the edges).
    assert!(
        twisted_n > 100 && twisted_cut > 100,
        "{twisted_n} twisted, {twisted_cut} cut"
    );
    assert!(sections > 10_000, "{sections}");
}

/// Issue 25, item 5: NaN or infinite prism input gives a defined result — the empty
/// section, no panic, never a NaN vertex — whichever coordinate (position x, y or z,
/// uvw) of whichever vertex it is in.
#[test]
fn nan_prism_input_gives_an_empty_section() {
    let base = boxed([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])[0];
    let uvw = uvw_of(&base);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for v in 0..6 {
            for c in 0..3 {
                let mut p = base;
                p[v][c] = bad;
                for z in [0.0, 0.25, 0.5, 1.0] {
                    let poly = intersect_prism_plane(&p, &uvw, z);
                    assert!(poly.is_empty(), "pos[{v}][{c}] = {bad}, z {z}: {poly:?}");
                }
                let mut t = uvw;
                t[v][c] = bad;
                let poly = intersect_prism_plane(&base, &t, 0.5);
                assert!(poly.is_empty(), "uvw[{v}][{c}] = {bad}: {poly:?}");
            }
        }
        let poly = intersect_prism_plane(&base, &uvw, bad);
        assert!(poly.is_empty(), "z_slice {bad}: {poly:?}");
    }
}
