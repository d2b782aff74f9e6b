//! The typed Volume asset (volumetric billboard) on top of the container.
//!
//! Chunks, in the order the writer emits them:
//! - `VLEV` × `mip_count`, element `U8`: colour texels of level 0, 1, …
//! - `VNRM` × `mip_count`, element `I8`, iff `volume.normals` is set: normals per level;
//!   `VMOM` instead iff `volume.moments` is set (format 1.4): normal moments per level.
//! - `CELL` × 1, element `F32`: the prisms, [`PRISM_BYTES`] each.
//! - LOD bands, format 1.1, only when [`VolumeAsset::bands`] is not empty: `VBND`,
//!   `BLEV`…, `BNRM`… (or `BMOM`…), `BCEL`… ([`crate::bands`]).
//!
//! [`VolumeAsset::normals`] holds the normal texels whichever kind the header declares
//! ([`VolumeHeader::normal_kind`]); the reader and writer pick the tags from it
//! ([`NormalTags`]).

use std::path::Path;

use crate::bands::{band_table, validate_bands, LodBand, RawBands};
use crate::bands::{TAG_BCEL, TAG_BLEV, TAG_VBND};
use crate::blocks::TAG_BLB7;
use crate::blocks::{
    check_block_levels, decode_levels, unorm_to_snorm_in_place, VolumeBlocks, TAG_VLB7,
};
use crate::container::{encode_with_minor, with_parts_minor, write_with_minor, ChunkRef};
use crate::grid::{
    check_level_sizes, full_mip_count, mip_dims, prism_bytes, Prism, MAX_DIM, PRISM_BYTES,
};
use crate::normal_tags::NormalTags;
pub use crate::normal_tags::{TAG_VMOM, TAG_VNRM};
use crate::{
    from_bytes, AssetKind, Chunk, Container, ElemType, FormatError, Header, NormalKind,
    TexelFormat, VolumeHeader,
};

/// Tag of a colour MIP level chunk (one per level, in level order).
pub const TAG_VLEV: [u8; 4] = *b"VLEV";
/// Tag of the prism cell chunk (exactly one).
pub const TAG_CELL: [u8; 4] = *b"CELL";

/// Refuses normal chunk `tag` in a volume whose header declares normal texels `declared`:
/// a chunk of the other kind (`VNRM` in a moments volume, `VMOM` in one of mean normals)
/// or of either kind when the header declares none.
fn check_normal_tag(tag: &[u8; 4], declared: Option<NormalKind>) -> Result<(), FormatError> {
    let Some(kind) = NormalTags::kind_of_tag(tag) else {
        return Ok(());
    };
    if declared == Some(kind) {
        return Ok(());
    }
    let t = crate::error::tag_str(tag);
    match declared {
        None => bad(format!(
            "{t} chunks present but header.{} is None",
            NormalTags::field(kind)
        )),
        Some(d) => bad(format!(
            "{t} chunk in a volume whose header sets {} (its normal texels are {} chunks, not {t})",
            NormalTags::field(d),
            crate::error::tag_str(&NormalTags::of(Some(d)).base)
        )),
    }
}

/// A volumetric billboard asset.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeAsset {
    /// `kind == Volume`, `volume: Some(..)`.
    pub header: Header,
    /// MIP level i: RGBA8 texels, x fastest then y then z, `mip_dims(dims, i)`.
    pub levels: Vec<Vec<u8>>,
    /// Normals per level, same layout, 4 bytes (i8) per texel: mean normals (`VNRM`) or
    /// normal moments (`VMOM`, format 1.4) as the header says
    /// ([`VolumeHeader::normal_kind`]).
    pub normals: Option<Vec<Vec<u8>>>,
    pub cells: Vec<Prism>,
    /// Extra LOD bands (format 1.1, SPEC §8.6), finest first; empty for an ordinary volume.
    pub bands: Vec<LodBand>,
}

fn bad<T>(m: String) -> Result<T, FormatError> {
    Err(FormatError::Volume(m))
}

