//! The human-readable RON header (chunk `HEAD`).
//!
//! Unknown fields are ignored when reading (a newer minor version may add
//! fields), so none of these types use `deny_unknown_fields`. Fields added in a
//! later minor version must be `Option` or have a `#[serde(default)]`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::FormatError;

/// What an asset contains. Stored as a `u32` in the preamble and by name in the header.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AssetKind {
    /// A volumetric billboard: a 3D RGBA texture with MIP levels plus prism cells.
    Volume,
    /// A billboard cloud (reserved; the typed API comes later).
    Cloud,
}

impl AssetKind {
    /// The `u32` stored at preamble offset 12.
    pub const fn code(self) -> u32 {
        match self {
            AssetKind::Volume => 1,
            AssetKind::Cloud => 2,
        }
    }

    /// Inverse of [`AssetKind::code`].
    pub const fn from_code(code: u32) -> Option<AssetKind> {
        match code {
            1 => Some(AssetKind::Volume),
            2 => Some(AssetKind::Cloud),
            _ => None,
        }
    }
}

/// The asset header, serialized as RON in the `HEAD` chunk.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct Header {
    pub kind: AssetKind,
    /// Tool and version that wrote the asset, e.g. `"billow 0.1.0"`.
    pub tool: String,
    /// The input file the asset was baked from, if any.
    pub source: Option<SourceInfo>,
    /// World-space axis-aligned bounds of the baked content.
    pub bounds: Bounds,
    pub colour_space: ColourSpace,
    /// Random seed of the bake, if it used one.
    pub seed: Option<u64>,
    /// Bake parameters as given on the command line, e.g. `"res" -> "128x128x128"`.
    pub params: BTreeMap<String, String>,
    /// Present iff `kind == Volume`.
    pub volume: Option<VolumeHeader>,
}

/// Identity of the input file. Only the file name is kept (no directories) so
/// the same bake on two machines gives identical bytes.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq, Eq)]
pub struct SourceInfo {
    pub file_name: String,
    /// SHA-256 of the file's bytes, 64 lowercase hex digits.
    pub sha256: String,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// World-space axis-aligned box; `min[i] <= max[i]`, all finite.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

/// How colour texels are encoded. Both are premultiplied by alpha.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColourSpace {
    /// `rgb = srgb_oetf(linear_rgb * alpha)`, alpha linear. Decode with the sRGB
    /// EOTF to get linear premultiplied colour (what blending needs).
    SrgbPremultiplied,
    /// `rgb = linear_rgb * alpha`, alpha linear.
    LinearPremultiplied,
}

/// Volume-specific header fields.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolumeHeader {
    /// Level-0 size in texels, x, y, z.
    pub dims: [u32; 3],
    /// Number of MIP levels stored, `1..=full_mip_count(dims)`.
    pub mip_count: u32,
    pub texel: TexelFormat,
    /// Per-texel mean normals, if baked (`VNRM`/`BNRM`/`VNB7`/`BNB7`, SPEC §8.4).
    /// Exclusive with [`VolumeHeader::moments`].
    pub normals: Option<NormalEncoding>,
    /// Per-texel second moments of the normals instead of mean normals (format 1.4:
    /// `VMOM`/`BMOM`/`VMB7`/`BMB7`, SPEC §8.4a), if baked. Exclusive with
    /// [`VolumeHeader::normals`]. Not written when `None`, so the header of every file
    /// without moments is the bytes it was before 1.4. The texels are the same
    /// `Rgba8Snorm` bytes, held where mean normals are ([`crate::VolumeAsset::normals`],
    /// [`crate::LodBand::normals`]); [`VolumeHeader::normal_kind`] says which they are.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moments: Option<NormalEncoding>,
}

/// What a volume's normal texels hold ([`VolumeHeader::normal_kind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NormalKind {
    /// The Toksvig mean normal (`volume.normals`; chunks `VNRM`, `BNRM`, `VNB7`, `BNB7`).
    Mean,
    /// The diagonal of the normals' second moment E\[n nᵀ\] (`volume.moments`, format
    /// 1.4; chunks `VMOM`, `BMOM`, `VMB7`, `BMB7`, SPEC §8.4a).
    Moments,
}

