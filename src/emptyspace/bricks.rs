//! Copying bricks and their aprons from the source volume into the atlas, level by level
//! (formats/SPEC.md §8.6).
//!
//! Atlas texel `j` of level `L` (centre at atlas level-0 coordinate
//! `X' = (j + 0.5) · N_0 / N_L`) of a brick placed at atlas origin `a` whose source origin
//! is `o` shows the source at `X = X' − a + o`, i.e. source level-`L` texel coordinate
//! `x = X · n_L / n_0 − 0.5`, sampled trilinearly with clamp-to-edge addressing. When `x`
//! is an integer on every axis — always for `L ≤ log2 A` when the source's sides are
//! multiples of `2^L` — that is a byte-exact copy of one source texel; otherwise the value
//! is interpolated in linear premultiplied space and re-encoded.
//!
//! Each brick writes its whole slot (brick plus apron) at every level; at levels where
//! slots overlap (coarser than `log2 A`) later bricks overwrite earlier ones.

use billow_format::ColourSpace;
use glam::Vec4;

use crate::texture::srgb_to_linear_lut;
use crate::voxelize::quantize::encode_rgba8;

/// One brick: where it comes from and where it goes, in level-0 voxels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Brick {
    /// Source origin `o`.
    pub src: [usize; 3],
    /// Atlas origin `a`.
    pub dst: [usize; 3],
    /// Slot in the atlas: `[slot_lo, slot_hi)` (brick plus apron).
    pub slot_lo: [usize; 3],
    pub slot_hi: [usize; 3],
}

/// Bytes per texel and how to decode / encode them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Colour(ColourSpace),
    Normal,
}

fn decode(ch: Channel, t: &[u8]) -> Vec4 {
    match ch {
        Channel::Colour(ColourSpace::SrgbPremultiplied) => {
            let lut = srgb_to_linear_lut();
            Vec4::new(
                lut[t[0] as usize],
                lut[t[1] as usize],
                lut[t[2] as usize],
                f32::from(t[3]) / 255.0,
            )
        }
        Channel::Colour(ColourSpace::LinearPremultiplied) => {
            Vec4::new(t[0] as f32, t[1] as f32, t[2] as f32, t[3] as f32) / 255.0
        }
        Channel::Normal => {
            let f = |b: u8| (f32::from(b as i8) / 127.0).max(-1.0);
            Vec4::new(f(t[0]), f(t[1]), f(t[2]), f(t[3]))
        }
    }
}

fn encode(ch: Channel, v: Vec4) -> [u8; 4] {
    let u = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    match ch {
        Channel::Colour(ColourSpace::SrgbPremultiplied) => encode_rgba8(v),
        Channel::Colour(ColourSpace::LinearPremultiplied) => [u(v.x), u(v.y), u(v.z), u(v.w)],
        Channel::Normal => {
            let s = |x: f32| ((x.clamp(-1.0, 1.0) * 127.0).round() as i8) as u8;
            [s(v.x), s(v.y), s(v.z), 0]
        }
    }
}

/// Per axis, per atlas texel index of the slot at this level: the source texel pair and
/// weight (`i0`, `i1`, `t`), `t == 0` meaning an exact copy of `i0`.
fn axis_taps(
    j0: usize,
    j1: usize,
    scale_dst: f64,
    shift: f64,
    scale_src: f64,
    n: usize,
) -> Vec<(usize, usize, f32)> {
    (j0..j1)
        .map(|j| {
            let x_dst = (j as f64 + 0.5) * scale_dst; // atlas level-0 coordinate
            let x = (x_dst + shift) * scale_src - 0.5; // source level-L texel coordinate
            let r = x.round();
            let (f, t) = if (x - r).abs() < 1e-6 {
                (r, 0.0)
            } else {
                (x.floor(), x - x.floor())
            };
            let c = |i: f64| i.clamp(0.0, (n - 1) as f64) as usize;
            (c(f), c(f + 1.0), t as f32)
        })
        .collect()
}

