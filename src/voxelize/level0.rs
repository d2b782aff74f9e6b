//! Level 0 of a preset combination (VB paper §3.2, the function `f` of Figure 3 at the
//! finest level) for `voxelize --prune`, folded **one direction at a time** into one
//! sparse accumulator, so that each direction's level-0 stack can be freed as soon as it
//! is folded (issue 26: the six stacks held together were the peak at 1024³).
//!
//! The accumulator holds, per z plane, the voxels some direction has seen so far, sorted
//! by their index in the plane, each with the preset's running value (the floats of
//! [`super::combine::Accum`]) and, with normals, the running Toksvig sums. A direction is
//! merged into it plane by plane; every voxel receives exactly the folds it received when
//! the six stacks were combined together (one per direction that saw it, in
//! [`super::Dir::ALL`] order, the same f32 operations), so the bytes are the same.
//!
//! With `mean` and `opaque` the normals' alpha sum is the colour's own fourth float (the
//! same additions from 0 in the same order), so it is not stored twice.

use glam::Vec3;
use rayon::prelude::*;

use super::brick_grid::{local, B, B3};
use super::combine::{finished_value, plane_table, Accum, Preset};
use super::quantize::{clamp_premultiplied, encode_normal, Encoder};
use super::slices::DirSlices;
use super::toksvig::average_normal;
use crate::sparse_level::{BrickMask, SparseLevel};

/// The level-0 accumulator (see the module docs).
pub(crate) struct Level0 {
    preset: Preset,
    dims: [usize; 3],
    /// Colour floats per voxel: 4, or 5 for `opaque` and `min` (see [`Accum`]).
    w: usize,
    /// Normal floats per voxel: 0 without normals; 3 when the alpha sum is the colour's
    /// (`mean`, `opaque`), else 4.
    nw: usize,
    planes: Vec<Plane>,
}

/// One z plane of [`Level0`].
#[derive(Default)]
struct Plane {
    /// In-plane indices (`x + X · y`) of the voxels folded into, increasing.
    keys: Vec<u32>,
    /// `w + nw` floats per key.
    vals: Vec<f32>,
}

impl Plane {
    /// Merges `run` (`(key, voxel)`, keys increasing and distinct) into the plane: keys
    /// not held yet are inserted with zero floats; `fold(floats, voxel)` is called once
    /// per entry of `run`. Grows the buffers by exactly what is inserted.
    fn merge(&mut self, run: &[(u32, u32)], width: usize, fold: impl Fn(&mut [f32], usize)) {
        if run.is_empty() {
            return;
        }
        let n = self.keys.len();
        let (mut fresh, mut i) = (0, 0);
        for &(key, _) in run {
            while i < n && self.keys[i] < key {
                i += 1;
            }
            if i < n && self.keys[i] == key {
                i += 1;
            } else {
                fresh += 1;
            }
        }
        self.keys.reserve_exact(fresh);
        self.keys.resize(n + fresh, 0);
        self.vals.reserve_exact(fresh * width);
        self.vals.resize((n + fresh) * width, 0.0);
        // From the back, so that every held entry moves at most once, towards the end.
        let (mut i, mut j, mut o) = (n, run.len(), n + fresh);
        while j > 0 {
            let (key, k) = run[j - 1];
            o -= 1;
            let held = if i > 0 { Some(self.keys[i - 1]) } else { None };
            if held.is_some_and(|h| h >= key) {
                let from = i - 1;
                self.keys[o] = self.keys[from];
                if o != from {
                    self.vals
                        .copy_within(from * width..(from + 1) * width, o * width);
                }
                i -= 1;
                if held != Some(key) {
                    continue;
                }
            } else {
                self.keys[o] = key;
                self.vals[o * width..(o + 1) * width].fill(0.0);
            }
            fold(&mut self.vals[o * width..(o + 1) * width], k as usize);
            j -= 1;
        }
        debug_assert_eq!(o, i);
    }
}

/// One finished voxel: its in-plane index, plane within the brick layer, colour and
/// normal bytes (at least one of them not zero).
type Texel = (u32, u8, [u8; 4], [u8; 4]);

impl Level0 {
    pub fn new(preset: Preset, dims: [usize; 3], normals: bool) -> Self {
        let w = if matches!(preset, Preset::Opaque | Preset::Min) {
            5
        } else {
            4
        };
        let nw = match (normals, preset) {
            (false, _) => 0,
            (true, Preset::Mean | Preset::Opaque) => 3,
            (true, _) => 4,
        };
        Level0 {
            preset,
            dims,
            w,
            nw,
            planes: (0..dims[2]).map(|_| Plane::default()).collect(),
        }
    }

