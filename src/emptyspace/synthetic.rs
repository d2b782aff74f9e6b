//! Small synthetic volume assets for tests, examples and docs: a level-0 texel function,
//! box-filtered MIPs (odd sizes by the voxelizer's rule: parent `j` averages children
//! `floor(j·r) ..` with `r = n / (n >> 1)`, rounded to whole texels — good enough for a
//! test volume), one box cell over `[0, 1]³`.

use billow_format::{
    full_mip_count, mip_dims, AssetKind, Bounds, ColourSpace, Header, NormalEncoding, TexelFormat,
    VolumeAsset, VolumeHeader,
};
use glam::Vec3;

use crate::voxelize::box_prisms;

/// A `LinearPremultiplied` volume with level 0 given by `f(x, y, z) → [r, g, b, a]`
/// (premultiplied bytes), the full MIP chain and, if `normals`, a constant +y normal
/// wherever alpha > 0.
pub fn volume_from_fn(
    dims: [u32; 3],
    normals: bool,
    f: impl Fn(u32, u32, u32) -> [u8; 4],
) -> VolumeAsset {
    let mips = full_mip_count(dims);
    let mut l0 = Vec::with_capacity(dims.iter().product::<u32>() as usize * 4);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                l0.extend_from_slice(&f(x, y, z));
            }
        }
    }
    let mut levels = vec![l0];
    for l in 1..mips {
        let (pd, cd) = (mip_dims(dims, l), mip_dims(dims, l - 1));
        let prev = &levels[(l - 1) as usize];
        let mut out = Vec::with_capacity(pd.iter().product::<u32>() as usize * 4);
        let span = |j: u32, a: usize| {
            let (n, p) = (cd[a], pd[a]);
            let lo = (j as u64 * n as u64 / p as u64) as u32;
            let hi = (((j + 1) as u64 * n as u64).div_ceil(p as u64) as u32).max(lo + 1);
            lo..hi.min(n)
        };
        for z in 0..pd[2] {
            for y in 0..pd[1] {
                for x in 0..pd[0] {
                    let (mut sum, mut cnt) = ([0u32; 4], 0u32);
                    for cz in span(z, 2) {
                        for cy in span(y, 1) {
                            for cx in span(x, 0) {
                                let o = 4 * (cx + cd[0] * (cy + cd[1] * cz)) as usize;
                                for (c, v) in sum.iter_mut().enumerate() {
                                    *v += u32::from(prev[o + c]);
                                }
                                cnt += 1;
                            }
                        }
                    }
                    out.extend(sum.map(|s| ((s + cnt / 2) / cnt) as u8));
                }
            }
        }
        levels.push(out);
    }
    let normal_levels = normals.then(|| {
        levels
            .iter()
            .map(|l| {
                l.chunks(4)
                    .flat_map(|t| if t[3] > 0 { [0, 127, 0, 0] } else { [0; 4] })
                    .collect()
            })
            .collect()
    });
    let mut params = std::collections::BTreeMap::new();
    params.insert("res".into(), format!("{}x{}x{}", dims[0], dims[1], dims[2]));
    VolumeAsset {
        header: Header {
            kind: AssetKind::Volume,
            tool: "billow synthetic".into(),
            source: None,
            bounds: Bounds {
                min: [0.0; 3],
                max: [1.0; 3],
            },
            colour_space: ColourSpace::LinearPremultiplied,
            seed: None,
            params,
            volume: Some(VolumeHeader {
                dims,
                mip_count: mips,
                texel: TexelFormat::Rgba8Unorm,
                normals: normals.then_some(NormalEncoding::Rgba8Snorm),
            }),
        },
        levels,
        normals: normal_levels,
        cells: box_prisms(Vec3::ZERO, Vec3::ONE).to_vec(),
    }
}
