//! The one error type of scenes.

use crate::toml_locate::describe;

/// Why a scene could not be found, read, parsed or accepted, or why a scene computation refused its argument.
///
/// Every message names where: the file (or built-in) with line and column when known, and the key path inside
/// the scene (`plate.thickness_m`, `actuators[2].x_m`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// Neither a built-in scene of that name nor a readable file at that path.
    #[error("no built-in scene `{name}` (the built-ins are: {known}), and no file at that path")]
    NotFound {
        /// The name or path asked for.
        name: String,
        /// The built-in names, comma-separated.
        known: String,
    },
    /// The file exists but could not be read.
    #[error("cannot read scene file {path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's reason.
        reason: String,
    },
    /// The text is not TOML.
    #[error("{location}: not valid TOML: {message}")]
    Syntax {
        /// `origin:line:column`.
        location: String,
        /// What the TOML parser expected.
        message: String,
    },
    /// The TOML does not have the scene's shape: an unknown key, a missing key, or a value of the wrong type.
    #[error("{}", describe(.location, .key_path, .message))]
    Schema {
        /// `origin:line:column`.
        location: String,
        /// Dotted path of the offending key, empty at the top level.
        key_path: String,
        /// What was wrong, with a hint where one is likely (a unit in a key's name).
        message: String,
    },
    /// A value has the right type but is outside its valid range (negative thickness, an actuator off the plate).
    #[error("{}", describe(.location, .key_path, .message))]
    Invalid {
        /// `origin:line:column` when the key is in a file, else the scene's origin.
        location: String,
        /// Dotted path of the offending key.
        key_path: String,
        /// What was wrong and what is accepted.
        message: String,
    },
    /// An argument of a scene computation (a frequency, say) lies outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidArgument {
        /// Argument name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
}

impl SceneError {
    pub(crate) fn invalid_argument(name: &'static str, reason: String) -> Self {
        Self::InvalidArgument { name, reason }
    }

    /// The dotted key path the error is about, when it is about one.
    pub fn key_path(&self) -> Option<&str> {
        match self {
            Self::Schema { key_path, .. } | Self::Invalid { key_path, .. } => Some(key_path),
            _ => None,
        }
    }
}
