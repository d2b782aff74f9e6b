//! Six-direction slice stacks (VB paper §3.2): what an orthographic camera looking along
//! one axis sees between the near and far planes of each slice.
//!
//! Instead of rendering every slice with its own clip planes, each triangle is rasterized
//! once per direction and its fragments are binned into slices by depth, which gives the
//! same images in one pass.
//!
//! # Conventions
//! - [`Dir::PosX`] is the camera on the **+X side looking towards −X** (it sees faces whose
//!   normal has `n.x > 0`), and so on; its front-to-back order is decreasing x.
//! - The image of direction `d` uses the two other axes in increasing order (x,y,z) as
//!   (u, v); pixel `(i, j)` is voxel column `(i, j)` of the grid.
//! - **Supersampling** (MSAA-style): each pixel has `K × K` stratified coverage samples
//!   at `((i + (si + ½)/K), (j + (sj + ½)/K))`. Coverage is exact with integer edge
//!   functions on vertices snapped to `1/(32 K)` of a voxel and a consistent tie rule on
//!   shared edges (a sample on an edge shared by two triangles belongs to exactly one of
//!   them). A triangle's covered samples in one pixel are grouped by slice, and each group
//!   (a *fragment*) is **shaded once**, at the centroid of its samples; for `Mask`
//!   materials the alpha test is done per sample (alpha channel only), so cut-out edges
//!   keep their sub-voxel shape.
//! - **Slice binning**: a sample at depth `t` (in voxels from the grid's min face along
//!   the view axis) belongs to slice `k = floor(t)`, i.e. voxel k spans `[k, k + 1)` ×
//!   voxel size, whichever side the camera is on; `t = dims` (the far face of the grid)
//!   belongs to the last slice; samples outside `[0, dims]` are clipped.
//! - Within one voxel, fragments are composited front to back per sample, ordered by the
//!   depth of their shading point (ties: lower triangle index first); the voxel is the
//!   mean of its `K²` samples, so thin geometry gets fractional alpha.
//! - **Faces**: single-sided triangles are seen only from the directions their front
//!   (counter-clockwise) face faces; double-sided ones from both, their normal flipped
//!   towards the camera when seen from the back. Edge-on triangles are not seen.
//! - **Normals** (optional): per voxel, `Σ` over samples and fragments of
//!   `visible weight × unit shading normal` / `K²` — the alpha-weighted normal sum, which
//!   filters like a premultiplied colour (see [`super::toksvig`]); a fragment's normal is
//!   taken at its shading point.
//! - The result is sparse ([`DirSlices`]): the non-empty voxels of each image row.

use half::f16;
use rayon::prelude::*;

use super::fragments::{
    cross2, row_fn, simd_available, NormalSums, RowCtx, RowOut, Scratch, TriSetup, Vox, SUB,
};
use super::grid::GridSpec;
use super::grid3::{Grid3, Texel};
use super::Dir;
use crate::material::Shader;
use crate::scene::Scene;

/// Largest projected coordinate kept, in voxels (keeps edge functions in i64).
const MAX_COORD: f64 = (1u64 << 20) as f64;
/// Largest supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 8;

/// One direction's slices at level 0, sparse: the non-empty voxels of every image row.
pub(crate) struct DirSlices {
    pub dir: Dir,
    /// The grid's level-0 dimensions.
    pub dims: [usize; 3],
    /// Row `j`'s voxels are `vox[rows[j]..rows[j + 1]]`, sorted by `(u, s)`.
    pub vox: Vec<Vox>,
    pub rows: Vec<usize>,
    /// Σ weight·normal per voxel (parallel to `vox`), when normals were asked for.
    pub nrm: Option<Vec<[f32; 3]>>,
    pub fragments: u64,
    /// The projected coverage the direction saw, exactly: over its pixel columns, the
    /// mean over each column's `K²` samples of `1 − Π(1 − α)` of every fragment covering
    /// the sample (whatever its slice), in level-0 texel faces. Compositing the column's
    /// voxels instead (`1 − Π(1 − α_voxel)`) loses what a surface crossing a slice
    /// boundary inside a column covers on both sides of it (disjoint samples): 5–10 %
    /// of the eztree flowers' broad leaves (`super::coverage`).
    pub coverage: f64,
}

