//! The second half of a row of [`super::raster_row`]: its fragments shaded (batched),
//! grouped by voxel with counting sorts, and composited front to back per sample in each
//! direction's own depth order.

use glam::{Vec3, Vec4};

use super::{Frag, NormalSums, RowOut, Scratch, Vox};
use crate::material::Shader;

/// The shading normals of a row's fragments, as a direction sees them.
struct FragNormals<'a> {
    sums: NormalSums,
    n: &'a [Vec3],
}

impl FragNormals<'_> {
    /// Fragment `i`'s normal from direction `side` (zero when normals are off), or with
    /// [`NormalSums::Moments`] the squares of its components (the same from either side).
    #[inline(always)]
    fn get(&self, i: u32, side: usize) -> Vec3 {
        match self.sums {
            NormalSums::Off => Vec3::ZERO,
            NormalSums::Moments => self.n[i as usize] * self.n[i as usize],
            NormalSums::Mean if side == 0 => self.n[i as usize],
            // The − direction sees the other face: the shading normal flipped (exactly).
            NormalSums::Mean => -self.n[i as usize],
        }
    }
}

/// A fragment alone in its voxel (the common case), with normal `n`: no compositing.
#[inline(always)]
fn single(f: &Frag, n: Vec3) -> (Vec4, Vec3) {
    let w = f.mask.count_ones() as f32;
    (f.rgba * w, n * (f.rgba.w * w))
}

impl Scratch {
    /// Shades the row's fragments, batched (their texture fetches are independent, so
    /// their cache misses overlap); those shading discards get mask 0. Returns the
    /// survivors' count and per direction how many it sees; `start[slice + 1]` holds
    /// each slice's count.
    #[inline(always)]
    pub(super) fn shade(&mut self, shader: &Shader<'_>, depth_n: u32) -> (u64, [u64; 2]) {
        let mut count = 0u64;
        let mut seen = [0u64; 2];
        self.start.clear();
        self.start.resize(depth_n as usize + 1, 0);
        for f in self.frags.iter_mut() {
            let shaded = if f.shaded {
                Some(f.rgba)
            } else {
                shader.shade_tested(shader.material(f.material), f.uv, f.rgba)
            };
            match shaded {
                Some(c) => {
                    f.rgba = c;
                    self.start[(f.key >> 32) as usize + 1] += 1;
                    count += 1;
                    seen[0] += (f.vis & 1) as u64;
                    seen[1] += (f.vis >> 1) as u64;
                }
                None => f.mask = 0,
            }
        }
        (count, seen)
    }

    /// Groups the `count` survivors of [`Scratch::shade`] by (column, slice) with two
    /// stable counting sorts (by slice, then by column), in generation order within a
    /// voxel: column u's fragments are then `order[start[u]..start[u + 1]]`.
    #[inline(always)]
    pub(super) fn sort_by_voxel(&mut self, count: u64, depth_n: u32, width: usize) {
        let Scratch {
            frags,
            start,
            by_slice,
            order,
            ..
        } = self;
        for z in 0..depth_n as usize {
            start[z + 1] += start[z];
        }
        by_slice.clear();
        by_slice.resize(count as usize, 0);
        for (i, f) in frags.iter().enumerate() {
            if f.mask != 0 {
                let p = &mut start[(f.key >> 32) as usize];
                by_slice[*p as usize] = i as u32;
                *p += 1;
            }
        }
        start.clear();
        start.resize(width + 1, 0);
        for &i in by_slice.iter() {
            start[frags[i as usize].u as usize + 1] += 1;
        }
        for u in 0..width {
            start[u + 1] += start[u];
        }
        order.clear();
        order.resize(count as usize, (0, 0, 0));
        let mut fill = start[..width].to_vec();
        for &i in by_slice.iter() {
            let f = &frags[i as usize];
            let p = &mut fill[f.u as usize];
            order[*p as usize] = (f.key, f.tri, i);
            *p += 1;
        }
    }

