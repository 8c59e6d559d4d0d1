//! Signal processing for metaplate, in `f64` throughout.
//!
//! What every recipe stands on: swept-sine excitations ([`sweep`]), deconvolution of a recording by its excitation or
//! by the recorded loopback reference ([`deconv`]), coherent averaging of repetitions with clock-drift correction
//! ([`average`], [`drift`]), Kirkeby inverse filters that flatten the actuators ([`kirkeby`], refined over a smoothed band by [`equalise`]), and the windows,
//! band limits and band-limited impulses they share ([`window`], [`band`], [`impulse`]), and pink masking noise
//! ([`noise`]).
//!
//! Every public routine checks its input: an empty signal, a NaN or infinity, or a parameter outside the routine's
//! stated valid range is a [`DspError`], never a panic and never a NaN in the result.

pub mod accuracy;
pub mod average;
pub mod band;
pub mod conv;
pub mod deconv;
pub mod drift;
pub mod equalise;
pub mod error;
pub mod excitation;
pub mod fft;
pub mod impulse;
pub mod kirkeby;
pub mod lstsq;
pub mod noise;
pub mod pipeline;
pub mod resample;
pub mod smooth;
pub mod stats;
pub mod sweep;
pub mod window;

pub use error::DspError;
