//! How far a measured response is from a reference: the relative error energy in dB that the tests, the mock lab's
//! accuracy, `metaplate demo` and `metaplate tradeoff` all report, and the band they compare over.

use num_complex::Complex64;

use crate::error::{DspError, check_signal};

/// The band a Green's function's error is measured over, Hz: inside the flat part of the paper's deconvolution band
/// (62..625 Hz, with skirts outside it) and the sweep.
pub const ERROR_BAND_HZ: (f64, f64) = (80.0, 600.0);

/// What [`relative_error_db`] returns for a measurement equal to its reference: far below anything f64 rounding
/// resolves, and finite.
pub const IDENTICAL_DB: f64 = -400.0;

/// Relative error of `measured` against `reference`, dB: `10 log10(sum (m - r)^2 / sum r^2)` over their samples
/// (by Parseval, the same as over their spectra). -20 dB is a 10 % error in amplitude; 0 dB an error as large as
/// the reference; a measurement equal to the reference gives [`IDENTICAL_DB`].
///
/// Valid range: finite signals of equal, nonzero length; a reference with some energy.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for either signal; [`DspError::LengthMismatch`] for different
/// lengths; [`DspError::InvalidParameter`] for an all-zero reference.
pub fn relative_error_db(measured: &[f64], reference: &[f64]) -> Result<f64, DspError> {
    check_signal("measured", measured)?;
    check_signal("reference", reference)?;
    same_length(measured.len(), reference.len())?;
    let error: f64 = measured.iter().zip(reference).map(|(m, r)| (m - r) * (m - r)).sum();
    error_ratio_db(error, reference.iter().map(|r| r * r).sum())
}

/// As [`relative_error_db`] over spectra (complex values at the same frequencies, for example the FFT bins of a
/// band): `10 log10(sum |m - r|^2 / sum |r|^2)`.
///
/// # Errors
/// As [`relative_error_db`]; a non-finite real or imaginary part is [`DspError::NonFinite`] at its value's index.
pub fn spectral_error_db(measured: &[Complex64], reference: &[Complex64]) -> Result<f64, DspError> {
    check_spectrum("measured", measured)?;
    check_spectrum("reference", reference)?;
    same_length(measured.len(), reference.len())?;
    let error: f64 = measured.iter().zip(reference).map(|(m, r)| (m - r).norm_sqr()).sum();
    error_ratio_db(error, reference.iter().map(Complex64::norm_sqr).sum())
}

fn same_length(a: usize, b: usize) -> Result<(), DspError> {
    if a != b {
        return Err(DspError::LengthMismatch { what: "measured and reference", a, b });
    }
    Ok(())
}

fn check_spectrum(input: &'static str, x: &[Complex64]) -> Result<(), DspError> {
    if x.is_empty() {
        return Err(DspError::Empty { input });
    }
    match x.iter().enumerate().find(|(_, c)| !(c.re.is_finite() && c.im.is_finite())) {
        Some((index, c)) => {
            Err(DspError::NonFinite { input, index, value: if c.re.is_finite() { c.im } else { c.re } })
        }
        None => Ok(()),
    }
}

/// `10 log10(error / energy)`, at least [`IDENTICAL_DB`]; an error for a reference without energy.
fn error_ratio_db(error: f64, energy: f64) -> Result<f64, DspError> {
    // `!(energy > 0.0)` also refuses a NaN energy (finite inputs whose squares overflow).
    if !(energy > 0.0 && energy.is_finite() && error.is_finite()) {
        return Err(DspError::InvalidParameter {
            name: "reference",
            reason: format!("has no usable energy (error {error}, reference energy {energy})"),
        });
    }
    Ok((10.0 * (error / energy).log10()).max(IDENTICAL_DB))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_in_db() {
        let r = [1.0, -2.0, 3.0, 0.5];
        let m: Vec<f64> = r.iter().map(|v| v * 1.1).collect();
        assert!((relative_error_db(&m, &r).unwrap() + 20.0).abs() < 1e-9);
        assert!(relative_error_db(&[0.0; 4], &r).unwrap().abs() < 1e-12);
        assert_eq!(relative_error_db(&r, &r).unwrap(), IDENTICAL_DB);
        assert!(relative_error_db(&r, &[0.0; 4]).is_err());
        assert!(relative_error_db(&r[..3], &r).is_err());
        assert!(relative_error_db(&[], &[]).is_err());
        assert!(relative_error_db(&[f64::NAN; 4], &r).is_err());
        assert!(relative_error_db(&[1e300; 4], &r).is_err(), "an overflowing error is refused, not infinite");
    }

    #[test]
    fn spectral_error_matches_the_real_one() {
        let r = [1.0, -2.0, 3.0, 0.5];
        let m = [1.1, -1.9, 2.5, 0.0];
        let c = |x: &[f64]| x.iter().map(|&v| Complex64::new(v, 0.0)).collect::<Vec<_>>();
        assert_eq!(spectral_error_db(&c(&m), &c(&r)).unwrap(), relative_error_db(&m, &r).unwrap());
        let mut bad = c(&m);
        bad[2].im = f64::INFINITY;
        assert!(matches!(spectral_error_db(&bad, &c(&r)), Err(DspError::NonFinite { index: 2, .. })));
        assert!(spectral_error_db(&c(&r), &[Complex64::new(0.0, 0.0); 4]).is_err());
    }
}
