//! Fixed-column fields: writing numbers the way C's `%W.De` does (as pyuff writes them) and reading Fortran
//! `I`, `E`, `D` and `A` fields back.

use std::io::Write as _;

/// Appends `value` as C's `%{width}.{decimals}e` would: mantissa with `decimals` digits after the point, `e`,
/// sign, at least two exponent digits, right-justified in `width` columns. With `exponent_letter` `b'D'` the
/// letter is `D` (Fortran double precision, as dataset 164 and 2411 write it).
pub(crate) fn push_exp(out: &mut Vec<u8>, value: f64, width: usize, decimals: usize, exponent_letter: u8) {
    // Formatted on the stack: an exporter writes 10^8 values, and two heap strings each would dominate.
    let mut text = [0u8; 64];
    let mut cursor = std::io::Cursor::new(&mut text[..]);
    // `{:.*e}` rounds the exact binary value to nearest, ties to even, as glibc's printf does.
    let _ = write!(cursor, "{value:.decimals$e}");
    let len = usize::try_from(cursor.position()).unwrap_or(0);
    let text = text.get(..len).unwrap_or(&[]);
    let split = text.iter().position(|&b| b == b'e').unwrap_or(text.len());
    let (mantissa, exponent) = text.split_at(split);
    let exponent = std::str::from_utf8(exponent.get(1..).unwrap_or(&[])).ok().and_then(|e| e.parse::<i32>().ok());
    let exponent = exponent.unwrap_or(0);
    let magnitude = exponent.unsigned_abs();
    let digits = if magnitude >= 100 { 3 } else { 2 };
    out.resize(out.len() + width.saturating_sub(mantissa.len() + 2 + digits), b' ');
    out.extend_from_slice(mantissa);
    out.push(exponent_letter);
    out.push(if exponent < 0 { b'-' } else { b'+' });
    if magnitude >= 100 {
        out.push(b'0' + (magnitude / 100) as u8);
    }
    out.push(b'0' + (magnitude / 10 % 10) as u8);
    out.push(b'0' + (magnitude % 10) as u8);
}

/// Appends `value` right-justified in `width` columns (`%{width}i`).
pub(crate) fn push_int(out: &mut Vec<u8>, value: i64, width: usize) {
    push_right(out, value.to_string().as_bytes(), width);
}

/// Appends `text` right-justified in `width` columns (`%{width}s`).
pub(crate) fn push_right(out: &mut Vec<u8>, text: &[u8], width: usize) {
    out.resize(out.len() + width.saturating_sub(text.len()), b' ');
    out.extend_from_slice(text);
}

/// Appends `text` left-justified in `width` columns (`%-{width}s`).
pub(crate) fn push_left(out: &mut Vec<u8>, text: &[u8], width: usize) {
    out.extend_from_slice(text);
    out.resize(out.len() + width.saturating_sub(text.len()), b' ');
}

/// The columns `start .. start + width` of `line` (0-based), shorter or empty where the line is shorter.
pub(crate) fn columns(line: &[u8], start: usize, width: usize) -> &[u8] {
    let end = start.saturating_add(width).min(line.len());
    line.get(start.min(end)..end).unwrap_or(&[])
}

/// The field without leading and trailing blanks (spaces and tabs).
pub(crate) fn trim(field: &[u8]) -> &[u8] {
    let is_blank = |b: &u8| *b == b' ' || *b == b'\t';
    let start = field.iter().position(|b| !is_blank(b)).unwrap_or(field.len());
    let end = field.iter().rposition(|b| !is_blank(b)).map_or(start, |i| i + 1);
    field.get(start..end).unwrap_or(&[])
}

/// An integer field (`I`): optional sign and digits between blanks. `None` if blank or anything else.
pub(crate) fn parse_int(field: &[u8]) -> Option<i64> {
    let text = std::str::from_utf8(trim(field)).ok()?;
    if text.is_empty() || text.len() > 19 {
        return None;
    }
    text.parse().ok()
}

/// A real field (`E`, `D`, `F`, `G`): `1.5E+03`, `0.15D+04`, Fortran's `0.15+004` without a letter (written when
/// the exponent needs three digits), `1500.`. Infinities and NaN parse (as the words Rust knows), so that the
/// caller reports them as non-finite values rather than as syntax. `None` if blank or not a number.
pub(crate) fn parse_real(field: &[u8]) -> Option<f64> {
    let field = trim(field);
    if field.is_empty() || field.len() > 40 {
        return None;
    }
    let mut text = [0u8; 41];
    let mut len = 0;
    let mut has_letter = false;
    for (i, &b) in field.iter().enumerate() {
        let b = match b {
            b'D' | b'd' | b'E' | b'e' => {
                has_letter = true;
                b'e'
            }
            b'+' | b'-' if i > 0 && !has_letter && matches!(field[i - 1], b'0'..=b'9' | b'.') => {
                // Fortran drops the letter when the exponent has three digits: `0.12345+100`.
                text[len] = b'e';
                len += 1;
                has_letter = true;
                b
            }
            b'0'..=b'9' | b'+' | b'-' | b'.' | b'a'..=b'z' | b'A'..=b'Z' => b,
            _ => return None,
        };
        text[len] = b;
        len += 1;
    }
    std::str::from_utf8(text.get(..len)?).ok()?.parse().ok()
}

