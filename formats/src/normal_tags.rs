//! The chunk tags of normal texels, of either kind ([`NormalKind`]: mean normals or their
//! moments, SPEC §8.4 and §8.4a), shared by the base texture (`volume`), the LOD bands
//! (`bands`) and the block-compressed chunks (`blocks`). A leaf: it imports no other
//! module of the format but the header's [`NormalKind`].

use crate::NormalKind;

/// Tag of a normal MIP level chunk (one per level, in level order).
pub const TAG_VNRM: [u8; 4] = *b"VNRM";
/// Tag of a normal-moment MIP level chunk (format 1.4, SPEC §8.4a; one per level, in level
/// order): what a volume with `volume.moments` stores instead of `VNRM`.
pub const TAG_VMOM: [u8; 4] = *b"VMOM";
/// Tag of a band normal level chunk.
pub const TAG_BNRM: [u8; 4] = *b"BNRM";
/// Tag of a band normal-moment level chunk (format 1.4, SPEC §8.4a; replaces `BNRM` in a
/// volume with `volume.moments`).
pub const TAG_BMOM: [u8; 4] = *b"BMOM";
/// Volume normal level, BC7 of the normal bytes XOR 0x80 (replaces `VNRM`).
pub const TAG_VNB7: [u8; 4] = *b"VNB7";
/// Volume normal-moment level (format 1.4, SPEC §8.4a), BC7 of the moment bytes XOR 0x80
/// (replaces `VMOM`, as `VNB7` replaces `VNRM`).
pub const TAG_VMB7: [u8; 4] = *b"VMB7";
/// LOD band normal level, BC7 of the normal bytes XOR 0x80 (format 1.3; replaces `BNRM`).
pub const TAG_BNB7: [u8; 4] = *b"BNB7";
/// LOD band normal-moment level (format 1.4), BC7 of the moment bytes XOR 0x80 (replaces
/// `BMOM`).
pub const TAG_BMB7: [u8; 4] = *b"BMB7";

/// The chunk tags of one kind of normal texels ([`NormalKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct NormalTags {
    /// Base texture levels, raw (`VNRM`/`VMOM`, element `I8`).
    pub base: [u8; 4],
    /// Base texture levels, BC7 (`VNB7`/`VMB7`, element `U8`).
    pub base_bc: [u8; 4],
    /// LOD band levels, raw (`BNRM`/`BMOM`, element `I8`).
    pub band: [u8; 4],
    /// LOD band levels, BC7 (`BNB7`/`BMB7`, element `U8`).
    pub band_bc: [u8; 4],
}

impl NormalTags {
    pub(crate) const MEAN: NormalTags = NormalTags {
        base: TAG_VNRM,
        base_bc: TAG_VNB7,
        band: TAG_BNRM,
        band_bc: TAG_BNB7,
    };
    pub(crate) const MOMENTS: NormalTags = NormalTags {
        base: TAG_VMOM,
        base_bc: TAG_VMB7,
        band: TAG_BMOM,
        band_bc: TAG_BMB7,
    };

    /// The tags of a volume whose normal texels are `kind` (those of mean normals for a
    /// volume without normals: named in messages only).
    pub(crate) fn of(kind: Option<NormalKind>) -> NormalTags {
        match kind {
            Some(NormalKind::Moments) => NormalTags::MOMENTS,
            Some(NormalKind::Mean) | None => NormalTags::MEAN,
        }
    }

    fn all(&self) -> [[u8; 4]; 4] {
        [self.base, self.base_bc, self.band, self.band_bc]
    }

    /// The kind of normal texels `tag` holds, `None` for a tag of no normal texels.
    pub(crate) fn kind_of_tag(tag: &[u8; 4]) -> Option<NormalKind> {
        if NormalTags::MEAN.all().contains(tag) {
            Some(NormalKind::Mean)
        } else if NormalTags::MOMENTS.all().contains(tag) {
            Some(NormalKind::Moments)
        } else {
            None
        }
    }

    /// The header field that declares `kind`: `volume.normals` or `volume.moments`.
    pub(crate) fn field(kind: NormalKind) -> &'static str {
        match kind {
            NormalKind::Mean => "volume.normals",
            NormalKind::Moments => "volume.moments",
        }
    }
}