impl DirSlices {
    /// Number of image rows.
    pub fn row_count(&self) -> usize {
        self.rows.len() - 1
    }
    /// Row `j`'s voxels and the index of its first one in `vox`.
    #[inline]
    pub fn row(&self, j: usize) -> (&[Vox], usize) {
        (&self.vox[self.rows[j]..self.rows[j + 1]], self.rows[j])
    }
    /// The grid index (x fastest) of voxel `v` of row `j`.
    #[inline]
    pub fn index(&self, j: usize, v: &Vox) -> usize {
        let (a, [ua, va]) = (self.dir.axis(), self.dir.image_axes());
        let mut p = [0usize; 3];
        p[a] = v.s as usize;
        p[ua] = v.u as usize;
        p[va] = j;
        p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])
    }
    /// The grid indices of all voxels, in `vox` order.
    pub fn indices(&self) -> Vec<usize> {
        (0..self.row_count())
            .into_par_iter()
            .flat_map_iter(|j| {
                let (row, _) = self.row(j);
                row.iter().map(move |v| self.index(j, v))
            })
            .collect()
    }
    /// The colour as a dense grid.
    pub fn to_dense<T: Texel>(&self) -> Grid3<T> {
        let mut g = Grid3::<T>::new(self.dims);
        for (i, v) in self.indices().into_iter().zip(&self.vox) {
            g.data[i] = T::store(v.rgba);
        }
        g
    }
    /// The weighted normals as a dense grid `(Σ w·n, 0)`, when present.
    pub fn dense_normals(&self) -> Option<Grid3<[f16; 4]>> {
        let nrm = self.nrm.as_ref()?;
        let mut g = Grid3::<[f16; 4]>::new(self.dims);
        for (i, n) in self.indices().into_iter().zip(nrm) {
            g.data[i] = <[f16; 4]>::store([n[0], n[1], n[2], 0.0]);
        }
        Some(g)
    }
}

/// The triangle set-up buffers of [`rasterize`], kept from one pass to the next so
/// that the passes write the same memory (≈ 200 bytes a triangle twice) instead of
/// asking the system for fresh, zeroed pages each time. Contents do not carry over.
#[derive(Default)]
pub(crate) struct SetupBufs {
    unsorted: Vec<Option<TriSetup>>,
    sorted: Vec<TriSetup>,
}

