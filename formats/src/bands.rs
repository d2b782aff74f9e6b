//! LOD bands of a Volume asset (format 1.1, SPEC.md §8.6): extra textures, each with its
//! own MIP chain and cells, that a renderer draws instead of the base texture on the
//! slices whose level of detail falls in the band.
//!
//! Chunks (only in files that have bands):
//! - `VBND` × 1, element `U32`: one 32-byte record per band, in band order:
//!   `first_level, dims.x, dims.y, dims.z, mip_count, 0, 0, 0`;
//! - `BLEV` × Σ `mip_count`, element `U8`: band 1's colour levels 0.., then band 2's, …;
//! - `BNRM` × Σ `mip_count`, element `I8`, iff `volume.normals`: normals likewise
//!   (`BMOM`, format 1.4, iff `volume.moments`: normal moments likewise);
//! - `BCEL` × number of bands, element `F32`: each band's prisms ([`PRISM_BYTES`] each).

use crate::blocks::{check_block_levels, decode_levels, unorm_to_snorm_in_place, BandBlocks};
use crate::error::tag_str;
use crate::grid::{check_level_sizes, full_mip_count, mip_dims, Prism, MAX_DIM, PRISM_BYTES};
use crate::normal_tags::NormalTags;
pub use crate::normal_tags::{TAG_BMOM, TAG_BNRM};
use crate::{FormatError, NormalKind};

/// Tag of the band table chunk.
pub const TAG_VBND: [u8; 4] = *b"VBND";
/// Tag of a band colour level chunk.
pub const TAG_BLEV: [u8; 4] = *b"BLEV";
/// Tag of a band's prism chunk.
pub const TAG_BCEL: [u8; 4] = *b"BCEL";
/// Bytes per `VBND` record: 8 little-endian u32.
pub const BAND_RECORD_BYTES: usize = 32;
/// Largest allowed `first_level` of a band.
pub const MAX_FIRST_LEVEL: u32 = 16;

/// One extra level-of-detail band (SPEC §8.6). Band 0 is the asset's base texture and
/// cells (`VLEV`/`VNRM`/`CELL`), with first level 0.
#[derive(Clone, Debug, PartialEq)]
pub struct LodBand {
    /// The slice LOD at which this band takes over from the previous one; it samples its
    /// own texture at `λ − first_level`.
    pub first_level: u32,
    /// Level-0 size of the band's texture.
    pub dims: [u32; 3],
    /// Colour levels, `mip_dims(dims, i)` each; `mip_count = levels.len()`.
    pub levels: Vec<Vec<u8>>,
    /// Normal levels, present iff the header's `volume.normals` (mean normals) or
    /// `volume.moments` (normal moments, format 1.4) is set.
    pub normals: Option<Vec<Vec<u8>>>,
    pub cells: Vec<Prism>,
}

impl LodBand {
    pub fn mip_count(&self) -> u32 {
        self.levels.len() as u32
    }
}

fn bad<T>(m: String) -> Result<T, FormatError> {
    Err(FormatError::Volume(m))
}

