//! The one error type of this crate.

use std::path::PathBuf;

use metaplate_analysis::AnalysisError;
use metaplate_core::grid::GridError;
use metaplate_core::scene::SceneError;
use metaplate_dsp::DspError;
use metaplate_dsp::excitation::ProtocolNameError;
use metaplate_lab::LabError;
use metaplate_plate::PlateError;
use metaplate_recipes::RecipeError;
use metaplate_store::StoreError;

/// Why an evaluation could not be made: the step that failed, and the lower crate's error.
#[derive(Debug, thiserror::Error)]
pub enum EvaluationError {
    /// A scene could not be loaded or used.
    #[error("{step}")]
    Scene {
        /// What was being done (with the scene's name or file).
        step: String,
        /// The core crate's reason.
        #[source]
        source: SceneError,
    },
    /// A protocol name that names no protocol.
    #[error(transparent)]
    Protocol(#[from] ProtocolNameError),
    /// A grid subset or grid index that does not fit the scene's grid.
    #[error("{step}")]
    Grid {
        /// What was being done.
        step: String,
        /// The core crate's reason.
        #[source]
        source: GridError,
    },
    /// The mock lab could not be built or refused a comparison.
    #[error("{step}")]
    Lab {
        /// What was being done.
        step: String,
        /// The lab's reason.
        #[source]
        source: LabError,
    },
    /// A recipe (scan, calibrate, a calibration's loading) failed.
    #[error("{step}")]
    Recipe {
        /// What was being done.
        step: String,
        /// The recipe's reason.
        #[source]
        source: RecipeError,
    },
    /// A dataset could not be read or written.
    #[error("{step}")]
    Store {
        /// What was being done (with the dataset's directory).
        step: String,
        /// The store's reason.
        #[source]
        source: StoreError,
    },
    /// An analysis or its figures failed.
    #[error("{step}")]
    Analysis {
        /// What was being done.
        step: String,
        /// The analysis crate's reason.
        #[source]
        source: AnalysisError,
    },
    /// The plate model could not be built or solved.
    #[error("{step}")]
    Plate {
        /// What was being done.
        step: String,
        /// The plate crate's reason.
        #[source]
        source: PlateError,
    },
    /// Focusing (rendering a pattern) failed.
    #[error("{step}")]
    Control {
        /// What was being done.
        step: String,
        /// The control crate's reason.
        #[source]
        source: metaplate_control::ControlError,
    },
    /// A figure could not be drawn or written.
    #[error("{step}")]
    Figure {
        /// What was being drawn, where.
        step: String,
        /// The figures crate's reason.
        #[source]
        source: metaplate_figures::FigureError,
    },
    /// Signal processing refused its input.
    #[error("{step}")]
    Dsp {
        /// What was being done.
        step: String,
        /// The dsp crate's reason.
        #[source]
        source: DspError,
    },
    /// A file or directory could not be read, written or removed.
    #[error("{step} {}", path.display())]
    Io {
        /// What was being done ("writing", "creating", ...).
        step: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The system's reason.
        #[source]
        source: std::io::Error,
    },
    /// An input that the evaluation refuses (named, with what is accepted).
    #[error("{0}")]
    Invalid(String),
    /// A result that cannot be used (a dataset with fewer rows than planned, no row to compare).
    #[error("{0}")]
    Incomplete(String),
}

/// Attaches the failed step to a lower crate's error: `result.step(|| "scanning ...".into())?` (the step as its
/// message, the lower error as its source).
pub(crate) trait StepExt<T> {
    /// The result with the error wrapped in its [`EvaluationError`] variant, `step` naming what was being done.
    fn step(self, step: impl FnOnce() -> String) -> Result<T, EvaluationError>;
}

macro_rules! step_ext {
    ($error:ty, $variant:ident) => {
        impl<T> StepExt<T> for Result<T, $error> {
            fn step(self, step: impl FnOnce() -> String) -> Result<T, EvaluationError> {
                self.map_err(|source| EvaluationError::$variant { step: step(), source })
            }
        }
    };
}

step_ext!(SceneError, Scene);
step_ext!(GridError, Grid);
step_ext!(LabError, Lab);
step_ext!(RecipeError, Recipe);
step_ext!(StoreError, Store);
step_ext!(AnalysisError, Analysis);
step_ext!(PlateError, Plate);
step_ext!(DspError, Dsp);
step_ext!(metaplate_control::ControlError, Control);
step_ext!(metaplate_figures::FigureError, Figure);

/// A file-system failure on `path` while `step` ("writing", "creating", "removing").
pub(crate) fn io_error(step: &'static str, path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> EvaluationError {
    let path = path.into();
    move |source| EvaluationError::Io { step, path, source }
}
