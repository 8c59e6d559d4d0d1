//! The truth as a scan's window keeps it, beside the full truth, for the error budget.
//!
//! A scan stores each response in a window of `ir_len` samples, `pre_samples` of them before time 0, band-limited
//! by the deconvolution. [`MockLab::response_error_db`] compares it with the full truth, so its error also counts
//! what lies outside the window: the plate's ring-down after it (and the band limit's smear beyond it), which no
//! processing of the window can hold. [`WindowedTruth`] separates the two:
//! - the **windowed truth**: the true chain response ([`MockLab::true_response`]), band-limited exactly as the
//!   deconvolution band-limits (its [`DeconvConfig::band`]), as a time response on a grid long enough to hold it
//!   without time aliasing, cut to the window: what a perfect measurement of this window returns;
//! - the **truncation**: the windowed truth's error against the full truth, from the truth alone: what a perfect
//!   measurement of this window still misses (a property of the plate's decay and of the window chosen, not of the
//!   processing);
//! - optionally the truth **as a periodic excitation of period `P` measures it**: the response folded modulo `P`
//!   (a sweep period shorter than the response wraps its tail onto its start), then cut to the window.
//!
//! All three are compared as [`MockLab::response_error_db`] compares: on the window's own DFT bins within a band,
//! by [`spectral_error_db`].

use metaplate_dsp::accuracy::spectral_error_db;
use metaplate_dsp::deconv::{DeconvConfig, RINGING_GUARD_CYCLES};
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::KirkebyFilter;
use num_complex::Complex64;

use crate::accuracy::filter_response_at_bins;
use crate::{LabError, MockLab};

/// Guard on each side of the response on the long grid when the band limit has a zero-width skirt (a brick wall,
/// whose ringing decays only as `1 / t`), or none, in windows: the coil's own ring-down is far shorter.
const GUARD_WINDOWS_WITHOUT_SKIRT: usize = 4;

/// One row's truth on the DFT bins of a scan's window (`n = ir_len` samples, time 0 first as
/// [`crate::time_zero_first`] arranges a measured response).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowedTruth {
    /// Window length, samples.
    n: usize,
    /// Sample rate, Hz.
    sample_rate_hz: f64,
    /// The full truth at the window's bins `0..=n/2` (as [`MockLab::true_response`], through the compensation if
    /// any).
    full: Vec<Complex64>,
    /// The windowed truth's DFT, bins `0..=n/2`.
    windowed: Vec<Complex64>,
    /// The truth folded modulo the period, then windowed, bins `0..=n/2`, when a period was given.
    periodic: Option<Vec<Complex64>>,
    /// The band-limited truth on the long grid, time 0 at index 0 and negative times at the end.
    response: Vec<f64>,
}

