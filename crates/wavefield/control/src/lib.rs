//! Wave-field control: propagation matrices, inverse filtering, time reversal, targets and drive-signal rendering.
//!
//! [`propagation`]: `G(omega)` (M points x N actuators per bin of the operating band) from a dataset.
//! [`solve`]: per-bin Tikhonov-regularised least squares (by SVD, never the normal equations) and time reversal.
//! [`target`]: what each pixel should do (impulses, noise, sinusoids, wavelet trains, null) and its spectrum.
//! [`focal`]: single-pixel focal fields at focus time for many targets at once (one GEMM).
//! [`pixels`]: where a pixel can be focused (on the plate, near a measured point) and the point it snaps to.
//! [`render`]: drive signals (Kirkeby compensation, peak normalisation) and the predicted field `v(x, t)`.
//! [`focus`]: pixels in metres with their targets rendered into calibrated, peak-normalised drives (what `focus`,
//! `play` and the experiments play), and the predicted field at the pixels.

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
