//! Why a recipe stopped.

use metaplate_core::aim::AimError;
use metaplate_core::audio::AudioError;
use metaplate_core::daq::DaqError;
use metaplate_core::vibrometer::VibrometerError;
use metaplate_dsp::DspError;
use metaplate_store::StoreError;

/// Why a recipe could not go on. Device faults that recovery handles never reach the caller; what does is either a
/// configuration to fix, an instrument that refuses for good, or the store refusing to write.
#[derive(Debug, thiserror::Error)]
pub enum RecipeError {
    /// The recipe's configuration or inputs are invalid (a wiring, a grid, a calibration that does not fit).
    #[error("invalid recipe configuration: {0}")]
    Config(String),
    /// An instrument kept failing in a way that repeating the step could not fix (every acquisition in a row spoiled,
    /// every recording with a gap): the rig needs a person.
    #[error("instrument: {0}")]
    Device(String),
    /// A failure inside the recipe itself (a worker thread that stopped, a playback shot with no buffers): a bug,
    /// never the user's configuration.
    #[error("internal error: {0}")]
    Internal(String),
    /// The vibrometer failed in a way recovery cannot fix (it refuses the command).
    #[error(transparent)]
    Vibrometer(#[from] VibrometerError),
    /// The aimer refused a point or failed in a way recovery cannot fix.
    #[error(transparent)]
    Aim(#[from] AimError),
    /// The DAQ failed in a way recovery cannot fix.
    #[error(transparent)]
    Daq(#[from] DaqError),
    /// The audio interface failed in a way recovery cannot fix.
    #[error(transparent)]
    Audio(#[from] AudioError),
    /// Signal processing refused its input (a bug or a configuration outside the valid range, never a bad point:
    /// those are flagged in the dataset).
    #[error("signal processing: {0}")]
    Dsp(#[from] DspError),
    /// The dataset could not be written or read.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// Rendering a pattern's drives failed (a pixel off the plate or in a gap of the scan, a bad target).
    #[error(transparent)]
    Control(#[from] metaplate_control::ControlError),
    /// A pattern cannot be played as asked (a dataset or calibration that does not fit it, a rig of another plate).
    #[error("{reason}")]
    PlayRefused {
        /// Why, naming the dataset, calibration or plate.
        reason: String,
    },
    /// The calibration dataset is missing, incomplete or inconsistent.
    #[error("calibration {dir}: {reason}")]
    Calibration {
        /// The calibration directory.
        dir: String,
        /// What is wrong.
        reason: String,
    },
    /// A pattern would clip at the requested level: nothing was played.
    #[error(
        "the drive would clip: at level {level} its peak is {peak_fs:.3} of full scale ({:.2} dB over); the highest \
         level that does not clip is {max_level:.4}",
        20.0 * peak_fs.log10()
    )]
    Clipping {
        /// The level asked for, relative to full scale.
        level: f64,
        /// The drives' peak at that level, full scale (above 1).
        peak_fs: f64,
        /// The highest level that plays without clipping.
        max_level: f64,
    },
    /// The run was stopped on request (Ctrl-C) before it completed; everything committed so far is kept.
    #[error("stopped on request after {committed} committed points; resume to continue")]
    Interrupted {
        /// Points (or actuators, for a calibration) committed in the dataset.
        committed: usize,
    },
}
