//! What a renderer holds on the GPU for an asset: the texture bytes `billow view` allocates
//! (`viewer/src/volume_pass/textures.rs` and `viewer/src/cloud_pass/upload.rs` upload by these
//! rules, and `viewer/tests/gpu_memory.rs` checks the sums against the textures they
//! create), on a device with BC7 support and on one without.
//!
//! - **Volumes.** The colour of every level of the base texture and of each LOD band:
//!   the asset's BC7 blocks where it stores them and the device samples them (16 bytes per
//!   4×4 block of every level: GPU block textures are dense, so the blocks a file omits
//!   are uploaded as zero blocks), else `Rgba16Float` texels in extinction space, 8 bytes
//!   each ([`VOLUME_TEXEL_BYTES`]). Normals, where stored, are `(α·n̄, α)` in
//!   `Rgba8Snorm` ([`VOLUME_NORMAL_TEXEL_BYTES`]) with or without BC: the file's normals
//!   are snorm8 already; the alpha-weighted filter's division by a small filtered alpha
//!   is coarse only where the texel is faint (measured in docs/viewer.md, "Runtime
//!   shading").
//! - **Clouds.** Each atlas with its stored MIP levels: BC7 blocks, or RGBA8 (4 bytes per
//!   texel); its normal map when the cloud is lit at runtime (baked unlit with normal
//!   maps), the same way; each mesh texture RGBA8 with a full MIP chain (the viewer builds
//!   it), whatever the device, once: the foliage mesh and every instance's kept mesh (a
//!   trunk) share it.
//!
//! Vertex, index and uniform buffers are not counted: they are small beside the textures
//! (a cloud's billboards are 4 vertices each).

use billow_format::{bc7_len, mip_dims, CloudAsset, VolumeAsset};

/// Bytes per texel of a volume's colour texture when it is not uploaded as BC7 blocks
/// (`Rgba16Float`, extinction space).
pub const VOLUME_TEXEL_BYTES: u64 = 8;
/// Bytes per texel of a volume's normal texture (`Rgba8Snorm`, `(α·n̄, α)`).
pub const VOLUME_NORMAL_TEXEL_BYTES: u64 = 4;
/// Bytes per texel of an uncompressed cloud texture (RGBA8).
pub const CLOUD_TEXEL_BYTES: u64 = 4;

/// GPU texture bytes of one asset, on a device that samples BC7 blocks and on one that
/// does not (which gets every texture decoded; `billow view` also decodes on software
/// adapters, where block fetches are slow).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuBytes {
    pub with_bc: u64,
    pub without_bc: u64,
}

impl GpuBytes {
    fn add(&mut self, with_bc: u64, without_bc: u64) {
        self.with_bc += with_bc;
        self.without_bc += without_bc;
    }
}

fn texels(d: [u32; 3]) -> u64 {
    d.iter().map(|&v| u64::from(v)).product()
}

/// Texels of `levels` MIP levels of a texture of level-0 size `dims0`.
fn chain_texels(dims0: [u32; 3], levels: usize) -> u64 {
    (0..levels as u32).map(|l| texels(mip_dims(dims0, l))).sum()
}

/// Dense BC7 bytes of `levels` MIP levels of a texture of level-0 size `dims0`.
fn chain_blocks(dims0: [u32; 3], levels: usize) -> u64 {
    (0..levels as u32)
        .map(|l| {
            let d = mip_dims(dims0, l);
            bc7_len(d[0], d[1], d[2])
        })
        .sum()
}

/// What `billow view` holds for `asset` (`compressed`: the file stores its textures as
/// BC7 blocks, `--compress bc`, as every billow bake does for the base texture and, since
/// format 1.3, for the LOD bands).
pub fn volume_gpu_bytes(asset: &VolumeAsset, compressed: bool) -> GpuBytes {
    let mut out = GpuBytes::default();
    // Normal moments are sampled as the file's BC7 blocks where the colour is (mean normals
    // are weighted by alpha on upload, so they are decoded).
    let moments = asset.has_moments();
    let mut texture = |dims: [u32; 3], levels: usize, has_normals: bool, compressed: bool| {
        let raw = VOLUME_TEXEL_BYTES * chain_texels(dims, levels);
        let colour = if compressed {
            chain_blocks(dims, levels)
        } else {
            raw
        };
        let decoded = VOLUME_NORMAL_TEXEL_BYTES * chain_texels(dims, levels);
        let (with_bc, without) = match (has_normals, moments && compressed) {
            (false, _) => (0, 0),
            (true, true) => (chain_blocks(dims, levels), decoded),
            (true, false) => (decoded, decoded),
        };
        out.add(colour + with_bc, raw + without);
    };
    texture(
        asset.level_dims(0),
        asset.levels.len(),
        asset.normals.is_some(),
        compressed,
    );
    for b in &asset.bands {
        texture(b.dims, b.levels.len(), b.normals.is_some(), compressed);
    }
    out
}

/// What `billow view` holds for `asset` (`compressed`: the file stores its atlases and
/// normal maps as BC7 blocks).
pub fn cloud_gpu_bytes(asset: &CloudAsset, compressed: bool) -> GpuBytes {
    let mut out = GpuBytes::default();
    let dims = |a: &billow_format::Atlas| [a.width, a.height, 1];
    for a in &asset.atlases {
        let raw = CLOUD_TEXEL_BYTES * chain_texels(dims(a), a.mips.len());
        let bc = if compressed {
            chain_blocks(dims(a), a.mips.len())
        } else {
            raw
        };
        out.add(bc, raw);
    }
    // Normal maps are drawn only by a cloud baked unlit (lit at runtime).
    let runtime_lit = asset.header.baked_light().is_ok_and(|l| l.is_unlit())
        && !asset.atlases.is_empty()
        && asset.atlases.iter().all(|a| a.normals.is_some());
    if runtime_lit {
        for a in &asset.atlases {
            let n = a.normals.as_ref().map_or(0, |n| n.len());
            let raw = CLOUD_TEXEL_BYTES * chain_texels(dims(a), n);
            out.add(
                if compressed {
                    chain_blocks(dims(a), n)
                } else {
                    raw
                },
                raw,
            );
        }
    }
    for t in &asset.textures {
        let full = 32 - t.width.max(t.height).max(1).leading_zeros();
        let b = CLOUD_TEXEL_BYTES * chain_texels([t.width, t.height, 1], full as usize);
        out.add(b, b);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 12×8×4 volume with 3 levels: its texels and 4×4 blocks over every level.
    #[test]
    fn volume_bytes_count_every_level() {
        let dims = [12u32, 8, 4];
        let t: u64 = (0..3).map(|l| texels(mip_dims(dims, l))).sum();
        assert_eq!(t, 12 * 8 * 4 + 6 * 4 * 2 + 3 * 2);
        let b = chain_blocks(dims, 3);
        // 3×2 blocks × 4 slices, 2×1 × 2, 1×1 × 1.
        assert_eq!(b, 16 * (3 * 2 * 4 + 2 * 2 + 1));
        assert_eq!(chain_texels([5, 3, 1], 3), 15 + 2 + 1);
    }
}
