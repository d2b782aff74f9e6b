//! The animated detail texture (Umenhoffer et al. §3.1–3.2 use frames of real smoke and
//! fire videos as a 3D texture; we synthesise one): periodic value noise in
//! `SIDE × SIDE × FRAMES` texels — x, y across a particle's patch, z = time — tiling in
//! all three axes, so sampling with repeat addressing loops seamlessly in time. Four
//! octaves, values in [0, 1] with mean ½. Built only when a scene has particles.

pub const SIDE: usize = 32;
pub const FRAMES: usize = 16;

fn hash(x: i64, y: i64, z: i64, seed: u64) -> f32 {
    let mut h = (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (y as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ (z as u64).wrapping_mul(0x1656_67b1_9e37_79f9)
        ^ seed;
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Periodic value noise with `cells` lattice cells per period along x, y and `zc` along z.
fn value(x: f32, y: f32, z: f32, cells: i64, zc: i64, seed: u64) -> f32 {
    let (fx, fy, fz) = (x.floor(), y.floor(), z.floor());
    let (ix, iy, iz) = (fx as i64, fy as i64, fz as i64);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let (tx, ty, tz) = (s(x - fx), s(y - fy), s(z - fz));
    let at = |dx: i64, dy: i64, dz: i64| {
        hash(
            (ix + dx).rem_euclid(cells),
            (iy + dy).rem_euclid(cells),
            (iz + dz).rem_euclid(zc),
            seed,
        )
    };
    let l = |a: f32, b: f32, t: f32| a + (b - a) * t;
    l(
        l(
            l(at(0, 0, 0), at(1, 0, 0), tx),
            l(at(0, 1, 0), at(1, 1, 0), tx),
            ty,
        ),
        l(
            l(at(0, 0, 1), at(1, 0, 1), tx),
            l(at(0, 1, 1), at(1, 1, 1), tx),
            ty,
        ),
        tz,
    )
}

/// The texture, x fastest, then y, then z (time), as R8 texels.
pub fn detail_texture(seed: u64) -> Vec<u8> {
    let mut out = Vec::with_capacity(SIDE * SIDE * FRAMES);
    for z in 0..FRAMES {
        for y in 0..SIDE {
            for x in 0..SIDE {
                let (mut v, mut amp, mut norm) = (0.0f32, 1.0f32, 0.0f32);
                for o in 0..4 {
                    let cells = 4i64 << o; // 4, 8, 16, 32 cells per period
                    let zc = (2i64 << o).min(FRAMES as i64);
                    let k = cells as f32 / SIDE as f32;
                    let kz = zc as f32 / FRAMES as f32;
                    v += amp
                        * value(
                            x as f32 * k,
                            y as f32 * k,
                            z as f32 * kz,
                            cells,
                            zc,
                            seed + o,
                        );
                    norm += amp;
                    amp *= 0.5;
                }
                out.push(((v / norm).clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_tiles_and_spans_a_useful_range() {
        let t = detail_texture(1);
        assert_eq!(t.len(), SIDE * SIDE * FRAMES);
        let mean = t.iter().map(|&v| f64::from(v)).sum::<f64>() / t.len() as f64;
        assert!((mean - 127.5).abs() < 25.0, "mean {mean}");
        let (lo, hi) = (t.iter().min().unwrap(), t.iter().max().unwrap());
        assert!(*lo < 80 && *hi > 175, "range {lo}..{hi}");
        // Periodic: the lattice values wrap, so the texel next to the last one (sampled at
        // x = SIDE) equals texel 0.
        for o in 0..4u64 {
            let cells = 4i64 << o;
            let a = value(0.0, 3.3, 1.7, cells, 4, o);
            let b = value(cells as f32, 3.3, 1.7, cells, 4, o);
            assert!((a - b).abs() < 1e-6);
        }
        assert_eq!(t, detail_texture(1), "deterministic");
    }
}
