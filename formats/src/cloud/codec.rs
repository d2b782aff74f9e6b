//! Encoding and decoding of the Cloud chunks (SPEC.md §9). Counts come from chunk lengths,
//! which the container has already checked against the file size.

use std::borrow::Cow;
use std::path::Path;

use super::{
    bad, Atlas, AtlasRect, Billboard, CloudAsset, CloudError, CloudLevel, Mesh, MeshMaterial,
    MeshTexture, MeshVertex, NO_INDEX,
};
use crate::blocks::{decode_bc7, sparse_len, CloudBlocks};
use crate::container::{encode, ChunkRef};
use crate::{from_bytes, write_atomic, AssetKind, Container, ElemType};

fn put_f32(out: &mut Vec<u8>, v: &[f32]) {
    v.iter()
        .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
}
fn put_u32(out: &mut Vec<u8>, v: &[u32]) {
    v.iter()
        .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
}
fn f32s(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect()
}
fn u32s(b: &[u8]) -> Vec<u32> {
    b.chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect()
}
fn v3(s: &[f32]) -> [f32; 3] {
    [s[0], s[1], s[2]]
}
fn opt(i: u32) -> Option<u32> {
    (i != NO_INDEX).then_some(i)
}

/// Every chunk tag of the Cloud kind with its element type and record size in elements.
const LAYOUT: [(&[u8; 4], ElemType, usize); 13] = [
    (b"CLVL", ElemType::U32, 4),
    (b"CLVF", ElemType::F32, 2),
    (b"BBRD", ElemType::F32, 36),
    (b"BBIX", ElemType::U32, 4),
    (b"ATLS", ElemType::U32, 4),
    (b"MMAT", ElemType::F32, 8),
    (b"MMAI", ElemType::U32, 4),
    (b"MTXI", ElemType::U32, 4),
    (b"TVTX", ElemType::F32, 8),
    (b"TIDX", ElemType::U32, 4),
    (b"FVTX", ElemType::F32, 11),
    (b"FIDX", ElemType::U32, 5),
    (b"ATEX", ElemType::U8, 1),
];

