//! The zero-anchored BC7 block of a volume's colour tiles that border empty space
//! ([`zero_anchored_block`], SPEC §12.3): one mode-6 line from zero, so the empty texels
//! decode to zero exactly, fitted so that the tile keeps its sum of each channel.

/// BC7 mode-6 interpolation weights of 4-bit indices.
const W4: [u32; 16] = [0, 4, 9, 13, 17, 21, 26, 30, 34, 38, 43, 47, 51, 55, 60, 64];

/// A BC7 mode-6 block (one subset, RGBA endpoints of 7 bits + a p-bit, 4-bit indices)
/// whose one endpoint is exactly `(0, 0, 0, 0)`: every texel lies on the line from zero
/// to the other endpoint, which premultiplied texels of one hue with varying alpha do.
/// Texels that are all zero get the zero endpoint and decode to zero exactly; the others
/// get the index of least squared error. The other endpoint starts at the tile's
/// per-channel maximum and is then refitted (up to four times, with the indices chosen
/// again) so that the block keeps the tile's sum of each channel, `e = 64·Σ t / Σ w`, with
/// the p-bit of least error (odd where a texel is opaque, so that alpha 255 is reached).
/// Every texel of the block has the same straight colour, and the sum is what a renderer
/// adds up: a least-squares fit took the opaque texels' colour and brightened the
/// partly covered ones (docs/accuracy.md, "Compressed volumes keep their brightness").
pub(super) fn zero_anchored_block(tile: &[u8; 64]) -> [u8; 16] {
    let texel = |i: usize| -> [u32; 4] { std::array::from_fn(|c| u32::from(tile[4 * i + c])) };
    let quant = |v: [u32; 4]| -> ([u32; 4], [u32; 4]) {
        // 8-bit endpoint = c7 << 1 | p with p = 1 (reaches 255).
        let c7 = v.map(|x| (x.min(255) >> 1).min(127));
        (c7, c7.map(|c| c << 1 | 1))
    };
    let choose = |e: [u32; 4]| -> ([usize; 16], u64) {
        // The 16 colours of the line from zero to `e`, each channel non-decreasing in the
        // index k. Past the first entry whose channels are all at or above the texel's
        // (`hi`, found by bisection) the error only grows, and below an entry whose
        // channels are all at or below it the error only grows too (strictly, once the
        // entry below differs). So the scan runs down from `hi` to there and keeps the
        // smallest k of least error: the same choice as trying all 16.
        let pal: [[i64; 4]; 16] =
            std::array::from_fn(|k| std::array::from_fn(|c| i64::from((W4[k] * e[c] + 32) >> 6)));
        let mut idx = [0usize; 16];
        let mut total = 0u64;
        for (i, slot) in idx.iter_mut().enumerate() {
            let t = texel(i);
            if t == [0; 4] {
                continue;
            }
            let t = t.map(i64::from);
            let err = |p: &[i64; 4]| -> u64 {
                (0..4).map(|c| ((p[c] - t[c]) * (p[c] - t[c])) as u64).sum()
            };
            // The first entry at or above the texel in every channel (the last if none is).
            let hi = pal[..15].partition_point(|p| !(0..4).all(|c| p[c] >= t[c]));
            let mut best = (err(&pal[hi]), hi);
            let mut k = hi;
            while k > 0 && !((0..4).all(|c| pal[k][c] <= t[c]) && pal[k - 1] != pal[k]) {
                k -= 1;
                let e = err(&pal[k]);
                if e <= best.0 {
                    best = (e, k);
                }
            }
            *slot = best.1;
            total += best.0;
        }
        (idx, total)
    };
    let max = (0..16).fold([0u32; 4], |m, i| {
        let t = texel(i);
        std::array::from_fn(|c| m[c].max(t[c]))
    });
    let (mut c7, e) = quant(max);
    let mut p = 1u32;
    let (mut idx, _) = choose(e);
    // An opaque texel (alpha 255) needs an odd endpoint (p-bit 1) to stay opaque.
    let p_bits: &[u32] = if (0..16).any(|i| tile[4 * i + 3] == 255) {
        &[1]
    } else {
        &[0, 1]
    };
    // The free endpoint keeps the tile's sum of each channel: e = 64·Σ t / Σ w per channel
    // (what a renderer adds up), its p-bit the one of least error.
    for _ in 0..4 {
        let (sw, st) = (0..16).fold((0f64, [0f64; 4]), |(a, b), i| {
            let w = f64::from(W4[idx[i]]);
            let t = texel(i);
            (a + w, std::array::from_fn(|c| b[c] + f64::from(t[c])))
        });
        if sw == 0.0 {
            break;
        }
        let fit = st.map(|v| 64.0 * v / sw);
        let best = p_bits
            .iter()
            .map(|&pb| {
                let c = fit.map(|v| ((v - f64::from(pb)) / 2.0).round().clamp(0.0, 127.0) as u32);
                let (i, err) = choose(c.map(|c| c << 1 | pb));
                (err, c, pb, i)
            })
            .min_by_key(|b| b.0)
            .unwrap();
        let same = best.3 == idx && best.1 == c7 && best.2 == p;
        (c7, p, idx) = (best.1, best.2, best.3);
        if same {
            break;
        }
    }
    // Endpoint 0 is zero (p-bit 0), endpoint 1 the fitted one (p-bit 1).
    mode6_bits(([0; 4], 0), (c7, p), idx)
}