impl MockLab {
    /// The truth of (`point`, `actuator`) as `window` keeps it (see the module docs): the full truth, the windowed
    /// truth and, with `period_samples`, the truth a periodic excitation of that period measures, all on the
    /// window's DFT bins. With `compensation`, the truth is taken through that inverse filter with its modelling
    /// delay removed, as [`MockLab::response_error_db`] takes it.
    ///
    /// The long grid holds the Green's function, the filter, the window and, on each side, [`RINGING_GUARD_CYCLES`]
    /// periods of the band limit's narrowest skirt (the band-limited response's smear), rounded up to a whole
    /// number of windows so that the window's bins are bins of the long grid: the full truth there is exact (the
    /// DFT of the zero-padded Green's function is its DTFT at those frequencies).
    ///
    /// Valid range: `window` valid ([`DeconvConfig::validate`]) at the lab's Green's-function rate (the DAQ's);
    /// `period_samples >= window.ir_len`; a filter at that rate.
    ///
    /// # Errors
    /// [`LabError::NotPrepared`] for a point or actuator the lab did not prepare; [`LabError::InvalidOption`] for a
    /// window, period or filter out of range; [`LabError::Dsp`] for a grid beyond the FFT's limit.
    pub fn windowed_truth(
        &self,
        point: usize,
        actuator: usize,
        window: &DeconvConfig,
        period_samples: Option<usize>,
        compensation: Option<&KirkebyFilter>,
    ) -> Result<WindowedTruth, LabError> {
        let invalid = |name: &'static str, reason: String| LabError::InvalidOption { name, reason };
        window.validate()?;
        let greens = &self.plate.greens;
        let fs = greens.sample_rate_hz;
        if window.sample_rate_hz.to_bits() != fs.to_bits() {
            return Err(invalid(
                "window",
                format!("at {} Hz; the lab's Green's functions are at {fs} Hz", window.sample_rate_hz),
            ));
        }
        if let Some(filter) = compensation
            && filter.sample_rate_hz.to_bits() != fs.to_bits()
        {
            return Err(invalid(
                "compensation",
                format!("the filter runs at {} Hz, the lab at {fs} Hz", filter.sample_rate_hz),
            ));
        }
        let (n, pre) = (window.ir_len, window.pre_samples);
        if let Some(p) = period_samples
            && p < n
        {
            return Err(invalid("period_samples", format!("{p} is shorter than the {n}-sample window")));
        }
        let point_k = self.prepared_point(point)?;
        let ir = greens.ir(point_k, actuator).ok_or(LabError::NotPrepared { what: format!("actuator {actuator}") })?;
        let coil = self.plate.coils.get(actuator).ok_or(LabError::NotPrepared { what: format!("coil {actuator}") })?;

        let narrowest_skirt_hz = window.band.map_or(0.0, |b| b.lo_transition_hz.min(b.hi_transition_hz).max(0.0));
        let guard = if narrowest_skirt_hz > 0.0 {
            (RINGING_GUARD_CYCLES * fs / narrowest_skirt_hz).ceil() as usize
        } else {
            GUARD_WINDOWS_WITHOUT_SKIRT * n
        };
        let taps = compensation.map_or(0, |f| f.taps.len());
        let needed = greens.ir_len + taps + n + 2 * guard;
        let m = needed.div_ceil(n).max(2);
        let long = m * n;

        let mut spectrum = fft::forward(ir, long)?;
        let filter_response = match compensation {
            Some(filter) => Some((filter_response_at_bins(filter, long)?, filter.modelling_delay_samples as f64)),
            None => None,
        };
        for (j, s) in spectrum.iter_mut().enumerate() {
            let f = fft::bin_freq_hz(j, long, fs);
            *s *= coil.frequency_response(f);
            if let Some((response, delay)) = &filter_response {
                let advance = Complex64::from_polar(1.0, std::f64::consts::TAU * j as f64 * delay / long as f64);
                *s *= response[j] * advance;
            }
        }
        let full: Vec<Complex64> = (0..fft::bin_count(n)).map(|k| spectrum[k * m]).collect();
        if let Some(band) = &window.band {
            for (j, s) in spectrum.iter_mut().enumerate() {
                *s *= band.gain(fft::bin_freq_hz(j, long, fs));
            }
        }
        // The band-limited response on the long circle: time 0 at index 0, negative times at the end.
        let response = fft::inverse(&spectrum, long)?;
        let cut = |at: &dyn Fn(isize) -> f64| -> Vec<f64> {
            (0..n).map(|i| at(if i < n - pre { i as isize } else { i as isize - n as isize })).collect()
        };
        let on_circle = |t: isize| response[t.rem_euclid(long as isize) as usize];
        let windowed = fft::forward(&cut(&on_circle), n)?;
        let periodic = match period_samples {
            Some(p) => {
                // The response's samples at signed times, the negative half of the long circle before time 0.
                let mut folded = vec![0.0; p];
                for (i, v) in response.iter().enumerate() {
                    let t = if i < long / 2 { i as isize } else { i as isize - long as isize };
                    folded[t.rem_euclid(p as isize) as usize] += v;
                }
                let on_period = |t: isize| folded[t.rem_euclid(p as isize) as usize];
                Some(fft::forward(&cut(&on_period), n)?)
            }
            None => None,
        };
        Ok(WindowedTruth { n, sample_rate_hz: fs, full, windowed, periodic, response })
    }
}

