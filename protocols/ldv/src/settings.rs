//! Single-valued settings and readings: signal level, velocity range, tracking filter, laser state, calibration state
//! and synchronisation token. `Display` gives each one's wire form and `FromStr` parses it.

use std::fmt;
use std::str::FromStr;

use crate::error::LdvProtocolError;
use crate::number::{check_range, parse_scaled};

/// Matches `text` case-insensitively against the wire words of `choices`.
fn parse_choice<T: Copy>(
    text: &str,
    what: &'static str,
    expected: &'static str,
    choices: &[(&str, T)],
) -> Result<T, LdvProtocolError> {
    choices
        .iter()
        .find(|(word, _)| word.eq_ignore_ascii_case(text))
        .map(|&(_, value)| value)
        .ok_or_else(|| LdvProtocolError::InvalidChoice { what, text: text.to_owned(), expected })
}

/// The demodulated Doppler signal strength, 0 to 100 % (integer percent).
///
/// It depends on the speckle pattern at the spot: moving the beam by a fraction of a millimetre can change it a lot.
/// The class reads below about 20 % as a dropout risk; the controller's bar graph shows this figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct SignalLevel(u8);

impl SignalLevel {
    /// The largest level, %.
    pub const MAX_PERCENT: u8 = 100;
    const WHAT: &'static str = "signal level (%)";
    const VALID: &'static str = "0..=100 %";

    /// A level of `level_percent` %.
    ///
    /// # Errors
    /// [`LdvProtocolError::OutOfRange`] above 100.
    pub fn from_percent(level_percent: u8) -> Result<Self, LdvProtocolError> {
        Self::checked(i64::from(level_percent))
    }

    fn checked(level_percent: i64) -> Result<Self, LdvProtocolError> {
        let level = check_range(level_percent, i32::from(Self::MAX_PERCENT), false, 0, Self::WHAT, Self::VALID)?;
        // 0..=100 fits a u8; map rather than unwrap all the same.
        u8::try_from(level).map(Self).map_err(|_| LdvProtocolError::OutOfRange {
            what: Self::WHAT,
            value: level.to_string(),
            valid: Self::VALID,
        })
    }

    /// The level, %.
    pub fn percent(self) -> u8 {
        self.0
    }

    /// The level as a fraction, 0 to 1.
    pub fn fraction(self) -> f64 {
        f64::from(self.0) / 100.0
    }
}

impl fmt::Display for SignalLevel {
    /// The wire form: an integer 0 to 100.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl FromStr for SignalLevel {
    type Err = LdvProtocolError;

    /// Parses an integer 0 to 100.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Self::checked(parse_scaled(text, 0, Self::WHAT)?)
    }
}

/// The velocity decoder's range: the scale of the analog velocity output, mm/s per volt. The output swings plus or
/// minus 10 V, so the full scale is ten times the range. The class offers a 1-5-25-125 ladder and a coarse
/// 1000 mm/s/V range; smaller ranges have lower noise and lower maximum velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum VelocityRange {
    /// 1 mm/s per V (full scale 10 mm/s).
    MmPerS1,
    /// 5 mm/s per V (full scale 50 mm/s).
    MmPerS5,
    /// 25 mm/s per V (full scale 250 mm/s); the power-on default.
    MmPerS25,
    /// 125 mm/s per V (full scale 1.25 m/s).
    MmPerS125,
    /// 1000 mm/s per V (full scale 10 m/s).
    MmPerS1000,
}

impl VelocityRange {
    /// Every range, smallest first.
    pub const ALL: [VelocityRange; 5] = [
        VelocityRange::MmPerS1,
        VelocityRange::MmPerS5,
        VelocityRange::MmPerS25,
        VelocityRange::MmPerS125,
        VelocityRange::MmPerS1000,
    ];
    /// Output voltage at full scale, V.
    pub const FULL_SCALE_V: f64 = 10.0;
    const WHAT: &'static str = "velocity range (mm/s/V)";
    const VALID: &'static str = "one of 1, 5, 25, 125, 1000 mm/s/V";