/// The set-up of triangle `tri_index` for both directions of the axis of `dir` (`dir` is
/// the + one): the projection, coverage and depth do not depend on the side the camera
/// is on, only which faces it sees and the compositing order do.
/// `sides` says which directions are wanted (bits as [`TriSetup::vis`]).
fn setup(
    scene: &Scene,
    grid: &GridSpec,
    dir: Dir,
    sides: u8,
    k: i64,
    tri_index: usize,
) -> Option<TriSetup> {
    let tri = &scene.triangles[tri_index];
    let (a, [ua, va]) = (dir.axis(), dir.image_axes());
    let facing = tri.cross()[a];
    let double_sided = scene.materials[tri.material as usize].double_sided;
    let sees = |facing: f32| facing > 0.0 || (double_sided && facing < 0.0);
    let vis = (sees(facing) as u8 | (sees(-facing) as u8) << 1) & sides;
    if vis == 0 {
        return None;
    }
    let f = (2 * k * SUB) as f64;
    let mut p = [[0i64; 2]; 3];
    let mut t = [0f64; 3];
    if !tri.v.iter().all(|v| v.position.is_finite()) {
        return None;
    }
    for (i, v) in tri.v.iter().enumerate() {
        let q = v.position;
        let rel = |ax: usize| (q[ax] as f64 - grid.min[ax] as f64) / grid.voxel[ax] as f64;
        let snap = |x: f64| (x.clamp(-MAX_COORD, MAX_COORD) * f).round() as i64;
        p[i] = [snap(rel(ua)), snap(rel(va))];
        t[i] = rel(a);
    }
    if !t.iter().all(|x| x.is_finite()) {
        return None;
    }
    let mut perm = [0, 1, 2];
    let mut area = cross2(p[0], p[1], p[2]);
    if area == 0 {
        return None;
    }
    if area < 0 {
        p.swap(1, 2);
        t.swap(1, 2);
        perm.swap(1, 2);
        area = -area;
    }
    // Edge i is opposite vertex i: from vertex i+1 to vertex i+2.
    let bias = [0, 1, 2].map(|i| {
        let (s, e) = (p[(i + 1) % 3], p[(i + 2) % 3]);
        let (dx, dy) = (e[0] - s[0], e[1] - s[1]);
        i64::from(!(dy > 0 || (dy == 0 && dx < 0)))
    });
    let fk = 2 * k * SUB;
    let range = |ax: usize, n: u32| {
        let lo = p.iter().map(|q| q[ax]).min().unwrap().div_euclid(fk).max(0);
        let hi = p
            .iter()
            .map(|q| q[ax])
            .max()
            .unwrap()
            .div_euclid(fk)
            .min(n as i64 - 1);
        (lo <= hi).then_some([lo as usize, hi as usize])
    };
    let cols = range(0, grid.dims[ua])?;
    let rows = range(1, grid.dims[va])?;
    if t.iter().all(|&x| x < 0.0) || t.iter().all(|&x| x > grid.dims[a] as f64) {
        return None;
    }
    let vx = |slot: usize| &tri.v[perm[slot]];
    Some(TriSetup {
        p,
        t,
        area,
        bias,
        uv: [vx(0).uv, vx(1).uv, vx(2).uv],
        col: [vx(0).color, vx(1).color, vx(2).color],
        tri: tri_index as u32,
        material: tri.material,
        perm: perm.map(|x| x as u8),
        back: facing < 0.0,
        vis,
        rows: rows.map(|x| x as u32),
        cols: cols.map(|x| x as u32),
    })
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// Which rasterization passes an axis takes (bits as [`TriSetup::vis`]): one for both
/// directions when many triangles are double-sided, else one per direction.
///
/// Double-sided triangles (foliage) are seen from both directions of an axis: one pass
/// for the two sets them up, covers and shades them once (see [`super::fragments`]).
/// A single-sided triangle is seen from one direction only, so there a pass per direction
/// is faster (fewer fragments per row, each stack built and handed on before the next).
/// The result is the same either way, bit for bit.
pub(crate) fn passes(scene: &Scene) -> &'static [u8] {
    let double = scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].double_sided)
        .count();
    if double >= scene.triangles.len().div_ceil(PAIRED_SHARE) {
        &[3]
    } else {
        &[1, 2]
    }
}

/// Rasterizes the slice stacks of the directions of `axis` (0 = x, 1 = y, 2 = z) in
/// `sides` (bit 0: +, bit 1: −) into their sparse level 0, + first. `progress` gets the
/// fraction of rows done.
#[allow(clippy::too_many_arguments)]
pub(crate) fn rasterize(
    bufs: &mut SetupBufs,
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    axis: usize,
    sides: u8,
    k: u32,
    normals: NormalSums,
    progress: &mut dyn FnMut(f32),
) -> Vec<DirSlices> {
    let simd = simd_available();
    rasterize_with(
        bufs, scene, shader, grid, axis, sides, k, normals, simd, progress,
    )
}

/// [`passes`] pairs the two directions when at least one triangle in this many is
/// double-sided (a pass for both costs about 1.1 single ones on a single-sided mesh, and
/// saves the second rasterization of every double-sided triangle).
const PAIRED_SHARE: usize = 5;

