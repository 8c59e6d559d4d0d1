//! Velocity ranges as the controller spells them: `5mm/s/V`, `1m/s/V`, `0.5mm/s/V`, `20µm/s/V`, and a VD-09's
//! low-pass variants `1m/s/V LP` (PLACE's VD-09 menu, `elm/plugins/PolytecOFV5000.elm`).

use std::fmt;

use crate::error::PolytecProtocolError;

/// One velocity range of a decoder: its spelling on the wire (sent back verbatim in a `Set`) and its scale.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityRange {
    text: String,
    m_s_per_v: f64,
    low_pass: bool,
}

impl VelocityRange {
    /// Parses a range: a plain decimal (`5`, `0.5`, `1000`), optional spaces, then `m/s/V`, `mm/s/V`, `um/s/V` or
    /// `µm/s/V`, then optionally ` LP` (the range with the decoder's low-pass filter). Valid range: a positive
    /// finite number of at most 12 characters.
    ///
    /// # Errors
    /// [`PolytecProtocolError::BadVelocityRange`] for anything else.
    pub fn parse(text: &str) -> Result<Self, PolytecProtocolError> {
        let t = text.trim();
        let bad = || PolytecProtocolError::BadVelocityRange { text: t.chars().take(64).collect() };
        let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).ok_or_else(bad)?;
        let (number, unit) = t.split_at(split);
        let plain = !number.is_empty()
            && number.len() <= 12
            && number.bytes().filter(|&b| b == b'.').count() <= 1
            && !number.starts_with('.')
            && !number.ends_with('.');
        if !plain {
            return Err(bad());
        }
        let value: f64 = number.parse().map_err(|_| bad())?;
        let unit = unit.trim_start();
        let (unit, low_pass) = match unit.strip_suffix("LP") {
            Some(u) if u.ends_with(' ') => (u.trim_end(), true),
            _ => (unit, false),
        };
        let per_unit = match unit {
            "m/s/V" => 1.0,
            "mm/s/V" => 1e-3,
            "um/s/V" | "µm/s/V" => 1e-6,
            _ => return Err(bad()),
        };
        let m_s_per_v = value * per_unit;
        if !(m_s_per_v.is_finite() && m_s_per_v > 0.0) {
            return Err(bad());
        }
        Ok(Self { text: t.to_owned(), m_s_per_v, low_pass })
    }

    /// The spelling, as the controller gave it.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Velocity per volt of the decoder's output, (m/s)/V.
    pub fn m_s_per_v(&self) -> f64 {
        self.m_s_per_v
    }

    /// Whether this is a low-pass variant (` LP`).
    pub fn low_pass(&self) -> bool {
        self.low_pass
    }

    /// Whether `other` names the same scale (`1000mm/s/V` and `1m/s/V` do), to a relative 1e-9.
    pub fn same_scale(&self, other: &VelocityRange) -> bool {
        (self.m_s_per_v - other.m_s_per_v).abs() <= 1e-9 * self.m_s_per_v.max(other.m_s_per_v)
    }
}

impl fmt::Display for VelocityRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_of_the_manual_and_place_parse_to_si() {
        // Spellings from PLACE's range menus (elm/plugins/PolytecOFV5000.elm: "5mm/s/V", "1m/s/V", "0.5mm/s/V").
        for (text, want) in [
            ("5mm/s/V", 5e-3),
            ("1m/s/V", 1.0),
            ("0.5mm/s/V", 5e-4),
            ("20µm/s/V", 2e-5),
            ("125 mm/s/V", 0.125),
            ("1m/s/V LP", 1.0),
        ] {
            let r = VelocityRange::parse(text).unwrap();
            assert!((r.m_s_per_v() - want).abs() <= 1e-15, "{text}");
        }
        assert!(
            VelocityRange::parse("50mm/s/V LP").unwrap().low_pass()
                && !VelocityRange::parse("50mm/s/V").unwrap().low_pass()
        );
        assert!(VelocityRange::parse("1000mm/s/V").unwrap().same_scale(&VelocityRange::parse("1m/s/V").unwrap()));
    }

    #[test]
    fn anything_else_is_refused() {
        for text in [
            "",
            "mm/s/V",
            "5",
            "5mm/V",
            ".5mm/s/V",
            "5.mm/s/V",
            "-5mm/s/V",
            "0mm/s/V",
            "1e3mm/s/V",
            "1.2.3m/s/V",
            "99999999999999m/s/V",
            "5mm/s/VLP",
            "5mm/s/V HP",
        ] {
            assert!(VelocityRange::parse(text).is_err(), "{text}");
        }
    }
}
