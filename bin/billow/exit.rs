//! Exit codes (documented in docs/cli.md; scripts rely on them, keep them stable), and the
//! one mapping from every library error to its code: one exhaustive `From<&E> for Code`
//! per error enum, without catch-all arms, so that a new error variant does not compile
//! until someone decides its code.

use std::fmt::Display;

use billow::bbcloud::BbcloudError;
use billow::emptyspace::EmptySpaceError;
use billow::eval::EvalError;
use billow::export::ExportError;
use billow::import::{ImportError, ImportErrorKind};
use billow::shell::ShellError;
use billow::target_error::TargetError;
use billow::voxelize::{CombineParseError, GridError, OptionError, ResolutionError, VoxelizeError};
use billow_format::{CloudError, FormatError};
use billow_view::ViewError;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Code {
    /// Something unexpected inside billow (a bug), including a panic.
    Internal = 1,
    /// A usage error: an unknown flag, a missing argument, or a value that does not parse
    /// as what the flag takes (`--res abc`, `--views bogus`). clap exits 2 for the errors
    /// it finds; billow's own parsers of structured values (`WxH`, `x,y,z`, keywords)
    /// use the same code.
    Usage = 2,
    /// An input file could not be read (missing, permissions, not a regular file, over
    /// the input size limit).
    InputIo = 3,
    /// An input file is malformed or invalid (broken glTF/OBJ, NaN vertices, corrupt asset).
    InvalidInput = 4,
    /// The input uses something billow does not support (a required glTF extension, a newer format).
    Unsupported = 5,
    /// `--strict` turned a warning (e.g. a missing texture) into an error.
    Strict = 6,
    /// The output could not be written (nothing partial is left behind).
    OutputIo = 7,
    /// A parameter parses but is out of range (e.g. `--res 0`, `--res 4097`).
    BadParameter = 8,
    /// The input is valid but holds nothing this command bakes: a mesh without triangles
    /// (points, lines or an empty scene) for every baking command, a mesh without foliage
    /// for bbcloud. `make batch` skips such a mesh with its reason.
    NothingToBake = 9,
    /// `--target-error`: no setting tried reaches the target error (nothing is written).
    TargetNotMet = 10,
}

/// An error on its way to the user: one line, and the exit code it maps to.
#[derive(Debug)]
pub struct CliError {
    pub code: Code,
    pub message: String,
}

impl CliError {
    pub fn new(code: Code, message: impl Display) -> Self {
        // One line, always: collapse any newline a library message might contain.
        let message = message.to_string().replace('\n', " ");
        CliError { code, message }
    }
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// The `billow voxelize` flag a library [`OptionError`] is about.
pub fn option_flag(e: &OptionError) -> &'static str {
    match e {
        OptionError::Align(_) => "--align",
        OptionError::MemoryLimit(_) => "--memory-limit",
        OptionError::AoRays(_) => "--ao-rays",
        OptionError::AoDistance(_) => "--ao-distance",
        OptionError::BoundsNotFinite | OptionError::BoundsEmpty => "--bounds",
    }
}

/// An [`OptionError`] as the command's error, after its flag
/// (`--align: must be between 1 and 2048 voxels, got 0`, exit 8).
pub fn option_error(e: OptionError) -> CliError {
    bad(option_flag(&e), e)
}

/// A [`VoxelizeError`] as the command's error: an option's error names the flag it came
/// from (`--supersample: 9 is out of range (1 to 8)`), the rest the input file.
pub fn voxelize_error(input: &str, e: &VoxelizeError) -> CliError {
    use billow::voxelize::OptionName;
    match e {
        VoxelizeError::OutOfRange(o) | VoxelizeError::Grid(GridError::BadAlign(o)) => {
            return CliError::new(Code::from(e), format!("{}: {o}", option_flag(o)));
        }
        _ => {}
    }
    let flag = match e {
        VoxelizeError::InvalidOption { option, .. } => Some(match option {
            OptionName::Supersample => "--supersample",
            OptionName::MipLevels => "--mips",
            OptionName::Combine => "--combine",
        }),
        VoxelizeError::Resolution(_) | VoxelizeError::Grid(GridError::Resolution(_)) => {
            Some("--res")
        }
        VoxelizeError::Grid(GridError::BadMargin(_)) => Some("--margin"),
        VoxelizeError::Grid(GridError::AlignTooLarge { .. }) => Some("--align"),
        _ => None,
    };
    match (flag, e) {
        (Some(flag), VoxelizeError::InvalidOption { message, .. }) => {
            CliError::new(Code::from(e), format!("{flag}: {message}"))
        }
        (Some(flag), VoxelizeError::Grid(g)) => {
            CliError::new(Code::from(e), format!("{flag}: {g}"))
        }
        (Some(flag), _) => CliError::new(Code::from(e), format!("{flag}: {e}")),
        (None, _) => CliError::new(Code::from(e), format!("{input}: {e}")),
    }
}

