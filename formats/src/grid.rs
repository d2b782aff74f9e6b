//! The volume grid's geometry, shared by the plain volume (`volume`) and its LOD bands
//! (`bands`): the size limit, MIP level sizes, texel bytes and the prism cells. A leaf:
//! it imports no other module of the format but its error.

use crate::FormatError;

/// Largest allowed size of level 0 along any axis.
pub const MAX_DIM: u32 = 4096;
/// Bytes per colour or normal texel.
pub const TEXEL_BYTES: u64 = 4;
/// Bytes per prism in a `CELL` chunk: 36 little-endian f32.
pub const PRISM_BYTES: usize = 144;

/// A triangular prism cell mapping a slab of the volume texture into the world.
/// Vertices 0,1,2 are the bottom triangle, 3,4,5 the top one, vertex 3 above
/// 0, 4 above 1, 5 above 2. Seen from the top, 0→1→2 is counter-clockwise
/// (the bottom triangle's right-handed normal points towards the top). A box
/// is two prisms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prism {
    /// World-space vertex positions.
    pub pos: [[f32; 3]; 6],
    /// Texture coordinates in `[0,1]³` of the volume (u along x, v along y, w along z).
    pub uvw: [[f32; 3]; 6],
}

impl Prism {
    pub(crate) fn write_le(&self, out: &mut Vec<u8>) {
        for v in self.pos.iter().chain(self.uvw.iter()) {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }

    pub(crate) fn read_le(b: &[u8]) -> Prism {
        let f = |i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().expect("4 bytes"));
        let v = |k: usize| [f(3 * k), f(3 * k + 1), f(3 * k + 2)];
        Prism {
            pos: std::array::from_fn(v),
            uvw: std::array::from_fn(|k| v(6 + k)),
        }
    }
}

/// Size of MIP level `level`: `max(1, d >> level)` per axis.
pub fn mip_dims(dims0: [u32; 3], level: u32) -> [u32; 3] {
    dims0.map(|d| d.checked_shr(level).unwrap_or(0).max(1))
}

/// Number of levels from `dims0` down to 1×1×1 inclusive: `floor(log2(max d)) + 1`.
pub fn full_mip_count(dims0: [u32; 3]) -> u32 {
    let m = dims0.iter().copied().max().unwrap_or(1).max(1);
    32 - m.leading_zeros()
}

fn level_bytes(dims: [u32; 3]) -> u64 {
    dims.iter().map(|&d| u64::from(d)).product::<u64>() * TEXEL_BYTES
}

fn bad<T>(m: String) -> Result<T, FormatError> {
    Err(FormatError::Volume(m))
}

/// The `CELL` chunk's bytes of `cells` ([`PRISM_BYTES`] each, little-endian).
pub(crate) fn prism_bytes(cells: &[Prism]) -> Vec<u8> {
    let mut out = Vec::with_capacity(cells.len() * PRISM_BYTES);
    for p in cells {
        p.write_le(&mut out);
    }
    out
}

/// Each level `i` of `levels` holds exactly `mip_dims(dims, i)` texels.
pub(crate) fn check_level_sizes(
    tag: &str,
    levels: &[Vec<u8>],
    dims: [u32; 3],
) -> Result<(), FormatError> {
    for (i, l) in levels.iter().enumerate() {
        let d = mip_dims(dims, i as u32);
        let want = level_bytes(d);
        if l.len() as u64 != want {
            return bad(format!(
                "{tag} level {i} is {} bytes, expected {want} ({}x{}x{} texels x 4)",
                l.len(),
                d[0],
                d[1],
                d[2]
            ));
        }
    }
    Ok(())
}
