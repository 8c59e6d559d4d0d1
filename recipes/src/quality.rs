//! Quality measures and gates shared by the recipes.

use metaplate_dsp::DspError;

/// Flatness of a response over a band: its magnitude in dB at every FFT bin within `[lo_hz, hi_hz]`, relative to
/// the median of those bins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flatness {
    /// Median magnitude over the band, dB re 1 (response units).
    pub median_db: f64,
    /// Lowest bin relative to the median, dB (<= 0).
    pub min_db: f64,
    /// Highest bin relative to the median, dB (>= 0).
    pub max_db: f64,
}

impl Flatness {
    /// The larger excursion from the median, dB (>= 0).
    pub fn deviation_db(&self) -> f64 {
        self.max_db.max(-self.min_db)
    }
}

/// Flatness of `ir` (sampled at `sample_rate_hz`) over `band_hz`, on its power smoothed over `1/fraction` of an
/// octave within the band ([`metaplate_dsp::smooth::smoothed_levels_db`]): narrow peaks and notches narrower than
/// the smoothing do not count, and the roll-off outside the band does not pull the edges down.
///
/// Valid range: a finite, non-empty `ir`; `0 <= lo < hi <= sample_rate_hz / 2` with at least one bin inside;
/// `fraction >= 1`.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for `ir`; [`DspError::InvalidParameter`] for a band holding no bin,
/// a bad `fraction`, or a response with no power somewhere in the band (its level in dB would be -infinity).
pub fn smoothed_flatness(
    ir: &[f64],
    sample_rate_hz: f64,
    band_hz: (f64, f64),
    fraction: f64,
) -> Result<Flatness, DspError> {
    let levels = metaplate_dsp::smooth::smoothed_levels_db(ir, sample_rate_hz, fraction, band_hz)?;
    let mut levels_db: Vec<f64> = levels.iter().map(|(_, l)| *l).collect();
    // Not empty: smoothed_levels_db refuses a band without bins.
    let median_db = median(&mut levels_db).unwrap_or(0.0);
    let (min, max) = levels_db.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    Ok(Flatness { median_db, min_db: min - median_db, max_db: max - median_db })
}

/// Relative error of `measured` against `reference`, dB: `10 log10(sum (m - r)^2 / sum r^2)` over their samples
/// (by Parseval, the same as over their spectra). -20 dB is a 10 % error in amplitude; 0 dB an error as large as
/// the reference.
///
/// Valid range: finite signals of equal, nonzero length; a reference with some energy. The result is finite: a
/// measurement equal to the reference returns -400 dB (far below anything f64 rounding resolves).
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for either signal; [`DspError::LengthMismatch`] for different
/// lengths; [`DspError::InvalidParameter`] for an all-zero reference.
pub fn relative_error_db(measured: &[f64], reference: &[f64]) -> Result<f64, DspError> {
    metaplate_dsp::error::check_signal("measured", measured)?;
    metaplate_dsp::error::check_signal("reference", reference)?;
    if measured.len() != reference.len() {
        return Err(DspError::LengthMismatch { what: "measured and reference", a: measured.len(), b: reference.len() });
    }
    let energy: f64 = reference.iter().map(|r| r * r).sum();
    if energy <= 0.0 {
        return Err(DspError::InvalidParameter { name: "reference", reason: "is all zero".into() });
    }
    let error: f64 = measured.iter().zip(reference).map(|(m, r)| (m - r) * (m - r)).sum();
    // -400 dB stands for "identical": below anything f64 rounding can resolve, and finite.
    Ok((10.0 * (error / energy).log10()).max(-400.0))
}

/// Median of finite values (sorts in place); `None` for an empty slice. Even counts average the middle two.
pub fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let mid = values.len() / 2;
    Some(if values.len().is_multiple_of(2) { (values[mid - 1] + values[mid]) / 2.0 } else { values[mid] })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_impulse_is_flat_a_fine_comb_smooths_flat_and_a_coarse_one_does_not() {
        let mut impulse = vec![0.0; 64];
        impulse[3] = 2.0;
        let f = smoothed_flatness(&impulse, 24_000.0, (100.0, 5000.0), 3.0).unwrap();
        // |FFT| of a scaled impulse is exactly 2 at every bin: rounding only.
        assert!((f.median_db - 20.0 * 2f64.log10()).abs() < 1e-9 && f.deviation_db() < 1e-9, "{f:?}");
        // h = d[0] + 0.5 d[240]: ripple every 100 Hz, 9.5 dB peak to trough; a third octave at 1..5 kHz spans 230 Hz
        // or more, so the power averages to within a few tenths of a dB of 1 + 0.25.
        let mut fine = vec![0.0; 4096];
        fine[0] = 1.0;
        fine[240] = 0.5;
        let f = smoothed_flatness(&fine, 24_000.0, (1000.0, 5000.0), 3.0).unwrap();
        assert!(f.deviation_db() < 0.5 && (f.median_db - 10.0 * 1.25f64.log10()).abs() < 0.2, "{f:?}");
        // h = [1, 0.5]: |H| ranges from 0.5 to 1.5 over the full band, too broad for any smoothing to remove.
        let f = smoothed_flatness(&[1.0, 0.5], 24_000.0, (0.0, 12_000.0), 3.0).unwrap();
        assert!(f.max_db - f.min_db > 6.0, "{f:?}");
        assert!(smoothed_flatness(&[1.0, 0.5], 24_000.0, (100.0, 101.0), 3.0).is_err(), "no bin in the band");
        assert!(smoothed_flatness(&[], 24_000.0, (0.0, 1.0), 3.0).is_err());
        assert!(smoothed_flatness(&impulse, 24_000.0, (100.0, 5000.0), 0.5).is_err(), "fraction below 1");
    }

    #[test]
    fn relative_error_of_scaled_identical_and_bad_inputs() {
        let r = [1.0, -2.0, 0.5, 0.0];
        // m = 1.1 r: error energy 0.01 of the reference's: -20 dB up to rounding.
        let m: Vec<f64> = r.iter().map(|v| 1.1 * v).collect();
        assert!((relative_error_db(&m, &r).unwrap() + 20.0).abs() < 1e-9);
        // m = 0: 0 dB exactly; identical: the -400 dB floor.
        assert!(relative_error_db(&[0.0; 4], &r).unwrap().abs() < 1e-12);
        assert_eq!(relative_error_db(&r, &r).unwrap(), -400.0);
        assert!(relative_error_db(&r, &[0.0; 4]).is_err());
        assert!(relative_error_db(&r[..3], &r).is_err());
        assert!(relative_error_db(&[], &[]).is_err());
        assert!(relative_error_db(&[f64::NAN; 4], &r).is_err());
    }

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&mut []), None);
    }
}