    /// The scale, mm/s per V (the wire number).
    pub fn mm_per_s_per_v(self) -> u32 {
        match self {
            VelocityRange::MmPerS1 => 1,
            VelocityRange::MmPerS5 => 5,
            VelocityRange::MmPerS25 => 25,
            VelocityRange::MmPerS125 => 125,
            VelocityRange::MmPerS1000 => 1000,
        }
    }

    /// The scale, (m/s) per V: multiply a recorded voltage by it to get velocity in m/s.
    pub fn m_per_s_per_v(self) -> f64 {
        f64::from(self.mm_per_s_per_v()) * 1e-3
    }

    /// The largest velocity the output can represent, m/s.
    pub fn full_scale_m_per_s(self) -> f64 {
        self.m_per_s_per_v() * Self::FULL_SCALE_V
    }

    /// The range of `mm_per_s_per_v` mm/s per V.
    ///
    /// # Errors
    /// [`LdvProtocolError::OutOfRange`] for a value not on the list.
    pub fn from_mm_per_s_per_v(mm_per_s_per_v: u32) -> Result<Self, LdvProtocolError> {
        Self::from_wire(i64::from(mm_per_s_per_v))
    }

    fn from_wire(value: i64) -> Result<Self, LdvProtocolError> {
        Self::ALL.into_iter().find(|r| i64::from(r.mm_per_s_per_v()) == value).ok_or_else(|| {
            LdvProtocolError::OutOfRange { what: Self::WHAT, value: value.to_string(), valid: Self::VALID }
        })
    }
}

impl fmt::Display for VelocityRange {
    /// The wire form: the integer mm/s per V.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.mm_per_s_per_v())
    }
}

impl FromStr for VelocityRange {
    type Err = LdvProtocolError;

    /// Parses the integer mm/s per V.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Self::from_wire(parse_scaled(text, 0, Self::WHAT)?)
    }
}

/// The tracking filter: a phase-locked loop that rides through short signal dropouts (speckle) at the cost of
/// slew rate. `Slow` rejects the most dropouts and follows the least acceleration; `Off` passes everything.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TrackingFilter {
    /// No tracking filter (the power-on default).
    Off,
    /// Slow tracking.
    Slow,
    /// Medium tracking.
    Medium,
    /// Fast tracking.
    Fast,
}

impl TrackingFilter {
    /// Every setting.
    pub const ALL: [TrackingFilter; 4] =
        [TrackingFilter::Off, TrackingFilter::Slow, TrackingFilter::Medium, TrackingFilter::Fast];
    const WORDS: [(&'static str, TrackingFilter); 4] = [
        ("OFF", TrackingFilter::Off),
        ("SLOW", TrackingFilter::Slow),
        ("MEDIUM", TrackingFilter::Medium),
        ("FAST", TrackingFilter::Fast),
    ];

    fn word(self) -> &'static str {
        match self {
            TrackingFilter::Off => "OFF",
            TrackingFilter::Slow => "SLOW",
            TrackingFilter::Medium => "MEDIUM",
            TrackingFilter::Fast => "FAST",
        }
    }
}

impl fmt::Display for TrackingFilter {
    /// The wire form: `OFF`, `SLOW`, `MEDIUM` or `FAST`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.word())
    }
}

impl FromStr for TrackingFilter {
    type Err = LdvProtocolError;

    /// Parses `OFF`, `SLOW`, `MEDIUM` or `FAST`, in any case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        parse_choice(text, "tracking filter", "OFF, SLOW, MEDIUM, FAST", &Self::WORDS)
    }
}

/// Whether the measurement laser is emitting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LaserState {
    /// Laser off (shutter closed).
    Off,
    /// Laser on.
    On,
}

impl fmt::Display for LaserState {
    /// The wire form: `ON` or `OFF`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LaserState::Off => "OFF",
            LaserState::On => "ON",
        })
    }
}

impl FromStr for LaserState {
    type Err = LdvProtocolError;

    /// Parses `ON` or `OFF`, in any case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        parse_choice(text, "laser state", "ON, OFF", &[("ON", LaserState::On), ("OFF", LaserState::Off)])
    }
}

/// Whether the controller holds a valid mapping from plate coordinates to mirror angles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CalibrationState {
    /// No valid calibration: plate-coordinate commands fail with `ERR 5`.
    NotCalibrated,
    /// Calibrated.
    Calibrated,
}

