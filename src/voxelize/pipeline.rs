//! The pipeline of [`super::voxelize`] and [`super::voxelize_sparse`] (the module docs'
//! steps 1–4): each pass's slices rasterized (and AO-baked), each direction's MIP
//! pyramid built and folded into the combined volume, level 0 combined, the levels
//! quantized, densely or brick-sparse.

use std::time::Instant;

use half::f16;

use super::fragments::NormalSums;
use super::grid3::Texel;
use super::{
    ao, brick_grid, check, combine, coverage, level0, mip, slices, toksvig, Bake, CombineFn,
    CoverageScales, GridSpec, Stage, StageTimes, VoxelizeError, VoxelizeOptions, VoxelizeStats,
};
use crate::material;
use crate::scene::Scene;
use crate::sparse_level::SparseLevel;

pub(super) fn ao_baker<'a>(
    scene: &'a Scene,
    shader: &'a material::Shader<'a>,
    grid: &GridSpec,
    opts: &VoxelizeOptions,
) -> Option<ao::AoBaker<'a>> {
    match opts.bake {
        Bake::None => None,
        Bake::Ao { rays, .. } => {
            let distance = opts.bake.ao_distance(grid).expect("AO distance");
            Some(ao::AoBaker::new(scene, shader, *grid, rays, distance))
        }
    }
}

/// One level of a direction's pyramid, as [`pyramid`] hands it on.
// One value per MIP step, moved not copied: its size does not matter.
#[allow(clippy::large_enum_variant)]
enum Level<'a, T> {
    /// Level 0, sparse.
    Zero(&'a slices::DirSlices),
    /// A coarser level: colour and weighted normals, brick-sparse (the normals on the
    /// colour's bricks).
    Dense(
        brick_grid::Bricked<T>,
        Option<brick_grid::Bricked<[f16; 4]>>,
    ),
}

/// Builds the pyramid of one direction from its sparse level 0: level 1 is filtered
/// straight from it ([`mip::downsample_sparse`]) and every further level from the one
/// before; each level goes to `sink` as soon as the next one is built.
fn pyramid<T: Texel>(
    s: &slices::DirSlices,
    mips: u32,
    mip_secs: &mut f64,
    mut sink: impl FnMut(usize, Level<T>),
) {
    let dir = s.dir;
    let t = Instant::now();
    let first = (mips > 1).then(|| mip::downsample_sparse::<T>(s));
    *mip_secs += t.elapsed().as_secs_f64();
    sink(0, Level::Zero(s));
    let Some((mut rgba, mut nrm)) = first else {
        return;
    };
    for level in 1..mips as usize {
        if level + 1 == mips as usize {
            sink(level, Level::Dense(rgba, nrm));
            return;
        }
        let t = Instant::now();
        let next = mip::downsample_bricks::<T, T>(&rgba, None, dir, None);
        let next_n = nrm
            .as_ref()
            .map(|n| toksvig::downsample_normals(n, &rgba, dir, &next.layout));
        *mip_secs += t.elapsed().as_secs_f64();
        sink(level, Level::Dense(rgba, nrm));
        rgba = next;
        nrm = next_n;
    }
}

/// What [`voxelize_as`] produces.
pub(super) enum Output {
    /// RGBA8 levels and snorm8 normals, dense.
    Dense(Vec<Vec<u8>>, Option<Vec<Vec<u8>>>),
    Sparse(Vec<SparseLevel>),
}

