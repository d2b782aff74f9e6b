//! Exporting assets to interchange formats: a [`VolumeAsset`]'s 3D texture, and a billboard
//! cloud as glTF 2.0 ([`gltf`]: [`write_cloud_gltf`], `.glb` or `.gltf`).
//!
//! - [`write_ktx2`] ([`ktx2`]): the whole MIP chain as one KTX 2.0 3D texture, ready to
//!   upload to a GPU (`R8G8B8A8_SRGB` or `_UNORM`, premultiplied alpha declared in the
//!   data format descriptor).
//! - [`write_slices`] ([`slices`]): one image per z-slice of one MIP level, for looking
//!   at: 8-bit PNG with straight alpha, or float EXR, linear premultiplied.
//!
//! Every file is written atomically ([`billow_format::write_atomic`]): a reader never
//! sees a partial file and a failed write leaves an existing file untouched. Nothing is
//! printed; every problem comes back as an [`ExportError`] naming the file.

pub mod gltf;
pub mod ktx2;
pub mod slices;
pub mod straight;

use std::path::PathBuf;

use billow_format::{ColourSpace, FormatError, VolumeAsset};

pub use self::gltf::{
    cloud_glb_bytes, cloud_gltf_bytes, write_cloud_glb, write_cloud_gltf, GltfAlpha, GltfContainer,
    GltfError, GltfOptions,
};
pub use self::ktx2::{ktx2_bytes, ktx2_bytes_with, write_ktx2, Supercompression, ZstdLevelError};
pub use self::slices::{check_slices, slice_bytes, slice_file_name, write_slices, SliceFormat};

/// Everything that can go wrong exporting.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The asset breaks a format rule (`VolumeAsset::validate`); nothing was written.
    #[error("{path}: cannot export an invalid volume asset: {source}")]
    InvalidAsset {
        path: PathBuf,
        #[source]
        source: FormatError,
    },
    /// The requested MIP level does not exist in the asset.
    #[error("{path}: MIP level {level} does not exist: the asset has {mip_count} level(s), 0 to {}", mip_count - 1)]
    NoSuchLevel {
        path: PathBuf,
        level: u32,
        mip_count: u32,
    },
    /// Creating the output directory failed.
    #[error("{path}: cannot create directory: {source}")]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Encoding an image (PNG or EXR) failed.
    #[error("{path}: cannot encode {format}: {message}")]
    Encode {
        path: PathBuf,
        format: &'static str,
        message: String,
    },
    /// Writing the file failed (the error carries the path).
    #[error(transparent)]
    Write(FormatError),
}

impl ExportError {
    /// The file or directory the error is about.
    pub fn path(&self) -> Option<&std::path::Path> {
        match self {
            ExportError::InvalidAsset { path, .. }
            | ExportError::NoSuchLevel { path, .. }
            | ExportError::CreateDir { path, .. }
            | ExportError::Encode { path, .. } => Some(path),
            ExportError::Write(FormatError::Io { path, .. }) => Some(path),
            ExportError::Write(_) => None,
        }
    }
}

/// Validates `asset` before anything is written to `path`.
pub(crate) fn check_asset(
    asset: &VolumeAsset,
    path: &std::path::Path,
) -> Result<[u32; 3], ExportError> {
    asset
        .validate()
        .map_err(|source| ExportError::InvalidAsset {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(asset.header.volume.map_or([0; 3], |v| v.dims))
}

/// sRGB OETF (linear → encoded), `x` in [0, 1].
pub fn srgb_oetf(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB EOTF (encoded → linear), `x` in [0, 1].
pub fn srgb_eotf(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Decodes one stored colour texel to linear premultiplied RGBA in [0, 1].
pub fn decode_texel(colour_space: ColourSpace, t: [u8; 4]) -> [f32; 4] {
    let n = |v: u8| f32::from(v) / 255.0;
    let c = |v: u8| match colour_space {
        ColourSpace::SrgbPremultiplied => srgb_eotf(n(v)),
        ColourSpace::LinearPremultiplied => n(v),
    };
    [c(t[0]), c(t[1]), c(t[2]), n(t[3])]
}

/// Quantizes a value in [0, 1] (clamped; NaN → 0) to a byte, rounding to nearest.
pub(crate) fn to_u8(x: f32) -> u8 {
    if x.is_nan() {
        return 0;
    }
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}
