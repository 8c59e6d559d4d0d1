//! One universal-file function as a metaplate impulse response.

use metaplate_dsp::fft;
use metaplate_uff::{Complex64, Function58, FunctionType, Ordinate};

use crate::error::{InterchangeError, refuse};
use crate::quantity::Motion;

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
/// (see [`crate::import`](mod@crate::import)), in SI units: ordinates times `to_si` (the ordinate's factor over the
/// denominator's), then turned into velocity from `motion` (`None`: a quantity declared unknown, kept as it is):
/// an FRF's bins at frequency f divided by j2πf (acceleration) or multiplied by it (displacement), 0 Hz set to zero
/// when dividing; a time response through the frequency domain of its own record (its FFT, the same factors, the
/// inverse FFT: integration or differentiation over the record's band, the record taken as one period).
/// `spectrum` is a reusable buffer.
///
/// # Errors
/// [`InterchangeError::Refused`] for a function that is neither a real time response nor a frequency response, an
/// abscissa that is not a time step or a real FFT's frequencies, a time response starting after time 0, values out
/// of the f32 range; [`InterchangeError::Dsp`] if a transform fails.
pub(crate) fn to_ir(
    function: &Function58,
    to_si: f64,
    motion: Option<Motion>,
    spectrum: &mut Vec<Complex64>,
) -> Result<Converted, InterchangeError> {
    let h = &function.header;
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
            let velocity;
            let values = match motion {
                Some(Motion::Velocity) | None => values,
                Some(motion) => {
                    velocity = time_to_velocity(values, sample_rate_hz, motion, spectrum)?;
                    &velocity
                }
            };
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
            for (k, bin) in spectrum.iter_mut().enumerate().take(last + 1).skip(k0) {
                *bin = to_velocity(*bin, k as f64 * df, motion);
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

/// A spectrum's bin at `freq_hz` of `motion` as velocity: divided by j2πf (acceleration; 0 at 0 Hz), multiplied by it
/// (displacement), kept (velocity, or `None`: declared unknown).
fn to_velocity(bin: Complex64, freq_hz: f64, motion: Option<Motion>) -> Complex64 {
    let jw = Complex64::new(0.0, 2.0 * std::f64::consts::PI * freq_hz);
    match motion {
        Some(Motion::Acceleration) if freq_hz > 0.0 => bin / jw,
        Some(Motion::Acceleration) => Complex64::new(0.0, 0.0),
        Some(Motion::Displacement) => bin * jw,
        Some(Motion::Velocity) | None => bin,
    }
}

/// A time record of `motion` at `sample_rate_hz` as velocity, through its FFT (the record taken as one period).
fn time_to_velocity(
    values: &[f64],
    sample_rate_hz: f64,
    motion: Motion,
    spectrum: &mut Vec<Complex64>,
) -> Result<Vec<f64>, InterchangeError> {
    let n = values.len();
    spectrum.clear();
    spectrum.resize(fft::bin_count(n), Complex64::new(0.0, 0.0));
    fft::forward_into(values, n, spectrum)?;
    let df = sample_rate_hz / n as f64;
    for (k, bin) in spectrum.iter_mut().enumerate() {
        *bin = to_velocity(*bin, k as f64 * df, Some(motion));
    }
    if n.is_multiple_of(2)
        && let Some(nyquist) = spectrum.last_mut()
    {
        // Real at Nyquist: the imaginary part j·f gives it has no real signal.
        nyquist.im = 0.0;
    }
    Ok(fft::inverse(spectrum, n)?)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn a_sine_of_acceleration_integrates_to_its_velocity() {
        // 8 periods of 1 kHz over 8 ms at 64 kHz: a(t) = A sin(wt), v(t) = -A/w cos(wt).
        let (fs, f, n) = (64_000.0, 1000.0, 512);
        let w = 2.0 * std::f64::consts::PI * f;
        let a: Vec<f64> = (0..n).map(|i| 3.0 * (w * i as f64 / fs).sin()).collect();
        let v = time_to_velocity(&a, fs, Motion::Acceleration, &mut Vec::new()).unwrap();
        for (i, got) in v.iter().enumerate() {
            let want = -3.0 / w * (w * i as f64 / fs).cos();
            // A whole number of periods: exact but for rounding (relative to the amplitude 3/w).
            assert!((got - want).abs() < 1e-9 * 3.0 / w, "{i}: {got} vs {want}");
        }
        let d: Vec<f64> = (0..n).map(|i| 2.0 * (w * i as f64 / fs).cos()).collect();
        let v = time_to_velocity(&d, fs, Motion::Displacement, &mut Vec::new()).unwrap();
        for (i, got) in v.iter().enumerate() {
            let want = -2.0 * w * (w * i as f64 / fs).sin();
            assert!((got - want).abs() < 1e-9 * 2.0 * w, "{i}: {got} vs {want}");
        }
    }
}