pub(super) fn voxelize_as(
    scene: &Scene,
    opts: &VoxelizeOptions,
    progress: &dyn Fn(Stage, f32),
    sparse: bool,
) -> Result<(GridSpec, Output, VoxelizeStats, CoverageScales), VoxelizeError> {
    let t_all = Instant::now();
    let (grid, mips, estimated_peak_bytes) = check(scene, opts, sparse)?;
    let shader = material::Shader::new(scene);
    let dims: Vec<[usize; 3]> = (0..mips)
        .map(|l| grid.level_dims(l).map(|d| d as usize))
        .collect();
    let mut times = StageTimes::default();
    let mut fragments = 0u64;
    // Level-0 voxels with a non-zero alpha byte, when the level-0 combine counted them.
    let mut non_empty = None;
    // With a preset, level 0's normals are combined with its colour (see below).
    let mut nacc = match opts.combine {
        CombineFn::Preset(_) => None,
        _ => opts.normals.then(|| toksvig::NormalAccum::new(&dims, true)),
    };
    let t = Instant::now();
    let mut baker = ao_baker(scene, &shader, &grid, opts);
    times.bake += t.elapsed().as_secs_f64();
    let k = opts.supersample;
    /// The directions of `axis` in `sides` (see `slices::passes`), + first.
    fn raster(
        bufs: &mut slices::SetupBufs,
        ctx: (&Scene, &material::Shader, &GridSpec, u32, NormalSums),
        (axis, sides): (usize, u8),
        times: &mut StageTimes,
        baker: Option<&mut ao::AoBaker>,
        progress: &dyn Fn(Stage, f32),
    ) -> Vec<slices::DirSlices> {
        let (scene, shader, grid, k, normals) = ctx;
        let t = Instant::now();
        // Progress in directions done: this pass covers [d, d + n).
        let (d, n) = (
            (2 * axis) as f32 + sides.trailing_zeros() as f32,
            sides.count_ones() as f32,
        );
        let mut stacks = slices::rasterize(
            bufs,
            scene,
            shader,
            grid,
            axis,
            sides,
            k,
            normals,
            &mut |x| progress(Stage::Rasterize, (d + n * x) / 6.0),
        );
        times.rasterize += t.elapsed().as_secs_f64();
        if let Some(b) = baker {
            let t = Instant::now();
            stacks.iter_mut().for_each(|s| b.apply_sparse(s));
            times.bake += t.elapsed().as_secs_f64();
        }
        stacks
    }
    let ctx = (
        scene,
        &shader,
        &grid,
        k,
        NormalSums::of(opts.normals, opts.moments),
    );
    // (axis, sides) in the order the directions are combined: +X, −X, +Y, …
    let sides = slices::passes(scene);
    let passes: Vec<(usize, u8)> = (0..3)
        .flat_map(|a| sides.iter().map(move |&p| (a, p)))
        .collect();
    let mut bufs = slices::SetupBufs::default();
    let voxel = grid.voxel.as_dvec3().to_array();
    let mut cover = CoverageScales::default();
    let levels: Vec<Vec<u8>> = match &opts.combine {
        CombineFn::Preset(p) => {
            // Level 0 is combined at the end from the six sparse stacks, plane by plane;
            // the coarser levels are folded as each direction's pyramid is built.
            let mut acc = combine::Accum::new(*p, &dims);
            nacc = opts
                .normals
                .then(|| toksvig::NormalAccum::new(&dims, false));
            let mut zero = Vec::with_capacity(6);
            // `--prune`: level 0 folded direction by direction, each stack then freed.
            let mut level0 = sparse.then(|| level0::Level0::new(*p, dims[0], opts.normals));
            // Each direction's projected coverage at level 0 (the mesh's, as rasterized).
            let mut seen = [0.0f64; 6];
            for &pass in &passes {
                let stacks = raster(&mut bufs, ctx, pass, &mut times, baker.as_mut(), progress);
                for s in stacks {
                    let dir = s.dir;
                    fragments += s.fragments;
                    let mut fold_secs = 0.0;
                    seen[dir.index()] = coverage::stack_coverage(&s);
                    pyramid::<[f32; 4]>(&s, mips, &mut times.mip, |level, data| {
                        if let Level::Dense(c, n) = data {
                            let t = Instant::now();
                            acc.fold(level, &c);
                            if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                                na.fold(level, n, &c);
                            }
                            fold_secs += t.elapsed().as_secs_f64();
                        }
                    });
                    match level0.as_mut() {
                        Some(l0) => {
                            let t = Instant::now();
                            l0.fold(&s);
                            drop(s);
                            fold_secs += t.elapsed().as_secs_f64();
                        }
                        None => zero.push(s),
                    }
                    times.combine += fold_secs;
                    progress(Stage::Mip, (dir.index() + 1) as f32 / 6.0);
                }
            }
            drop(std::mem::take(&mut bufs)); // before the level-0 combine's peak
            let t = Instant::now();
            cover.mesh = coverage::mesh_coverage(&seen);
            // Level 0's scale (thinned to the mesh), then each coarser level's (to level 0).
            let opaque_too = opts.surface == Some(false);
            let level0_scale = |cols: coverage::Columns, cover: &mut CoverageScales| {
                let (k, before, after) =
                    coverage::level0_scale(&cols, voxel, &cover.mesh, true, opaque_too);
                cover.level0_opaque_thinned = opaque_too;
                (cover.level0_before, cover.level0_after) = (before, after);
                cover.scales.push(k);
                k
            };
            let coarse_scale = |acc: &combine::Accum, l: usize, cover: &mut CoverageScales| {
                let k = coverage::level_scale(&acc.columns(l), dims[0], voxel, &cover.mesh);
                cover.scales.push(k);
                k
            };
            // Level 0's scale is applied once the normals are settled (`settle_level0`).
            if let Some(l0) = level0 {
                let (level0, count) = l0.finish_sparse();
                level0_scale(coverage::Columns::from_sparse(&level0), &mut cover);
                progress(Stage::Combine, 1.0);
                let mut out = vec![level0];
                for (l, &d) in dims.iter().enumerate().skip(1) {
                    let k = coarse_scale(&acc, l, &mut cover);
                    let c = acc.finish_level_bricks(l, k);
                    let n = nacc.as_mut().map(|na| na.finish_level_bricks(l));
                    out.push(sparse_level(d, c, n));
                }
                times.combine += t.elapsed().as_secs_f64();
                progress(Stage::Quantize, 1.0);
                times.total = t_all.elapsed().as_secs_f64();
                let stats = VoxelizeStats {
                    non_empty_voxels: count,
                    fragments,
                    triangles: scene.triangles.len(),
                    estimated_peak_bytes,
                    seconds: times,
                };
                return Ok((grid, Output::Sparse(out), stats, cover));
            }
            let (level0, normals0, count) = combine::combine_level0(*p, &zero, opts.normals);
            non_empty = Some(count);
            drop(zero);
            level0_scale(coverage::Columns::from_rgba8(dims[0], &level0), &mut cover);
            progress(Stage::Combine, 1.0);
            let mut out = vec![level0];
            for l in 1..mips as usize {
                let k = coarse_scale(&acc, l, &mut cover);
                out.push(acc.finish_level(l, k));
            }
            if let (Some(na), Some(n0)) = (nacc.as_mut(), normals0) {
                na.set_level0(n0);
            }
            times.combine += t.elapsed().as_secs_f64();
            out
        }
        f => {
            // Six brick-sparse f16 pyramids: only the bricks a direction's voxels reach.
            let mut pyrs: Vec<Vec<Option<brick_grid::Bricked<[f16; 4]>>>> = Vec::with_capacity(6);
            let mut seen = [0.0f64; 6];
            for &pass in &passes {
                let stacks = raster(&mut bufs, ctx, pass, &mut times, baker.as_mut(), progress);
                for s in stacks {
                    // Stored in f16 (the arithmetic stays f32/f64).
                    let dir = s.dir;
                    fragments += s.fragments;
                    seen[dir.index()] = coverage::stack_coverage(&s);
                    let mut levels = Vec::with_capacity(mips as usize);
                    pyramid::<[f16; 4]>(&s, mips, &mut times.mip, |level, data| match data {
                        Level::Zero(s) => {
                            if let Some(na) = nacc.as_mut() {
                                na.fold_sparse(s);
                            }
                            levels.push(Some(brick_grid::Bricked::from_slices(s)));
                        }
                        Level::Dense(c, n) => {
                            if let (Some(na), Some(n)) = (nacc.as_mut(), n.as_ref()) {
                                na.fold(level, n, &c);
                            }
                            levels.push(Some(c));
                        }
                    });
                    pyrs.push(levels);
                    progress(Stage::Mip, (dir.index() + 1) as f32 / 6.0);
                }
            }
            drop(std::mem::take(&mut bufs));
            cover.mesh = coverage::mesh_coverage(&seen);
            let t = Instant::now();
            let mut out = Vec::with_capacity(mips as usize);
            for l in 0..mips as usize {
                let grids: Vec<brick_grid::Bricked<[f16; 4]>> = pyrs
                    .iter_mut()
                    .map(|p| p[l].take().expect("level stored"))
                    .collect();
                let refs = [
                    &grids[0], &grids[1], &grids[2], &grids[3], &grids[4], &grids[5],
                ];
                out.push(combine::combine_level_bricks(f, refs));
                progress(Stage::Combine, (l + 1) as f32 / mips as f32);
            }
            // The function's level 0 is kept; the coarser levels keep its coverage.
            let cols = coverage::Columns::from_rgba8(dims[0], &out[0]);
            let (k, before, after) =
                coverage::level0_scale(&cols, voxel, &cover.mesh, false, false);
            (cover.level0_before, cover.level0_after) = (before, after);
            cover.scales.push(k);
            for l in 1..out.len() {
                let cols = coverage::Columns::from_rgba8(dims[l], &out[l]);
                let k = coverage::level_scale(&cols, dims[0], voxel, &after);
                coverage::scale_level_rgba8(&mut out[l], k, false);
                cover.scales.push(k);
            }
            times.combine += t.elapsed().as_secs_f64();
            out
        }
    };
    let t = Instant::now();
    let normals = nacc.map(|mut na| (0..mips as usize).map(|l| na.finish_level(l)).collect());
    let non_empty_voxels =
        non_empty.unwrap_or_else(|| levels[0].chunks_exact(4).filter(|p| p[3] != 0).count() as u64);
    times.quantize += t.elapsed().as_secs_f64();
    progress(Stage::Quantize, 1.0);
    times.total = t_all.elapsed().as_secs_f64();
    let stats = VoxelizeStats {
        non_empty_voxels,
        fragments,
        triangles: scene.triangles.len(),
        estimated_peak_bytes,
        seconds: times,
    };
    Ok((grid, Output::Dense(levels, normals), stats, cover))
}

