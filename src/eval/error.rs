//! Errors of the evaluation tools.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {message}")]
    Encode { path: PathBuf, message: String },
    #[error("image sizes differ: {a_w}x{a_h} vs {b_w}x{b_h}")]
    SizeMismatch {
        a_w: u32,
        a_h: u32,
        b_w: u32,
        b_h: u32,
    },
    #[error("invalid volume asset: {0}")]
    InvalidAsset(String),
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    #[error("invalid parameter: {0}")]
    InvalidParam(String),
    #[error("too many slices: {needed} exceed the limit {limit}; raise the spacing or the limit")]
    TooManySlices { needed: usize, limit: usize },
}

impl From<billow_core::slicing::TooManySlices> for EvalError {
    fn from(e: billow_core::slicing::TooManySlices) -> Self {
        EvalError::TooManySlices {
            needed: e.needed,
            limit: e.limit,
        }
    }
}