    /// Folds direction `s` (directions must come in [`super::Dir::ALL`] order).
    pub fn fold(&mut self, s: &DirSlices) {
        let dims = self.dims;
        debug_assert_eq!(s.dims, dims);
        let plane = dims[0] * dims[1];
        let (preset, w, nw) = (self.preset, self.w, self.nw);
        let width = w + nw;
        // Directions whose image rows are not z planes (view axis z): their voxels bucketed
        // by slice (a counting sort), in row order, so each plane's keys increase.
        let table = (s.dir.image_axes()[1] != 2).then(|| plane_table(s, dims));
        // Rows of the y directions are sorted by (x, y), not by the key x + X·y.
        let resort = s.dir.axis() == 1;
        let nrm = s.nrm.as_deref();
        let fold = |a: &mut [f32], k: usize| {
            let v = &s.vox[k];
            Accum::fold_one(preset, &mut a[..w], v.rgba);
            if let Some(n) = nrm {
                let n = n[k];
                let sum = &mut a[w..];
                sum[0] += n[0];
                sum[1] += n[1];
                sum[2] += n[2];
                if nw == 4 {
                    sum[3] += v.rgba[3];
                }
            }
        };
        self.planes
            .par_iter_mut()
            .enumerate()
            .for_each_init(Vec::new, |run, (z, p)| {
                let run: &[(u32, u32)] = match &table {
                    Some((start, list)) => &list[start[z]..start[z + 1]],
                    None => {
                        let (row, first) = s.row(z);
                        run.clear();
                        run.extend(row.iter().enumerate().map(|(k, v)| {
                            ((s.index(z, v) - z * plane) as u32, (first + k) as u32)
                        }));
                        if resort {
                            run.sort_unstable_by_key(|e| e.0);
                        }
                        run
                    }
                };
                p.merge(run, width, fold);
            });
    }

    /// The finished texels of plane `p` (colour RGBA8, Toksvig normal snorm8, the voxels
    /// with a non-zero byte only), the plane's floats freed; also the number of voxels
    /// whose alpha byte is not 0.
    fn finish_plane(&self, p: Plane, dz: u8, enc: &Encoder, out: &mut Vec<Texel>) -> u64 {
        let (w, nw) = (self.w, self.nw);
        let mut count = 0;
        for (&key, a) in p.keys.iter().zip(p.vals.chunks_exact(w + nw)) {
            let c = finished_value(self.preset, &a[..w]).map_or([0; 4], |v| {
                let px = enc.rgba8(clamp_premultiplied(v));
                count += u64::from(px[3] != 0);
                px
            });
            let n = if nw == 0 {
                [0; 4]
            } else {
                let alpha = if nw == 4 { a[w + 3] } else { a[3] };
                if a[w..w + 3] == [0.0; 3] && alpha == 0.0 {
                    [0; 4]
                } else {
                    let s = Vec3::new(a[w], a[w + 1], a[w + 2]);
                    encode_normal(average_normal(s, alpha))
                }
            };
            if c != [0; 4] || n != [0; 4] {
                out.push((key, dz, c, n));
            }
        }
        count
    }

    /// The combined level 0, brick-sparse ([`SparseLevel`]: the 8³ bricks with a non-zero
    /// colour or normal byte, in increasing brick order, each storing those texels), and
    /// the number of voxels whose alpha byte is not 0. Each brick layer's floats are freed
    /// as it is encoded.
    pub fn finish_sparse(mut self) -> (SparseLevel, u64) {
        let dims = self.dims;
        let nb = dims.map(|d| d.div_ceil(B));
        let layer = nb[0] * nb[1];
        let enc = Encoder::get();
        let mut planes = std::mem::take(&mut self.planes);
        let this = &self;
        // Per brick layer: its bricks (brick index), their masks, the stored texels'
        // colour and normal bytes in brick then texel order, and the layer's count.
        type Part = (Vec<u32>, Vec<BrickMask>, Vec<[u8; 4]>, Vec<[u8; 4]>, u64);
        let normals = self.nw > 0;
        let parts: Vec<Part> = planes
            .par_chunks_mut(B)
            .enumerate()
            .map(|(bz, ps)| {
                let (mut texels, mut count) = (Vec::new(), 0);
                for (dz, p) in ps.iter_mut().enumerate() {
                    count += this.finish_plane(std::mem::take(p), dz as u8, enc, &mut texels);
                }
                // (brick in the layer, texel in the brick) of each.
                let at = |&(key, dz, ..): &Texel| {
                    let (x, y) = (key as usize % dims[0], key as usize / dims[0]);
                    (x / B + nb[0] * (y / B), local([x, y, dz as usize]))
                };
                texels.sort_unstable_by_key(|t| at(t));
                let (mut bricks, mut masks) = (Vec::new(), Vec::<BrickMask>::new());
                let mut colour = Vec::with_capacity(texels.len());
                let mut nrm = Vec::with_capacity(if normals { texels.len() } else { 0 });
                for t in &texels {
                    let (b, i) = at(t);
                    let b = (b + bz * layer) as u32;
                    if bricks.last() != Some(&b) {
                        bricks.push(b);
                        masks.push([0; B3 / 64]);
                    }
                    masks.last_mut().expect("a brick")[i / 64] |= 1 << (i % 64);
                    colour.push(t.2);
                    if normals {
                        nrm.push(t.3);
                    }
                }
                (bricks, masks, colour, nrm, count)
            })
            .collect();
        drop(planes);
        let total: usize = parts.iter().map(|p| p.2.len()).sum();
        let slots: usize = parts.iter().map(|p| p.0.len()).sum();
        let (mut bricks, mut masks) = (Vec::with_capacity(slots), Vec::with_capacity(slots));
        let mut colour = Vec::with_capacity(total);
        let mut nrm = Vec::with_capacity(if normals { total } else { 0 });
        let mut count = 0;
        for (b, m, c, n, k) in parts {
            bricks.extend_from_slice(&b);
            masks.extend_from_slice(&m);
            colour.extend_from_slice(&c);
            nrm.extend_from_slice(&n);
            count += k;
        }
        let level = SparseLevel::from_packed(dims, bricks, masks, colour, normals.then_some(nrm));
        (level, count)
    }
}
