//! Converting a [`Volume`] into the asset format's [`VolumeAsset`].

use std::collections::BTreeMap;

use billow_format::{
    AssetKind, Bounds, ColourSpace, Header, NormalKind, SourceInfo, TexelFormat, VolumeAsset,
    VolumeHeader,
};

use super::{Bake, GridSpec, Volume, VoxelizeOptions};
use billow_core::cells::box_prisms;

/// The bake parameters `voxelize` records in the header (`res`, `combine`, `supersample`,
/// `normals`, `margin`, `dims`; with AO also `bake = ao`, `ao_rays`, `ao_distance` (scene
/// units, resolved), `ao_seed`), to which `extra` is added (and may override).
pub fn bake_params(
    volume: &Volume,
    opts: &VoxelizeOptions,
    extra: &BTreeMap<String, String>,
) -> BTreeMap<String, String> {
    bake_params_for(&volume.grid, opts, extra)
}

/// [`bake_params`] of a volume on `grid` (e.g. a [`super::SparseVolume`]'s).
pub fn bake_params_for(
    grid: &GridSpec,
    opts: &VoxelizeOptions,
    extra: &BTreeMap<String, String>,
) -> BTreeMap<String, String> {
    let d = grid.dims;
    let mut p = BTreeMap::new();
    p.insert("res".into(), opts.resolution.to_string());
    p.insert("dims".into(), format!("{}x{}x{}", d[0], d[1], d[2]));
    p.insert("combine".into(), opts.combine.to_string());
    p.insert("supersample".into(), opts.supersample.to_string());
    let normals = if opts.normals && opts.moments {
        "moments".to_string()
    } else {
        opts.normals.to_string()
    };
    p.insert("normals".into(), normals);
    p.insert(
        "margin".into(),
        if opts.bounds.is_some() {
            "bounds".into()
        } else {
            opts.margin.to_string()
        },
    );
    if opts.align > 1 {
        p.insert("align".into(), opts.align.to_string());
    }
    if let Bake::Ao { rays, .. } = opts.bake {
        billow_format::VolumeBake::Ao.write(&mut p);
        p.insert("ao_rays".into(), rays.to_string());
        p.insert(
            "ao_distance".into(),
            opts.bake.ao_distance(grid).unwrap_or(0.0).to_string(),
        );
        p.insert("ao_seed".into(), super::AO_SEED.to_string());
    }
    p.extend(extra.iter().map(|(k, v)| (k.clone(), v.clone())));
    p
}

impl Volume {
    /// The asset header: `kind = Volume`, `SrgbPremultiplied`, `Rgba8Unorm`, normals
    /// `Rgba8Snorm` when present, bounds = the voxel grid's box. `tool` is e.g. `"billow 0.1.0"`.
    pub fn asset_header(
        &self,
        tool: &str,
        source: Option<SourceInfo>,
        params: BTreeMap<String, String>,
    ) -> Header {
        let b = self.grid.bounds();
        Header {
            kind: AssetKind::Volume,
            tool: tool.into(),
            source,
            bounds: Bounds {
                min: b.min.to_array(),
                max: b.max.to_array(),
            },
            colour_space: ColourSpace::SrgbPremultiplied,
            seed: None,
            params,
            volume: Some({
                let mut v = VolumeHeader {
                    dims: self.dims(),
                    mip_count: self.mip_count(),
                    texel: TexelFormat::Rgba8Unorm,
                    normals: None,
                    moments: None,
                };
                v.set_normal_kind(self.normals.as_ref().map(|_| {
                    if self.moments {
                        NormalKind::Moments
                    } else {
                        NormalKind::Mean
                    }
                }));
                v
            }),
        }
    }

    /// The asset ([`Volume::asset_header`], the levels, and the grid's box as two prisms,
    /// [`box_prisms`]), consuming the volume (no copy of the texels).
    pub fn into_asset(
        self,
        tool: &str,
        source: Option<SourceInfo>,
        params: BTreeMap<String, String>,
    ) -> VolumeAsset {
        let header = self.asset_header(tool, source, params);
        let b = self.grid.bounds();
        VolumeAsset {
            header,
            levels: self.levels,
            normals: self.normals,
            bands: Vec::new(),
            cells: box_prisms(b.min, b.max).to_vec(),
        }
    }
}
