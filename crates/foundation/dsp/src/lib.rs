//! Signal processing for metaplate, in `f64` throughout.
//!
//! What every recipe stands on: swept-sine excitations and the protocols that play them, deconvolution of a
//! recording by its excitation or by the recorded loopback reference, coherent averaging of repetitions with
//! clock-drift correction, the per-point pipeline that turns one acquisition into an impulse response, Kirkeby
//! inverse filters and the calibration's equaliser that flatten the actuators, smoothing, and the error measure and
//! statistics the tests, the mock lab and the reports share. It depends on nothing else in the workspace and draws no
//! random numbers (a caller's seeded generator supplies any noise).
//!
//! # Modules
//!
//! | module | what lives there |
//! |---|---|
//! | [`error`] | [`DspError`], and the input and output checks every routine uses (`check_signal`, `check_result`) |
//! | [`fft`] | real FFTs of any length 1 to 2^25, plans cached per thread; `fast_len` (7-smooth lengths) |
//! | [`conv`] | linear convolution by FFT |
//! | [`band`] | `BandLimit`: unity in band, raised-cosine skirts outside (deconvolution, the Kirkeby profile) |
//! | [`window`] | Hann, Blackman and Tukey windows, and the half-Hann fades (the sweeps' fades too) |
//! | [`sweep`] | linear and exponential sweeps; `SweepSpec::default()` is the paper's: 3 s, 62 to 625 Hz, 24 kHz |
//! | [`excitation`] | excitation protocols for one grid point, their registry of names, shots, drives and decoding |
//! | [`deconv`] | regularised spectral division; linear, reference (loopback) and periodic deconvolution; harmonics |
//! | [`average`] | coherent (weighted) averaging of repetitions, with an SNR estimate from their spread |
//! | [`drift`] | sub-sample repetition positions, the player-to-recorder clock line (latency, drift in ppm) |
//! | [`resample`] | band-limited resampling: a Kaiser-windowed sinc `Interpolator` (re-exported by [`drift`]) |
//! | [`pipeline`] | one actuator at one grid point: repetitions and loopback in; response, SNR, drift, latency out |
//! | [`kirkeby`] | Kirkeby inverse filters: trapezoidal regularisation, minimum-phase target, FIR truncation |
//! | [`impulse`] | band-limited impulses; minimum phase by the real cepstrum |
//! | [`noise`] | pink noise from a caller's white noise, exactly 1/f over a band, periodic: the experiments' masker |
//! | [`smooth`] | fractional-octave smoothing (the project's and pyfar's standard one), levels over a band |
//! | [`equalise`] | the calibration's inverse filter, refined until the predicted verification is flat |
//! | [`lstsq`] | small dense real least squares by Householder QR (the equaliser's gain fit) |
//! | [`accuracy`] | the Green's-function error measure and its band, 80 to 600 Hz; the error estimated from noise |
//! | [`stats`] | the median and quantiles (nearest rank) |
//!
//! Some of them in more detail:
//!
//! - [`excitation`]: an `ExcitationProtocol` has a name, a `Scheme` (sequential, the paper's; Hadamard-coded, all
//!   actuators at once, decoded by the matrix's transpose, so 8 actuators need 8 x less time at equal noise;
//!   staggered, every actuator in one shot playing the periodic linear sweep circularly shifted by its slot, each
//!   response cut from its own slot of the periodic deconvolution by `pipeline::PreparedLayout::process_shifted`;
//!   interleaved exponential sweeps), a sweep, repetitions, a deconvolution, and optionally adaptive averaging to a
//!   target SNR or a target estimated error (`AdaptiveTarget`). `NAMES` and `parse` are the registry of names
//!   (`paper`, `quick`, `sequential:DxR`, `hadamard:DxR`, ...; the CLI's `--protocol` help is made from `NAMES`),
//!   and one `Decoder` decodes every scheme, sequential included; Hadamard decoding divides the shots' summed noise
//!   energy by N^2. A scan's responses start `PRE_SAMPLES` before time 0, with `LINEAR_REGULARISATION` or
//!   `EXP_REGULARISATION`.
//! - [`deconv`]: `division_gains` says how much the division scales each bin (a numerator's noise through it);
//!   `separate_harmonics` cuts an exponential sweep's harmonic responses out of the negative-time part.
//! - [`pipeline`]: a response is two-sided with `pre_samples` (the precursor taken from the end of the circular
//!   period). `ChannelResult::noise_energy` is the noise the response keeps within the error band (each bin's spread
//!   of the periods through the division, summed over the band, spread over the period of which the response keeps
//!   `ir_len` samples); `ChannelResult::estimated_error_db` turns it into the row's error estimate.
//! - [`smooth`]: the project's smoothing averages power over a triangular window (continuous as modes enter and
//!   leave it), optionally cut at a band's edges; `fractional_octave_standard` is pyfar's `smooth_fractional_octave`
//!   (log-frequency spline, rectangular mean of the magnitude) and `standard_levels_db` its levels over a band, for
//!   flatness as others report it; `minimum_phase_response` gives the minimum-phase response of a magnitude.
//! - [`equalise`]: the Kirkeby inverse of the smoothed response, refined until the response predicted through the
//!   taps (cut as the verification is) is flat over the band on the project's smoothing and, with
//!   `EqualiserConfig::standard`, on pyfar's standard one too (a minimax fit of both in dB, Lawson's reweighting over
//!   [`lstsq`]; gain nodes half a window apart, an eighth with the standard smoothing). It refuses a Kirkeby band
//!   that does not cover where the standard window reaches (`EqualiserConfig::fit_band_hz`) and reports the predicted
//!   ranges it could not flatten. `EqualiserConfig::calibration` holds the paper's calibration settings, and
//!   `CALIBRATION_MEASURED_BAND_HZ` (50 to 710 Hz) is the band the calibration sweeps, deconvolves and inverts.
//! - [`accuracy`]: `relative_error_db` and `spectral_error_db` (relative error energy in dB, of signals or spectra)
//!   over `ERROR_BAND_HZ`: what the tests, the mock lab, `demo` and `tradeoff` report; `band_energy`;
//!   `estimated_error_db`, the same measure predicted from a response and its noise energy (the random part of the
//!   error: a bias every repetition shares does not show).
//! - [`stats`]: `median` (the mean of the middle two for an even count) and `quantile` return `None` for empty or
//!   non-finite input.
//!
//! # One measurement
//!
//! One actuator at one grid point: the excitation (the sweep, repeated back to back) goes out through the actuator's
//! Kirkeby filter, and uncompensated on the loopback channel; the DAQ records velocity and loopback on its own clock;
//! [`pipeline`] locates each repetition in the loopback, fits the clock line, resamples both channels onto the
//! player's clock, averages the steady-state periods (the first period plus the tail after the last makes one more),
//! divides velocity by loopback (latency cancels), band-limits, maps the result back to the DAQ's clock and returns
//! the impulse response with its SNR.
//!
//! # Invariants
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
