//! Conversion between raw 16-bit codes and volts.
//!
//! A channel with range `R` V (`range_mv / 1000`) maps code `c` to `c * R / 32768` V: code -32768 is `-R` and code
//! 32767 is `R * 32767 / 32768` (one step, `R / 32768`, short of `+R`; 305 uV on +/-10 V). The two extreme codes are
//! the rails: a sample there may have been clipped.

use crate::error::DaqError;

/// Codes per volt-range: the magnitude of the most negative code.
const FULL_SCALE: f64 = 32768.0;

/// Whether a raw code sits on a rail (`i16::MIN` or `i16::MAX`), i.e. the input may have exceeded the range.
pub fn is_rail(raw: i16) -> bool {
    raw == i16::MIN || raw == i16::MAX
}

/// The voltage of raw code `raw` on a channel of range `range_mv` (mV), V.
///
/// Valid for every code and every `range_mv` (0 gives 0 V; a device never offers it). The result is exact in f64:
/// a 16-bit code times a 16-bit range needs 32 bits of mantissa.
pub fn raw_to_volts(raw: i16, range_mv: u16) -> f64 {
    f64::from(raw) * (f64::from(range_mv) / 1000.0) / FULL_SCALE
}

/// The nearest raw code to `volts` on a channel of range `range_mv` (mV), and whether it was clipped: the voltage
/// lay beyond the codes' span (`-R - half a step` to `R * 32767 / 32768 + half a step`) and the code was held at a
/// rail. This is what a device (the mock DAQ) does when it digitises.
///
/// Valid: any finite `volts`; `range_mv >= 1`.
///
/// # Errors
/// [`DaqError::NonFiniteVolts`] for NaN or infinite `volts`; [`DaqError::ConfigRejected`] for `range_mv` 0.
pub fn volts_to_raw(volts: f64, range_mv: u16) -> Result<(i16, bool), DaqError> {
    if !volts.is_finite() {
        return Err(DaqError::NonFiniteVolts { volts: volts.to_string() });
    }
    if range_mv == 0 {
        return Err(DaqError::ConfigRejected {
            code: crate::ErrorCode::BadConfig,
            reason: "a range of 0 mV cannot be quantised".into(),
        });
    }
    let code = (volts * FULL_SCALE / (f64::from(range_mv) / 1000.0)).round();
    let lo = f64::from(i16::MIN);
    let hi = f64::from(i16::MAX);
    let clipped = !(lo..=hi).contains(&code);
    // In range after the clamp, so the cast is exact.
    Ok((code.clamp(lo, hi) as i16, clipped))
}