/// Checks `bands` after a base texture of `base_mips` levels (`kind`: the normal texels
/// the header declares).
pub(crate) fn validate_bands(
    bands: &[LodBand],
    base_mips: u32,
    kind: Option<NormalKind>,
) -> Result<(), FormatError> {
    let normals = kind.is_some();
    let nrm = tag_str(&NormalTags::of(kind).band);
    let (mut prev_first, mut prev_mips) = (0u32, base_mips);
    for (i, b) in bands.iter().enumerate() {
        let n = i + 1;
        if b.first_level <= prev_first || b.first_level > MAX_FIRST_LEVEL {
            return bad(format!(
                "band {n}: first_level {} must be in {}..={MAX_FIRST_LEVEL}",
                b.first_level,
                prev_first + 1
            ));
        }
        if prev_mips < b.first_level - prev_first + 1 {
            return bad(format!(
                "band {n} starts at level {} but band {} (first level {prev_first}) has only {prev_mips} levels; it needs {}",
                b.first_level,
                n - 1,
                b.first_level - prev_first + 1
            ));
        }
        if b.dims.iter().any(|&d| d == 0 || d > MAX_DIM) {
            return bad(format!(
                "band {n}: dims {:?} must each be in 1..={MAX_DIM}",
                b.dims
            ));
        }
        let m = b.mip_count();
        let full = full_mip_count(b.dims);
        if m == 0 || m > full {
            return bad(format!(
                "band {n}: {m} levels, must be in 1..={full} for dims {:?}",
                b.dims
            ));
        }
        check_level_sizes(&format!("band {n} BLEV"), &b.levels, b.dims)?;
        match (&b.normals, normals) {
            (Some(l), true) => {
                if l.len() != b.levels.len() {
                    return bad(format!(
                        "band {n}: {} {nrm} levels but {m} BLEV levels",
                        l.len()
                    ));
                }
                check_level_sizes(&format!("band {n} {nrm}"), l, b.dims)?;
            }
            (None, false) => {}
            (Some(_), false) => {
                return bad(format!(
                "band {n} has normals but neither header.volume.normals nor volume.moments is set"
            ))
            }
            (None, true) => {
                return bad(format!(
                    "band {n} has no normals but header.{} is set",
                    NormalTags::field(kind.expect("normals"))
                ))
            }
        }
        for (k, p) in b.cells.iter().enumerate() {
            if !p
                .pos
                .iter()
                .chain(p.uvw.iter())
                .flatten()
                .all(|c| c.is_finite())
            {
                return bad(format!("band {n}: prism {k} has a non-finite coordinate"));
            }
        }
        prev_first = b.first_level;
        prev_mips = m;
    }
    Ok(())
}

