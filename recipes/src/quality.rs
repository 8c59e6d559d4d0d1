//! The calibration's flatness measure (the error measure and the median live in dsp: `accuracy`, `stats`).

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
    Ok(of_levels(&metaplate_dsp::smooth::smoothed_levels_db(ir, sample_rate_hz, fraction, band_hz)?))
}

/// Flatness of `ir` (sampled at `sample_rate_hz`) over `band_hz` as others would report it: its magnitude spectrum
/// (an FFT of its own length) smoothed by pyfar's standard fractional-octave smoothing
/// ([`metaplate_dsp::smooth::standard_levels_db`]: magnitude averaged with a rectangular window over the whole
/// spectrum), in dB at every bin within the band, relative to their median. It differs from [`smoothed_flatness`] by
/// averaging magnitudes, not power, with a window that steps as narrow modes enter and leave it, and by letting the
/// response half a window beyond the band's edges count.
///
/// Valid range: a finite `ir` of at least 6 samples; `0 <= lo < hi <= sample_rate_hz / 2` with at least one bin
/// inside; `fraction` finite, > 0 and wide enough to hold more than one of the smoothing's points.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for `ir`; [`DspError::InvalidParameter`] for a band holding no bin,
/// a bad `fraction`, or a smoothed level of zero in the band.
pub fn standard_flatness(
    ir: &[f64],
    sample_rate_hz: f64,
    band_hz: (f64, f64),
    fraction: f64,
) -> Result<Flatness, DspError> {
    Ok(of_levels(&metaplate_dsp::smooth::standard_levels_db(ir, sample_rate_hz, fraction, band_hz)?))
}

/// The flatness of `(freq_hz, level_db)` levels: their median and extremes relative to it (the levels are
/// non-empty and finite: the smoothing functions' guarantee).
fn of_levels(levels: &[(f64, f64)]) -> Flatness {
    let mut levels_db: Vec<f64> = levels.iter().map(|(_, l)| *l).collect();
    let median_db = metaplate_dsp::stats::median(&mut levels_db).unwrap_or(0.0);
    let (min, max) = levels_db.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
    Flatness { median_db, min_db: min - median_db, max_db: max - median_db }
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
    fn the_standard_smoothing_averages_magnitude_so_a_comb_reads_lower_than_its_power() {
        let mut impulse = vec![0.0; 4096];
        impulse[3] = 2.0;
        let f = standard_flatness(&impulse, 24_000.0, (100.0, 5000.0), 3.0).unwrap();
        assert!((f.median_db - 20.0 * 2f64.log10()).abs() < 1e-9 && f.deviation_db() < 1e-9, "{f:?}");
        // The comb 1 + 0.5 e^{-j w 240}: its magnitude averages to 1.0635 (the mean of |1 + 0.5 e^{jx}| over x,
        // an elliptic integral) where its power averages to 1.25 (0.97 dB): the same response reads 0.43 dB lower
        // on the standard smoothing. Its rectangular third octave spans 2.3 to 11 ripple periods over 1 to 5 kHz,
        // so a part-period of ripple (+/-0.5 around 1.06) is left: +/-0.6 dB at most at the bottom.
        let mut fine = vec![0.0; 4096];
        fine[0] = 1.0;
        fine[240] = 0.5;
        let standard = standard_flatness(&fine, 24_000.0, (1000.0, 5000.0), 3.0).unwrap();
        let own = smoothed_flatness(&fine, 24_000.0, (1000.0, 5000.0), 3.0).unwrap();
        assert!((standard.median_db - 20.0 * 1.0635f64.log10()).abs() < 0.1, "{standard:?}");
        assert!((own.median_db - standard.median_db - 0.43).abs() < 0.15, "{own:?} against {standard:?}");
        assert!(standard.deviation_db() < 0.6, "{standard:?}");
        assert!(standard_flatness(&fine[..5], 24_000.0, (1000.0, 5000.0), 3.0).is_err(), "too short");
        assert!(standard_flatness(&fine, 24_000.0, (100.0, 100.1), 3.0).is_err(), "no bin in the band");
    }
}
