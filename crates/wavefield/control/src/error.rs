//! The one error type of this crate.

use metaplate_dsp::DspError;
use metaplate_store::StoreError;

/// Why a control routine refused its input or could not produce a finite result.
#[derive(Debug, thiserror::Error)]
pub enum ControlError {
    /// A parameter lies outside the routine's valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Parameter name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// Two inputs that must match in size do not.
    #[error("{what}: sizes {a} and {b} differ")]
    LengthMismatch {
        /// What was compared.
        what: &'static str,
        /// First size.
        a: usize,
        /// Second size.
        b: usize,
    },
    /// An input had no elements where at least one is needed.
    #[error("{input} is empty")]
    Empty {
        /// Which input.
        input: &'static str,
    },
    /// The dataset lacks the impulse response of a (point, actuator) pair that a propagation matrix needs.
    #[error("the dataset has no impulse response for grid point {point_index}, actuator {actuator}")]
    MissingResponse {
        /// Grid point (flat index).
        point_index: u32,
        /// Actuator number.
        actuator: u16,
    },
    /// A requested grid point is not among the points of the propagation matrices.
    #[error("grid point {point_index} is not among the measured points")]
    UnknownPoint {
        /// Grid point (flat index).
        point_index: u32,
    },
    /// No FFT bin of the impulse responses falls inside the requested band.
    #[error(
        "no frequency bin lies in the band {lo_hz} .. {hi_hz} Hz (bin spacing {spacing_hz} Hz, Nyquist {nyquist_hz} Hz)"
    )]
    EmptyBand {
        /// Lower band edge, Hz.
        lo_hz: f64,
        /// Upper band edge, Hz.
        hi_hz: f64,
        /// Bin spacing, Hz.
        spacing_hz: f64,
        /// Nyquist frequency, Hz.
        nyquist_hz: f64,
    },
    /// An input held NaN or an infinity.
    #[error("{input} contains a non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        input: &'static str,
        /// First offending index.
        index: usize,
    },
    /// The computation overflowed to NaN or infinity although the inputs were finite.
    #[error("{what} produced a non-finite result; the input is outside the routine's valid range")]
    NonFiniteResult {
        /// Which computation.
        what: &'static str,
    },
    /// The linear-algebra backend failed (an SVD that did not converge).
    #[error("{what} failed: {reason}")]
    LinearAlgebra {
        /// Which computation.
        what: &'static str,
        /// The backend's message.
        reason: String,
    },
    /// A pixel lies off the plate's outline (or has non-finite coordinates): nothing there can be focused.
    #[error("pixel ({x_m}, {y_m}) is off the plate")]
    PixelOffPlate {
        /// x on the plate, m.
        x_m: f64,
        /// y on the plate, m.
        y_m: f64,
    },
    /// A pixel lies farther than half the measured step from the nearest measured point: the focus would land
    /// elsewhere.
    #[error(
        "pixel ({x_m}, {y_m}) is {distance_mm:.1} mm from the nearest measured point ({:.4}, {:.4}), more than half \
         the measured spacing ({:.1} x {:.1} mm): it lies in a gap of the scan (a support or a masked point)",
        nearest_m.0, nearest_m.1, step_mm.0, step_mm.1
    )]
    PixelInGap {
        /// x on the plate, m.
        x_m: f64,
        /// y on the plate, m.
        y_m: f64,
        /// Distance to the nearest measured point, mm.
        distance_mm: f64,
        /// The nearest measured point, m.
        nearest_m: (f64, f64),
        /// The measured lattice's step along x and y, mm.
        step_mm: (f64, f64),
    },
    /// A pixel on scattered points (an imported scan mesh) lies farther from the nearest point than that point's
    /// own cell reaches: outside the points or in a gap between them.
    #[error(
        "pixel ({x_m}, {y_m}) is {distance_mm:.1} mm from the nearest measured point ({:.4}, {:.4}), more than \
         {limit_mm:.1} mm (0.71 of that point's distance to its nearest neighbour, the corner of its cell on a square \
         mesh): it lies outside the scattered points or in a gap between them",
        nearest_m.0, nearest_m.1
    )]
    PixelOffPoints {
        /// x in the points' plane, m.
        x_m: f64,
        /// y in the points' plane, m.
        y_m: f64,
        /// Distance to the nearest measured point, mm.
        distance_mm: f64,
        /// The nearest measured point, m.
        nearest_m: (f64, f64),
        /// The largest distance accepted there, mm.
        limit_mm: f64,
    },
    /// The point a pixel snaps to was excluded for its Green's functions' estimated error
    /// ([`crate::pixels::PointSelection`]).
    #[error(
        "the pixel at ({x_m} m, {y_m} m) snaps to point {point_index}, whose Green's functions' estimated error \
         ({error_db:.1} dB) exceeds the limit of {max_error_db:.1} dB: move the pixel, re-measure the point, or raise \
         the limit"
    )]
    PixelExcluded {
        /// x on the plate, m.
        x_m: f64,
        /// y on the plate, m.
        y_m: f64,
        /// The point it snaps to (grid flat index).
        point_index: u32,
        /// That point's worst estimated error over its actuators, dB.
        error_db: f64,
        /// The limit in force, dB.
        max_error_db: f64,
    },
    /// A pixel given as text (`X_M,Y_M[:TARGET]`) does not parse.
    #[error("--pixel `{text}`: {reason}")]
    Pixel {
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A step of a longer computation failed: which step, and why.
    #[error("{context}: {cause}")]
    During {
        /// The step (`building G(omega)`, `solving the drives`).
        context: &'static str,
        /// Its error.
        cause: Box<ControlError>,
    },
    /// Reading the dataset failed.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A shared signal-processing helper refused its input.
    #[error(transparent)]
    Dsp(#[from] DspError),
}

/// The first non-finite value of `values`, as a [`ControlError::NonFinite`] naming `input`.
pub(crate) fn check_finite(input: &'static str, values: impl IntoIterator<Item = f64>) -> Result<(), ControlError> {
    match values.into_iter().position(|v| !v.is_finite()) {
        Some(index) => Err(ControlError::NonFinite { input, index }),
        None => Ok(()),
    }
}