impl VolumeHeader {
    /// Which normal texels the volume has: `Mean` when `normals` is set, `Moments` when
    /// `moments` is, `None` when neither (both set is invalid: [`Header::validate`]
    /// refuses it; this says `Mean` then).
    pub fn normal_kind(&self) -> Option<NormalKind> {
        match (self.normals, self.moments) {
            (Some(_), _) => Some(NormalKind::Mean),
            (None, Some(_)) => Some(NormalKind::Moments),
            (None, None) => None,
        }
    }

    /// Sets `normals` and `moments` for `kind` (`Rgba8Snorm`, the only encoding); `None`
    /// clears both.
    pub fn set_normal_kind(&mut self, kind: Option<NormalKind>) {
        let enc = Some(NormalEncoding::Rgba8Snorm);
        (self.normals, self.moments) = match kind {
            None => (None, None),
            Some(NormalKind::Mean) => (enc, None),
            Some(NormalKind::Moments) => (None, enc),
        };
    }
}

/// Colour texel format.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TexelFormat {
    /// 4 bytes per texel: r, g, b, a, each `value / 255`.
    Rgba8Unorm,
}

/// Normal texel encoding.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NormalEncoding {
    /// 4 signed bytes per texel: x, y, z, w, each `max(value / 127, -1)`.
    /// xyz is the Toksvig-shortened mean normal: the average of the unit
    /// normals inside the texel, so a length below 1 means the normals spread
    /// (length 0: no preferred direction). w is unused and written as 0.
    Rgba8Snorm,
}

/// The ambient fraction of a baked directional light when the header does not say
/// ([`param::AMBIENT`]); what billow's bakers write by default.
pub const DEFAULT_AMBIENT: f32 = 0.3;

/// The lighting baked into an asset's colours ([`Header::baked_light`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BakedLight {
    /// `light = "unlit"`: the colours are albedo. A renderer lights them at runtime where
    /// the asset has normals (a cloud's `ANRM` normal maps), else draws them as they are.
    Unlit,
    /// `light = "x,y,z"`: the colours are final, lit by a directional light towards
    /// `dir` (unit) with `ambient` the unshadowed fraction.
    Directional { dir: [f32; 3], ambient: f32 },
    /// No `light` key (a writer other than billow): the colours are final as stored,
    /// under a light nobody recorded; drawn without runtime lighting.
    Unknown,
}

impl BakedLight {
    /// Whether a renderer lights the colours at runtime (given normals to do it with).
    pub fn is_unlit(&self) -> bool {
        matches!(self, BakedLight::Unlit)
    }

    /// The baked light of header `params` (`Err`: a `light` or `ambient` that is neither
    /// of the forms of [`BakedLight`]; an `ambient` outside `0..=1`).
    pub fn read(params: &BTreeMap<String, String>) -> Result<BakedLight, String> {
        let Some(light) = params.get(param::LIGHT) else {
            return Ok(BakedLight::Unknown);
        };
        let light = light.trim();
        if light == "unlit" {
            return Ok(BakedLight::Unlit);
        }
        let v: Vec<f32> = light
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("header parameter light='{light}': {e}"))?;
        let [x, y, z] = v[..] else {
            return Err(format!(
                "header parameter light='{light}': expected x,y,z or unlit"
            ));
        };
        let len = (x * x + y * y + z * z).sqrt();
        if !(len.is_finite() && len > 1e-6) {
            return Err(format!("header parameter light='{light}': not a direction"));
        }
        let ambient = match params.get(param::AMBIENT) {
            None => DEFAULT_AMBIENT,
            Some(a) => a
                .trim()
                .parse::<f32>()
                .map_err(|e| format!("header parameter ambient='{a}': {e}"))?,
        };
        if !(0.0..=1.0).contains(&ambient) {
            return Err(format!(
                "header parameter ambient={ambient} is out of range (0 to 1)"
            ));
        }
        Ok(BakedLight::Directional {
            dir: [x / len, y / len, z / len],
            ambient,
        })
    }

    /// Writes the keys [`BakedLight::read`] reads into `params` (`Unknown` removes both).
    pub fn write(&self, params: &mut BTreeMap<String, String>) {
        match *self {
            BakedLight::Unknown => {
                params.remove(param::LIGHT);
                params.remove(param::AMBIENT);
            }
            BakedLight::Unlit => {
                // An `ambient` key is left as it is: unlit colours do not read it.
                params.insert(param::LIGHT.into(), "unlit".into());
            }
            BakedLight::Directional { dir, ambient } => {
                let [x, y, z] = dir;
                params.insert(param::LIGHT.into(), format!("{x},{y},{z}"));
                params.insert(param::AMBIENT.into(), ambient.to_string());
            }
        }
    }
}

