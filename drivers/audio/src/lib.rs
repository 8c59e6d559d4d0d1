//! Audio interface drivers: the [`AudioOut`](metaplate_core::audio::AudioOut) capability on real and simulated
//! interfaces.
//!
//! - [`PcmSink`]: the narrow transport an audio driver needs: open a playback stream at an exact rate and channel
//!   count, submit one interleaved buffer to play in the background, wait for its end. The mock audio interface
//!   (`metaplate-mock-audio`) implements it in process; `AlsaSink` (feature `alsa`, Linux only) implements it on a
//!   sound card: the exact rate with ALSA's resampler off, the first sample format the device offers among
//!   `FLOAT_LE`, `S32_LE`, `S24_LE`, `S24_3LE` and `S16_LE` (converted from `f32`), a writer thread that recovers
//!   from underruns (xruns) and counts them.
//! - `AlsaCaptureDaq` (feature `alsa`): the interface's inputs as the [`Daq`](metaplate_core::daq::Daq)
//!   capability, through the same stream set-up, read in blocks of volts (the inputs' declared full scale).
//! - [`AudioDriver`]: `AudioOut` over any `PcmSink`: refuses a device that opens at another rate or channel count
//!   than asked, checks buffers, interleaves them as `f32` clipped at full scale, reports underruns, reopens and
//!   re-applies the configuration.
//!
//! The feature `alsa` is on by default for this crate's own tests; the workspace depends on the crate without it,
//! and the binary turns it on (through `metaplate-drivers`' `hardware` feature). Elsewhere than Linux it is
//! compiled out.

#[cfg(all(feature = "alsa", target_os = "linux"))]
pub mod alsa;
#[cfg(all(feature = "alsa", target_os = "linux"))]
pub mod capture;
pub mod driver;
pub mod samples;
pub mod sink;

#[cfg(all(feature = "alsa", target_os = "linux"))]
pub use alsa::{AlsaSink, PcmListing, capture_pcms, playback_pcms};
#[cfg(all(feature = "alsa", target_os = "linux"))]
pub use capture::AlsaCaptureDaq;

pub use driver::AudioDriver;
pub use samples::{SampleFormat, decode, encode};
pub use sink::{PcmError, PcmParams, PcmSink, PcmStatus};
