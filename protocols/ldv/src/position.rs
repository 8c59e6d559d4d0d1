//! Beam positions: calibrated plate coordinates (mm on the wire, 1 um steps) and raw mirror angles (degrees on the
//! wire, 0.001 degree steps).
//!
//! Both are stored as whole steps, so that a value survives encoding and decoding exactly; constructors from `f64`
//! round to the nearest step and refuse anything non-finite or out of range.

use std::fmt;
use std::str::FromStr;

use crate::error::LdvProtocolError;
use crate::number::{check_range, format_scaled, parse_scaled, quantize};

/// Decimals on the wire of both coordinates (mm) and angles (degrees): 1 um and 1 millidegree steps.
const WIRE_DECIMALS: u32 = 3;

/// One calibrated plate coordinate (x or y), in whole micrometres.
///
/// Valid range: `-PlateCoord::MAX_UM..=PlateCoord::MAX_UM` (plus or minus 500 mm, a field well beyond any plate the
/// lab uses, 25 x 15 cm). The frame is the one taught to the controller at calibration. On the wire: millimetres
/// with exactly three decimals (`-12.345`), which is what `Display` and `FromStr` use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct PlateCoord(i32);

impl PlateCoord {
    /// The largest magnitude, um (500 mm).
    pub const MAX_UM: i32 = 500_000;
    const WHAT: &'static str = "plate coordinate (mm)";
    const VALID: &'static str = "-500.000..=500.000 mm";

    /// A coordinate of `x_um` micrometres.
    ///
    /// # Errors
    /// [`LdvProtocolError::OutOfRange`] beyond plus or minus [`Self::MAX_UM`].
    pub fn from_um(x_um: i32) -> Result<Self, LdvProtocolError> {
        check_range(i64::from(x_um), Self::MAX_UM, true, WIRE_DECIMALS, Self::WHAT, Self::VALID).map(Self)
    }

    /// A coordinate of `x_m` metres, rounded to the nearest micrometre. Valid range: finite, within plus or minus
    /// 0.5 m after rounding.
    ///
    /// # Errors
    /// [`LdvProtocolError::NonFinite`] for NaN or infinity; [`LdvProtocolError::OutOfRange`] beyond 0.5 m.
    pub fn from_m(x_m: f64) -> Result<Self, LdvProtocolError> {
        quantize(x_m, 1e6, Self::MAX_UM, Self::WHAT, Self::VALID).map(Self)
    }

    /// The coordinate, um.
    pub fn um(self) -> i32 {
        self.0
    }

    /// The coordinate, m.
    pub fn m(self) -> f64 {
        f64::from(self.0) * 1e-6
    }

    /// The coordinate, mm.
    pub fn mm(self) -> f64 {
        f64::from(self.0) * 1e-3
    }
}

impl fmt::Display for PlateCoord {
    /// The wire form: millimetres with three decimals.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&format_scaled(i64::from(self.0), WIRE_DECIMALS))
    }
}

impl FromStr for PlateCoord {
    type Err = LdvProtocolError;

    /// Parses the wire form: millimetres with at most three decimals.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let x_um = parse_scaled(text, WIRE_DECIMALS, Self::WHAT)?;
        check_range(x_um, Self::MAX_UM, true, WIRE_DECIMALS, Self::WHAT, Self::VALID).map(Self)
    }
}

/// A point in the calibrated plate frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PlatePoint {
    /// x coordinate.
    pub x: PlateCoord,
    /// y coordinate.
    pub y: PlateCoord,
}

impl PlatePoint {
    /// The point (`x_m`, `y_m`) in metres, each rounded to the nearest micrometre (see [`PlateCoord::from_m`]).
    ///
    /// # Errors
    /// As [`PlateCoord::from_m`], for either coordinate.
    pub fn from_m(x_m: f64, y_m: f64) -> Result<Self, LdvProtocolError> {
        Ok(Self { x: PlateCoord::from_m(x_m)?, y: PlateCoord::from_m(y_m)? })
    }
}

/// One raw mirror angle (x or y scanner axis), in whole millidegrees.
///
/// Valid range: `-MirrorAngle::MAX_MDEG..=MirrorAngle::MAX_MDEG` (plus or minus 25 degrees, the scan field of the
/// class). On the wire: degrees with exactly three decimals (`-3.250`), which is what `Display` and `FromStr` use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct MirrorAngle(i32);

impl MirrorAngle {
    /// The largest magnitude, millidegrees (25 degrees).
    pub const MAX_MDEG: i32 = 25_000;
    const WHAT: &'static str = "mirror angle (deg)";
    const VALID: &'static str = "-25.000..=25.000 deg";

    /// An angle of `angle_mdeg` millidegrees.
    ///
    /// # Errors
    /// [`LdvProtocolError::OutOfRange`] beyond plus or minus [`Self::MAX_MDEG`].
    pub fn from_mdeg(angle_mdeg: i32) -> Result<Self, LdvProtocolError> {
        check_range(i64::from(angle_mdeg), Self::MAX_MDEG, true, WIRE_DECIMALS, Self::WHAT, Self::VALID).map(Self)
    }

    /// An angle of `angle_deg` degrees, rounded to the nearest millidegree. Valid range: finite, within plus or
    /// minus 25 degrees after rounding.
    ///
    /// # Errors
    /// [`LdvProtocolError::NonFinite`] for NaN or infinity; [`LdvProtocolError::OutOfRange`] beyond 25 degrees.
    pub fn from_deg(angle_deg: f64) -> Result<Self, LdvProtocolError> {
        quantize(angle_deg, 1e3, Self::MAX_MDEG, Self::WHAT, Self::VALID).map(Self)
    }

    /// The angle, millidegrees.
    pub fn mdeg(self) -> i32 {
        self.0
    }

