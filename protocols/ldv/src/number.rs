//! Fixed-point decimal numbers on the wire: the one grammar every numeric argument uses.
//!
//! Grammar: `[+|-] digits [ . digits ]`, at most [`MAX_NUMBER_LEN`] characters, at most as many decimals as the
//! quantity's resolution allows. No exponents, no `nan`/`inf`, no hex, no bare `.5` or `5.`: a value is either
//! exactly representable at the quantity's resolution or refused, so nothing is rounded silently on either side.

use crate::error::LdvProtocolError;

/// The longest numeric token accepted, characters: room for every documented value with leading zeros to spare,
/// small enough that a hostile token costs nothing.
pub const MAX_NUMBER_LEN: usize = 16;

/// Parses a decimal token into an integer count of `10^-decimals` units (`"-1.5"` with 3 decimals gives `-1500`).
///
/// Valid range: any `decimals`; any token of at most [`MAX_NUMBER_LEN`] characters whose scaled value fits an `i64`.
///
/// # Errors
/// [`LdvProtocolError::MalformedNumber`] naming `what` for a token that is too long, breaks the grammar, has more
/// than `decimals` decimals, or whose scaled value overflows an `i64`.
pub(crate) fn parse_scaled(text: &str, decimals: u32, what: &'static str) -> Result<i64, LdvProtocolError> {
    let malformed = |reason| LdvProtocolError::MalformedNumber { what, text: text.to_owned(), reason };
    if text.len() > MAX_NUMBER_LEN {
        return Err(malformed("too many characters"));
    }
    let (negative, unsigned) = match text.as_bytes().first() {
        Some(b'-') => (true, &text[1..]),
        Some(b'+') => (false, &text[1..]),
        _ => (false, text),
    };
    let (int_part, frac_part) = match unsigned.split_once('.') {
        Some((int_part, frac_part)) => (int_part, Some(frac_part)),
        None => (unsigned, None),
    };
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !all_digits(int_part) || frac_part.is_some_and(|f| !all_digits(f)) {
        return Err(malformed("expected [+|-]digits[.digits]"));
    }
    let frac = frac_part.unwrap_or("");
    if frac.len() > decimals as usize {
        return Err(malformed("more decimals than the resolution"));
    }
    // Sixteen digits scaled by 10^3 can exceed i64::MAX (9.2e18), so every step is checked.
    let overflow = || malformed("too large");
    let mut value: i64 = 0;
    for b in int_part.bytes().chain(frac.bytes()) {
        value = value.checked_mul(10).and_then(|v| v.checked_add(i64::from(b - b'0'))).ok_or_else(overflow)?;
    }
    // Pad the missing decimals: "1.5" with 3 decimals is 1500 units.
    for _ in frac.len()..decimals as usize {
        value = value.checked_mul(10).ok_or_else(overflow)?;
    }
    Ok(if negative { -value } else { value })
}

/// Formats `value` units of `10^-decimals` as a decimal with exactly `decimals` decimals (`-1` with 3 decimals gives
/// `"-0.001"`; with 0 decimals, a plain integer).
pub(crate) fn format_scaled(value: i64, decimals: u32) -> String {
    if decimals == 0 {
        return value.to_string();
    }
    let scale = 10_u64.pow(decimals);
    let magnitude = value.unsigned_abs();
    let sign = if value < 0 { "-" } else { "" };
    format!("{sign}{}.{:0width$}", magnitude / scale, magnitude % scale, width = decimals as usize)
}

/// Checks that a scaled integer lies in `-limit..=limit` (or `0..=limit` when `signed` is false) and narrows it.
///
/// # Errors
/// [`LdvProtocolError::OutOfRange`] naming `what`, showing the value with `decimals` decimals.
pub(crate) fn check_range(
    value: i64,
    limit: i32,
    signed: bool,
    decimals: u32,
    what: &'static str,
    valid: &'static str,
) -> Result<i32, LdvProtocolError> {
    let min = if signed { -i64::from(limit) } else { 0 };
    if value < min || value > i64::from(limit) {
        return Err(LdvProtocolError::OutOfRange { what, value: format_scaled(value, decimals), valid });
    }
    // In range of an i32 limit, so the conversion cannot fail; map rather than unwrap all the same.
    i32::try_from(value).map_err(|_| LdvProtocolError::OutOfRange { what, value: value.to_string(), valid })
}