/// The `VBND` payload.
pub(crate) fn band_table(bands: &[LodBand]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bands.len() * BAND_RECORD_BYTES);
    for b in bands {
        for v in [
            b.first_level,
            b.dims[0],
            b.dims[1],
            b.dims[2],
            b.mip_count(),
            0,
            0,
            0,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Band chunks collected by tag while reading, in file order.
#[derive(Default)]
pub(crate) struct RawBands {
    pub table: Option<Vec<u8>>,
    pub levels: Vec<Vec<u8>>,
    pub normals: Vec<Vec<u8>>,
    pub cells: Vec<Vec<u8>>,
    /// `BLB7` and `BNB7` (or `BMB7`) payloads (format 1.3), instead of `BLEV`/`BNRM`.
    pub bc_levels: Vec<Vec<u8>>,
    pub bc_normals: Vec<Vec<u8>>,
}

impl RawBands {
    fn is_empty(&self) -> bool {
        self.table.is_none()
            && self.levels.is_empty()
            && self.normals.is_empty()
            && self.cells.is_empty()
            && self.bc_levels.is_empty()
            && self.bc_normals.is_empty()
    }

    /// Splits the collected chunks into bands (sizes are checked by [`validate_bands`]),
    /// decoding compressed levels (`BLB7`/`BNB7`); returns their blocks too, if any.
    /// `kind`: the normal texels the header declares (which names the normal chunks).
    pub(crate) fn into_bands(
        mut self,
        kind: Option<NormalKind>,
    ) -> Result<(Vec<LodBand>, Option<Vec<BandBlocks>>), FormatError> {
        if self.is_empty() {
            return Ok((Vec::new(), None));
        }
        let normals = kind.is_some();
        let tags = NormalTags::of(kind);
        let (band, band_bc) = (tag_str(&tags.band), tag_str(&tags.band_bc));
        let compressed = !self.bc_levels.is_empty() || !self.bc_normals.is_empty();
        if compressed {
            if !self.levels.is_empty() || !self.normals.is_empty() {
                return bad(format!(
                    "both raw (BLEV/{band}) and compressed (BLB7/{band_bc}) band levels: compressed bands store all their levels as blocks"
                ));
            }
            self.levels = std::mem::take(&mut self.bc_levels);
            self.normals = std::mem::take(&mut self.bc_normals);
        }
        let (lev_tag, nrm_tag) = if compressed {
            ("BLB7", band_bc.as_str())
        } else {
            ("BLEV", band.as_str())
        };
        let Some(table) = self.table else {
            return bad(format!(
                "BLEV/{band}/BLB7/{band_bc}/BCEL chunks without a VBND band table"
            ));
        };
        if table.is_empty() || !table.len().is_multiple_of(BAND_RECORD_BYTES) {
            return bad(format!(
                "VBND length {} is not a positive multiple of the {BAND_RECORD_BYTES}-byte record",
                table.len()
            ));
        }
        let recs: Vec<[u32; 8]> = table
            .chunks_exact(BAND_RECORD_BYTES)
            .map(|r| {
                std::array::from_fn(|i| {
                    u32::from_le_bytes(r[4 * i..4 * i + 4].try_into().expect("4 bytes"))
                })
            })
            .collect();
        let mut want_levels = 0u64;
        for (i, r) in recs.iter().enumerate() {
            if r[5..].iter().any(|&v| v != 0) {
                return bad(format!(
                    "VBND record {} has non-zero reserved fields",
                    i + 1
                ));
            }
            if r[4] == 0 || r[4] > 32 {
                return bad(format!(
                    "VBND record {}: mip_count {} not in 1..=32",
                    i + 1,
                    r[4]
                ));
            }
            want_levels += u64::from(r[4]);
        }
        if self.levels.len() as u64 != want_levels {
            return bad(format!(
                "{} {lev_tag} chunks but the bands have {want_levels} levels",
                self.levels.len()
            ));
        }
        let want_normals = if normals { want_levels } else { 0 };
        if self.normals.len() as u64 != want_normals {
            return bad(format!(
                "{} {nrm_tag} chunks, expected {want_normals}",
                self.normals.len()
            ));
        }
        if self.cells.len() != recs.len() {
            return bad(format!(
                "{} BCEL chunks for {} bands",
                self.cells.len(),
                recs.len()
            ));
        }
        let mut levels = self.levels.into_iter();
        let mut nrm = self.normals.into_iter();
        let mut out = Vec::with_capacity(recs.len());
        let mut blocks = Vec::new();
        for (n, (r, cells)) in recs.iter().zip(self.cells).enumerate() {
            if !cells.len().is_multiple_of(PRISM_BYTES) {
                return bad(format!(
                    "BCEL length {} is not a multiple of the {PRISM_BYTES}-byte prism",
                    cells.len()
                ));
            }
            let m = r[4] as usize;
            let dims = [r[1], r[2], r[3]];
            let mut band_levels: Vec<Vec<u8>> = levels.by_ref().take(m).collect();
            let mut band_normals: Option<Vec<Vec<u8>>> =
                normals.then(|| nrm.by_ref().take(m).collect());
            if compressed {
                if dims.iter().any(|&d| d == 0 || d > MAX_DIM) || m as u32 > full_mip_count(dims) {
                    return bad(format!(
                        "band {}: dims {dims:?} with {m} levels cannot hold BC7 levels",
                        n + 1
                    ));
                }
                let dims_of = |i| mip_dims(dims, i);
                let what = format!("band {} BLB7", n + 1);
                check_block_levels(&what, &band_levels, dims_of).map_err(FormatError::Volume)?;
                let colour = std::mem::take(&mut band_levels);
                band_levels = decode_levels(&colour, dims_of, 0);
                let nb = match band_normals.take() {
                    Some(nb) => {
                        let what = format!("band {} {nrm_tag}", n + 1);
                        check_block_levels(&what, &nb, dims_of).map_err(FormatError::Volume)?;
                        let mut dec = decode_levels(&nb, dims_of, 0x80);
                        dec.iter_mut().for_each(|l| unorm_to_snorm_in_place(l));
                        band_normals = Some(dec);
                        Some(nb)
                    }
                    None => None,
                };
                blocks.push(BandBlocks {
                    colour,
                    normals: nb,
                });
            }
            out.push(LodBand {
                first_level: r[0],
                dims,
                levels: band_levels,
                normals: band_normals,
                cells: cells
                    .chunks_exact(PRISM_BYTES)
                    .map(Prism::read_le)
                    .collect(),
            });
        }
        Ok((out, compressed.then_some(blocks)))
    }
}