/// A text field (`A`): trimmed, each byte read as Latin-1 (ISO 8859-1, what the I-DEAS era and many writers use
/// for `²`, `°`, `µ`), control characters (below 0x20 and 0x7f to 0x9f) replaced by `?`; blank becomes "NONE",
/// the specification's word for unused. One byte is one character, so a record decoded can always be written back
/// column for column ([`latin1`]). UTF-8 text (catman writes `m/s²` so) reads as its bytes in Latin-1 (`m/sÂ²`); a
/// user of the text recovers it with [`crate::as_written`].
pub(crate) fn parse_text(field: &[u8]) -> String {
    let field = trim(field);
    if field.is_empty() {
        return "NONE".to_owned();
    }
    field.iter().map(|&b| if is_text_byte(b) { char::from(b) } else { '?' }).collect()
}

/// A text record that fills a line (`80A1`: ID lines, the header's names): as [`parse_text`] of its 80 columns, but
/// never `-1`, which written back would read as the dataset's closing delimiter (the line held more past column 80):
/// that is shown as `(-1)`.
pub(crate) fn parse_line_text(line: &[u8]) -> String {
    let text = parse_text(columns(line, 0, 80));
    if text == "-1" { "(-1)".to_owned() } else { text }
}

/// `text` as a text field of at most `width` characters can hold it: each character that is not printable Latin-1
/// as `_`, then cut to `width` (what a writer does with a name it did not choose, where [`latin1`] refuses).
pub fn printable(text: &str, width: usize) -> String {
    text.chars().map(|c| if u8::try_from(u32::from(c)).is_ok_and(is_text_byte) { c } else { '_' }).take(width).collect()
}

/// Whether a byte is printable Latin-1 (a text field's bytes).
fn is_text_byte(b: u8) -> bool {
    (0x20..=0x7e).contains(&b) || b >= 0xa0
}

/// The Latin-1 bytes of `text`, one per character, or `None` if a character is not printable Latin-1.
pub(crate) fn latin1(text: &str) -> Option<Vec<u8>> {
    text.chars().map(|c| u8::try_from(u32::from(c)).ok().filter(|&b| is_text_byte(b))).collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn exp(value: f64, width: usize, decimals: usize) -> String {
        let mut out = Vec::new();
        push_exp(&mut out, value, width, decimals, b'e');
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn exponents_are_written_as_c_writes_them() {
        assert_eq!(exp(1.0, 13, 5), "  1.00000e+00");
        assert_eq!(exp(-2.0833333e-5, 13, 5), " -2.08333e-05");
        assert_eq!(exp(-1.234567e-100, 13, 5), "-1.23457e-100");
        assert_eq!(exp(0.0, 20, 11), "   0.00000000000e+00");
        assert_eq!(exp(-0.0, 13, 5), " -0.00000e+00");
        assert_eq!(exp(0.125, 8, 1), " 1.2e-01");
        assert_eq!(exp(1e300, 20, 11), "  1.00000000000e+300");
    }

    #[test]
    fn fortran_reals_parse() {
        assert_eq!(parse_real(b"  0.15D+04"), Some(1500.0));
        assert_eq!(parse_real(b"  0.15+004"), Some(1500.0));
        assert_eq!(parse_real(b"0.15-002"), Some(0.0015));
        assert_eq!(parse_real(b" -1.5e-3 "), Some(-0.0015));
        assert_eq!(parse_real(b"1500."), Some(1500.0));
        assert_eq!(parse_real(b"   "), None);
        assert_eq!(parse_real(b"1.0e+0x"), None);
        assert!(parse_real(b"NaN").unwrap().is_nan());
        assert_eq!(parse_int(b"   -12"), Some(-12));
        assert_eq!(parse_int(b" 1 2"), None);
        assert_eq!(parse_text(b"  caf\xe9 m/s\xb2 \x07 "), "caf\u{e9} m/s\u{b2} ?");
        assert_eq!(parse_text(b"caf\xc3\xa9"), "caf\u{c3}\u{a9}");
        assert_eq!(latin1("m/s\u{b2}"), Some(b"m/s\xb2".to_vec()));
        assert_eq!(latin1("\u{20ac}"), None);
        assert_eq!(parse_text(b"    "), "NONE");
        assert_eq!(printable("caf\u{e9} \u{20ac}\u{7}", 80), "caf\u{e9} __");
        assert_eq!(printable(&"\u{e9}".repeat(90), 80).chars().count(), 80);
        assert_eq!(printable("", 80), "");
        assert_eq!(parse_line_text(format!("-1{}x", " ".repeat(80)).as_bytes()), "(-1)");
        assert_eq!(parse_line_text(b" -12"), "-12");
    }
}