/// Packs a BC7 mode-6 block: endpoints as (7-bit RGBA, p-bit) and 4-bit indices. Texel
/// 0's index must have its top bit clear (the anchor), else the endpoints are swapped and
/// every index mirrored (the same decoded texels).
fn mode6_bits(a: ([u32; 4], u32), b: ([u32; 4], u32), mut idx: [usize; 16]) -> [u8; 16] {
    let swap = idx[0] >= 8;
    let ((e0, p0), (e1, p1)) = if swap { (b, a) } else { (a, b) };
    let (p0, p1) = (u128::from(p0), u128::from(p1));
    if swap {
        idx.iter_mut().for_each(|k| *k = 15 - *k);
    }
    let mut bits: u128 = 1 << 6; // mode 6
    let mut pos = 7;
    let mut put = |v: u128, n: u32| {
        bits |= v << pos;
        pos += n;
    };
    for c in 0..4 {
        put(u128::from(e0[c]), 7);
        put(u128::from(e1[c]), 7);
    }
    put(p0, 1);
    put(p1, 1);
    put(idx[0] as u128, 3);
    for &k in &idx[1..] {
        put(k as u128, 4);
    }
    bits.to_le_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use billow_format::decode_bc7_block;

    #[test]
    fn anchored_blocks_keep_the_sum_of_each_channel() {
        // Leaf-edge tiles in linear bytes: empty texels, opaque texels of a mid green, and
        // partly covered rim texels of a darker green (premultiplied). One line through
        // zero gives every texel of a tile the same straight colour; a least-squares fit
        // takes the opaque texels' and brightened the rims: the generated tree's leaves
        // were +3.7 % in luminance over their level 0 (docs/accuracy.md, "Compressed
        // volumes keep their brightness"). Summed over many tiles, each channel must come
        // back within 1 %.
        let mut rng = crate::rng::Pcg32::seeded(38, 5);
        let (mut src, mut dec) = ([0f64; 4], [0f64; 4]);
        for _ in 0..2000 {
            let mut tile = [0u8; 64];
            let g = 30 + rng.below(40) as u8;
            for t in tile.chunks_exact_mut(4) {
                match rng.below(3) {
                    0 => {}
                    1 => t.copy_from_slice(&[g / 4, g, g / 6, 255]),
                    _ => {
                        let a = 40 + rng.below(180);
                        let c = |v: u8| (u32::from(v) * a / 255 / 2) as u8;
                        t.copy_from_slice(&[c(g / 4), c(g), c(g / 6), a as u8]);
                    }
                }
            }
            let back = decode_bc7_block(&zero_anchored_block(&tile));
            for (s, d) in tile.chunks_exact(4).zip(back.chunks_exact(4)) {
                for c in 0..4 {
                    src[c] += f64::from(s[c]);
                    dec[c] += f64::from(d[c]);
                }
            }
        }
        for c in 0..4 {
            let rel = dec[c] / src[c] - 1.0;
            assert!(rel.abs() < 0.01, "channel {c}: {:+.2} %", 100.0 * rel);
        }
    }
}
