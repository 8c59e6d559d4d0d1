//! Wave-field control: propagation matrices, inverse filtering, time reversal, targets and drive-signal rendering.
//!
//! From a dataset of Green's functions to the drive signals that focus chosen waveforms on virtual pixels of the
//! plate, and the field those drives are predicted to make: what `metaplate focus` writes, what `metaplate play` and
//! the experiments play, and what the analyses and the demo predict with.
//!
//! - [`propagation`]: [`PropagationMatrices`], `G(omega)` (M points x N actuators per bin of the operating band,
//!   [`DEFAULT_BAND_HZ`] by default) from a dataset.
//! - [`solve`]: per-bin Tikhonov-regularised least squares (by SVD, never the normal equations, which would square
//!   the condition number) and time reversal.
//! - [`target`]: what each pixel should do (impulses, noise, sinusoids, wavelet trains, null for suppression) and
//!   its spectrum at the band's bins.
//! - [`focal`]: single-pixel focal fields at focus time for every target at once (one GEMM).
//! - [`pixels`]: where a pixel can be focused (on the plate's outline, and within half the measured lattice's step
//!   of a measured point) and the point it snaps to, with the typed refusals `focus` and `play` share
//!   ([`ControlError::PixelOffPlate`], [`ControlError::PixelInGap`]); [`pixels::PointSelection`], the points whose
//!   every row's estimated error is within a limit (`--max-error-db` of `analyze`, `focus` and `play`), and
//!   [`ControlError::PixelExcluded`] for a pixel on a point left out.
//! - [`render`]: drive signals (Kirkeby compensation, peak normalisation) and the predicted field `v(x, t)` (from
//!   the uncompensated drives: the Green's functions were measured through the calibrated actuators).
//! - [`focus`]: pixels in metres with their targets rendered into calibrated, peak-normalised drives (what `focus`,
//!   `play` and the experiments play), and the predicted field at the pixels; by default the impulse responses are
//!   zero-padded by their own length so that a single playback gives the predicted field. With the feature `clap`,
//!   [`focus::RenderOptions`] are command-line arguments.
//!
//! Every error is a [`ControlError`].

pub mod error;
pub mod focal;
pub mod focus;
pub mod pixels;
pub mod propagation;
pub mod render;
pub mod solve;
pub mod target;

pub use error::ControlError;
pub use propagation::{DEFAULT_BAND_HZ, PropagationMatrices};