/// [`rasterize`] with the AVX2 build of the row loop (`simd`, when the CPU has it) or
/// the baseline one: the same result either way.
#[allow(clippy::too_many_arguments)]
pub(crate) fn rasterize_with(
    bufs: &mut SetupBufs,
    scene: &Scene,
    shader: &Shader,
    grid: &GridSpec,
    axis: usize,
    sides: u8,
    k: u32,
    normals: NormalSums,
    simd: bool,
    progress: &mut dyn FnMut(f32),
) -> Vec<DirSlices> {
    let k = k.clamp(1, MAX_SUPERSAMPLE) as i64;
    let dir = Dir::ALL[2 * axis];
    let va = dir.image_axes()[1];
    let dims = grid.dims.map(|d| d as usize);
    let nrows = dims[va];
    // Indexed (collected in place), with the culled triangles as `None`.
    let unsorted = &mut bufs.unsorted;
    (0..scene.triangles.len())
        .into_par_iter()
        .map(|i| setup(scene, grid, dir, sides, k, i))
        .collect_into_vec(unsorted);
    // Sorted by first row (then triangle: a stable counting sort of the indices, then one
    // gather), so that a row's triangles lie close together in memory; the order of
    // triangles within a row does not change the result (fragments are sorted by a key
    // that includes the triangle).
    let mut first = vec![0u32; nrows + 1];
    for s in unsorted.iter().flatten() {
        first[s.rows[0] as usize + 1] += 1;
    }
    for r in 0..nrows {
        first[r + 1] += first[r];
    }
    let mut perm = vec![0u32; first[nrows] as usize];
    for (i, s) in unsorted.iter().enumerate() {
        if let Some(s) = s {
            let p = &mut first[s.rows[0] as usize];
            perm[*p as usize] = i as u32;
            *p += 1;
        }
    }
    let unsorted = &bufs.unsorted;
    perm.par_iter()
        .with_min_len(4096)
        .map(|&i| unsorted[i as usize].expect("not culled"))
        .collect_into_vec(&mut bufs.sorted);
    let setups = &bufs.sorted;
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nrows];
    for (i, s) in setups.iter().enumerate() {
        for bin in &mut bins[s.rows[0] as usize..=s.rows[1] as usize] {
            bin.push(i as u32);
        }
    }
    let row = row_fn(k as usize, simd);
    let ctx = RowCtx {
        scene,
        shader,
        grid,
        dir,
        normals,
        sides,
        setups,
        bins: &bins,
    };
    let chunk = nrows.div_ceil(8).max(8);
    let mut outs: Vec<[RowOut; 2]> = Vec::with_capacity(nrows);
    for chunk_start in (0..nrows).step_by(chunk) {
        outs.par_extend(
            (chunk_start..(chunk_start + chunk).min(nrows))
                .into_par_iter()
                .map(|j| SCRATCH.with_borrow_mut(|scratch| row(&ctx, j, scratch))),
        );
        progress(((chunk_start + chunk).min(nrows)) as f32 / nrows.max(1) as f32);
    }
    (0..2)
        .filter(|side| sides >> side & 1 == 1)
        .map(|side| concat(Dir::ALL[2 * axis + side], dims, normals.on(), &outs, side))
        .collect()
}

/// One direction's rows (`side` of each pair) as one sparse stack, concatenated once at
/// the exact size (growing the stack row by row would copy it again at every doubling).
/// The rows are copied in parallel, each into its own range (the copy, and the page
/// faults of the fresh stack, would otherwise run on one thread).
fn concat(
    dir: Dir,
    dims: [usize; 3],
    normals: bool,
    outs: &[[RowOut; 2]],
    side: usize,
) -> DirSlices {
    let mut rows = Vec::with_capacity(outs.len() + 1);
    rows.push(0);
    let mut fragments = 0u64;
    let mut coverage = 0.0f64;
    for (v, _, count, c) in outs.iter().map(|o| &o[side]) {
        fragments += count;
        coverage += c;
        rows.push(rows.last().expect("starts with 0") + v.len());
    }
    let vox = gather(outs, |o| &o[side].0);
    let nrm = normals.then(|| gather(outs, |o| &o[side].1));
    DirSlices {
        dir,
        dims,
        vox,
        rows,
        nrm,
        fragments,
        coverage,
    }
}