/// The lighting baked into a volume's colours (`params["bake"]`, SPEC §8.4;
/// [`Header::volume_bake`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VolumeBake {
    /// No key, `"none"` or blank: the colours are albedo (shaded at runtime where the
    /// volume has normals).
    None,
    /// `"ao"`: ambient occlusion multiplied into the colours (how: `ao_rays`,
    /// `ao_distance`, `ao_seed`).
    Ao,
    /// Any other value (a newer writer): lighting a reader cannot reproduce.
    Other(String),
}

impl VolumeBake {
    /// The bake of header `params`.
    pub fn read(params: &BTreeMap<String, String>) -> VolumeBake {
        match params.get(param::BAKE).map(|b| b.trim()) {
            None | Some("" | "none") => VolumeBake::None,
            Some("ao") => VolumeBake::Ao,
            Some(other) => VolumeBake::Other(other.to_string()),
        }
    }

    /// Writes the key [`VolumeBake::read`] reads (`None` removes it).
    pub fn write(&self, params: &mut BTreeMap<String, String>) {
        match self {
            VolumeBake::None => {
                params.remove(param::BAKE);
            }
            b => {
                params.insert(param::BAKE.into(), b.name().into());
            }
        }
    }

    /// As written: `"none"`, `"ao"` or the other value.
    pub fn name(&self) -> &str {
        match self {
            VolumeBake::None => "none",
            VolumeBake::Ao => "ao",
            VolumeBake::Other(s) => s,
        }
    }
}

/// Names of the header `params` that a reader acts on (the baker writes them, the
/// viewer and the evaluators read them; SPEC.md §8). Read them through the typed
/// accessors on [`Header`] ([`Header::shell`], [`Header::baked_light`]), not as string
/// literals.
pub mod param {
    /// Present on a shell asset (a volume on prism cells, tiled in x and z): the shell's
    /// description, e.g. `"height=0.1 ..."`.
    pub const SHELL: &str = "shell";
    /// The light a billboard cloud's colours were baked under: `"x,y,z"` or `"unlit"`
    /// ([`super::Header::baked_light`]).
    pub const LIGHT: &str = "light";
    /// The ambient fraction of a baked directional light, `0..=1` (default
    /// [`super::DEFAULT_AMBIENT`]).
    pub const AMBIENT: &str = "ambient";
    /// Block compression of the texels, e.g. `"bc7"` ([`super::Header::compress`]).
    pub const COMPRESS: &str = "compress";
    /// The lighting baked into a volume's colours ([`super::VolumeBake`]).
    pub const BAKE: &str = "bake";
    /// Present on a volume whose empty space was removed (`billow emptyspace`, `voxelize
    /// --prune`): the prune's parameters ([`super::Header::pruned`]).
    pub const EMPTYSPACE: &str = "emptyspace";
}

impl Header {
    /// The shell description (`params["shell"]`), present iff the asset is a shell
    /// (prism cells; repeat addressing in x and z).
    pub fn shell(&self) -> Option<&str> {
        self.params.get(param::SHELL).map(String::as_str)
    }

    /// Whether the asset is a shell (`params` has `"shell"`).
    pub fn is_shell(&self) -> bool {
        self.params.contains_key(param::SHELL)
    }

    /// Marks the asset as a shell with `description` (see [`Header::shell`]).
    pub fn set_shell(&mut self, description: impl Into<String>) {
        self.params.insert(param::SHELL.into(), description.into());
    }

    /// The lighting baked into the colours (`params["light"]` and `params["ambient"]`,
    /// SPEC §9): what every reader acts on, one rule for all ([`BakedLight::read`]).
    pub fn baked_light(&self) -> Result<BakedLight, String> {
        BakedLight::read(&self.params)
    }

    /// Records the lighting baked into the colours ([`BakedLight::write`]).
    pub fn set_baked_light(&mut self, light: BakedLight) {
        light.write(&mut self.params);
    }

    /// Records the texels' block compression (`params["compress"]`, e.g. `"bc7"`).
    pub fn set_compress(&mut self, codec: impl Into<String>) {
        self.params.insert(param::COMPRESS.into(), codec.into());
    }

