//! The WGSL prism/plane intersection (run in a compute pass, read back) against the Rust
//! reference `billow_core::prism_plane::intersect_prism_plane`, on the hard cases of the
//! stability suite (tests/eval_prism_plane.rs): planes on cap faces, vertical edges
//! parallel to the plane, planes through vertices and diagonals, degenerate prisms,
//! huge and tiny coordinates, inverted prisms; plus seeded random prisms cut through
//! their own vertices and at random depths.
//!
//! Tolerance: the same vertex count and order; each coordinate within
//! `1e-5 · (1 + max |coordinate of the prism|)` (the GPU may fuse multiply-adds), uvw
//! within 1e-5. z must equal the plane exactly (both write it, not compute it).

mod common;

use billow::test_support::box_positions_z as boxed;
use billow_core::prism_plane::intersect_prism_plane;
use billow_view::prism_plane_gpu::intersect_on_gpu;

type P6 = [[f32; 3]; 6];

/// uvw = a fixed affine function of the position (distinct per vertex).
fn uvw_of(p: &P6) -> P6 {
    std::array::from_fn(|i| {
        [
            0.1 + 0.05 * i as f32,
            (p[i][0] * 0.3 + p[i][1] * 0.2).fract().abs(),
            if i < 3 { 0.0 } else { 1.0 },
        ]
    })
}

/// A small deterministic generator (xorshift) for the random cases.
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn hard_cases() -> Vec<(P6, f32)> {
    let mut cases = Vec::new();
    let [p0, p1] = boxed([0.0, 0.0, 0.0], [1.5, 1.0, 0.5]);
    for z in [0.0, 0.5, 0.25, -1.0, 1.0] {
        cases.push((p0, z));
        cases.push((p1, z));
    }
    for prism in boxed([0.0; 3], [1.0; 3]) {
        let p = prism.map(|v| [v[0], v[2], v[1]]);
        for z in [0.0, 0.25, 0.5, 0.999, 1.0] {
            cases.push((p, z));
        }
        let t = prism.map(|v| [v[0], v[1], v[0] + v[1] + v[2]]);
        for z in [0.0, 1.0, 2.0, 3.0, 0.5, 1.5, 2.5] {
            cases.push((t, z));
        }
        let d = prism.map(|v| [v[0], v[2], v[0] + v[1]]);
        for z in [0.0, 1.0, 2.0] {
            cases.push((d, z));
        }
        for s in [1e-6f32, 1e6] {
            let h = prism.map(|v| [v[0] * s, v[1] * s, (v[0] * 0.3 + v[1] * 0.6 + v[2]) * s]);
            for z in [0.0, 0.2, 0.5, 0.9, 1.0, 1.3, 1.9] {
                cases.push((h, z * s));
            }
        }
    }
    let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.3], [0.0, 1.0, 0.7]];
    let flat: P6 = [tri[0], tri[1], tri[2], tri[0], tri[1], tri[2]];
    for z in [0.0, 0.1, 0.3, 0.5, 0.7] {
        cases.push((flat, z));
    }
    let line: P6 = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.5],
        [2.0, 0.0, 1.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
        [2.0, 1.0, 1.0],
    ];
    for z in [0.0, 0.25, 0.5, 1.0] {
        cases.push((line, z));
    }
    for z in [0.0, 0.5, 1.0] {
        cases.push(([[0.5, 0.5, 0.5]; 6], z));
    }
    let [b0, _] = boxed([0.0; 3], [1.0; 3]);
    let inv: P6 = [b0[3], b0[4], b0[5], b0[0], b0[1], b0[2]];
    cases.push((inv, 0.5));
    // Random prisms: planes through each vertex, and at random depths.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for _ in 0..300 {
        let base: [[f32; 3]; 3] = std::array::from_fn(|_| {
            [
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
            ]
        });
        let h = [rng.f() - 0.3, rng.f() - 0.3, rng.f() - 0.3];
        let p: P6 = std::array::from_fn(|i| {
            let b = base[i % 3];
            if i < 3 {
                b
            } else {
                [b[0] + 0.2 * h[0], b[1] + 0.2 * h[1], b[2] + h[i % 3]]
            }
        });
        for v in &p {
            cases.push((p, v[2]));
        }
        for _ in 0..4 {
            cases.push((p, rng.f() * 3.0 - 1.5));
        }
    }
    cases
}

#[test]
fn wgsl_prism_plane_matches_the_rust_reference() {
    let Some(gpu) = common::gpu_or_skip("wgsl_prism_plane_matches_the_rust_reference") else {
        return;
    };
    let cases = hard_cases();
    let input: Vec<(P6, P6, f32)> = cases.iter().map(|(p, z)| (*p, uvw_of(p), *z)).collect();
    let got = intersect_on_gpu(&gpu, &input).expect("GPU intersection");
    assert_eq!(got.len(), input.len());
    let mut non_empty = 0;
    let mut failures = Vec::new();
    for (i, ((pos, uvw, z), g)) in input.iter().zip(&got).enumerate() {
        let want = intersect_prism_plane(pos, uvw, *z);
        let scale = pos.iter().flatten().fold(0.0f32, |m, c| m.max(c.abs()));
        let tol = 1e-5 * (1.0 + scale);
        let mut ok = want.count == g.count;
        for k in 0..want.count.min(g.count) {
            for a in 0..3 {
                ok &= (want.pos[k][a] - g.pos[k][a]).abs() <= tol;
                ok &= (want.uvw[k][a] - g.uvw[k][a]).abs() <= 1e-5;
            }
            ok &= g.pos[k][2] == *z;
        }
        if want.count > 0 {
            non_empty += 1;
        }
        if !ok {
            failures.push(format!(
                "case {i} z={z}: prism {pos:?}\n  want {} {:?}\n  got  {} {:?}",
                want.count,
                &want.pos[..want.count],
                g.count,
                &g.pos[..g.count]
            ));
        }
    }
    println!(
        "{} cases, {} non-empty, {} mismatches",
        input.len(),
        non_empty,
        failures.len()
    );
    assert!(
        non_empty > input.len() / 3,
        "the cases must mostly cut their prisms"
    );
    assert!(
        failures.is_empty(),
        "{} mismatches:\n{}",
        failures.len(),
        failures[..failures.len().min(5)].join("\n")
    );
}