    /// The row's voxels per direction in `sides` (`seen`: how many fragments each sees),
    /// from the fragments [`Scratch::sort_by_voxel`] grouped: each the mean of its `K²`
    /// samples' front-to-back composites.
    #[inline(always)]
    pub(super) fn composite<const K: usize>(
        &mut self,
        sides: u8,
        sums: NormalSums,
        seen: [u64; 2],
        width: usize,
    ) -> [RowOut; 2] {
        let Scratch {
            frags,
            normals: frag_n,
            start,
            order,
            voxel,
            ..
        } = self;
        let normals = sums.on();
        let inv_samples = 1.0 / (K * K) as f32;
        // A direction has at most as many voxels as fragments: sized once, no regrowing.
        let mut out: [RowOut; 2] = [0, 1].map(|side| {
            let n = seen[side];
            let n_nrm = if normals { n as usize } else { 0 };
            (
                Vec::with_capacity(n as usize),
                Vec::with_capacity(n_nrm),
                n,
                0.0,
            )
        });
        let mut transmit = [1.0f32; 64];
        let mut column = [1.0f32; 64];
        let nrm = FragNormals { sums, n: frag_n };
        for u in 0..width {
            let col = &order[start[u] as usize..start[u + 1] as usize];
            // Per direction, whether what it sees of the column lies in one slice: then
            // that voxel's alpha is the column's coverage (added below).
            let one_slice = [0, 1].map(|side| {
                let bit = 1u8 << side;
                let mut seen = col.iter().filter(|e| frags[e.2 as usize].vis & bit != 0);
                seen.next()
                    .is_none_or(|f| seen.all(|g| g.0 >> 32 == f.0 >> 32))
            });
            for (side, o) in out.iter_mut().enumerate() {
                if sides & (1u8 << side) != 0 && !one_slice[side] {
                    o.3 += column_coverage::<K>(frags, col, side, &mut column);
                }
            }
            let mut g = 0;
            while g < col.len() {
                let slice = (col[g].0 >> 32) as u32;
                let mut end = g + 1;
                while end < col.len() && (col[end].0 >> 32) as u32 == slice {
                    end += 1;
                }
                for (side, (vox, vox_n, _, cover)) in out.iter_mut().enumerate() {
                    if sides & (1u8 << side) == 0 {
                        continue;
                    }
                    let entries = &col[g..end];
                    let Some((c, nsum)) =
                        composite_voxel::<K>(frags, &nrm, entries, side, voxel, &mut transmit)
                    else {
                        continue;
                    };
                    if one_slice[side] {
                        // `out[side].3`, borrowed as `vox` and `vox_n` above.
                        *cover += f64::from(c.w * inv_samples);
                    }
                    if c.w > 0.0 {
                        vox.push(Vox {
                            u: u as u16,
                            s: slice as u16,
                            rgba: (c * inv_samples).to_array(),
                        });
                        if normals {
                            vox_n.push((nsum * inv_samples).to_array());
                        }
                    }
                }
                g = end;
            }
        }
        out
    }
}

/// The projected coverage of one pixel column's `(key, triangle, fragment)` `entries` as
/// direction `side` sees them: the mean over the `K²` samples of `1 − Π(1 − α)` over
/// every fragment covering the sample, whatever its slice (the order does not matter).
#[inline(always)]
fn column_coverage<const K: usize>(
    frags: &[Frag],
    entries: &[(u64, u32, u32)],
    side: usize,
    transmit: &mut [f32; 64],
) -> f64 {
    let bit = 1u8 << side;
    transmit[..K * K].fill(1.0);
    for &(_, _, i) in entries {
        let f = &frags[i as usize];
        if f.vis & bit == 0 {
            continue;
        }
        let keep = 1.0 - f.rgba.w;
        let mut bits = f.mask;
        while bits != 0 {
            let b = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            transmit[b] *= keep;
        }
    }
    let covered: f32 = transmit[..K * K].iter().map(|t| 1.0 - t).sum();
    f64::from(covered) / (K * K) as f64
}

/// One voxel's `(key, triangle, fragment)` `entries` composited as direction `side` sees
/// them: the sum over its samples of their colours and of their alpha-weighted normals
/// (`None`: no fragment of the voxel faces `side`).
#[inline(always)]
fn composite_voxel<const K: usize>(
    frags: &[Frag],
    nrm: &FragNormals<'_>,
    entries: &[(u64, u32, u32)],
    side: usize,
    voxel: &mut Vec<(u64, u32, u32)>,
    transmit: &mut [f32; 64],
) -> Option<(Vec4, Vec3)> {
    let bit = 1u8 << side;
    if entries.len() == 1 {
        let i = entries[0].2;
        if frags[i as usize].vis & bit == 0 {
            return None;
        }
        return Some(single(&frags[i as usize], nrm.get(i, side)));
    }
    // The voxel's fragments seen from this side, by (depth front to back, triangle): the
    // + camera sees high depths first.
    voxel.clear();
    voxel.extend(
        entries
            .iter()
            .filter(|e| frags[e.2 as usize].vis & bit != 0)
            .map(|&(key, tri, i)| {
                let key = if side == 0 { key ^ 0xffff_ffff } else { key };
                (key, tri, i)
            }),
    );
    match voxel.len() {
        0 => None,
        1 => {
            let i = voxel[0].2;
            Some(single(&frags[i as usize], nrm.get(i, side)))
        }
        _ => {
            sort_small(voxel);
            // Per-sample front-to-back compositing (ties in depth: lower triangle first).
            let (mut c, mut nsum) = (Vec4::ZERO, Vec3::ZERO);
            transmit[..K * K].fill(1.0);
            for &(_, _, i) in voxel.iter() {
                let f = &frags[i as usize];
                let mut w = 0.0f32;
                let keep = 1.0 - f.rgba.w;
                let mut bits = f.mask;
                while bits != 0 {
                    let b = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    w += transmit[b];
                    transmit[b] *= keep;
                }
                c += f.rgba * w;
                nsum += nrm.get(i, side) * (f.rgba.w * w);
            }
            Some((c, nsum))
        }
    }
}

/// Sorts a voxel's `(key, triangle, index)` entries (few, usually): insertion sort for
/// short runs, the standard sort otherwise. Keys and triangles are never both equal.
#[inline]
fn sort_small(v: &mut [(u64, u32, u32)]) {
    if v.len() > 24 {
        v.sort_unstable();
        return;
    }
    for i in 1..v.len() {
        let x = v[i];
        let key = (x.0, x.1);
        let mut p = i;
        while p > 0 && (v[p - 1].0, v[p - 1].1) > key {
            v[p] = v[p - 1];
            p -= 1;
        }
        v[p] = x;
    }
}