    /// The texels' block compression (`params["compress"]`), `None` when stored raw.
    pub fn compress(&self) -> Option<&str> {
        self.params.get(param::COMPRESS).map(String::as_str)
    }

    /// Records that the texels are stored raw (removes `params["compress"]`).
    pub fn clear_compress(&mut self) {
        self.params.remove(param::COMPRESS);
    }

    /// The lighting baked into a volume's colours ([`VolumeBake::read`]).
    pub fn volume_bake(&self) -> VolumeBake {
        VolumeBake::read(&self.params)
    }

    /// Records the lighting baked into a volume's colours ([`VolumeBake::write`]).
    pub fn set_volume_bake(&mut self, bake: &VolumeBake) {
        bake.write(&mut self.params);
    }

    /// The parameters of the prune that removed the volume's empty space
    /// (`params["emptyspace"]`), `None` when it was not pruned.
    pub fn pruned(&self) -> Option<&str> {
        self.params.get(param::EMPTYSPACE).map(String::as_str)
    }

    /// Records the prune's parameters (see [`Header::pruned`]).
    pub fn set_pruned(&mut self, params: impl Into<String>) {
        self.params.insert(param::EMPTYSPACE.into(), params.into());
    }

    /// Check the rules a header must follow, independent of the chunks.
    pub fn validate(&self) -> Result<(), FormatError> {
        let bad = |m: String| Err(FormatError::Header(m));
        let b = &self.bounds;
        for i in 0..3 {
            if !b.min[i].is_finite() || !b.max[i].is_finite() {
                return bad(format!("bounds {:?}..{:?} are not finite", b.min, b.max));
            }
            if b.min[i] > b.max[i] {
                return bad(format!("bounds min {:?} exceeds max {:?}", b.min, b.max));
            }
        }
        if let Some(s) = &self.source {
            if s.file_name.contains(['/', '\\']) {
                return bad(format!(
                    "source.file_name {:?} must be a bare file name without directories",
                    s.file_name
                ));
            }
            let hex_ok = s.sha256.len() == 64
                && s.sha256
                    .bytes()
                    .all(|c| c.is_ascii_digit() || (b'a'..=b'f').contains(&c));
            if !hex_ok {
                return bad(format!(
                    "source.sha256 {:?} is not 64 lowercase hex digits",
                    s.sha256
                ));
            }
        }
        if let Some(v) = &self.volume {
            if v.normals.is_some() && v.moments.is_some() {
                return bad(
                    "volume.normals and volume.moments are both set: a volume stores mean normals or normal moments, not both"
                        .into(),
                );
            }
        }
        match (self.kind, self.volume.is_some()) {
            (AssetKind::Volume, false) => bad("kind is Volume but `volume` is missing".into()),
            (AssetKind::Cloud, true) => bad("kind is Cloud but `volume` is present".into()),
            _ => Ok(()),
        }
    }

    /// A Volume header: level-0 `dims`, `mip_count` levels of RGBA8 colour in
    /// `colour_space`, snorm8 normals when `normals`; unit bounds and no source, seed or
    /// params — set those with struct update syntax (`Header { bounds, ..Header::volume(..) }`).
    /// For synthetic assets and tests; bakers fill every field.
    pub fn volume(
        tool: impl Into<String>,
        colour_space: ColourSpace,
        dims: [u32; 3],
        mip_count: u32,
        normals: bool,
    ) -> Header {
        Header {
            kind: AssetKind::Volume,
            tool: tool.into(),
            source: None,
            bounds: Bounds {
                min: [0.0; 3],
                max: [1.0; 3],
            },
            colour_space,
            seed: None,
            params: BTreeMap::new(),
            volume: Some(VolumeHeader {
                dims,
                mip_count,
                texel: TexelFormat::Rgba8Unorm,
                normals: normals.then_some(NormalEncoding::Rgba8Snorm),
                moments: None,
            }),
        }
    }