/// Fills atlas level `L` (`dst`, size `nd`, atlas level-0 size `nd0`) from source level
/// `L` (`src`, size `ns`, source level-0 size `ns0`) for every brick, in order.
#[allow(clippy::too_many_arguments)]
pub fn fill_level(
    ch: Channel,
    src: &[u8],
    ns: [usize; 3],
    ns0: [usize; 3],
    dst: &mut [u8],
    nd: [usize; 3],
    nd0: [usize; 3],
    bricks: &[Brick],
) {
    for b in bricks {
        let taps: [Vec<(usize, usize, f32)>; 3] = std::array::from_fn(|a| {
            let r = nd[a] as f64 / nd0[a] as f64;
            let j0 = (b.slot_lo[a] as f64 * r).floor() as usize;
            let j1 = ((b.slot_hi[a] as f64 * r).ceil() as usize).min(nd[a]);
            axis_taps(
                j0.min(j1),
                j1,
                nd0[a] as f64 / nd[a] as f64,
                b.src[a] as f64 - b.dst[a] as f64,
                ns[a] as f64 / ns0[a] as f64,
                ns[a],
            )
        });
        let j0: [usize; 3] = std::array::from_fn(|a| {
            let r = nd[a] as f64 / nd0[a] as f64;
            (b.slot_lo[a] as f64 * r).floor() as usize
        });
        let at = |x: usize, y: usize, z: usize| 4 * (x + ns[0] * (y + ns[1] * z));
        for (kz, &(z0, z1, tz)) in taps[2].iter().enumerate() {
            for (ky, &(y0, y1, ty)) in taps[1].iter().enumerate() {
                let row = 4 * (j0[0] + nd[0] * (j0[1] + ky + nd[1] * (j0[2] + kz)));
                for (kx, &(x0, x1, tx)) in taps[0].iter().enumerate() {
                    let o = row + 4 * kx;
                    if tx == 0.0 && ty == 0.0 && tz == 0.0 {
                        let s = at(x0, y0, z0);
                        dst[o..o + 4].copy_from_slice(&src[s..s + 4]);
                        continue;
                    }
                    let v = |x, y, z| {
                        let s = at(x, y, z);
                        decode(ch, &src[s..s + 4])
                    };
                    let lerp = |a: Vec4, b: Vec4, t: f32| a + (b - a) * t;
                    let c00 = lerp(v(x0, y0, z0), v(x1, y0, z0), tx);
                    let c10 = lerp(v(x0, y1, z0), v(x1, y1, z0), tx);
                    let c01 = lerp(v(x0, y0, z1), v(x1, y0, z1), tx);
                    let c11 = lerp(v(x0, y1, z1), v(x1, y1, z1), tx);
                    let c = lerp(lerp(c00, c10, ty), lerp(c01, c11, ty), tz);
                    dst[o..o + 4].copy_from_slice(&encode(ch, c));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_bricks_are_byte_exact_copies_with_clamped_aprons() {
        // Source 4×1×1 texels 10, 20, 30, 40 (alpha); brick = source voxels [2, 4) placed at
        // atlas [1, 3) with a 1-voxel apron: atlas slot [0, 4).
        let src: Vec<u8> = [10u8, 20, 30, 40]
            .iter()
            .flat_map(|&a| [0, 0, 0, a])
            .collect();
        let mut dst = vec![0u8; 16];
        let b = Brick {
            src: [2, 0, 0],
            dst: [1, 0, 0],
            slot_lo: [0, 0, 0],
            slot_hi: [4, 1, 1],
        };
        let ch = Channel::Colour(ColourSpace::SrgbPremultiplied);
        fill_level(
            ch,
            &src,
            [4, 1, 1],
            [4, 1, 1],
            &mut dst,
            [4, 1, 1],
            [4, 1, 1],
            &[b],
        );
        let alphas: Vec<u8> = dst.chunks(4).map(|t| t[3]).collect();
        // Apron left = source voxel 1; right = clamp of voxel 4 → voxel 3.
        assert_eq!(alphas, vec![20, 30, 40, 40]);
    }
}
