//! The viewer's errors (the binary turns them into one-line messages).

/// What the driver-install hint says, everywhere a missing adapter is reported.
pub const DRIVER_HINT: &str =
    "install a Vulkan driver, e.g. `apt-get install -y mesa-vulkan-drivers libvulkan1` \
(Mesa's software Vulkan, lavapipe; `.ci/ensure-vulkan` does this), or a GPU vendor driver";

#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No GPU adapter (no Vulkan/Metal/DX12/GL driver found).
    #[error("no GPU adapter found ({0}); {DRIVER_HINT}")]
    NoAdapter(String),
    /// No window system to open a window on (no display server).
    #[error("no window system ({0}); render without one: --headless --screenshot OUT.png")]
    NoDisplay(String),
    /// The adapter refused to create a device, or a GPU operation failed.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A volume asset the renderer cannot use.
    #[error("invalid asset: {0}")]
    InvalidAsset(String),
    /// A parameter out of range (spacing, image size, camera).
    #[error("{0}")]
    InvalidParam(String),
    /// The slice spacing would need more slices than the limit.
    #[error(
        "{needed} slices needed, more than the limit of {limit} (raise the spacing or the limit)"
    )]
    TooManySlices { needed: usize, limit: usize },
    /// A scene file problem: the file and the field or value at fault.
    #[error("{file}: {problem}")]
    Scene { file: String, problem: String },
    /// A file a scene needs could not be read: the scene file itself, or an asset or
    /// mesh it names that does not exist.
    #[error("{file}: {problem}")]
    SceneInput { file: String, problem: String },
}

impl From<billow_core::slicing::TooManySlices> for ViewError {
    fn from(e: billow_core::slicing::TooManySlices) -> Self {
        ViewError::TooManySlices {
            needed: e.needed,
            limit: e.limit,
        }
    }
}