/// Which truth a measured response is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Truth {
    /// The whole response ([`MockLab::true_response`]).
    Full,
    /// The response band-limited and cut to the window: what a perfect measurement of the window returns.
    Windowed,
    /// The response folded modulo the excitation's period, then windowed (when a period was given).
    Periodic,
}

impl WindowedTruth {
    /// The error of `ir` (a window-long response, time 0 first: [`crate::time_zero_first`]) against `truth`, over
    /// the window's bins within `band_hz`, dB (as [`MockLab::response_error_db`]).
    ///
    /// Valid range: finite `ir` of the window's length; `0 <= lo < hi <= sample_rate / 2` holding a bin where the
    /// truth is not zero.
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] for another length, no periodic truth, or a band with no bin or no truth in it;
    /// [`LabError::Dsp`] for a non-finite `ir`.
    pub fn error_db(&self, ir: &[f64], truth: Truth, band_hz: (f64, f64)) -> Result<f64, LabError> {
        if ir.len() != self.n {
            return Err(LabError::InvalidOption {
                name: "ir",
                reason: format!("{} samples against a {}-sample window", ir.len(), self.n),
            });
        }
        let measured = fft::forward(ir, self.n)?;
        self.compare(&measured, self.truth(truth)?, band_hz)
    }

    /// The band-limited true response on the long grid (m/s per full scale, at the lab's rate), time 0 at index 0 and
    /// negative times at the end of the circle: a whole number of windows long, and long enough that the response
    /// is negligible half-way round.
    pub fn response(&self) -> &[f64] {
        &self.response
    }

    /// What a perfect measurement of the window misses against the full truth over `band_hz`, dB: the windowed
    /// truth's error against the full truth (the truncation; from the truth alone).
    ///
    /// # Errors
    /// As [`WindowedTruth::error_db`] for the band.
    pub fn truncation_db(&self, band_hz: (f64, f64)) -> Result<f64, LabError> {
        self.compare(&self.windowed, &self.full, band_hz)
    }

    /// What the period's wrap adds against the windowed truth over `band_hz`, dB: the periodic truth's error
    /// against the windowed truth (from the truth alone).
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] without a period; as [`WindowedTruth::error_db`] for the band.
    pub fn aliasing_db(&self, band_hz: (f64, f64)) -> Result<f64, LabError> {
        self.compare(self.truth(Truth::Periodic)?, &self.windowed, band_hz)
    }

    fn truth(&self, truth: Truth) -> Result<&[Complex64], LabError> {
        match truth {
            Truth::Full => Ok(&self.full),
            Truth::Windowed => Ok(&self.windowed),
            Truth::Periodic => self.periodic.as_deref().ok_or(LabError::InvalidOption {
                name: "truth",
                reason: "no period was given for a periodic truth".into(),
            }),
        }
    }

    fn compare(&self, measured: &[Complex64], truth: &[Complex64], band_hz: (f64, f64)) -> Result<f64, LabError> {
        let bins: Vec<usize> = (0..truth.len())
            .filter(|&k| (band_hz.0..=band_hz.1).contains(&fft::bin_freq_hz(k, self.n, self.sample_rate_hz)))
            .collect();
        let pick = |x: &[Complex64]| bins.iter().map(|&k| x[k]).collect::<Vec<_>>();
        spectral_error_db(&pick(measured), &pick(truth)).map_err(|e| LabError::InvalidOption {
            name: "band_hz",
            reason: format!("{band_hz:?} Hz holds no bin where the truth is non-zero and finite ({e})"),
        })
    }
}
