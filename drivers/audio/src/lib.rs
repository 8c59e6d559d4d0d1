//! Audio interface drivers: the [`AudioOut`](metaplate_core::audio::AudioOut) capability on real and simulated
//! interfaces.
//!
//! - [`PcmSink`]: the narrow transport an audio driver needs: open a playback stream at an exact rate and channel
//!   count, submit one interleaved buffer to play in the background, wait for its end. The mock audio interface
//!   (`metaplate-mock-audio`) implements it in process; [`AlsaSink`] (feature `alsa`, on by default, Linux only)
//!   implements it on a sound card.
//! - [`AudioDriver`]: `AudioOut` over any `PcmSink`: checks configurations and buffers, converts to the sink's
//!   sample format, reports underruns, reopens and re-applies the configuration.

#[cfg(all(feature = "alsa", target_os = "linux"))]
pub mod alsa;
pub mod driver;
pub mod sink;

#[cfg(all(feature = "alsa", target_os = "linux"))]
pub use alsa::{AlsaSink, PcmListing, SampleFormat, playback_pcms};

pub use driver::AudioDriver;
pub use sink::{PcmError, PcmParams, PcmSink, PcmStatus};
