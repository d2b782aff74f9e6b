//! The typed Cloud asset (billboard cloud, kind 2) on top of the container. SPEC.md §9.
//!
//! Chunks, in the order the writer emits them (each exactly once unless noted):
//! - `CLVL` U32 ×4 per LOD level, `CLVF` F32 ×2 per level;
//! - `BBRD` F32 ×36 per billboard, `BBIX` U32 ×4 per billboard;
//! - `ATLS` U32 ×4 per atlas, then `ATEX` U8 × (sum of the atlases' MIP counts), atlas-major;
//! - optionally (format 1.1) `ANRM` U8, one per `ATEX`, in the same order: normal maps;
//! - `MMAT` F32 ×8 and `MMAI` U32 ×4 per material; `MTXI` U32 ×4 per texture, `MTEX` U8 × textures;
//! - `TVTX` F32 ×8 per vertex, `TIDX` U32 ×4 per triangle (the kept, non-foliage mesh);
//! - `FVTX` F32 ×11 per vertex, `FIDX` U32 ×5 per triangle (the foliage base mesh + morph targets).
//!
//! Everything is validated on read; counts come from chunk lengths that the container has
//! already checked against the file size, so nothing is allocated from a length field.

mod codec;

use crate::{AssetKind, FormatError, Header};

/// Largest atlas or mesh texture side.
pub const MAX_TEXTURE_SIDE: u32 = 16384;
/// "None" in index fields (parent billboard, material texture).
pub const NO_INDEX: u32 = u32::MAX;

/// Why a cloud asset is not valid (or could not be decoded).
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    #[error(transparent)]
    Format(#[from] FormatError),
    #[error("cloud asset: {0}")]
    Invalid(String),
}

/// One LOD level: a contiguous range of billboards and of atlases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudLevel {
    pub first_billboard: u32,
    pub billboard_count: u32,
    pub first_atlas: u32,
    pub atlas_count: u32,
    /// Slab half-width used by the plane search, world units.
    pub epsilon: f32,
    /// Texels per world unit of this level's textures.
    pub texel_density: f32,
}

/// Where one side of a billboard lives: atlas index and `[u0, v0, u1, v1]` (corner 0 → (u0, v0),
/// corner 2 → (u1, v1); glTF convention, v down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasRect {
    pub atlas: u32,
    pub uv: [f32; 4],
}

/// A textured quad. Corners: c1 = c0 + U·w, c2 = c0 + U·w + V·h, c3 = c0 + V·h, with
/// (U × V) = plane normal. Front = seen from the +normal side, back from −normal; both
/// textures use the same (U, V) parametrisation (the back is not mirrored).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Billboard {
    /// `(nx, ny, nz, r)`: the plane `n·x = r`, `|n| = 1`.
    pub plane: [f32; 4],
    pub corners: [[f32; 3]; 4],
    /// Orthogonal projection of each corner onto the parent billboard's plane (own corners
    /// for billboards of the last level).
    pub parent_corners: [[f32; 3]; 4],
    pub front: AtlasRect,
    pub back: AtlasRect,
    /// Index (global) of the parent billboard in the next level, or `None` in the last level.
    pub parent: Option<u32>,
    /// How many input elements (triangles or child quads) the search put on it.
    pub elements: u32,
}

/// An RGBA8 `SrgbPremultiplied` atlas with its MIP chain (level i is `max(1, w >> i)` ×
/// `max(1, h >> i)`), rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    pub width: u32,
    pub height: u32,
    pub mips: Vec<Vec<u8>>,
    /// The normal map of the same layout (format 1.1, SPEC §9.4): one RGBA8 level per colour
    /// level, RGB the tangent-space unit normal · 0.5 + 0.5, A the mean normal's length.
    /// Either every atlas of an asset has one or none has.
    pub normals: Option<Vec<Vec<u8>>>,
}

/// Material of a mesh triangle. `alpha_mode`: 0 opaque, 1 mask (with `alpha_cutoff`), 2 blend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshMaterial {
    pub base_color_factor: [f32; 4],
    pub alpha_cutoff: f32,
    pub texture: Option<u32>,
    pub alpha_mode: u32,
    pub double_sided: bool,
}