/// One sparse level from the colour and normal accumulators' bricks (each `(bricks,
/// 4 · B3 bytes per brick)`); both come from the same layouts in the same order, so their
/// brick lists agree, but a difference is merged all the same.
fn sparse_level(
    dims: [usize; 3],
    (bricks, colour): (Vec<u32>, Vec<u8>),
    normals: Option<(Vec<u32>, Vec<u8>)>,
) -> SparseLevel {
    let Some((nb, nbytes)) = normals else {
        return SparseLevel::from_bricks(dims, bricks, colour, None);
    };
    if nb == bricks {
        return SparseLevel::from_bricks(dims, bricks, colour, Some(nbytes));
    }
    let per = 4 * brick_grid::B3;
    let mut all = bricks.clone();
    let mut c = colour;
    let at: std::collections::HashMap<u32, usize> =
        bricks.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    for &b in &nb {
        if !at.contains_key(&b) {
            all.push(b);
            c.resize(c.len() + per, 0);
        }
    }
    let at: std::collections::HashMap<u32, usize> =
        all.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    let mut n = vec![0u8; all.len() * per];
    for (i, &b) in nb.iter().enumerate() {
        let j = at[&b];
        n[j * per..(j + 1) * per].copy_from_slice(&nbytes[i * per..(i + 1) * per]);
    }
    SparseLevel::from_bricks(dims, all, c, Some(n))
}
