//! Green's functions: impulse responses from actuators to grid points, computed in the frequency domain.
//!
//! **Frequency-resolution rule (no time aliasing).** Sampling a spectrum at spacing `df` folds the impulse response
//! with period `1 / df`. With hysteretic loss, a mode at `f` with loss factor `eta` rings with the envelope
//! `exp(-eta pi f t)`. The period must hold a decay of [`ALIAS_DECAY_DB`] (60 dB) for the slowest mode in the band:
//! `1 / df >= max over f in band of ln(10^(60/20)) / (eta_min(f) pi f)`, where `eta_min(f)` is a lower bound on
//! the loss factor of any mode near `f` ([`crate::PlateModel::loss_factor_bound`]: the smallest loss factor of the
//! plate and pads, lowered towards the rods' own as `f` approaches their resonance); on a plain plate the maximum
//! sits at the band's lower edge. The period is also at least the requested duration plus a guard (below). The FFT
//! length is the next fast length of `sample_rate_hz / df`; the responses are then cut to the requested duration
//! with a short fade-out.
//!
//! **Band.** The spectrum is computed only on the bins inside `band_hz` and is zero outside it; raised-cosine
//! tapers lie *inside* the band, 20 % of the lower edge wide at the bottom and 10 % of the upper edge at the top
//! (each at most a quarter of the band), so the band edges ring neither in time nor in frequency.
//!
//! **Zero-phase band limit.** The band limit is a real gain, so it smears the response symmetrically in time: the
//! band-limited response has a precursor before `t = 0`, within a few `1 / taper` seconds, which the inverse FFT
//! wraps to the end of the period. The period is made at least `2 / taper` longer than the requested duration
//! (taper the narrower of the two), so the kept response `[0, duration)` never contains that wrapped precursor; the
//! precursor itself is dropped, as it is from a measured impulse response. Consequently the DFT of a returned
//! response equals the model's frequency response only to within that precursor's share, largest next to sharp
//! resonances.

use std::f64::consts::PI;

use metaplate_dsp::band::BandLimit;
use metaplate_dsp::error::check_sample_rate;
use metaplate_dsp::{fft, window};
use num_complex::Complex64;

use crate::error::PlateError;
use crate::model::{PlateModel, Workspace};

/// Decay (dB) an impulse response must reach within one FFT period (see the module documentation).
pub const ALIAS_DECAY_DB: f64 = 60.0;

/// The longest impulse response returned: 2^24 samples (about 12 minutes at 24 kHz).
pub const MAX_IR_SAMPLES: usize = 1 << 24;

/// The largest memory the spectra and impulse responses of one request may take, bytes (4 GiB).
pub const MAX_GREENS_BYTES: usize = 4 << 30;

/// Frequencies sampled across the band when looking for the slowest ring-down.
const RING_SAMPLES: usize = 1024;

/// Length of the fade-out at the end of each truncated impulse response: 10 ms, at most a tenth of it.
const FADE_OUT_S: f64 = 0.010;

/// What to compute.
///
/// Valid range: non-empty `points` (flat grid indices on the plate) and `actuators` (scene indices);
/// `0 < band_hz.0 < band_hz.1 <= sample_rate_hz / 2`; `duration_s > 0` with `1 <= round(duration_s * sample_rate_hz)
/// <=` [`MAX_IR_SAMPLES`]; finite positive `sample_rate_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct GreensRequest {
    /// Flat grid indices of the points, in the order wanted. Index `grid.len() + k` (past the grid) is actuator
    /// k's own position, its driving point, where the calibration recipe aims the beam (on the magnet).
    pub points: Vec<usize>,
    /// Actuator indices, in the order wanted.
    pub actuators: Vec<usize>,
    /// The band `(f_lo, f_hi)`, Hz: zero outside, tapered just inside its edges.
    pub band_hz: (f64, f64),
    /// Length of each impulse response, s.
    pub duration_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// Impulse responses, point-major: plate normal velocity per unit force, as a discrete-time filter (convolve it,