/// A [`BbcloudError`] as the command's error: an option's error names its flag
/// (`--samples: 0 is out of range (1 to 1000000)`), the rest the input file.
pub fn bbcloud_error(input: &str, e: &BbcloudError) -> CliError {
    match e {
        BbcloudError::BadParameter { option, message } => {
            let flag = match *option {
                "view" => "--view-dirs".to_string(),
                o => format!("--{}", o.replace('_', "-")),
            };
            CliError::new(Code::from(e), format!("{flag}: {message}"))
        }
        _ => CliError::new(Code::from(e), format!("{input}: {e}")),
    }
}

/// A value that parses but is out of range for `flag` (exit 8).
pub fn bad(flag: &str, e: impl Display) -> CliError {
    CliError::new(Code::BadParameter, format!("{flag}: {e}"))
}

/// A value that does not parse as what `flag` takes (exit 2, like clap's own errors).
pub fn usage(flag: &str, e: impl Display) -> CliError {
    CliError::new(Code::Usage, format!("{flag}: {e}"))
}

impl From<&ImportError> for Code {
    fn from(e: &ImportError) -> Code {
        match e.kind() {
            ImportErrorKind::Io => Code::InputIo,
            ImportErrorKind::Parse | ImportErrorKind::Invalid => Code::InvalidInput,
            ImportErrorKind::Unsupported => Code::Unsupported,
            ImportErrorKind::Strict => Code::Strict,
        }
    }
}

/// A format error met while reading an asset (the writers' errors go through
/// [`ExportError`] or are mapped to [`Code::OutputIo`] where they are written).
impl From<&FormatError> for Code {
    fn from(e: &FormatError) -> Code {
        match e {
            FormatError::Io { .. } => Code::InputIo,
            FormatError::InFile { source, .. } => Code::from(&**source),
            FormatError::NewerMajor { .. } | FormatError::OlderMajor { .. } => Code::Unsupported,
            FormatError::BadMagic { .. }
            | FormatError::Truncated(_)
            | FormatError::Preamble(_)
            | FormatError::Chunk { .. }
            | FormatError::Header(_)
            | FormatError::Volume(_) => Code::InvalidInput,
            // Only the writer raises it: an asset billow built breaks a format rule.
            FormatError::Encode(_) => Code::Internal,
        }
    }
}

/// A cloud asset read from a file.
impl From<&CloudError> for Code {
    fn from(e: &CloudError) -> Code {
        match e {
            CloudError::Format(f) => Code::from(f),
            CloudError::Invalid(_) => Code::InvalidInput,
        }
    }
}

impl From<&ResolutionError> for Code {
    fn from(e: &ResolutionError) -> Code {
        match e {
            ResolutionError::Empty
            | ResolutionError::NotANumber { .. }
            | ResolutionError::WrongArity { .. } => Code::Usage,
            ResolutionError::Zero { .. }
            | ResolutionError::TooLarge { .. }
            | ResolutionError::Negative { .. } => Code::BadParameter,
        }
    }
}

impl From<&CombineParseError> for Code {
    fn from(e: &CombineParseError) -> Code {
        match e {
            CombineParseError::Unknown(_) => Code::Usage,
            CombineParseError::Expr(x) if x.too_large => Code::BadParameter,
            CombineParseError::Expr(_) => Code::Usage,
        }
    }
}

impl From<&GridError> for Code {
    fn from(e: &GridError) -> Code {
        match e {
            // Every grid failure comes from the flags (resolution, margin, alignment) applied
            // to the scene's bounds: a bad parameter, as before this mapping was spelled out.
            GridError::BadBounds { .. }
            | GridError::BadMargin(_)
            | GridError::Resolution(_)
            | GridError::BadAlign(_)
            | GridError::AlignTooLarge { .. } => Code::BadParameter,
        }
    }
}