impl fmt::Display for CalibrationState {
    /// The wire form: `YES` or `NO`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CalibrationState::NotCalibrated => "NO",
            CalibrationState::Calibrated => "YES",
        })
    }
}

impl FromStr for CalibrationState {
    type Err = LdvProtocolError;

    /// Parses `YES` or `NO`, in any case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let words = [("YES", CalibrationState::Calibrated), ("NO", CalibrationState::NotCalibrated)];
        parse_choice(text, "calibration state", "YES, NO", &words)
    }
}

/// The token of a `SYNC` exchange: any `u32`, echoed back unchanged. A driver uses a fresh one (a counter) each time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct SyncToken(pub u32);

impl fmt::Display for SyncToken {
    /// The wire form: the decimal integer.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl FromStr for SyncToken {
    type Err = LdvProtocolError;

    /// Parses a decimal integer 0 to 4294967295.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        const WHAT: &str = "sync token";
        let value = parse_scaled(text, 0, WHAT)?;
        u32::try_from(value).map(SyncToken).map_err(|_| LdvProtocolError::OutOfRange {
            what: WHAT,
            value: value.to_string(),
            valid: "0..=4294967295",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signal_level_range_is_0_to_100() {
        assert_eq!(SignalLevel::from_percent(0).unwrap().fraction(), 0.0);
        assert_eq!(SignalLevel::from_percent(100).unwrap().fraction(), 1.0);
        assert!(matches!(SignalLevel::from_percent(101), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!(SignalLevel::from_percent(u8::MAX), Err(LdvProtocolError::OutOfRange { .. })));
        assert_eq!("100".parse::<SignalLevel>().unwrap().percent(), 100);
        assert!(matches!("101".parse::<SignalLevel>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("-1".parse::<SignalLevel>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("87.5".parse::<SignalLevel>(), Err(LdvProtocolError::MalformedNumber { .. })));
    }

    #[test]
    fn velocity_ranges_are_the_documented_list() {
        let scales: Vec<u32> = VelocityRange::ALL.iter().map(|r| r.mm_per_s_per_v()).collect();
        assert_eq!(scales, [1, 5, 25, 125, 1000]);
        for range in VelocityRange::ALL {
            assert_eq!(range.to_string().parse::<VelocityRange>().unwrap(), range);
            assert_eq!(VelocityRange::from_mm_per_s_per_v(range.mm_per_s_per_v()).unwrap(), range);
        }
        // 25 * 1e-3 * 10 takes two roundings of at most half an ulp each (about 3e-17 near 0.25): 1e-15 is ample.
        assert!((VelocityRange::MmPerS25.full_scale_m_per_s() - 0.25).abs() < 1e-15);
        for bad in [0, 2, 10, 1001, u32::MAX] {
            assert!(matches!(VelocityRange::from_mm_per_s_per_v(bad), Err(LdvProtocolError::OutOfRange { .. })));
        }
        assert!(matches!("-5".parse::<VelocityRange>(), Err(LdvProtocolError::OutOfRange { .. })));
    }

    #[test]
    fn choice_words_are_case_insensitive_and_closed() {
        for filter in TrackingFilter::ALL {
            assert_eq!(filter.to_string().to_lowercase().parse::<TrackingFilter>().unwrap(), filter);
        }
        assert!(matches!("BRISK".parse::<TrackingFilter>(), Err(LdvProtocolError::InvalidChoice { .. })));
        assert_eq!("on".parse::<LaserState>().unwrap(), LaserState::On);
        assert!(matches!("1".parse::<LaserState>(), Err(LdvProtocolError::InvalidChoice { .. })));
        assert_eq!("No".parse::<CalibrationState>().unwrap(), CalibrationState::NotCalibrated);
        assert!("".parse::<CalibrationState>().is_err());
    }

    #[test]
    fn sync_token_covers_all_of_u32() {
        assert_eq!("0".parse::<SyncToken>().unwrap(), SyncToken(0));
        assert_eq!("4294967295".parse::<SyncToken>().unwrap(), SyncToken(u32::MAX));
        assert!(matches!("4294967296".parse::<SyncToken>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("-1".parse::<SyncToken>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("abc".parse::<SyncToken>(), Err(LdvProtocolError::MalformedNumber { .. })));
    }
}
