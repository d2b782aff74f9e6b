//! Exit codes (documented in docs/cli.md; scripts rely on them, keep them stable).

use std::fmt::Display;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Code {
    /// Something unexpected inside billow.
    Internal = 1,
    // 2 is clap's code for a usage error (bad flags or values).
    /// An input file could not be read (missing, permissions).
    InputIo = 3,
    /// An input file is malformed or invalid (broken glTF/OBJ, NaN vertices, corrupt asset).
    InvalidInput = 4,
    /// The input uses something billow does not support (a required glTF extension, a newer format).
    Unsupported = 5,
    /// `--strict` turned a warning (e.g. a missing texture) into an error.
    Strict = 6,
    /// The output could not be written (nothing partial is left behind).
    OutputIo = 7,
    /// A parameter is out of range (e.g. `--res 0`).
    BadParameter = 8,
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