/// as a plain sum without a `dt` factor, with a force signal in N at `sample_rate_hz` to get velocity in m/s).
#[derive(Debug, Clone, PartialEq)]
pub struct GreensFunctions {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples per impulse response.
    pub ir_len: usize,
    /// Flat grid indices, as requested.
    pub points: Vec<usize>,
    /// Actuator indices, as requested.
    pub actuators: Vec<usize>,
    /// `points.len() * actuators.len() * ir_len` samples: response `(point_k, actuator_k)` starts at
    /// `(point_k * actuators.len() + actuator_k) * ir_len`.
    pub data: Vec<f64>,
}

impl GreensFunctions {
    /// The impulse response from the `actuator_k`-th requested actuator to the `point_k`-th requested point
    /// (positions in the request's lists, not scene indices); `None` when either is out of range.
    pub fn ir(&self, point_k: usize, actuator_k: usize) -> Option<&[f64]> {
        if point_k >= self.points.len() || actuator_k >= self.actuators.len() {
            return None;
        }
        let start = (point_k * self.actuators.len() + actuator_k) * self.ir_len;
        self.data.get(start..start + self.ir_len)
    }
}

/// The frequency grid of a request: FFT length, band gains and the bins to compute.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralPlan {
    /// FFT length, samples.
    pub fft_len: usize,
    /// Samples kept per impulse response.
    pub ir_len: usize,
    /// Bins to compute: (bin index, frequency in Hz, band gain > 0).
    pub bins: Vec<(usize, f64, f64)>,
}

impl SpectralPlan {
    /// The plan for `request` on a model whose modes near `f` (Hz) have a loss factor of at least `loss_bound(f)`
    /// (see the module documentation for the rule).
    ///
    /// Valid range: as [`GreensRequest`], and `0 < loss_bound(f) <= 1` over the band (a lossless plate rings
    /// forever).
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] naming the offending field; [`PlateError::Dsp`] or
    /// [`PlateError::TooLarge`] for an FFT or response longer than the limits.
    pub fn new(request: &GreensRequest, loss_bound: &dyn Fn(f64) -> f64) -> Result<Self, PlateError> {
        let fs = request.sample_rate_hz;
        check_sample_rate(fs)?;
        let (lo, hi) = request.band_hz;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi && hi <= fs / 2.0) {
            return Err(PlateError::invalid(
                "band_hz",
                format!("needs 0 < f_lo < f_hi <= sample_rate_hz / 2 = {} Hz, got ({lo}, {hi})", fs / 2.0),
            ));
        }
        let ir_len_f = (request.duration_s * fs).round();
        if !(request.duration_s > 0.0 && ir_len_f >= 1.0 && ir_len_f <= MAX_IR_SAMPLES as f64) {
            return Err(PlateError::invalid(
                "duration_s",
                format!("must give 1 to {MAX_IR_SAMPLES} samples at {fs} Hz, got {} s", request.duration_s),
            ));
        }
        let ir_len = ir_len_f as usize;
        // The bound varies smoothly (a parabola in f below the rods' resonance): 1024 samples of the band, edges
        // included, find its worst point to well within the FFT length's own rounding up.
        let mut ring_s: f64 = 0.0;
        for i in 0..=RING_SAMPLES {
            let f = lo + (hi - lo) * i as f64 / RING_SAMPLES as f64;
            let eta = loss_bound(f);
            if !(eta.is_finite() && eta > 0.0 && eta <= 1.0) {
                return Err(PlateError::invalid(
                    "loss_factor",
                    format!("Green's functions need every loss factor in (0, 1]; at {f} Hz the bound is {eta}"),
                ));
            }
            ring_s = ring_s.max(ALIAS_DECAY_DB / 20.0 * std::f64::consts::LN_10 / (eta * PI * f));
        }
        let taper_lo = (0.2 * lo).min((hi - lo) / 4.0);
        let taper_hi = (0.1 * hi).min((hi - lo) / 4.0);
        let guard_s = 2.0 / taper_lo.min(taper_hi);
        let min_len = (ring_s * fs).max(ir_len as f64 + guard_s * fs).ceil();
        if min_len > fft::MAX_FFT_LEN as f64 {
            return Err(PlateError::TooLarge {
                what: "FFT for the ring-down",
                needed: min_len as usize,
                max: fft::MAX_FFT_LEN,
            });
        }
        let fft_len = fft::fast_len(min_len as usize)?;
        let band = BandLimit::new(lo + taper_lo, hi - taper_hi, taper_lo, taper_hi)?;
        let df = fs / fft_len as f64;
        let bins = ((lo / df).ceil() as usize..=(hi / df).floor() as usize)
            .map(|k| (k, k as f64 * df))
            .map(|(k, f)| (k, f, band.gain(f)))
            .filter(|&(_, _, g)| g > 0.0)
            .collect();
        Ok(Self { fft_len, ir_len, bins })
    }
}