/// Rounds a floating-point value given in whole units to the nearest `1 / units_per_step` step and range-checks it
/// against `-limit..=limit` steps.
///
/// Valid range: any finite `value`; values that round outside the limit are refused.
///
/// # Errors
/// [`LdvProtocolError::NonFinite`] for NaN or infinity; [`LdvProtocolError::OutOfRange`] beyond the limit.
pub(crate) fn quantize(
    value: f64,
    steps_per_unit: f64,
    limit: i32,
    what: &'static str,
    valid: &'static str,
) -> Result<i32, LdvProtocolError> {
    if !value.is_finite() {
        return Err(LdvProtocolError::NonFinite { what });
    }
    let steps = (value * steps_per_unit).round();
    if steps.abs() > f64::from(limit) {
        return Err(LdvProtocolError::OutOfRange { what, value: value.to_string(), valid });
    }
    // |steps| <= limit <= i32::MAX and it is a whole number, so the cast is exact.
    Ok(steps as i32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse3(text: &str) -> Result<i64, LdvProtocolError> {
        parse_scaled(text, 3, "test")
    }

    #[test]
    fn parses_every_allowed_shape() {
        assert_eq!(parse3("0").unwrap(), 0);
        assert_eq!(parse3("-0").unwrap(), 0);
        assert_eq!(parse3("+12").unwrap(), 12_000);
        assert_eq!(parse3("1.5").unwrap(), 1_500);
        assert_eq!(parse3("-1.25").unwrap(), -1_250);
        assert_eq!(parse3("-0.001").unwrap(), -1);
        assert_eq!(parse3("007.100").unwrap(), 7_100);
        assert_eq!(parse_scaled("4294967295", 0, "t").unwrap(), 4_294_967_295);
    }

    #[test]
    fn longest_token_is_accepted_and_one_more_is_refused() {
        let longest = "-99999999999.999";
        assert_eq!(longest.len(), MAX_NUMBER_LEN);
        assert_eq!(parse3(longest).unwrap(), -99_999_999_999_999);
        assert!(matches!(parse3("-99999999999.9990"), Err(LdvProtocolError::MalformedNumber { .. })));
    }

    #[test]
    fn scaled_overflow_is_an_error_not_a_wrap() {
        // 16 nines scaled by 10^3 is about 1e19, beyond i64::MAX (9.2e18); 10^15 scaled by 10^3 fits.
        assert!(matches!(parse3("9999999999999999"), Err(LdvProtocolError::MalformedNumber { .. })));
        assert_eq!(parse3("1000000000000000").unwrap(), 1_000_000_000_000_000_000);
        assert_eq!(parse_scaled("9223372036854775", 3, "t").unwrap(), 9_223_372_036_854_775_000);
        assert!(parse_scaled("9223372036854776", 3, "t").is_err());
    }

    #[test]
    fn refuses_non_finite_and_foreign_notations() {
        for text in
            ["", "-", "+", ".", "nan", "NaN", "inf", "-inf", "infinity", "1e3", "1E3", "0x10", "1.", ".5", "--1", "+-1"]
        {
            assert!(matches!(parse3(text), Err(LdvProtocolError::MalformedNumber { .. })), "{text:?} was accepted");
        }
        for text in ["1.2.3", "1,5", " 1", "1 ", "١"] {
            assert!(parse3(text).is_err(), "{text:?} was accepted");
        }
    }

    #[test]
    fn refuses_decimals_beyond_the_resolution() {
        assert!(matches!(parse3("1.0001"), Err(LdvProtocolError::MalformedNumber { .. })));
        assert!(matches!(parse_scaled("5.0", 0, "t"), Err(LdvProtocolError::MalformedNumber { .. })));
    }

    #[test]
    fn formats_with_fixed_decimals() {
        assert_eq!(format_scaled(0, 3), "0.000");
        assert_eq!(format_scaled(-1, 3), "-0.001");
        assert_eq!(format_scaled(500_000, 3), "500.000");
        assert_eq!(format_scaled(-25_000, 3), "-25.000");
        assert_eq!(format_scaled(42, 0), "42");
        assert_eq!(format_scaled(i64::MIN, 3), "-9223372036854775.808");
    }

    #[test]
    fn range_check_is_inclusive_at_both_ends() {
        assert_eq!(check_range(500, 500, true, 0, "t", "v").unwrap(), 500);
        assert_eq!(check_range(-500, 500, true, 0, "t", "v").unwrap(), -500);
        assert!(check_range(501, 500, true, 0, "t", "v").is_err());
        assert!(check_range(-501, 500, true, 0, "t", "v").is_err());
        assert!(check_range(-1, 500, false, 0, "t", "v").is_err());
        assert!(check_range(i64::MAX, i32::MAX, true, 0, "t", "v").is_err());
    }

    #[test]
    fn quantize_rounds_to_nearest_and_refuses_non_finite() {
        assert_eq!(quantize(1.0004, 1000.0, 2000, "t", "v").unwrap(), 1000);
        assert_eq!(quantize(-1.0006, 1000.0, 2000, "t", "v").unwrap(), -1001);
        assert_eq!(quantize(2.0004, 1000.0, 2000, "t", "v").unwrap(), 2000);
        assert!(matches!(quantize(2.0006, 1000.0, 2000, "t", "v"), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!(quantize(1e300, 1000.0, 2000, "t", "v"), Err(LdvProtocolError::OutOfRange { .. })));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(matches!(quantize(bad, 1000.0, 2000, "t", "v"), Err(LdvProtocolError::NonFinite { .. })));
        }
    }
}
