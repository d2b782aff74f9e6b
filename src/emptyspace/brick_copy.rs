//! Copying bricks and their aprons from the source into a tier's atlas (formats/SPEC.md
//! §8.6), level by level: byte-exact copies, rotated by the slot's axis permutation, with
//! clamp-to-edge reads outside the source — what a renderer sampling the source reads
//! there.
//!
//! Slots are whole blocks (2×2×2 texels of the tier's first level, one texel of its
//! second), so at both levels a brick sits at an integer texel offset and its texels map
//! one to one onto the source's. Slots overlap only where both hold zeros
//! ([`super::pack`]), so the order of the copies does not matter.

/// One slot: where it comes from and where it goes, in blocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Brick {
    /// Source origin of the slot (brick origin minus its apron: may be −1).
    pub src: [i64; 3],
    /// Slot size in blocks, along the source's axes.
    pub size: [usize; 3],
    /// Atlas origin.
    pub dst: [usize; 3],
    /// Atlas axis `a` holds the source's axis `perm[a]`.
    pub perm: [usize; 3],
}

/// Fills one atlas level (`dst`, size `nd`) from the source level (`src`, size `ns`) for
/// every brick; `t` texels per block at this level (2 for the tier's first level, 1 for
/// its second). 4 bytes per texel (colour or normals alike).
pub fn fill_level(
    src: &[u8],
    ns: [usize; 3],
    dst: &mut [u8],
    nd: [usize; 3],
    t: usize,
    bricks: &[Brick],
) {
    let stride = [1, ns[0], ns[0] * ns[1]];
    fill_level_with(
        |p| {
            let s = 4 * (p[0] * stride[0] + p[1] * stride[1] + p[2] * stride[2]);
            [src[s], src[s + 1], src[s + 2], src[s + 3]]
        },
        ns,
        dst,
        nd,
        t,
        bricks,
    );
}

/// [`fill_level`] reading the source texel at `p` (inside `ns`) through `src` (a
/// brick-sparse source, [`crate::sparse_level`]).
pub fn fill_level_with(
    src: impl Fn([usize; 3]) -> [u8; 4],
    ns: [usize; 3],
    dst: &mut [u8],
    nd: [usize; 3],
    t: usize,
    bricks: &[Brick],
) {
    for b in bricks {
        let size: [usize; 3] = b.perm.map(|p| b.size[p] * t);
        // Source texel of atlas-local texel j: along source axis perm[a], src·t + j[a].
        let src_of = |a: usize, j: usize| -> usize {
            let s = b.perm[a];
            let v = b.src[s] * t as i64 + j as i64;
            v.clamp(0, ns[s] as i64 - 1) as usize
        };
        let mut p = [0usize; 3];
        for jz in 0..size[2] {
            p[b.perm[2]] = src_of(2, jz);
            for jy in 0..size[1] {
                p[b.perm[1]] = src_of(1, jy);
                let row =
                    4 * (b.dst[0] * t + nd[0] * (b.dst[1] * t + jy + nd[1] * (b.dst[2] * t + jz)));
                for jx in 0..size[0] {
                    p[b.perm[0]] = src_of(0, jx);
                    let d = row + 4 * jx;
                    dst[d..d + 4].copy_from_slice(&src(p));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bricks_are_byte_exact_rotated_copies_with_clamped_aprons() {
        // Source 4×2×1 texels, value = 10·x + y in the alpha byte.
        let src: Vec<u8> = (0..8u8)
            .flat_map(|i| [0, 0, 0, 10 * (i % 4) + i / 4])
            .collect();
        // Slot = source blocks x ∈ [1, 3) (texels 2..6; 4 and 5 are beyond the edge and
        // read texel 3), one block in y, stored transposed: atlas x ← source y, atlas y ←
        // source x; z is one texel thick (clamped).
        let b = Brick {
            src: [1, 0, 0],
            size: [2, 1, 1],
            dst: [0, 0, 0],
            perm: [1, 0, 2],
        };
        let ns = [4, 2, 1];
        let mut dst = vec![0u8; 4 * 4 * 2 * 2];
        fill_level(&src, ns, &mut dst, [2, 4, 2], 2, &[b]);
        let alpha = |x: usize, y: usize| dst[4 * (x + 2 * y) + 3];
        // t = 2: source x 2, 3, 4→3, 5→3 along atlas y; source y 0, 1 along atlas x.
        assert_eq!(
            [0, 1, 2, 3].map(|y| (alpha(0, y), alpha(1, y))),
            [(20, 21), (30, 31), (30, 31), (30, 31)]
        );
    }
}