/// A mesh texture as authored: RGBA8, RGB sRGB-encoded, straight alpha. Wrap: 0 repeat,
/// 1 clamp-to-edge, 2 mirrored repeat.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshTexture {
    pub width: u32,
    pub height: u32,
    pub wrap: [u32; 2],
    pub texels: Vec<u8>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

/// An indexed triangle mesh. For the foliage mesh, `morph[i]` is vertex i projected onto
/// the level-0 billboard of its triangle, and `billboard[t]` that billboard's index.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<MeshVertex>,
    pub triangles: Vec<[u32; 3]>,
    pub materials: Vec<u32>,
    pub morph: Vec<[f32; 3]>,
    pub billboard: Vec<u32>,
}

/// A billboard cloud asset (kind `Cloud`).
#[derive(Clone, Debug, PartialEq)]
pub struct CloudAsset {
    pub header: Header,
    pub levels: Vec<CloudLevel>,
    pub billboards: Vec<Billboard>,
    pub atlases: Vec<Atlas>,
    pub materials: Vec<MeshMaterial>,
    pub textures: Vec<MeshTexture>,
    /// The kept (non-foliage) mesh; `morph` and `billboard` are empty.
    pub trunk: Mesh,
    /// The foliage base mesh with its morph targets.
    pub foliage: Mesh,
}

fn bad<T>(m: impl Into<String>) -> Result<T, CloudError> {
    Err(CloudError::Invalid(m.into()))
}