impl SpectralPlan {
    /// For each of `other`'s bins, the index of this plan's bin at the same frequency, bit for bit; `None` when one
    /// has none. Both plans' bins ascend in frequency.
    pub(crate) fn bins_at(&self, other: &SpectralPlan) -> Option<Vec<usize>> {
        let mut next = 0;
        other
            .bins
            .iter()
            .map(|&(_, f, _)| {
                let found = self.bins[next..].iter().position(|&(_, g, _)| g.to_bits() == f.to_bits())? + next;
                next = found + 1;
                Some(found)
            })
            .collect()
    }
}

impl PlateModel {
    /// Green's functions of this model for `request` (see the module documentation for the frequency grid), the
    /// frequency bins shared among [`crate::ModelOptions::threads`] threads. Deterministic: the same model and request
    /// give bit-identical results whatever the thread count, and a response does not depend on which other points
    /// and actuators are requested with it (each solve has a right-hand side for every actuator of the scene), so a
    /// request cut from a larger one ([`crate::greens_functions`]'s cache) equals it bit for bit.
    ///
    /// # Errors
    /// As [`SpectralPlan::new`] and [`PlateModel::frequency_response`]; [`PlateError::TooLarge`] beyond
    /// [`MAX_GREENS_BYTES`].
    pub fn greens_functions(&self, request: &GreensRequest) -> Result<GreensFunctions, PlateError> {
        let (act, pts) = self.resolve(&request.actuators, &request.points)?;
        let plan = SpectralPlan::new(request, &|f| self.loss_factor_bound(f))?;
        let n_pairs = act.len() * pts.len();
        check_bytes(n_pairs as f64 * (plan.bins.len() as f64 * 16.0 + plan.ir_len as f64 * 8.0))?;
        let spectra = self.band_spectra(&plan, &act, &pts)?;
        let data = impulse_responses(&plan, request.sample_rate_hz, self.options().threads, n_pairs, &|pair, b| {
            spectra[b * n_pairs + pair]
        })?;
        Ok(GreensFunctions {
            sample_rate_hz: request.sample_rate_hz,
            ir_len: plan.ir_len,
            points: request.points.clone(),
            actuators: request.actuators.clone(),
            data,
        })
    }

    /// The spectra at `plan`'s bins from `actuators` (checked scene indices) to `points` (interpolation weights),
    /// bin-major: bin `b`'s row holds `points.len() * actuators.len()` values, point-major. Every bin solves for
    /// all of the scene's actuators and reads out the requested ones.
    pub(crate) fn band_spectra(
        &self,
        plan: &SpectralPlan,
        actuators: &[usize],
        points: &[&[(usize, f64)]],
    ) -> Result<Vec<Complex64>, PlateError> {
        let n_pairs = actuators.len() * points.len();
        let rhs = self.actuator_weights();
        let threads = self.options().threads.min(plan.bins.len()).max(1);
        // Bin-major spectra: each bin's solve writes one contiguous row.
        let mut spectra = vec![Complex64::new(0.0, 0.0); plan.bins.len() * n_pairs];
        let mut rows: Vec<(usize, &mut [Complex64])> = spectra.chunks_mut(n_pairs).enumerate().collect();
        run_interleaved(&mut rows, threads, |chunk| {
            let mut ws = Workspace::new(self, rhs.len())?;
            for (b, row) in chunk.iter_mut() {
                ws.solve(self, plan.bins[*b].1, &rhs, actuators, points, row)?;
            }
            Ok(())
        })?;
        Ok(spectra)
    }
}