    /// Serialize to the canonical RON text stored in `HEAD` (deterministic:
    /// fixed pretty-printing settings, `\n` line ends, maps sorted).
    pub fn to_ron(&self) -> Result<String, FormatError> {
        let config = ron::ser::PrettyConfig::new()
            .depth_limit(8)
            .new_line("\n")
            .indentor("    ")
            .separator(" ")
            .struct_names(false)
            .separate_tuple_members(false)
            .enumerate_arrays(false)
            .compact_arrays(true)
            .extensions(ron::extensions::Extensions::empty())
            .escape_strings(true)
            .compact_structs(false)
            .compact_maps(false)
            .number_suffixes(false);
        let mut text = ron::ser::to_string_pretty(self, config)
            .map_err(|e| FormatError::Encode(format!("header to RON: {e}")))?;
        text.push('\n');
        Ok(text)
    }

    /// Parse RON header text (unknown fields are ignored).
    pub fn from_ron(text: &str) -> Result<Header, FormatError> {
        ron::from_str(text).map_err(|e| FormatError::Header(format!("invalid RON: {e}")))
    }
}

#[cfg(test)]
mod baked_light_tests {
    use super::*;

    /// One rule for every reader: a missing key is a final colour under an unknown light,
    /// `unlit` is albedo, `x,y,z` a directional light with the one default ambient; what
    /// is written is read back; anything else is an error, never a silent unlit.
    #[test]
    fn baked_light_reads_what_it_writes_and_refuses_the_rest() {
        let mut p = BTreeMap::new();
        assert_eq!(BakedLight::read(&p), Ok(BakedLight::Unknown));
        BakedLight::Unlit.write(&mut p);
        assert_eq!(BakedLight::read(&p), Ok(BakedLight::Unlit));
        let d = BakedLight::Directional {
            dir: [0.0, 1.0, 0.0],
            ambient: 0.25,
        };
        d.write(&mut p);
        assert_eq!(p["light"], "0,1,0");
        assert_eq!(BakedLight::read(&p), Ok(d));
        p.remove(param::AMBIENT);
        assert_eq!(
            BakedLight::read(&p),
            Ok(BakedLight::Directional {
                dir: [0.0, 1.0, 0.0],
                ambient: DEFAULT_AMBIENT
            })
        );
        p.insert(param::LIGHT.into(), "0,2,0".into());
        assert!(matches!(
            BakedLight::read(&p),
            Ok(BakedLight::Directional {
                dir: [0.0, 1.0, 0.0],
                ..
            })
        ));
        for bad in ["", " ", "0,0", "0,0,0", "x,y,z", "sun"] {
            p.insert(param::LIGHT.into(), bad.into());
            assert!(BakedLight::read(&p).is_err(), "light={bad:?}");
        }
        p.insert(param::LIGHT.into(), "1,1,1".into());
        p.insert(param::AMBIENT.into(), "1.5".into());
        assert!(BakedLight::read(&p).is_err());
        BakedLight::Unknown.write(&mut p);
        assert!(p.is_empty());
    }
}

#[cfg(test)]
mod volume_bake_tests {
    use super::*;

    /// A missing, blank or `none` bake is albedo, `ao` is ambient occlusion, anything
    /// else is kept by name; writing reads back (and `None` removes the key).
    #[test]
    fn volume_bake_reads_what_it_writes() {
        let mut p = BTreeMap::new();
        assert_eq!(VolumeBake::read(&p), VolumeBake::None);
        for (v, want) in [
            ("", VolumeBake::None),
            (" none ", VolumeBake::None),
            ("ao", VolumeBake::Ao),
            ("gi", VolumeBake::Other("gi".into())),
        ] {
            p.insert(param::BAKE.into(), v.into());
            assert_eq!(VolumeBake::read(&p), want, "{v:?}");
        }
        for b in [
            VolumeBake::Ao,
            VolumeBake::Other("gi".into()),
            VolumeBake::None,
        ] {
            b.write(&mut p);
            assert_eq!(VolumeBake::read(&p), b);
        }
        assert!(!p.contains_key(param::BAKE), "None removes the key");
    }

    /// The compression and prune markers read what their setters write.
    #[test]
    fn compress_and_pruned_markers_round_trip() {
        let mut h = Header::volume("t", ColourSpace::SrgbPremultiplied, [1, 1, 1], 1, false);
        assert_eq!((h.compress(), h.pruned()), (None, None));
        h.set_compress("bc7");
        h.set_pruned("threshold=0");
        assert_eq!(
            (h.compress(), h.pruned()),
            (Some("bc7"), Some("threshold=0"))
        );
        h.clear_compress();
        assert_eq!(h.compress(), None);
    }
}
