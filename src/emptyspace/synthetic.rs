//! Small synthetic volume assets for tests, examples and docs: a level-0 texel function,
//! box-filtered MIPs (odd sizes by the voxelizer's rule: parent `j` averages children
//! `floor(j·r) ..` with `r = n / (n >> 1)`, rounded to whole texels — good enough for a
//! test volume), one box cell over `[0, 1]³`.

use billow_format::{full_mip_count, mip_dims, ColourSpace, Header, NormalEncoding, VolumeAsset};
use glam::Vec3;

use billow_core::cells::box_prisms;

/// Level `pd` from level `cd` by the rule in the module docs; `signed`: bytes are i8.
fn box_filter(prev: &[u8], cd: [u32; 3], pd: [u32; 3], signed: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(pd.iter().product::<u32>() as usize * 4);
    let span = |j: u32, a: usize| {
        let (n, p) = (cd[a], pd[a]);
        let lo = (j as u64 * n as u64 / p as u64) as u32;
        let hi = (((j + 1) as u64 * n as u64).div_ceil(p as u64) as u32).max(lo + 1);
        lo..hi.min(n)
    };
    let val = |b: u8| {
        if signed {
            i32::from(b as i8)
        } else {
            i32::from(b)
        }
    };
    for z in 0..pd[2] {
        for y in 0..pd[1] {
            for x in 0..pd[0] {
                let (mut sum, mut cnt) = ([0i32; 4], 0i32);
                for cz in span(z, 2) {
                    for cy in span(y, 1) {
                        for cx in span(x, 0) {
                            let o = 4 * (cx + cd[0] * (cy + cd[1] * cz)) as usize;
                            for (c, v) in sum.iter_mut().enumerate() {
                                *v += val(prev[o + c]);
                            }
                            cnt += 1;
                        }
                    }
                }
                out.extend(sum.map(|s| {
                    let m = (f64::from(s) / f64::from(cnt)).round() as i32;
                    if signed {
                        (m as i8) as u8
                    } else {
                        m as u8
                    }
                }));
            }
        }
    }
    out
}

/// Replaces the normals of a [`volume_from_fn`] volume by `nf(x, y, z)` (snorm xyz) at
/// every level-0 texel with alpha > 0 (0 elsewhere), box-filtered down the chain like the
/// colour: a normal field whose texels all differ, to check where normals land.
pub fn set_normal_field(asset: &mut VolumeAsset, nf: impl Fn(u32, u32, u32) -> [i8; 3]) {
    let dims = asset.level_dims(0);
    let mut l0 = Vec::with_capacity(asset.levels[0].len());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let o = 4 * (x + dims[0] * (y + dims[1] * z)) as usize;
                let n = if asset.levels[0][o + 3] > 0 {
                    nf(x, y, z)
                } else {
                    [0; 3]
                };
                l0.extend([n[0] as u8, n[1] as u8, n[2] as u8, 0]);
            }
        }
    }
    let mut levels = vec![l0];
    for l in 1..asset.levels.len() as u32 {
        let next = box_filter(
            &levels[(l - 1) as usize],
            mip_dims(dims, l - 1),
            mip_dims(dims, l),
            true,
        );
        levels.push(next);
    }
    asset.normals = Some(levels);
    asset.header.volume.as_mut().expect("volume").normals = Some(NormalEncoding::Rgba8Snorm);
}

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
        let next = box_filter(
            &levels[(l - 1) as usize],
            mip_dims(dims, l - 1),
            mip_dims(dims, l),
            false,
        );
        levels.push(next);
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
            params,
            ..Header::volume(
                "billow synthetic",
                ColourSpace::LinearPremultiplied,
                dims,
                mips,
                normals,
            )
        },
        levels,
        normals: normal_levels,
        bands: Vec::new(),
        cells: box_prisms(Vec3::ZERO, Vec3::ONE).to_vec(),
    }
}