/// Checks the memory a computation needs, bytes, against [`MAX_GREENS_BYTES`].
pub(crate) fn check_bytes(bytes: f64) -> Result<(), PlateError> {
    if bytes > MAX_GREENS_BYTES as f64 {
        return Err(PlateError::TooLarge {
            what: "Green's functions (bytes)",
            needed: bytes as usize,
            max: MAX_GREENS_BYTES,
        });
    }
    Ok(())
}

/// The impulse responses of `n_pairs` pairs, pair-major (`plan.ir_len` samples each), from their band spectra:
/// `spectrum(pair, b)` is the pair's value at `plan.bins[b]`. Each response is the inverse FFT of the spectrum times
/// the band gains (zero outside the band), cut to `plan.ir_len` samples with a short fade-out; the pairs are shared
/// among `threads` threads (the result does not depend on it). Every path to a response goes through here, so a
/// response synthesised from stored spectra equals the directly computed one bit for bit.
///
/// # Errors
/// [`PlateError::Dsp`] from the FFT; [`PlateError::NonFiniteResult`].
pub(crate) fn impulse_responses(
    plan: &SpectralPlan,
    sample_rate_hz: f64,
    threads: usize,
    n_pairs: usize,
    spectrum: &(dyn Fn(usize, usize) -> Complex64 + Sync),
) -> Result<Vec<f64>, PlateError> {
    let mut data = vec![0.0; n_pairs * plan.ir_len];
    let mut irs: Vec<(usize, &mut [f64])> = data.chunks_mut(plan.ir_len).enumerate().collect();
    let fade = window::fade_out(((FADE_OUT_S * sample_rate_hz).round() as usize).min(plan.ir_len / 10));
    let threads = threads.min(n_pairs).max(1);
    run_interleaved(&mut irs, threads, |chunk| {
        let mut full_spectrum = vec![Complex64::new(0.0, 0.0); fft::bin_count(plan.fft_len)];
        for (pair, ir) in chunk.iter_mut() {
            for (b, &(k, _, gain)) in plan.bins.iter().enumerate() {
                full_spectrum[k] = spectrum(*pair, b) * gain;
            }
            let full = fft::inverse(&full_spectrum, plan.fft_len)?;
            ir.copy_from_slice(&full[..plan.ir_len]);
            let start = plan.ir_len - fade.len();
            ir[start..].iter_mut().zip(&fade).for_each(|(v, g)| *v *= g);
        }
        Ok(())
    })?;
    metaplate_dsp::error::check_result("Green's functions", &data)?;
    Ok(data)
}

/// Runs `work` on `threads` interleaved shares of `items` (item i goes to thread i mod threads), returning the first
/// error. With one thread it runs inline.
fn run_interleaved<T: Send>(
    items: &mut [T],
    threads: usize,
    work: impl Fn(&mut [&mut T]) -> Result<(), PlateError> + Sync,
) -> Result<(), PlateError> {
    let mut shares: Vec<Vec<&mut T>> = (0..threads).map(|_| Vec::new()).collect();
    for (i, item) in items.iter_mut().enumerate() {
        shares[i % threads].push(item);
    }
    if threads == 1 {
        return shares.iter_mut().try_for_each(|s| work(s));
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> = shares.iter_mut().map(|s| scope.spawn(|| work(s))).collect();
        handles.into_iter().try_for_each(|h| {
            h.join().unwrap_or(Err(PlateError::NonFiniteResult { what: "a Green's-function worker (it panicked)" }))
        })
    })
}