/// The slices `part(o)` of every `o` in `outs`, one after another, copied in parallel.
fn gather<T: Copy + Send + Sync>(
    outs: &[[RowOut; 2]],
    part: impl Fn(&[RowOut; 2]) -> &Vec<T> + Sync,
) -> Vec<T> {
    let total = outs.iter().map(|o| part(o).len()).sum();
    let mut all = Vec::with_capacity(total);
    let mut rest = &mut all.spare_capacity_mut()[..total];
    let mut ranges = Vec::with_capacity(outs.len());
    for o in outs {
        let (head, tail) = rest.split_at_mut(part(o).len());
        ranges.push(head);
        rest = tail;
    }
    ranges
        .into_par_iter()
        .zip(outs)
        .with_min_len(4)
        .for_each(|(dst, o)| {
            dst.write_copy_of_slice(part(o));
        });
    // SAFETY: the ranges cover `..total` exactly (`total` is the sum of their lengths)
    // and every one was written just above.
    unsafe { all.set_len(total) };
    all
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3, Vec4};

    use super::*;
    use crate::scene::{AlphaMode, Material, SceneBuilder, Texture, Vertex, Wrap};
    use crate::voxelize::grid::{fit_grid, Resolution};

    /// Random small and large triangles in every orientation, with a textured cut-out
    /// (`Mask`), a blended double-sided and an opaque single-sided material, vertex
    /// colours and normals.
    fn scene() -> Scene {
        let mut x = 0x1234_5678_9abc_def1u64;
        let mut rnd = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f32 / (1u64 << 53) as f32
        };
        let mut sb = SceneBuilder::new();
        let mesh = sb.mesh("m");
        for m in [
            Material {
                base_color_texture: Some(0),
                alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
                double_sided: true,
                ..Material::default()
            },
            Material {
                base_color_factor: Vec4::new(0.8, 0.4, 0.2, 0.6),
                base_color_texture: Some(0),
                alpha_mode: AlphaMode::Blend,
                double_sided: true,
                ..Material::default()
            },
            Material::default(),
        ] {
            sb.material(m);
        }
        for i in 0..1500 {
            let c = Vec3::new(rnd(), rnd(), rnd());
            let size = if i % 10 == 0 { 0.4 } else { 0.05 };
            let p =
                |r: &mut dyn FnMut() -> f32| c + size * Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5);
            let v: [Vertex; 3] = std::array::from_fn(|_| Vertex {
                position: p(&mut rnd),
                normal: Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or_zero(),
                uv: Vec2::new(rnd() * 3.0 - 1.0, rnd() * 3.0 - 1.0),
                color: Vec4::new(rnd(), rnd(), rnd(), 0.5 + 0.5 * rnd()),
            });
            sb.triangle(v, i % 3, mesh);
        }
        let mut s = sb.finish();
        s.textures.push(Texture {
            name: "t".into(),
            width: 16,
            height: 8,
            texels: (0..128u32)
                .map(|i| {
                    let v = i.wrapping_mul(2_654_435_761).to_le_bytes();
                    [v[0], v[1], v[2], if v[3] < 100 { 0 } else { v[3] }]
                })
                .collect(),
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::MirroredRepeat,
            encoded: None,
        });
        s
    }

    /// A cut-out whose colour depends on where it passes (discs, light at the rim and
    /// dark in the middle, one per voxel column): the voxels hold the colour of the area
    /// that passes, as a ray tracer shading every sample sees it, not the colour at the
    /// middle, where the centroid of a fragment's passed samples lies (which made the
    /// oak's leaves 10 % too dark).
    #[test]
    fn cut_out_fragments_are_shaded_with_the_mean_of_their_samples() {
        let size = 64u32;
        let texels = (0..size * size)
            .map(|i| {
                let (x, y) = ((i % size) % 16, (i / size) % 16);
                let r = (x as f32 - 7.5).hypot(y as f32 - 7.5);
                let c = if r >= 3.5 { 255 } else { 0 };
                [c, c, c, if r < 6.0 { 255 } else { 0 }]
            })
            .collect();
        let mut sb = SceneBuilder::new();
        let mesh = sb.mesh("quad");
        sb.material(Material {
            base_color_texture: Some(0),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            double_sided: true,
            ..Material::default()
        });
        let v = |x: f32, y: f32| Vertex {
            position: Vec3::new(x, y, 0.5),
            normal: Vec3::Z,
            uv: Vec2::new(x, y),
            color: Vec4::ONE,
        };
        sb.triangle([v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)], 0, mesh);
        sb.triangle([v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)], 0, mesh);
        let mut s = sb.finish();
        s.textures.push(Texture {
            name: "discs".into(),
            width: size,
            height: size,
            texels,
            wrap_u: Wrap::Repeat,
            wrap_v: Wrap::Repeat,
            encoded: None,
        });
        let shader = Shader::new(&s);
        // What the mesh shows: the mean colour over the area that passes, 512² points.
        let m = &s.materials[0];
        let (mut sum, mut n) = (0.0f64, 0u32);
        for j in 0..512 {
            for i in 0..512 {
                let uv = Vec2::new((i as f32 + 0.5) / 512.0, (j as f32 + 0.5) / 512.0);
                if shader.mask_pass(m, 0.5, uv, 1.0) {
                    sum += f64::from(shader.texel(m, uv).unwrap().x);
                    n += 1;
                }
            }
        }
        let want = sum / f64::from(n);
        let grid = GridSpec {
            dims: [4, 4, 4],
            min: Vec3::ZERO,
            voxel: Vec3::splat(0.25),
        };
        let mut bufs = SetupBufs::default();
        let out = rasterize_with(
            &mut bufs,
            &s,
            &shader,
            &grid,
            2,
            1,
            8,
            NormalSums::Off,
            false,
            &mut |_| {},
        );
        let (c, a) = out[0].vox.iter().fold((0.0f64, 0.0f64), |(c, a), v| {
            (c + f64::from(v.rgba[0]), a + f64::from(v.rgba[3]))
        });
        assert_eq!(out[0].vox.len(), 16);
        let got = c / a;
        assert!(want > 0.5 && (got - want).abs() < 0.06, "{got} vs {want}");
    }

    /// The AVX2 build of the row loop gives the same voxels, bit for bit, as the
    /// baseline build, for every direction and several supersampling factors; and a pass
    /// for both directions of an axis the same as a pass for each.
    #[test]
    fn simd_and_baseline_rows_agree_bit_for_bit() {
        if !simd_available() {
            crate::test_support::skip(
                "simd_and_baseline_rows_agree_bit_for_bit",
                "no AVX2/BMI1/BMI2/LZCNT/POPCNT on this CPU",
            );
            return;
        }
        let s = scene();
        let shader = Shader::new(&s);
        let grid = fit_grid(&s.bounds, Resolution::Longest(37), 0.5).unwrap();
        let bits = |d: &DirSlices| {
            let v: Vec<_> = d
                .vox
                .iter()
                .map(|v| (v.u, v.s, v.rgba.map(f32::to_bits)))
                .collect();
            let n: Vec<_> = d
                .nrm
                .iter()
                .flatten()
                .map(|n| n.map(f32::to_bits))
                .collect();
            (v, n, d.rows.clone(), d.fragments)
        };
        for k in [1, 3, 4, 8] {
            for axis in 0..3 {
                let run = |simd, sides| {
                    let mut bufs = SetupBufs::default();
                    rasterize_with(
                        &mut bufs,
                        &s,
                        &shader,
                        &grid,
                        axis,
                        sides,
                        k,
                        NormalSums::Mean,
                        simd,
                        &mut |_| {},
                    )
                };
                let (a, b) = (run(false, 3), run(true, 3));
                assert!(a.len() == 2 && b.len() == 2, "axis {axis} K={k}");
                for (a, b) in a.iter().zip(&b) {
                    let dir = a.dir;
                    assert!(a.fragments > 500, "{dir:?} K={k}: {}", a.fragments);
                    assert!(bits(a) == bits(b), "{dir:?} K={k}");
                }
                // One pass for both directions = one pass each.
                let one: Vec<_> = [1, 2].into_iter().flat_map(|s| run(true, s)).collect();
                assert_eq!(one.len(), 2);
                for (a, b) in one.iter().zip(&b) {
                    assert!(a.dir == b.dir && bits(a) == bits(b), "{:?} K={k}", a.dir);
                }
            }
        }
    }
}