impl VolumeAsset {
    /// Size of MIP level `level`; `[0, 0, 0]` if the header has no volume part.
    pub fn level_dims(&self, level: u32) -> [u32; 3] {
        self.header
            .volume
            .map_or([0; 3], |v| mip_dims(v.dims, level))
    }

    /// The kind of normal texels the header declares (`normals` holds them), `None` for a
    /// volume without normals.
    pub fn normal_kind(&self) -> Option<NormalKind> {
        self.header.volume.and_then(|v| v.normal_kind())
    }

    /// Whether the normals are second moments (SPEC §8.4a), lit two-sided.
    pub fn has_moments(&self) -> bool {
        self.normal_kind() == Some(NormalKind::Moments)
    }

    /// Check the asset against its header and the format rules.
    pub fn validate(&self) -> Result<(), FormatError> {
        self.header.validate()?;
        if self.header.kind != AssetKind::Volume {
            return bad(format!("header kind is {:?}, not Volume", self.header.kind));
        }
        let Some(v) = self.header.volume else {
            return bad("header has no `volume` section".into());
        };
        validate_volume_header(&v)?;
        check_levels("VLEV", &self.levels, v)?;
        let kind = v.normal_kind();
        let base_tag = crate::error::tag_str(&NormalTags::of(kind).base);
        match (&self.normals, kind) {
            (Some(n), Some(_)) => check_levels(&base_tag, n, v)?,
            (None, None) => {}
            (Some(_), None) => {
                return bad(
                    "normals given but neither header.volume.normals nor volume.moments is set"
                        .into(),
                )
            }
            (None, Some(k)) => {
                return bad(format!(
                    "header.{} is set but no normals given",
                    NormalTags::field(k)
                ))
            }
        }
        for (i, p) in self.cells.iter().enumerate() {
            if !p
                .pos
                .iter()
                .chain(p.uvw.iter())
                .flatten()
                .all(|c| c.is_finite())
            {
                return bad(format!("CELL prism {i} has a non-finite coordinate"));
            }
        }
        validate_bands(&self.bands, v.mip_count, kind)
    }

    /// The largest slice LOD a renderer uses (SPEC §8.6): `mip_count − 1` for an ordinary
    /// volume, the last band's `first_level + mip_count − 1` otherwise.
    pub fn max_lod(&self) -> u32 {
        match self.bands.last() {
            Some(b) => b.first_level + b.mip_count() - 1,
            None => self.header.volume.map_or(1, |v| v.mip_count) - 1,
        }
    }

    /// Texel bytes of every colour and normal level of the base texture and every band.
    pub fn texel_bytes(&self) -> u64 {
        let sum = |l: &[Vec<u8>]| l.iter().map(|x| x.len() as u64).sum::<u64>();
        let mut n = sum(&self.levels) + self.normals.as_deref().map_or(0, sum);
        for b in &self.bands {
            n += sum(&b.levels) + b.normals.as_deref().map_or(0, sum);
        }
        n
    }