impl CloudAsset {
    /// Check the asset against the format rules (SPEC.md §9).
    pub fn validate(&self) -> Result<(), CloudError> {
        self.header.validate()?;
        if self.header.kind != AssetKind::Cloud {
            return bad(format!("header kind is {:?}, not Cloud", self.header.kind));
        }
        let (nb, na) = (self.billboards.len() as u64, self.atlases.len() as u64);
        if self.levels.is_empty() {
            return bad("no LOD levels");
        }
        let (mut b, mut a) = (0u64, 0u64);
        for (i, l) in self.levels.iter().enumerate() {
            if u64::from(l.first_billboard) != b || u64::from(l.first_atlas) != a {
                return bad(format!(
                    "level {i} does not start where level {} ends",
                    i.max(1) - 1
                ));
            }
            if l.billboard_count == 0 || l.atlas_count == 0 {
                return bad(format!("level {i} has no billboards or no atlases"));
            }
            let pos = |x: f32| x.is_finite() && x > 0.0;
            if !pos(l.epsilon) || !pos(l.texel_density) {
                return bad(format!(
                    "level {i}: epsilon and texel_density must be finite and > 0"
                ));
            }
            b += u64::from(l.billboard_count);
            a += u64::from(l.atlas_count);
        }
        if b != nb || a != na {
            return bad(format!(
                "levels cover {b} billboards and {a} atlases, file has {nb} and {na}"
            ));
        }
        for (i, at) in self.atlases.iter().enumerate() {
            check_image(&format!("atlas {i}"), at.width, at.height)?;
            let m = at.mips.len() as u32;
            if m == 0 || m > full_mips(at.width, at.height) {
                return bad(format!(
                    "atlas {i}: {m} MIP levels for {}x{}",
                    at.width, at.height
                ));
            }
            for (k, lv) in at.mips.iter().enumerate() {
                if lv.len() as u64 != mip_len(at.width, at.height, k as u32) {
                    return bad(format!("atlas {i} MIP {k} is {} bytes", lv.len()));
                }
            }
            if let Some(n) = &at.normals {
                if n.len() != at.mips.len()
                    || n.iter().zip(&at.mips).any(|(a, b)| a.len() != b.len())
                {
                    return bad(format!(
                        "atlas {i}: its normal map does not match its colour levels"
                    ));
                }
            }
            if at.normals.is_some() != self.atlases[0].normals.is_some() {
                return bad("either every atlas has a normal map or none has");
            }
        }
        for (li, l) in self.levels.iter().enumerate() {
            let atl = u64::from(l.first_atlas)..u64::from(l.first_atlas) + u64::from(l.atlas_count);
            let next = self.levels.get(li + 1);
            for bi in l.first_billboard..l.first_billboard + l.billboard_count {
                let bb = &self.billboards[bi as usize];
                let fl = bb.plane.iter().chain(bb.corners.iter().flatten());
                let fl = fl.chain(bb.parent_corners.iter().flatten());
                if !fl
                    .chain(&bb.front.uv)
                    .chain(&bb.back.uv)
                    .all(|x| x.is_finite())
                {
                    return bad(format!("billboard {bi} has a non-finite value"));
                }
                let n = bb.plane[0] * bb.plane[0]
                    + bb.plane[1] * bb.plane[1]
                    + bb.plane[2] * bb.plane[2];
                if (n - 1.0).abs() > 1e-3 {
                    return bad(format!("billboard {bi}: plane normal is not unit length"));
                }
                for r in [&bb.front, &bb.back] {
                    if !atl.contains(&u64::from(r.atlas)) {
                        return bad(format!(
                            "billboard {bi}: atlas {} is not in its level",
                            r.atlas
                        ));
                    }
                    let [u0, v0, u1, v1] = r.uv;
                    if !(0.0 <= u0 && u0 <= u1 && u1 <= 1.0 && 0.0 <= v0 && v0 <= v1 && v1 <= 1.0) {
                        return bad(format!("billboard {bi}: UV rect {:?} outside [0,1]", r.uv));
                    }
                }
                match (next, bb.parent) {
                    (None, None) => {}
                    (Some(nl), Some(p))
                        if (nl.first_billboard..nl.first_billboard + nl.billboard_count)
                            .contains(&p) => {}
                    _ => {
                        return bad(format!(
                            "billboard {bi}: parent {:?} is not in the next level",
                            bb.parent
                        ))
                    }
                }
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            check_image(&format!("mesh texture {i}"), t.width, t.height)?;
            if t.texels.len() as u64 != mip_len(t.width, t.height, 0)
                || t.wrap.iter().any(|&w| w > 2)
            {
                return bad(format!("mesh texture {i}: wrong size or wrap mode"));
            }
        }
        for (i, m) in self.materials.iter().enumerate() {
            let tex_ok = m.texture.is_none_or(|t| (t as usize) < self.textures.len());
            let fin =
                m.base_color_factor.iter().all(|x| x.is_finite()) && m.alpha_cutoff.is_finite();
            if !tex_ok || m.alpha_mode > 2 || !fin {
                return bad(format!("material {i} is invalid"));
            }
        }
        self.check_mesh("trunk", &self.trunk, false)?;
        self.check_mesh("foliage", &self.foliage, true)
    }

    fn check_mesh(&self, what: &str, m: &Mesh, foliage: bool) -> Result<(), CloudError> {
        let nv = m.vertices.len() as u64;
        let nt = m.triangles.len();
        if m.materials.len() != nt
            || (foliage && (m.billboard.len() != nt || m.morph.len() as u64 != nv))
        {
            return bad(format!(
                "{what} mesh: per-triangle/per-vertex arrays disagree"
            ));
        }
        if !foliage && (!m.billboard.is_empty() || !m.morph.is_empty()) {
            return bad(format!("{what} mesh must have no morph data"));
        }
        let lvl0 = self.levels.first().map_or(0, |l| l.billboard_count);
        for t in 0..nt {
            if m.triangles[t].iter().any(|&i| u64::from(i) >= nv)
                || m.materials[t] as usize >= self.materials.len()
                || (foliage && m.billboard[t] >= lvl0)
            {
                return bad(format!(
                    "{what} mesh triangle {t} has an index out of range"
                ));
            }
        }
        let v = m
            .vertices
            .iter()
            .flat_map(|v| v.position.iter().chain(&v.normal).chain(&v.uv));
        if !v.chain(m.morph.iter().flatten()).all(|x| x.is_finite()) {
            return bad(format!("{what} mesh has a non-finite vertex value"));
        }
        Ok(())
    }
}

fn check_image(what: &str, w: u32, h: u32) -> Result<(), CloudError> {
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return bad(format!(
            "{what}: size {w}x{h} outside 1..={MAX_TEXTURE_SIDE}"
        ));
    }
    Ok(())
}

pub(crate) fn mip_len(w: u32, h: u32, level: u32) -> u64 {
    let d = |x: u32| u64::from(x.checked_shr(level).unwrap_or(0).max(1));
    d(w) * d(h) * 4
}

pub(crate) fn full_mips(w: u32, h: u32) -> u32 {
    32 - w.max(h).max(1).leading_zeros()
}