impl From<&VoxelizeError> for Code {
    fn from(e: &VoxelizeError) -> Code {
        match e {
            VoxelizeError::Resolution(r) => Code::from(r),
            VoxelizeError::Grid(g) => Code::from(g),
            VoxelizeError::InvalidOption { .. }
            | VoxelizeError::OutOfRange(_)
            | VoxelizeError::TooMuchMemory { .. } => Code::BadParameter,
            // A valid mesh without a triangle (points, lines, an empty scene).
            VoxelizeError::EmptyScene => Code::NothingToBake,
            VoxelizeError::InvalidScene(_) => Code::InvalidInput,
        }
    }
}

impl From<&ExportError> for Code {
    fn from(e: &ExportError) -> Code {
        match e {
            ExportError::NoSuchLevel { .. } => Code::BadParameter,
            ExportError::InvalidAsset { .. } => Code::Internal,
            ExportError::CreateDir { .. } | ExportError::Encode { .. } | ExportError::Write(_) => {
                Code::OutputIo
            }
        }
    }
}

impl From<&EvalError> for Code {
    fn from(e: &EvalError) -> Code {
        match e {
            EvalError::Io { .. } | EvalError::Encode { .. } => Code::OutputIo,
            EvalError::InvalidAsset(_) => Code::InvalidInput,
            EvalError::TooManySlices { .. } | EvalError::InvalidParam(_) => Code::BadParameter,
            // The binary checks sizes and cameras first: these are bugs when they happen.
            EvalError::SizeMismatch { .. } | EvalError::InvalidCamera(_) => Code::Internal,
        }
    }
}

impl From<&EmptySpaceError> for Code {
    fn from(e: &EmptySpaceError) -> Code {
        match e {
            EmptySpaceError::InvalidParam(_) | EmptySpaceError::TooMuchMemory { .. } => {
                Code::BadParameter
            }
            EmptySpaceError::Shell | EmptySpaceError::NotABox(_) => Code::Unsupported,
            EmptySpaceError::InvalidAsset(_)
            | EmptySpaceError::AlreadyPruned(_)
            | EmptySpaceError::HasBands => Code::InvalidInput,
        }
    }
}

impl From<&TargetError> for Code {
    fn from(e: &TargetError) -> Code {
        match e {
            TargetError::InvalidTarget(_) => Code::BadParameter,
            TargetError::Unreachable { .. } => Code::TargetNotMet,
        }
    }
}

impl From<&ShellError> for Code {
    fn from(e: &ShellError) -> Code {
        match e {
            ShellError::InvalidHeight(_) | ShellError::InvalidUvScale(_) => Code::BadParameter,
            ShellError::EmptySurface => Code::NothingToBake,
            ShellError::NoPrisms { .. } => Code::InvalidInput,
        }
    }
}

impl From<&BbcloudError> for Code {
    fn from(e: &BbcloudError) -> Code {
        match e {
            BbcloudError::NoFoliage | BbcloudError::EmptyScene => Code::NothingToBake,
            // TooLarge: the atlases the parameters ask for exceed the limit (estimate refused).
            BbcloudError::UnknownMaterial(..)
            | BbcloudError::BadParameter { .. }
            | BbcloudError::TooLarge(_) => Code::BadParameter,
            // The cloud billow built breaks a format rule: a bug.
            BbcloudError::Asset(_) => Code::Internal,
        }
    }
}

impl From<&ViewError> for Code {
    fn from(e: &ViewError) -> Code {
        match e {
            ViewError::NoAdapter(_) | ViewError::NoDisplay(_) => Code::Unsupported,
            ViewError::Gpu(_) => Code::Internal,
            ViewError::SceneInput { .. } => Code::InputIo,
            ViewError::InvalidAsset(_) | ViewError::Scene { .. } => Code::InvalidInput,
            ViewError::InvalidParam(_) | ViewError::TooManySlices { .. } => Code::BadParameter,
        }
    }
}

/// Reading an image (`billow compare`).
impl From<&image::ImageError> for Code {
    fn from(e: &image::ImageError) -> Code {
        use image::ImageError as I;
        match e {
            I::IoError(_) => Code::InputIo,
            I::Decoding(_) | I::Parameter(_) => Code::InvalidInput,
            I::Unsupported(_) => Code::Unsupported,
            I::Limits(_) => Code::BadParameter,
            // Encoding is not reading: the caller maps a failed write itself.
            I::Encoding(_) => Code::OutputIo,
        }
    }
}
