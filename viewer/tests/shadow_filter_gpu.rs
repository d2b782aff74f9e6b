//! The receivers' shadow filter (`shaders/shadow_lookup.wgsl`'s `shadow_visibility`), run
//! in a compute pass on the headless device over a depth tile of known texels, against
//! its definition computed here in f64: nine bilinear depth-compare taps one texel apart
//! (3×3 percentage-closer filtering), each tap comparing its four texels (`LessEqual`:
//! lit where the point's depth less the bias is at most the texel's) and weighting them
//! bilinearly. The shader takes the same filter as four bilinear taps; this holds it to
//! the nine within `2e-3`, on hard cases too: a depth step every few texels, points on
//! texel centres and edges, biases that move the point across a step.

mod common;

use billow_view::shadow_gpu::{shadow_visibility_on_gpu, VisibilityCase};

const SIZE: u32 = 24;

/// A tile of steps: depth k/8 in blocks of 1–3 texels, so every 4×4 footprint meets
/// several steps.
fn tile() -> Vec<f32> {
    let mut d = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let h = (x / 2 + 3 * (y / 3) + (x * y) % 5) % 8;
            d.push(h as f32 / 8.0);
        }
    }
    d
}

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Points inside the tile's filter margin (1.5 texels), at random positions and on texel
/// centres and edges, with depths between the steps and biases of 0 and one step.
fn cases() -> Vec<VisibilityCase> {
    let n = f64::from(SIZE);
    let inner = 1.0 - 3.0 / n;
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut out = Vec::new();
    for i in 0..600 {
        let (mut x, mut y) = (
            (2.0 * rng.next() - 1.0) * inner,
            (2.0 * rng.next() - 1.0) * inner,
        );
        if i % 3 == 1 {
            // On a texel centre (pixel coordinate k + 0.5) or edge (k).
            let snap = |v: f64, half: f64| {
                let p = ((v * 0.5 + 0.5) * n).floor() + half;
                (p / n * 2.0 - 1.0).clamp(-inner, inner)
            };
            let half = if i % 2 == 0 { 0.5 } else { 0.0 };
            (x, y) = (snap(x, half), snap(y, half));
        }
        let z = ((rng.next() * 8.0).floor() + 0.5) / 8.0;
        let bias = if i % 4 == 0 { 0.125 } else { 0.0 };
        out.push(VisibilityCase {
            p: [x as f32, y as f32, z as f32, bias],
        });
    }
    out
}

/// The nine-tap filter in f64 (module docs). The cascade's tile is the atlas's first
/// (2 × 2 tiles), mapped to the base NDC one to one.
fn reference(depth: &[f32], c: &VisibilityCase) -> f64 {
    let n = f64::from(SIZE);
    let [x, y, z, bias] = c.p.map(f64::from);
    let (u, v) = ((x * 0.5 + 0.5) * n, (0.5 - y * 0.5) * n);
    let d = z - bias;
    let lit = |i: i64, j: i64| -> f64 {
        // Past the tile's far edge (reached with weight 0 only): the next tile, cleared.
        let inside = i < i64::from(SIZE) && j < i64::from(SIZE);
        let t = if inside {
            f64::from(depth[(j * i64::from(SIZE) + i) as usize])
        } else {
            1.0
        };
        if d <= t {
            1.0
        } else {
            0.0
        }
    };
    let mut s = 0.0;
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (px, py) = (u + f64::from(dx) - 0.5, v + f64::from(dy) - 0.5);
            let (i, j) = (px.floor(), py.floor());
            let (fx, fy) = (px - i, py - j);
            let (i, j) = (i as i64, j as i64);
            s += (1.0 - fx) * (1.0 - fy) * lit(i, j)
                + fx * (1.0 - fy) * lit(i + 1, j)
                + (1.0 - fx) * fy * lit(i, j + 1)
                + fx * fy * lit(i + 1, j + 1);
        }
    }
    s / 9.0
}

#[test]
fn the_shadow_filter_is_nine_bilinear_taps() {
    let depth = tile();
    let Some((cases, got)) = common::check_on_gpu(
        "the_shadow_filter_is_nine_bilinear_taps",
        cases(),
        |gpu, c| shadow_visibility_on_gpu(gpu, SIZE, &depth, c),
    ) else {
        return;
    };
    let mut worst = (0.0f64, 0);
    let mut partial = 0;
    for (k, (c, g)) in cases.iter().zip(&got).enumerate() {
        let want = reference(&depth, c);
        if want > 0.01 && want < 0.99 {
            partial += 1;
        }
        let e = (f64::from(*g) - want).abs();
        if e > worst.0 {
            worst = (e, k);
        }
    }
    // The cases exercise the filter: most of them fall in a penumbra.
    assert!(
        partial > cases.len() / 2,
        "{partial} of {} partly lit",
        cases.len()
    );
    let (e, k) = worst;
    println!("worst |gpu − f64| {e:.2e} at {:?}", cases[k].p);
    assert!(
        e < 2e-3,
        "case {k} {:?}: gpu {}, nine-tap reference {}",
        cases[k].p,
        got[k],
        reference(&depth, &cases[k])
    );
}