    fn with_chunks<R>(
        &self,
        blocks: Option<&VolumeBlocks>,
        f: impl FnOnce(&[ChunkRef<'_>]) -> R,
    ) -> Result<R, FormatError> {
        self.validate()?;
        if let Some(b) = blocks {
            self.check_blocks(b)?;
        }
        let (colour, colour_tag) = match blocks {
            Some(b) => (&b.colour, TAG_VLB7),
            None => (&self.levels, TAG_VLEV),
        };
        let tags = NormalTags::of(self.header.volume.and_then(|v| v.normal_kind()));
        let (normals, normal_tag) = match blocks {
            Some(b) => (&b.normals, tags.base_bc),
            None => (&self.normals, tags.base),
        };
        let cells = prism_bytes(&self.cells);
        let table = band_table(&self.bands);
        let band_cells: Vec<Vec<u8>> = self.bands.iter().map(|b| prism_bytes(&b.cells)).collect();
        let mut refs: Vec<ChunkRef<'_>> = colour
            .iter()
            .map(|l| ChunkRef {
                tag: colour_tag,
                elem: ElemType::U8,
                data: l,
            })
            .collect();
        for n in normals.iter().flatten() {
            refs.push(ChunkRef {
                tag: normal_tag,
                elem: if blocks.is_some() {
                    ElemType::U8
                } else {
                    ElemType::I8
                },
                data: n,
            });
        }
        refs.push(ChunkRef {
            tag: TAG_CELL,
            elem: ElemType::F32,
            data: &cells,
        });
        if !self.bands.is_empty() {
            refs.push(ChunkRef {
                tag: TAG_VBND,
                elem: ElemType::U32,
                data: &table,
            });
            match blocks.filter(|b| !b.bands.is_empty()) {
                Some(b) => {
                    for l in b.bands.iter().flat_map(|b| &b.colour) {
                        refs.push(ChunkRef {
                            tag: TAG_BLB7,
                            elem: ElemType::U8,
                            data: l,
                        });
                    }
                    for l in b.bands.iter().flat_map(|b| b.normals.iter().flatten()) {
                        refs.push(ChunkRef {
                            tag: tags.band_bc,
                            elem: ElemType::U8,
                            data: l,
                        });
                    }
                }
                None => {
                    for l in self.bands.iter().flat_map(|b| &b.levels) {
                        refs.push(ChunkRef {
                            tag: TAG_BLEV,
                            elem: ElemType::U8,
                            data: l,
                        });
                    }
                    for l in self.bands.iter().flat_map(|b| b.normals.iter().flatten()) {
                        refs.push(ChunkRef {
                            tag: tags.band,
                            elem: ElemType::I8,
                            data: l,
                        });
                    }
                }
            }
            for c in &band_cells {
                refs.push(ChunkRef {
                    tag: TAG_BCEL,
                    elem: ElemType::F32,
                    data: c,
                });
            }
        }
        Ok(f(&refs))
    }

    /// The container for this asset (validates first).
    pub fn to_container(&self) -> Result<Container, FormatError> {
        self.with_chunks(None, |refs| Container {
            header: self.header.clone(),
            chunks: refs
                .iter()
                .map(|r| Chunk {
                    tag: r.tag,
                    elem: r.elem,
                    data: r.data.to_vec(),
                })
                .collect(),
        })
    }

    /// Encode to file bytes without copying the texel data into a [`Container`] first.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FormatError> {
        self.to_bytes_with(None)
    }

    /// [`VolumeAsset::to_bytes`] storing the base texture as the BC7 `blocks` (format 1.2,
    /// SPEC §12) instead of raw texels when given. `blocks` must decode to `levels` and
    /// `normals` (what a reader gets back); only their sizes are checked here.
    pub fn to_bytes_with(&self, blocks: Option<&VolumeBlocks>) -> Result<Vec<u8>, FormatError> {
        // The minor follows from the chunk tags (SPEC §5: 1.1 for bands, 1.2 for blocks, 1.3
        // for band blocks, 1.4 for normal moments).
        self.with_chunks(blocks, |refs| encode_with_minor(&self.header, refs, 0))?
    }

    /// Whether `blocks` has the shape of this asset's base texture (sizes only).
    fn check_blocks(&self, b: &VolumeBlocks) -> Result<(), FormatError> {
        let dims = self.level_dims(0);
        if b.colour.len() != self.levels.len() {
            return bad(format!(
                "{} colour block levels for {} levels",
                b.colour.len(),
                self.levels.len()
            ));
        }
        check_block_levels("VLB7", &b.colour, |i| mip_dims(dims, i))
            .map_err(FormatError::Volume)?;
        let tags = NormalTags::of(self.header.volume.and_then(|v| v.normal_kind()));
        let (base_bc, band_bc) = (
            crate::error::tag_str(&tags.base_bc),
            crate::error::tag_str(&tags.band_bc),
        );
        match (&b.normals, &self.normals) {
            (Some(n), Some(l)) if n.len() == l.len() => {
                check_block_levels(&base_bc, n, |i| mip_dims(dims, i))
                    .map_err(FormatError::Volume)?
            }
            (None, None) => {}
            _ => return bad("normal blocks do not match the asset's normals".into()),
        }
        if b.bands.is_empty() {
            return Ok(());
        }
        if b.bands.len() != self.bands.len() {
            return bad(format!(
                "{} band block sets for {} bands",
                b.bands.len(),
                self.bands.len()
            ));
        }
        for (n, (bb, band)) in b.bands.iter().zip(&self.bands).enumerate() {
            let dims_of = |i| mip_dims(band.dims, i);
            if bb.colour.len() != band.levels.len() {
                return bad(format!(
                    "band {}: {} colour block levels for {} levels",
                    n + 1,
                    bb.colour.len(),
                    band.levels.len()
                ));
            }
            check_block_levels(&format!("band {} BLB7", n + 1), &bb.colour, dims_of)
                .map_err(FormatError::Volume)?;
            match (&bb.normals, &band.normals) {
                (Some(nb), Some(l)) if nb.len() == l.len() => {
                    check_block_levels(&format!("band {} {band_bc}", n + 1), nb, dims_of)
                        .map_err(FormatError::Volume)?
                }
                (None, None) => {}
                _ => {
                    return bad(format!(
                        "band {}: normal blocks do not match its normals",
                        n + 1
                    ))
                }
            }
        }
        Ok(())
    }

    /// Decode and validate a volume asset from a container. Chunks with
    /// unknown tags are skipped.
    pub fn from_container(c: Container) -> Result<Self, FormatError> {
        Ok(Self::from_container_with_blocks(c)?.0)
    }

    /// [`VolumeAsset::from_container`] that also returns the BC7 blocks of a compressed
    /// base texture (format 1.2), `None` for raw texels. The asset's `levels` and
    /// `normals` are the decoded blocks either way.
    pub fn from_container_with_blocks(
        c: Container,
    ) -> Result<(Self, Option<VolumeBlocks>), FormatError> {
        let Container { header, chunks } = c;
        if header.kind != AssetKind::Volume {
            return bad(format!("asset kind is {:?}, not Volume", header.kind));
        }
        let Some(v) = header.volume else {
            return bad("header has no `volume` section".into());
        };
        validate_volume_header(&v)?;
        let kind = v.normal_kind();
        let tags = NormalTags::of(kind);
        let (mut levels, mut normals, mut cells) = (Vec::new(), Vec::new(), None);
        let (mut bc_colour, mut bc_normals) = (Vec::new(), Vec::new());
        let mut raw = RawBands::default();
        for (i, ch) in chunks.into_iter().enumerate() {
            // A normal chunk of the kind the header does not declare is an error (SPEC
            // §8.4a), not an unknown chunk to skip.
            check_normal_tag(&ch.tag, kind)?;
            let band_chunk = match &ch.tag {
                b"VBND" => Some((ElemType::U32, None)),
                b"BLEV" => Some((ElemType::U8, Some(&mut raw.levels))),
                b"BNRM" | b"BMOM" => Some((ElemType::I8, Some(&mut raw.normals))),
                b"BLB7" => Some((ElemType::U8, Some(&mut raw.bc_levels))),
                b"BNB7" | b"BMB7" => Some((ElemType::U8, Some(&mut raw.bc_normals))),
                b"BCEL" => Some((ElemType::F32, Some(&mut raw.cells))),
                _ => None,
            };
            if let Some((want, list)) = band_chunk {
                if ch.elem != want {
                    let tag = crate::error::tag_str(&ch.tag);
                    return bad(format!(
                        "{tag} chunk (container chunk {i}) has element type {:?}, expected {want:?}",
                        ch.elem
                    ));
                }
                match list {
                    Some(list) => list.push(ch.data),
                    None if raw.table.is_some() => return bad("more than one VBND chunk".into()),
                    None => raw.table = Some(ch.data),
                }
                continue;
            }
            let (want, list) = match &ch.tag {
                b"VLEV" => (ElemType::U8, &mut levels),
                b"VNRM" | b"VMOM" => (ElemType::I8, &mut normals),
                b"VLB7" => (ElemType::U8, &mut bc_colour),
                b"VNB7" | b"VMB7" => (ElemType::U8, &mut bc_normals),
                b"CELL" => {
                    if ch.elem != ElemType::F32 {
                        return bad(format!(
                            "CELL chunk has element type {:?}, expected F32",
                            ch.elem
                        ));
                    }
                    if cells.is_some() {
                        return bad("more than one CELL chunk".into());
                    }
                    cells = Some(ch.data);
                    continue;
                }
                _ => continue, // unknown chunk from a newer minor version: skip
            };
            if ch.elem != want {
                let tag = crate::error::tag_str(&ch.tag);
                return bad(format!(
                    "{tag} chunk (container chunk {i}) has element type {:?}, expected {want:?}",
                    ch.elem
                ));
            }
            if list.len() as u64 >= u64::from(v.mip_count) {
                let tag = crate::error::tag_str(&ch.tag);
                return bad(format!("more {tag} chunks than mip_count {}", v.mip_count));
            }
            list.push(ch.data);
        }
        let Some(cells) = cells else {
            return bad("missing CELL chunk".into());
        };
        if !cells.len().is_multiple_of(PRISM_BYTES) {
            return bad(format!(
                "CELL length {} is not a multiple of the {PRISM_BYTES}-byte prism",
                cells.len()
            ));
        }
        let (nrm_tag, nb7_tag) = (
            crate::error::tag_str(&tags.base),
            crate::error::tag_str(&tags.base_bc),
        );
        let blocks = if bc_colour.is_empty() && bc_normals.is_empty() {
            None
        } else {
            if !levels.is_empty() || !normals.is_empty() {
                return bad(format!(
                    "both raw (VLEV/{nrm_tag}) and compressed (VLB7/{nb7_tag}) levels: a compressed volume stores all its levels as blocks"
                ));
            }
            let dims_of = |i| mip_dims(v.dims, i);
            let count = |tag: &str, n: usize| {
                if n as u64 == u64::from(v.mip_count) {
                    Ok(())
                } else {
                    bad(format!("{n} {tag} levels but mip_count is {}", v.mip_count))
                }
            };
            count("VLB7", bc_colour.len())?;
            check_block_levels("VLB7", &bc_colour, dims_of).map_err(FormatError::Volume)?;
            levels = decode_levels(&bc_colour, dims_of, 0);
            let bc_normals = match kind {
                None if bc_normals.is_empty() => None,
                None => {
                    return bad(format!(
                        "{nb7_tag} chunks present but header.volume.normals is None"
                    ))
                }
                Some(_) => {
                    count(&nb7_tag, bc_normals.len())?;
                    check_block_levels(&nb7_tag, &bc_normals, dims_of)
                        .map_err(FormatError::Volume)?;
                    normals = decode_levels(&bc_normals, dims_of, 0x80);
                    normals.iter_mut().for_each(|l| unorm_to_snorm_in_place(l));
                    Some(bc_normals)
                }
            };
            Some(VolumeBlocks {
                colour: bc_colour,
                normals: bc_normals,
                bands: Vec::new(),
            })
        };
        let normals = match (kind, normals.is_empty()) {
            (None, true) => None,
            (None, false) => {
                return bad(format!(
                    "{nrm_tag} chunks present but header.volume.normals is None"
                ))
            }
            (Some(_), _) => Some(normals),
        };
        let (bands, band_blocks) = raw.into_bands(kind)?;
        let mut blocks = blocks;
        match (&mut blocks, band_blocks) {
            (_, None) => {}
            (Some(b), Some(bb)) => b.bands = bb,
            (None, Some(_)) => {
                return bad(format!(
                    "compressed band levels (BLB7/{}) but a raw base texture: a file with BLB7 stores its base texture as VLB7/{nb7_tag}",
                    crate::error::tag_str(&tags.band_bc)
                ))
            }
        }
        let asset = VolumeAsset {
            header,
            levels,
            normals,
            cells: cells
                .chunks_exact(PRISM_BYTES)
                .map(Prism::read_le)
                .collect(),
            bands,
        };
        asset.validate()?;
        Ok((asset, blocks))
    }

    /// Decode and validate a volume asset from file bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FormatError> {
        Self::from_container(from_bytes(bytes)?)
    }

