//! The brick-sparse side of [`super::voxelize`] (`voxelize --prune`, issue 26): the same
//! pipeline, with every MIP level kept as 8³ bricks ([`SparseLevel`]) instead of a dense
//! grid, handed to [`crate::emptyspace::prune_sparse`] without a dense volume in between.

use super::pipeline::{voxelize_as, Output};
use super::{
    quantize, CombineFn, GridSpec, Stage, Volume, VoxelizeError, VoxelizeOptions, VoxelizeStats,
};
use crate::scene::Scene;
use crate::sparse_level::SparseLevel;

/// The result of [`voxelize_sparse`]: every MIP level brick-sparse (8³ bricks of RGBA8
/// and snorm8 normals holding a non-zero byte), what `voxelize --prune` hands to
/// [`crate::emptyspace::prune_sparse`].
#[derive(Clone, Debug, PartialEq)]
pub struct SparseVolume {
    pub grid: GridSpec,
    pub levels: Vec<SparseLevel>,
    pub stats: VoxelizeStats,
    /// As [`Volume::coverage`].
    pub coverage: super::CoverageScales,
    /// As [`Volume::normal_coherence`].
    pub normal_coherence: Option<f32>,
    /// As [`Volume::moments`].
    pub moments: bool,
}

impl SparseVolume {
    pub fn dims(&self) -> [u32; 3] {
        self.grid.dims
    }
    pub fn mip_count(&self) -> u32 {
        self.levels.len() as u32
    }
    pub fn has_normals(&self) -> bool {
        self.levels.first().is_some_and(SparseLevel::has_normals)
    }
    /// Removes the normals of every level.
    pub fn drop_normals(&mut self) {
        self.levels.iter_mut().for_each(SparseLevel::drop_normals);
    }
    /// [`super::toksvig::normal_coherence`] of `level` (same sums in the same order, so the same
    /// value), `None` without normals or for an empty level.
    pub fn normal_coherence(&self, level: usize) -> Option<f32> {
        let l = self.levels.get(level).filter(|l| l.has_normals())?;
        let (mut num, mut den) = (0.0f64, 0.0f64);
        let d = l.dims;
        for z in 0..d[2] {
            for y in 0..d[1] {
                for x in 0..d[0] {
                    let c = l.get(false, [x, y, z]);
                    if c[3] == 0 {
                        continue;
                    }
                    let a = f64::from(c[3]) / 255.0;
                    let len = quantize::decode_normal(l.get(true, [x, y, z])).length();
                    num += a * f64::from(len.min(1.0));
                    den += a;
                }
            }
        }
        (den > 0.0).then(|| (num / den) as f32)
    }
    /// The asset that [`Volume::into_asset`] would make, without its texels (`levels`
    /// empty; `normals` `Some(empty)` when the volume has normals): the header and cells
    /// [`crate::emptyspace::prune_sparse`] takes beside [`SparseVolume::levels`].
    pub fn asset_shell(
        &self,
        tool: &str,
        source: Option<billow_format::SourceInfo>,
        params: std::collections::BTreeMap<String, String>,
    ) -> billow_format::VolumeAsset {
        let empty = Volume {
            grid: self.grid,
            levels: vec![Vec::new(); self.levels.len()],
            normals: self
                .has_normals()
                .then(|| vec![Vec::new(); self.levels.len()]),
            moments: self.moments,
            stats: self.stats,
            coverage: self.coverage.clone(),
            normal_coherence: self.normal_coherence,
        };
        let mut a = empty.into_asset(tool, source, params);
        a.levels = Vec::new();
        a.normals = a.normals.map(|_| Vec::new());
        a
    }
}

/// [`voxelize()`](super::voxelize()) whose levels stay brick-sparse ([`SparseVolume`]): no
/// level is ever dense.
/// Needs a preset combine ([`VoxelizeError::InvalidOption`] otherwise). The levels hold
/// exactly the bytes of [`voxelize()`](super::voxelize())'s (zeros where no brick is).
pub fn voxelize_sparse(
    scene: &Scene,
    opts: &VoxelizeOptions,
    progress: &dyn Fn(Stage, f32),
) -> Result<SparseVolume, VoxelizeError> {
    if !matches!(opts.combine, CombineFn::Preset(_)) {
        return Err(VoxelizeError::InvalidOption {
            option: super::OptionName::Combine,
            message: format!(
                "a brick-sparse volume needs a preset combine (mean, max, min, opaque), not {}",
                opts.combine
            ),
        });
    }
    let (grid, out, stats, coverage) = voxelize_as(scene, opts, progress, true)?;
    let Output::Sparse(levels) = out else {
        unreachable!("a sparse voxelize")
    };
    let mut v = SparseVolume {
        grid,
        levels,
        stats,
        coverage,
        normal_coherence: None,
        moments: false,
    };
    let (k, surface) = super::toksvig::judge_baked(
        v.levels.len(),
        v.has_normals() && !opts.moments,
        opts.surface,
        |l| v.normal_coherence(l),
    );
    v.normal_coherence = k;
    v.moments = opts.moments && v.has_normals();
    let level0 = v.levels.first_mut();
    let opaque_too = v.coverage.level0_opaque_thinned;
    v.coverage.settle_level0(surface, |k| {
        if let Some(l0) = level0 {
            super::coverage::scale_sparse_level(l0, k, opaque_too)
        }
    });
    Ok(v)
}