    /// The angle, degrees.
    pub fn deg(self) -> f64 {
        f64::from(self.0) * 1e-3
    }
}

impl fmt::Display for MirrorAngle {
    /// The wire form: degrees with three decimals.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&format_scaled(i64::from(self.0), WIRE_DECIMALS))
    }
}

impl FromStr for MirrorAngle {
    type Err = LdvProtocolError;

    /// Parses the wire form: degrees with at most three decimals.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let angle_mdeg = parse_scaled(text, WIRE_DECIMALS, Self::WHAT)?;
        check_range(angle_mdeg, Self::MAX_MDEG, true, WIRE_DECIMALS, Self::WHAT, Self::VALID).map(Self)
    }
}

/// The two mirror angles of the scanner.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MirrorAngles {
    /// x axis mirror.
    pub x: MirrorAngle,
    /// y axis mirror.
    pub y: MirrorAngle,
}

impl MirrorAngles {
    /// The angles (`x_deg`, `y_deg`) in degrees, each rounded to the nearest millidegree.
    ///
    /// # Errors
    /// As [`MirrorAngle::from_deg`], for either angle.
    pub fn from_deg(x_deg: f64, y_deg: f64) -> Result<Self, LdvProtocolError> {
        Ok(Self { x: MirrorAngle::from_deg(x_deg)?, y: MirrorAngle::from_deg(y_deg)? })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plate_coord_range_is_inclusive_at_500_mm() {
        assert_eq!(PlateCoord::from_um(500_000).unwrap().mm(), 500.0);
        assert_eq!(PlateCoord::from_um(-500_000).unwrap().mm(), -500.0);
        assert!(matches!(PlateCoord::from_um(500_001), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!(PlateCoord::from_um(i32::MIN), Err(LdvProtocolError::OutOfRange { .. })));
        assert_eq!("500.000".parse::<PlateCoord>().unwrap().um(), 500_000);
        assert_eq!("-500".parse::<PlateCoord>().unwrap().um(), -500_000);
        assert!(matches!("500.001".parse::<PlateCoord>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("-612".parse::<PlateCoord>(), Err(LdvProtocolError::OutOfRange { .. })));
    }

    #[test]
    fn plate_coord_from_m_rounds_to_the_micrometre() {
        // Half a micrometre either side of the limit decides: 0.5000004 m rounds to 500 mm, 0.5000006 m to 500.001.
        assert_eq!(PlateCoord::from_m(0.500_000_4).unwrap().um(), 500_000);
        assert!(PlateCoord::from_m(0.500_000_6).is_err());
        assert_eq!(PlateCoord::from_m(-0.123_456_4).unwrap().um(), -123_456);
        assert_eq!(PlateCoord::from_m(1e-9).unwrap().um(), 0);
        assert!(PlateCoord::from_m(f64::MAX).is_err());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(matches!(PlateCoord::from_m(bad), Err(LdvProtocolError::NonFinite { .. })));
        }
    }

    #[test]
    fn plate_coord_metres_round_trip_exactly_over_the_whole_range() {
        // m() is um * 1e-6 with a relative error of at most 1 ulp (about 1e-16 of 0.5 m, far below the 0.5 um that
        // rounding in from_m tolerates), so from_m(m()) must give back the very same step at every step tested.
        for x_um in (-PlateCoord::MAX_UM..=PlateCoord::MAX_UM).step_by(997).chain([PlateCoord::MAX_UM]) {
            let x = PlateCoord::from_um(x_um).unwrap();
            assert_eq!(PlateCoord::from_m(x.m()).unwrap(), x);
        }
    }

    #[test]
    fn plate_coord_wire_form_has_three_decimals() {
        assert_eq!(PlateCoord::from_um(-1).unwrap().to_string(), "-0.001");
        assert_eq!(PlateCoord::from_um(123_450).unwrap().to_string(), "123.450");
        assert_eq!(PlateCoord::default().to_string(), "0.000");
    }

    #[test]
    fn mirror_angle_range_is_inclusive_at_25_degrees() {
        assert_eq!(MirrorAngle::from_mdeg(25_000).unwrap().deg(), 25.0);
        assert_eq!(MirrorAngle::from_deg(-25.0).unwrap().mdeg(), -25_000);
        assert!(MirrorAngle::from_mdeg(25_001).is_err());
        assert!(MirrorAngle::from_deg(25.0006).is_err());
        assert_eq!(MirrorAngle::from_deg(25.0004).unwrap().mdeg(), 25_000);
        assert!(matches!(MirrorAngle::from_deg(f64::NAN), Err(LdvProtocolError::NonFinite { .. })));
        assert_eq!("-25.000".parse::<MirrorAngle>().unwrap().mdeg(), -25_000);
        assert!(matches!("25.001".parse::<MirrorAngle>(), Err(LdvProtocolError::OutOfRange { .. })));
        assert!(matches!("1.2345".parse::<MirrorAngle>(), Err(LdvProtocolError::MalformedNumber { .. })));
        assert_eq!(MirrorAngle::from_mdeg(3_250).unwrap().to_string(), "3.250");
    }

    #[test]
    fn pairs_check_both_axes() {
        assert!(PlatePoint::from_m(0.1, 0.6).is_err());
        assert!(PlatePoint::from_m(f64::NAN, 0.0).is_err());
        let p = PlatePoint::from_m(0.12, -0.06).unwrap();
        assert_eq!((p.x.um(), p.y.um()), (120_000, -60_000));
        assert!(MirrorAngles::from_deg(0.0, -30.0).is_err());
        let a = MirrorAngles::from_deg(-1.5, 2.0).unwrap();
        assert_eq!((a.x.mdeg(), a.y.mdeg()), (-1_500, 2_000));
    }
}