    /// [`VolumeAsset::from_bytes`] that also returns the BC7 blocks of a compressed file.
    pub fn from_bytes_with_blocks(
        bytes: &[u8],
    ) -> Result<(Self, Option<VolumeBlocks>), FormatError> {
        Self::from_container_with_blocks(from_bytes(bytes)?)
    }

    /// [`VolumeAsset::read`] that also returns the BC7 blocks of a compressed file.
    pub fn read_with_blocks(path: &Path) -> Result<(Self, Option<VolumeBlocks>), FormatError> {
        Self::from_container_with_blocks(crate::container::read_file(path)?)
            .map_err(|e| e.in_file(path))
    }

    /// Read a volume asset file (streamed, [`crate::read_file`]). Errors carry the path.
    pub fn read(path: &Path) -> Result<Self, FormatError> {
        Self::from_container(crate::container::read_file(path)?).map_err(|e| e.in_file(path))
    }

    /// The bytes of [`VolumeAsset::to_bytes`] as a list of slices (their concatenation is
    /// the file), handed to `f`, the texel data borrowed where it is: for a writer that
    /// streams the file somewhere without assembling it in memory first.
    pub fn with_parts<R>(&self, f: impl FnOnce(&[&[u8]]) -> R) -> Result<R, FormatError> {
        self.with_parts_with(None, f)
    }

