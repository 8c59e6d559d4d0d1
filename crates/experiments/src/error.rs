//! The one error type of experiments.

use std::path::PathBuf;

use metaplate_core::toml_locate::Located;

/// Why an experiment file, plan, session journal, simulated participant or statistic was refused.
///
/// File errors name where, as scene errors do: the file (or built-in) with line and column, the dotted key path and
/// the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExperimentError {
    /// Neither a built-in experiment of that name nor a readable file at that path.
    #[error("no built-in experiment `{name}` (the built-ins are: {known}), and no file at that path")]
    NotFound {
        /// The name or path asked for.
        name: String,
        /// The built-in names, comma-separated.
        known: String,
    },
    /// A file could not be read or written.
    #[error("{action} {path}: {reason}")]
    Io {
        /// What was being done (`read`, `append to`, `fsync`).
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        reason: String,
    },
    /// The experiment file is not TOML (where, and what the parser expected; no key path).
    #[error("{}: not valid TOML: {}", .0.location, .0.message)]
    Syntax(Located),
    /// The file does not have an experiment's shape (unknown key, missing key, wrong type) or a value is outside its
    /// valid range: where (`origin:line:column`), the key path (`stimuli[2].pixels.thumb.burst_s`) and why.
    #[error("{0}")]
    Invalid(Located),
    /// The session directory's stored participant, plan or experiment file differs from the one given (resume
    /// refused).
    #[error(
        "the session in {dir} was started with {what} {stored}, not {given}: resume with the same participant, \
         experiment file and seed, or force it"
    )]
    SessionMismatch {
        /// The session directory.
        dir: PathBuf,
        /// `participant`, `plan hash` or `experiment file hash`.
        what: &'static str,
        /// The stored hash.
        stored: String,
        /// The hash given now.
        given: String,
    },
    /// A session file is corrupt somewhere other than a torn last line.
    #[error("{path}: line {line}: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What could not be read.
        reason: String,
    },
    /// A journal entry names a trial the plan does not have, or is otherwise inconsistent with it.
    #[error("journal entry refused: {reason}")]
    BadEntry {
        /// Why.
        reason: String,
    },
    /// An argument outside its valid range (a statistic of no trials, a chance level of 1, an unknown option).
    #[error("invalid {name}: {reason}")]
    InvalidArgument {
        /// Argument name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// The store's durable write failed (its message names the file and the step).
    #[error("{reason}")]
    Store {
        /// The store's message.
        reason: String,
    },
    /// A stimulus could not be turned into control's waveforms.
    #[error("stimulus `{stimulus}`: {reason}")]
    Stimulus {
        /// The stimulus id.
        stimulus: String,
        /// Why.
        reason: String,
    },
    /// Rendering or playing a stimulus failed or was refused (a pixel off the plate or in a gap, a drive that would
    /// clip, a scan not measured through the calibration, a device error).
    #[error("{0}")]
    Playback(String),
    /// A session cannot run as asked (another participant's session, a response key the console keeps, a stored
    /// plan naming a stimulus the file lacks): the message says why and what to do.
    #[error("{0}")]
    Refused(String),
    /// Another process is running the session in this directory: only one writer at a time.
    #[error(
        "the session in {dir} is in use by another process ({holder}): only one `experiment run` may write a \
         session at a time; wait for it to finish, or stop it, then run the same command again"
    )]
    Locked {
        /// The session directory.
        dir: PathBuf,
        /// The holder as its lock records it: `pid N on HOST`, or `pid unknown`.
        holder: String,
    },
    /// The journal answers some trials more than once with different responses (written by two processes at once,
    /// before sessions were locked): the session cannot continue until each is settled.
    #[error(
        "the session in {dir} has trials journalled more than once with different answers: {trials}; settle each \
         with `metaplate experiment correct {dir} --trial N --response LABEL` (the answer that counts), then run \
         the same command again"
    )]
    ConflictingDuplicates {
        /// The session directory.
        dir: PathBuf,
        /// Each conflicting trial with its answers, `trial 33 (left, right)`, comma-separated.
        trials: String,
    },
    /// Writing a report or an event failed (standard output, a Parquet file, a figure).
    #[error("{0}")]
    Output(String),
}

impl From<metaplate_recipes::RecipeError> for ExperimentError {
    fn from(e: metaplate_recipes::RecipeError) -> Self {
        Self::Playback(e.to_string())
    }
}

impl From<metaplate_control::ControlError> for ExperimentError {
    fn from(e: metaplate_control::ControlError) -> Self {
        Self::Playback(e.to_string())
    }
}

impl From<std::io::Error> for ExperimentError {
    fn from(e: std::io::Error) -> Self {
        Self::Output(e.to_string())
    }
}

impl ExperimentError {
    pub(crate) fn io(action: &'static str, path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self + use<> {
        let path = path.to_path_buf();
        move |e| Self::Io { action, path, reason: e.to_string() }
    }

    pub(crate) fn invalid_argument(name: &'static str, reason: impl Into<String>) -> Self {
        Self::InvalidArgument { name, reason: reason.into() }
    }
}

impl From<Located> for ExperimentError {
    fn from(l: Located) -> Self {
        Self::Invalid(l)
    }
}

impl From<metaplate_store::StoreError> for ExperimentError {
    fn from(e: metaplate_store::StoreError) -> Self {
        Self::Store { reason: e.to_string() }
    }
}