impl CloudAsset {
    /// Every chunk in writing order; the large texel payloads are borrowed, not copied.
    /// With `blocks`, the atlas levels, normal maps and mesh textures are their BC7 blocks
    /// (`ATB7`, `ANB7`, `MTB7`, format 1.2) instead of raw texels.
    fn payloads<'a>(
        &'a self,
        blocks: Option<&'a CloudBlocks>,
    ) -> Vec<([u8; 4], ElemType, Cow<'a, [u8]>)> {
        let mut c: Vec<([u8; 4], ElemType, Cow<'_, [u8]>)> = Vec::new();
        let mut push = |tag: &[u8; 4], elem, data| c.push((*tag, elem, data));
        let (mut lv, mut lf) = (Vec::new(), Vec::new());
        for l in &self.levels {
            put_u32(
                &mut lv,
                &[
                    l.first_billboard,
                    l.billboard_count,
                    l.first_atlas,
                    l.atlas_count,
                ],
            );
            put_f32(&mut lf, &[l.epsilon, l.texel_density]);
        }
        push(b"CLVL", ElemType::U32, Cow::Owned(lv));
        push(b"CLVF", ElemType::F32, Cow::Owned(lf));
        let (mut bf, mut bi) = (Vec::new(), Vec::new());
        for b in &self.billboards {
            put_f32(&mut bf, &b.plane);
            b.corners
                .iter()
                .chain(&b.parent_corners)
                .for_each(|p| put_f32(&mut bf, p));
            put_f32(&mut bf, &b.front.uv);
            put_f32(&mut bf, &b.back.uv);
            put_u32(
                &mut bi,
                &[
                    b.front.atlas,
                    b.back.atlas,
                    b.parent.unwrap_or(NO_INDEX),
                    b.elements,
                ],
            );
        }
        push(b"BBRD", ElemType::F32, Cow::Owned(bf));
        push(b"BBIX", ElemType::U32, Cow::Owned(bi));
        let mut al = Vec::new();
        for a in &self.atlases {
            put_u32(&mut al, &[a.width, a.height, a.mips.len() as u32, 0]);
        }
        push(b"ATLS", ElemType::U32, Cow::Owned(al));
        match blocks {
            None => {
                for m in self.atlases.iter().flat_map(|a| &a.mips) {
                    push(b"ATEX", ElemType::U8, Cow::Borrowed(m));
                }
                for m in self.atlases.iter().flat_map(|a| a.normals.iter().flatten()) {
                    push(b"ANRM", ElemType::U8, Cow::Borrowed(m));
                }
            }
            Some(b) => {
                for m in b.atlases.iter().flatten() {
                    push(b"ATB7", ElemType::U8, Cow::Borrowed(m));
                }
                for m in b.atlas_normals.iter().flatten().flatten() {
                    push(b"ANB7", ElemType::U8, Cow::Borrowed(m));
                }
            }
        }
        let (mut mf, mut mi) = (Vec::new(), Vec::new());
        for m in &self.materials {
            put_f32(&mut mf, &m.base_color_factor);
            put_f32(&mut mf, &[m.alpha_cutoff, 0.0, 0.0, 0.0]);
            let t = m.texture.unwrap_or(NO_INDEX);
            put_u32(&mut mi, &[t, m.alpha_mode, u32::from(m.double_sided), 0]);
        }
        push(b"MMAT", ElemType::F32, Cow::Owned(mf));
        push(b"MMAI", ElemType::U32, Cow::Owned(mi));
        let mut ti = Vec::new();
        for t in &self.textures {
            put_u32(&mut ti, &[t.width, t.height, t.wrap[0], t.wrap[1]]);
        }
        push(b"MTXI", ElemType::U32, Cow::Owned(ti));
        match blocks {
            None => {
                for t in &self.textures {
                    push(b"MTEX", ElemType::U8, Cow::Borrowed(&t.texels));
                }
            }
            Some(b) => {
                for t in &b.textures {
                    push(b"MTB7", ElemType::U8, Cow::Borrowed(t));
                }
            }
        }
        for (m, vt, it) in [
            (&self.trunk, b"TVTX", b"TIDX"),
            (&self.foliage, b"FVTX", b"FIDX"),
        ] {
            let (mut v, mut i) = (Vec::new(), Vec::new());
            for (k, x) in m.vertices.iter().enumerate() {
                put_f32(&mut v, &x.position);
                put_f32(&mut v, &x.normal);
                put_f32(&mut v, &x.uv);
                if let Some(p) = m.morph.get(k) {
                    put_f32(&mut v, p);
                }
            }
            for (k, t) in m.triangles.iter().enumerate() {
                put_u32(&mut i, t);
                put_u32(&mut i, &[m.materials[k]]);
                if let Some(&b) = m.billboard.get(k) {
                    put_u32(&mut i, &[b]);
                }
            }
            push(vt, ElemType::F32, Cow::Owned(v));
            push(it, ElemType::U32, Cow::Owned(i));
        }
        c
    }

    /// The container for this asset (validates first).
    pub fn to_container(&self) -> Result<Container, CloudError> {
        self.validate()?;
        let chunks = self.payloads(None).into_iter();
        let chunks = chunks.map(|(tag, elem, data)| crate::Chunk {
            tag,
            elem,
            data: data.into_owned(),
        });
        Ok(Container {
            header: self.header.clone(),
            chunks: chunks.collect(),
        })
    }

    /// Encode to file bytes (validates first). Deterministic.
    pub fn to_bytes(&self) -> Result<Vec<u8>, CloudError> {
        self.to_bytes_with(None)
    }

    /// Whether `b` has the shape of this asset's textures (sizes only).
    fn check_blocks(&self, b: &CloudBlocks) -> Result<(), CloudError> {
        let dims = |w: u32, h: u32, k: usize| {
            let s = |x: u32| x.checked_shr(k as u32).unwrap_or(0).max(1);
            [s(w), s(h), 1]
        };
        let shape = |l: &[Vec<u8>], w, h, n: usize| {
            l.len() == n
                && l.iter()
                    .enumerate()
                    .all(|(k, x)| sparse_len(x, dims(w, h, k)).is_ok())
        };
        let atl_ok = b.atlases.len() == self.atlases.len()
            && b.atlases
                .iter()
                .zip(&self.atlases)
                .all(|(l, a)| shape(l, a.width, a.height, a.mips.len()));
        let nrm_ok = match (
            &b.atlas_normals,
            self.atlases.first().and_then(|a| a.normals.as_ref()),
        ) {
            (None, None) => true,
            (Some(n), Some(_)) => {
                n.len() == self.atlases.len()
                    && n.iter()
                        .zip(&self.atlases)
                        .all(|(l, a)| shape(l, a.width, a.height, a.mips.len()))
            }
            _ => false,
        };
        let tex_ok = b.textures.len() == self.textures.len()
            && b.textures
                .iter()
                .zip(&self.textures)
                .all(|(l, t)| sparse_len(l, [t.width, t.height, 1]).is_ok());
        if atl_ok && nrm_ok && tex_ok {
            Ok(())
        } else {
            bad("the BC7 blocks do not match the asset's atlases and textures")
        }
    }

    /// [`CloudAsset::to_bytes`] storing every atlas level, normal map and mesh texture as
    /// the BC7 `blocks` (format 1.2, SPEC §12) when given. The blocks must decode to the
    /// asset's texels (what a reader gets back); only their sizes are checked here.
    pub fn to_bytes_with(&self, blocks: Option<&CloudBlocks>) -> Result<Vec<u8>, CloudError> {
        self.validate()?;
        if let Some(b) = blocks {
            self.check_blocks(b)?;
        }
        let p = self.payloads(blocks);
        let refs: Vec<ChunkRef<'_>> = p
            .iter()
            .map(|(tag, elem, data)| ChunkRef {
                tag: *tag,
                elem: *elem,
                data,
            })
            .collect();
        Ok(encode(&self.header, &refs)?)
    }

    /// Decode and validate from a container; unknown chunk tags are skipped.
    pub fn from_container(c: Container) -> Result<Self, CloudError> {
        Ok(Self::from_container_with_blocks(c)?.0)
    }

    /// [`CloudAsset::from_container`] that also returns the BC7 blocks of a compressed
    /// file (format 1.2); the asset's texels are the decoded blocks either way.
    pub fn from_container_with_blocks(
        c: Container,
    ) -> Result<(Self, Option<CloudBlocks>), CloudError> {
        let Container { header, chunks } = c;
        if header.kind != AssetKind::Cloud {
            return bad(format!("asset kind is {:?}, not Cloud", header.kind));
        }
        let mut single: [Option<Vec<u8>>; 12] = Default::default();
        let (mut atex, mut mtex, mut anrm) = (Vec::new(), Vec::new(), Vec::new());
        let (mut atb7, mut mtb7, mut anb7) = (Vec::new(), Vec::new(), Vec::new());
        for ch in chunks {
            let Some(k) = LAYOUT.iter().position(|(t, _, _)| **t == ch.tag) else {
                for (tag, list) in [
                    (b"MTEX", &mut mtex),
                    (b"ANRM", &mut anrm),
                    (b"ATB7", &mut atb7),
                    (b"MTB7", &mut mtb7),
                    (b"ANB7", &mut anb7),
                ] {
                    if &ch.tag == tag {
                        if ch.elem != ElemType::U8 {
                            return bad(format!(
                                "{} chunk must have element type U8",
                                crate::tag_str(tag)
                            ));
                        }
                        list.push(ch.data);
                        break;
                    }
                }
                continue; // unknown chunk of a newer minor version
            };
            let (tag, elem, rec) = LAYOUT[k];
            let tag = crate::tag_str(tag);
            if ch.elem != elem {
                return bad(format!(
                    "{tag} chunk has element type {:?}, expected {elem:?}",
                    ch.elem
                ));
            }
            if k == 12 {
                atex.push(ch.data);
                continue;
            }
            if ch.data.len() % (rec * 4) != 0 {
                return bad(format!(
                    "{tag} length {} is not a multiple of {}",
                    ch.data.len(),
                    rec * 4
                ));
            }
            if single[k].replace(ch.data).is_some() {
                return bad(format!("more than one {tag} chunk"));
            }
        }
        let compressed = !(atb7.is_empty() && mtb7.is_empty() && anb7.is_empty());
        if compressed && !(atex.is_empty() && mtex.is_empty() && anrm.is_empty()) {
            return bad(
                "both raw (ATEX/ANRM/MTEX) and compressed (ATB7/ANB7/MTB7) textures: a compressed cloud stores all its textures as blocks",
            );
        }
        let mut take = |k: usize| {
            single[k].take().ok_or_else(|| {
                CloudError::Invalid(format!("missing {} chunk", crate::tag_str(LAYOUT[k].0)))
            })
        };
        let (lv, lf) = (u32s(&take(0)?), f32s(&take(1)?));
        if lv.len() / 4 != lf.len() / 2 {
            return bad("CLVL and CLVF disagree on the number of levels");
        }
        let levels = lv
            .chunks_exact(4)
            .zip(lf.chunks_exact(2))
            .map(|(a, f)| CloudLevel {
                first_billboard: a[0],
                billboard_count: a[1],
                first_atlas: a[2],
                atlas_count: a[3],
                epsilon: f[0],
                texel_density: f[1],
            });
        let (bf, bi) = (f32s(&take(2)?), u32s(&take(3)?));
        if bf.len() / 36 != bi.len() / 4 {
            return bad("BBRD and BBIX disagree on the number of billboards");
        }
        let billboards = bf
            .chunks_exact(36)
            .zip(bi.chunks_exact(4))
            .map(|(f, i)| Billboard {
                plane: [f[0], f[1], f[2], f[3]],
                corners: std::array::from_fn(|k| v3(&f[4 + 3 * k..])),
                parent_corners: std::array::from_fn(|k| v3(&f[16 + 3 * k..])),
                front: AtlasRect {
                    atlas: i[0],
                    uv: [f[28], f[29], f[30], f[31]],
                },
                back: AtlasRect {
                    atlas: i[1],
                    uv: [f[32], f[33], f[34], f[35]],
                },
                parent: opt(i[2]),
                elements: i[3],
            });
        let al = u32s(&take(4)?);
        let mut cblocks = compressed.then(CloudBlocks::default);
        if let Some(cb) = cblocks.as_mut() {
            // Decode the blocks into the raw chunks' texels (sizes checked first).
            let decode_chain = |chunks: Vec<Vec<u8>>,
                                tag: &str,
                                out: &mut Vec<Vec<Vec<u8>>>|
             -> Result<Vec<Vec<u8>>, CloudError> {
                let mut it = chunks.into_iter();
                let mut raw = Vec::new();
                for (i, a) in al.chunks_exact(4).enumerate() {
                    if a[2] == 0 || a[2] > 32 || a[0] == 0 || a[1] == 0 {
                        return bad(format!("atlas {i}: size or MIP count out of range"));
                    }
                    let mut lv = Vec::new();
                    for k in 0..a[2] {
                        let d = |x: u32| x.checked_shr(k).unwrap_or(0).max(1);
                        let Some(b) = it.next() else {
                            return bad(format!(
                                "atlas {i}: fewer {tag} chunks than its MIP count"
                            ));
                        };
                        let dims = [d(a[0]), d(a[1]), 1];
                        if let Err(e) = sparse_len(&b, dims) {
                            return bad(format!("atlas {i} {tag} level {k}: {e}"));
                        }
                        raw.push(decode_bc7(&b, dims, 0));
                        lv.push(b);
                    }
                    out.push(lv);
                }
                if it.next().is_some() {
                    return bad(format!("more {tag} chunks than the atlases' MIP counts"));
                }
                Ok(raw)
            };
            atex = decode_chain(atb7, "ATB7", &mut cb.atlases)?;
            if !anb7.is_empty() {
                let mut n = Vec::new();
                anrm = decode_chain(anb7, "ANB7", &mut n)?;
                cb.atlas_normals = Some(n);
            }
        }
        if !anrm.is_empty() && anrm.len() != atex.len() {
            return bad(format!(
                "{} ANRM chunks for {} ATEX chunks (must be none or one each)",
                anrm.len(),
                atex.len()
            ));
        }
        let mut anrm = (!anrm.is_empty()).then(|| anrm.into_iter());
        let mut atex = atex.into_iter();
        let mut atlases = Vec::with_capacity(al.len() / 4);
        for (i, a) in al.chunks_exact(4).enumerate() {
            if a[2] == 0 || a[2] > 32 {
                return bad(format!("atlas {i}: MIP count {} out of range", a[2]));
            }
            let mips: Vec<Vec<u8>> = atex.by_ref().take(a[2] as usize).collect();
            if mips.len() != a[2] as usize {
                return bad(format!("atlas {i}: fewer ATEX chunks than its MIP count"));
            }
            let normals = anrm
                .as_mut()
                .map(|n| n.by_ref().take(a[2] as usize).collect());
            atlases.push(Atlas {
                width: a[0],
                height: a[1],
                mips,
                normals,
            });
        }
        if atex.next().is_some() {
            return bad("more ATEX chunks than the atlases' MIP counts");
        }
        let (mf, mi) = (f32s(&take(5)?), u32s(&take(6)?));
        if mf.len() / 8 != mi.len() / 4 {
            return bad("MMAT and MMAI disagree on the number of materials");
        }
        let materials = mf
            .chunks_exact(8)
            .zip(mi.chunks_exact(4))
            .map(|(f, i)| MeshMaterial {
                base_color_factor: [f[0], f[1], f[2], f[3]],
                alpha_cutoff: f[4],
                texture: opt(i[0]),
                alpha_mode: i[1],
                double_sided: i[2] != 0,
            });
        let ti = u32s(&take(7)?);
        if let Some(cb) = cblocks.as_mut() {
            if ti.len() / 4 != mtb7.len() {
                return bad(format!(
                    "MTXI lists {} textures but there are {} MTB7 chunks",
                    ti.len() / 4,
                    mtb7.len()
                ));
            }
            for (i, (t, b)) in ti.chunks_exact(4).zip(mtb7).enumerate() {
                if t[0] == 0
                    || t[1] == 0
                    || t[0] > super::MAX_TEXTURE_SIDE
                    || t[1] > super::MAX_TEXTURE_SIDE
                {
                    return bad(format!(
                        "mesh texture {i}: size {}x{} out of range",
                        t[0], t[1]
                    ));
                }
                if let Err(e) = sparse_len(&b, [t[0], t[1], 1]) {
                    return bad(format!("mesh texture {i}: MTB7: {e}"));
                }
                mtex.push(decode_bc7(&b, [t[0], t[1], 1], 0));
                cb.textures.push(b);
            }
        }
        if ti.len() / 4 != mtex.len() {
            return bad(format!(
                "MTXI lists {} textures but there are {} MTEX chunks",
                ti.len() / 4,
                mtex.len()
            ));
        }
        let textures = ti.chunks_exact(4).zip(mtex).map(|(t, texels)| MeshTexture {
            width: t[0],
            height: t[1],
            wrap: [t[2], t[3]],
            texels,
        });
        let trunk = read_mesh(&f32s(&take(8)?), &u32s(&take(9)?), false);
        let foliage = read_mesh(&f32s(&take(10)?), &u32s(&take(11)?), true);
        let asset = CloudAsset {
            header,
            levels: levels.collect(),
            billboards: billboards.collect(),
            atlases,
            materials: materials.collect(),
            textures: textures.collect(),
            trunk,
            foliage,
        };
        asset.validate()?;
        Ok((asset, cblocks))
    }

    /// Decode and validate from file bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CloudError> {
        Self::from_container(from_bytes(bytes)?)
    }

    /// [`CloudAsset::from_bytes`] that also returns the BC7 blocks of a compressed file.
    pub fn from_bytes_with_blocks(bytes: &[u8]) -> Result<(Self, Option<CloudBlocks>), CloudError> {
        Self::from_container_with_blocks(from_bytes(bytes)?)
    }

    /// [`CloudAsset::read`] that also returns the BC7 blocks of a compressed file.
    pub fn read_with_blocks(path: &Path) -> Result<(Self, Option<CloudBlocks>), CloudError> {
        Self::from_container_with_blocks(crate::container::read_file(path)?).map_err(|e| match e {
            CloudError::Format(f) => CloudError::Format(f.in_file(path)),
            CloudError::Invalid(m) => CloudError::Invalid(format!("{}: {m}", path.display())),
        })
    }

    /// Read a cloud asset file.
    pub fn read(path: &Path) -> Result<Self, CloudError> {
        Self::from_container(crate::container::read_file(path)?).map_err(|e| match e {
            CloudError::Format(f) => CloudError::Format(f.in_file(path)),
            CloudError::Invalid(m) => CloudError::Invalid(format!("{}: {m}", path.display())),
        })
    }

    /// Encode and write atomically (see [`write_atomic`]).
    pub fn write(&self, path: &Path) -> Result<(), CloudError> {
        Ok(write_atomic(path, &self.to_bytes()?)?)
    }

    /// [`CloudAsset::write`] with the textures as BC7 `blocks` when given.
    pub fn write_with(&self, path: &Path, blocks: Option<&CloudBlocks>) -> Result<(), CloudError> {
        Ok(write_atomic(path, &self.to_bytes_with(blocks)?)?)
    }
}

fn read_mesh(v: &[f32], i: &[u32], foliage: bool) -> Mesh {
    let (vs, is) = if foliage { (11, 5) } else { (8, 4) };
    let mut m = Mesh::default();
    for c in v.chunks_exact(vs) {
        m.vertices.push(MeshVertex {
            position: v3(c),
            normal: v3(&c[3..]),
            uv: [c[6], c[7]],
        });
        if foliage {
            m.morph.push(v3(&c[8..]));
        }
    }
    for c in i.chunks_exact(is) {
        m.triangles.push([c[0], c[1], c[2]]);
        m.materials.push(c[3]);
        if foliage {
            m.billboard.push(c[4]);
        }
    }
    m
}