    /// [`VolumeAsset::with_parts`] with the base texture as BC7 `blocks` when given (see
    /// [`VolumeAsset::to_bytes_with`]).
    pub fn with_parts_with<R>(
        &self,
        blocks: Option<&VolumeBlocks>,
        f: impl FnOnce(&[&[u8]]) -> R,
    ) -> Result<R, FormatError> {
        self.with_chunks(blocks, |refs| with_parts_minor(&self.header, refs, 0, f))?
    }

    /// Encode and write atomically (see [`crate::write_atomic`]): the bytes of
    /// [`VolumeAsset::to_bytes`], written from the texel data where it is, without
    /// assembling the file in memory first.
    pub fn write(&self, path: &Path) -> Result<(), FormatError> {
        self.write_with(path, None)
    }

    /// [`VolumeAsset::write`] with the base texture as BC7 `blocks` when given (see
    /// [`VolumeAsset::to_bytes_with`]).
    pub fn write_with(
        &self,
        path: &Path,
        blocks: Option<&VolumeBlocks>,
    ) -> Result<(), FormatError> {
        self.with_chunks(blocks, |refs| write_with_minor(path, &self.header, refs, 0))?
    }
}

fn validate_volume_header(v: &VolumeHeader) -> Result<(), FormatError> {
    if v.dims.iter().any(|&d| d == 0 || d > MAX_DIM) {
        return bad(format!("dims {:?} must each be in 1..={MAX_DIM}", v.dims));
    }
    let full = full_mip_count(v.dims);
    if v.mip_count == 0 || v.mip_count > full {
        return bad(format!(
            "mip_count {} must be in 1..={full} for dims {:?}",
            v.mip_count, v.dims
        ));
    }
    match v.texel {
        TexelFormat::Rgba8Unorm => Ok(()),
    }
}

fn check_levels(tag: &str, levels: &[Vec<u8>], v: VolumeHeader) -> Result<(), FormatError> {
    if levels.len() as u64 != u64::from(v.mip_count) {
        return bad(format!(
            "{} {tag} levels but mip_count is {}",
            levels.len(),
            v.mip_count
        ));
    }
    check_level_sizes(tag, levels, v.dims)
}
