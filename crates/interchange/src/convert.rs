//! One universal-file function as a metaplate impulse response.

use metaplate_dsp::fft;
use metaplate_uff::{Complex64, Function58, FunctionType, Ordinate};

use crate::error::{InterchangeError, refuse};

/// An impulse response from one function.
pub(crate) struct Converted {
    /// The response, SI units.
    pub(crate) ir: Vec<f32>,
    /// Its sample rate, Hz.
    pub(crate) sample_rate_hz: f64,
    /// Samples before time 0.
    pub(crate) pre_samples: u32,
    /// Converted from a frequency response function.
    pub(crate) from_frf: bool,
}

/// The impulse response of a time response (as read, from its start time) or of a frequency response function
/// (see [`crate::import`](mod@crate::import)), in SI units: ordinates times `force_per_n / length_per_m` (dataset 164's factors).
/// `spectrum` is a reusable buffer.
///
/// # Errors
/// [`InterchangeError::Refused`] for a function that is neither a real time response nor a frequency response, an
/// abscissa that is not a time step or a real FFT's frequencies, a time response starting after time 0, values out
/// of the f32 range; [`InterchangeError::Dsp`] if the inverse transform fails.
pub(crate) fn to_ir(
    function: &Function58,
    length_per_m: f64,
    force_per_n: f64,
    spectrum: &mut Vec<Complex64>,
) -> Result<Converted, InterchangeError> {
    let h = &function.header;
    let to_si = force_per_n / length_per_m;
    let finite = |v: f64| -> Result<f32, InterchangeError> {
        let v = (v * to_si) as f32;
        if v.is_finite() { Ok(v) } else { refuse!("a value is out of the f32 range in SI units") }
    };
    match (h.function_type, &function.ordinate) {
        (FunctionType::TimeResponse, Ordinate::Real(values)) => {
            let Some(sample_rate_hz) = metaplate_uff::sample_rate_from_step(h.abscissa_step) else {
                refuse!("abscissa step {} s is not a time step", h.abscissa_step)
            };
            let pre = (-h.abscissa_start * sample_rate_hz).round();
            if !(0.0..=f64::from(u32::MAX)).contains(&pre) {
                refuse!(
                    "the response starts at {} s, after time 0; metaplate responses start at or before it",
                    h.abscissa_start
                );
            }
            let ir = values.iter().map(|&v| finite(v)).collect::<Result<Vec<f32>, _>>()?;
            Ok(Converted { ir, sample_rate_hz, pre_samples: pre as u32, from_frf: false })
        }
        (FunctionType::TimeResponse, Ordinate::Complex(_)) => refuse!("a complex time response"),
        (FunctionType::FrequencyResponse, ordinate) => {
            let df = h.abscissa_step;
            let k0 = (h.abscissa_start / df).round();
            if !(df.is_finite() && df > 0.0 && (0.0..1e9).contains(&k0)) {
                refuse!(
                    "the frequency response's abscissa ({} Hz step {} Hz) is not of a real FFT",
                    h.abscissa_start,
                    df
                );
            }
            if ordinate.is_empty() {
                refuse!("a frequency response without values");
            }
            let k0 = k0 as usize;
            let last = k0 + ordinate.len() - 1;
            let n = 2 * last.max(1);
            spectrum.clear();
            spectrum.resize(fft::bin_count(n), Complex64::new(0.0, 0.0));
            match ordinate {
                Ordinate::Complex(values) => spectrum[k0..=last].copy_from_slice(values),
                Ordinate::Real(values) => {
                    for (bin, &v) in spectrum[k0..=last].iter_mut().zip(values) {
                        *bin = Complex64::new(v, 0.0);
                    }
                }
            }
            // A real signal's spectrum is real at 0 Hz and at Nyquist.
            spectrum[0].im = 0.0;
            spectrum[n / 2].im = 0.0;
            let samples = fft::inverse(spectrum, n)?;
            let Some(sample_rate_hz) = metaplate_uff::sample_rate_from_step(1.0 / (n as f64 * df)) else {
                refuse!("frequency step {df} Hz gives no sample rate")
            };
            let ir = samples.iter().map(|&v| finite(v)).collect::<Result<Vec<f32>, _>>()?;
            Ok(Converted { ir, sample_rate_hz, pre_samples: 0, from_frf: true })
        }
        (FunctionType::Other(code), _) => refuse!("function type {code} is neither a time nor a frequency response"),
    }
}
