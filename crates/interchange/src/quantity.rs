//! What a function's ordinate and denominator hold, from records 9 and 10 (data type, units label) and dataset
//! 164: the quantity, its factor to SI, and so how an import turns it into velocity or refuses it by name.
//!
//! - Data types 8, 11 and 12 (displacement, velocity, acceleration) are that quantity, in dataset 164's length unit
//!   (metres without one); but a units label `g` is standard gravity (9.80665 m/s²), which 164 cannot express.
//! - Data types 0 and 1 (unknown, general: catman, PSV and scripts write these) are read from the units label:
//!   `m`, `mm`, `µm`, `in` over nothing, `s` or `s²` (written `s2`, `s^2`, `s**2` or `s²`), or `g`; a label per
//!   newton (`(1/N)*(m/s²)`, `m/s/N`) makes the function per newton whatever record 10 says.
//! - Any other data type (pressure, force, voltage, temperature, ...) is named, and refused unless the user declares
//!   it as unknown.
//!
//! Labels are read as written: a label decoded as Latin-1 whose bytes are UTF-8 (`m/sÂ²`) is read as UTF-8
//! (`m/s²`), since writers use both.

use metaplate_uff::{AxisCharacteristics, Units164};

/// Standard gravity, m/s² (the unit `g` of accelerometer software).
const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

/// Newtons per pound-force.
const NEWTONS_PER_LBF: f64 = 4.448_221_615_260_5;

/// Displacement, velocity or acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Motion {
    /// m.
    Displacement,
    /// m/s.
    Velocity,
    /// m/s².
    Acceleration,
}

impl Motion {
    /// The quantity's name and SI unit.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Motion::Displacement => "displacement (m)",
            Motion::Velocity => "velocity (m/s)",
            Motion::Acceleration => "acceleration (m/s²)",
        }
    }
}

/// What an ordinate (record 9) holds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum OrdinateQuantity {
    /// A motion: SI value = file value × `to_si`; `per_newton` when the label itself is per newton.
    Motion {
        /// Which.
        motion: Motion,
        /// SI units per file unit.
        to_si: f64,
        /// The label says per newton.
        per_newton: bool,
        /// How it was found (for the dataset's record of the import).
        basis: String,
    },
    /// Anything else, named (data type and label as written).
    Other {
        /// For example `sound pressure (data type 15, "Pa")`.
        name: String,
    },
}

/// What a denominator (record 10) holds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Denominator {
    /// Force: SI value = file value × `to_si`.
    Force {
        /// Newtons per file unit.
        to_si: f64,
    },
    /// Unused (data type 0, label NONE): the function is not a ratio (an operational time history).
    Unused,
    /// Anything else, with its label as written.
    Other {
        /// The units label.
        label: String,
    },
}

impl Denominator {
    /// The `ir` unit of a velocity over this denominator.
    pub(crate) fn ir_unit(&self) -> String {
        match self {
            Denominator::Force { .. } => metaplate_store::IR_UNIT_M_S_PER_N.to_owned(),
            Denominator::Unused => "m/s".to_owned(),
            Denominator::Other { label } => format!("m/s per {label}"),
        }
    }

    /// SI per file unit (1 when not a force).
    pub(crate) fn to_si(&self) -> f64 {
        match self {
            Denominator::Force { to_si } => *to_si,
            _ => 1.0,
        }
    }
}

/// A label as its writer meant it: a Latin-1 reading of UTF-8 bytes (`m/sÂ²`) back as UTF-8 (`m/s²`).
pub(crate) fn as_written(label: &str) -> String {
    let bytes: Option<Vec<u8>> = label.chars().map(|c| u8::try_from(u32::from(c)).ok()).collect();
    match bytes.map(String::from_utf8) {
        Some(Ok(utf8)) => utf8,
        _ => label.to_owned(),
    }
}

/// The specification's name of a specific data type code.
fn data_type_name(code: u32) -> &'static str {
    match code {
        0 => "unknown",
        1 => "general",
        2 => "stress",
        3 => "strain",
        5 => "temperature",
        6 => "heat flux",
        8 => "displacement",
        9 => "reaction force",
        11 => "velocity",
        12 => "acceleration",
        13 => "excitation force",
        15 => "pressure",
        16 => "mass",
        17 => "time",
        18 => "frequency",
        19 => "rpm",
        20 => "order",
        21 => "sound pressure",
        22 => "sound intensity",
        23 => "sound power",
        _ => "another quantity",
    }
}

/// An axis named for a message: `sound pressure (data type 15, "Pa")`.
pub(crate) fn describe(axis: &AxisCharacteristics) -> String {
    format!("{} (data type {}, {:?})", data_type_name(axis.data_type), axis.data_type, as_written(&axis.units_label))
}

/// An ordinate named for a unit string: the motion's SI unit, or the other quantity's name.
pub(crate) fn describe_ordinate(ordinate: &OrdinateQuantity) -> String {
    match ordinate {
        OrdinateQuantity::Motion { motion, .. } => motion.name().to_owned(),
        OrdinateQuantity::Other { name } => name.clone(),
    }
}

/// A units label's motion and factor to SI, and whether it is per newton: `None` if it is no motion unit.
fn motion_of_label(label: &str) -> Option<(Motion, f64, bool)> {
    let mut text: String = as_written(label)
        .chars()
        .filter(|c| !c.is_whitespace())
        .map(|c| match c {
            'µ' | 'μ' => 'u',
            c => c.to_ascii_lowercase(),
        })
        .collect();
    text = text.replace("**", "^").replace('²', "^2");
    let mut per_newton = false;
    for prefix in ["(1/n)*", "1/n*", "(1/n)"] {
        if let Some(rest) = text.strip_prefix(prefix) {
            text = rest.to_owned();
            per_newton = true;
        }
    }
    if let Some(rest) = text.strip_suffix("/n") {
        text = rest.to_owned();
        per_newton = true;
    }
    let text = text.trim_start_matches('(').trim_end_matches(')');
    let (length, motion) = match text.split_once('/') {
        None if text == "g" => return Some((Motion::Acceleration, STANDARD_GRAVITY_M_S2, per_newton)),
        None => (text, Motion::Displacement),
        Some((length, "s")) => (length, Motion::Velocity),
        Some((length, "s2" | "s^2")) => (length, Motion::Acceleration),
        Some(_) => return None,
    };
    let to_si = match length {
        "m" => 1.0,
        "mm" => 1e-3,
        "um" => 1e-6,
        "nm" => 1e-9,
        "in" => 0.0254,
        _ => return None,
    };
    Some((motion, to_si, per_newton))
}

/// What the ordinate `axis` holds, with dataset 164's `units` (SI without one).
pub(crate) fn ordinate(axis: &AxisCharacteristics, units: Option<&Units164>) -> OrdinateQuantity {
    let length_per_m = units.map_or(1.0, |u| u.length_per_m);
    let label = as_written(&axis.units_label);
    let by_type = match axis.data_type {
        8 => Some(Motion::Displacement),
        11 => Some(Motion::Velocity),
        12 => Some(Motion::Acceleration),
        _ => None,
    };
    let from_label = motion_of_label(&axis.units_label);
    match (by_type, from_label) {
        (Some(Motion::Acceleration), Some((Motion::Acceleration, to_si, per_newton)))
            if to_si == STANDARD_GRAVITY_M_S2 =>
        {
            OrdinateQuantity::Motion {
                motion: Motion::Acceleration,
                to_si,
                per_newton,
                basis: format!("data type 12, label {label:?}: standard gravity, 9.80665 m/s²"),
            }
        }
        (Some(motion), label_motion) => OrdinateQuantity::Motion {
            motion,
            to_si: 1.0 / length_per_m,
            per_newton: label_motion.is_some_and(|(m, _, per_n)| m == motion && per_n),
            basis: format!(
                "data type {} ({}), in dataset 164's length unit ({length_per_m} per metre)",
                axis.data_type,
                data_type_name(axis.data_type)
            ),
        },
        (None, Some((motion, to_si, per_newton))) if matches!(axis.data_type, 0 | 1) => OrdinateQuantity::Motion {
            motion,
            to_si,
            per_newton,
            basis: format!("data type {} ({}), units label {label:?}", axis.data_type, data_type_name(axis.data_type)),
        },
        _ => OrdinateQuantity::Other { name: describe(axis) },
    }
}

/// What the denominator `axis` holds, with dataset 164's `units`; `ordinate_per_newton` when the ordinate's label
/// already says per newton.
pub(crate) fn denominator(
    axis: &AxisCharacteristics,
    units: Option<&Units164>,
    ordinate_per_newton: bool,
) -> Denominator {
    let force_per_n = units.map_or(1.0, |u| u.force_per_n);
    let label = as_written(&axis.units_label);
    let force_label = match label.trim().to_ascii_lowercase().as_str() {
        "n" => Some(1.0),
        "kn" => Some(1e3),
        "lbf" => Some(NEWTONS_PER_LBF),
        _ => None,
    };
    match (axis.data_type, force_label) {
        (9 | 13, _) => Denominator::Force { to_si: 1.0 / force_per_n },
        (0 | 1, Some(to_si)) => Denominator::Force { to_si },
        (0, None) if label == "NONE" && ordinate_per_newton => Denominator::Force { to_si: 1.0 },
        (0, None) if label == "NONE" => Denominator::Unused,
        _ => Denominator::Other { label },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(data_type: u32, label: &str) -> AxisCharacteristics {
        AxisCharacteristics::new(data_type, "label", label)
    }

    fn motion(q: &OrdinateQuantity) -> Option<(Motion, f64, bool)> {
        match q {
            OrdinateQuantity::Motion { motion, to_si, per_newton, .. } => Some((*motion, *to_si, *per_newton)),
            OrdinateQuantity::Other { .. } => None,
        }
    }

    #[test]
    fn labels_as_writers_write_them() {
        // catman: general, `m/s²` in UTF-8 read as Latin-1.
        assert_eq!(motion(&ordinate(&axis(1, "m/s\u{c2}\u{b2}"), None)), Some((Motion::Acceleration, 1.0, false)));
        // An accelerance in Latin-1, per newton in its label.
        assert_eq!(motion(&ordinate(&axis(1, "(1/N)*(m/s\u{b2})"), None)), Some((Motion::Acceleration, 1.0, true)));
        assert_eq!(motion(&ordinate(&axis(0, "mm/s"), None)), Some((Motion::Velocity, 1e-3, false)));
        assert_eq!(motion(&ordinate(&axis(1, "µm"), None)), Some((Motion::Displacement, 1e-6, false)));
        assert_eq!(motion(&ordinate(&axis(12, "g"), None)), Some((Motion::Acceleration, 9.80665, false)));
        assert_eq!(motion(&ordinate(&axis(1, "m/s**2/N"), None)), Some((Motion::Acceleration, 1.0, true)));
        // Data type 11 in millimetres by dataset 164.
        let mut mm = Units164::si();
        mm.length_per_m = 1000.0;
        assert_eq!(motion(&ordinate(&axis(11, "mm/s"), Some(&mm))), Some((Motion::Velocity, 1e-3, false)));
    }

    #[test]
    fn other_quantities_are_named_not_taken_for_velocity() {
        for (data_type, label, name) in [
            (15, "Pa", "pressure (data type 15, \"Pa\")"),
            (21, "Pa", "sound pressure (data type 21, \"Pa\")"),
            (13, "N", "excitation force (data type 13, \"N\")"),
            (1, "V^2", "general (data type 1, \"V^2\")"),
            (0, "NONE", "unknown (data type 0, \"NONE\")"),
        ] {
            assert_eq!(ordinate(&axis(data_type, label), None), OrdinateQuantity::Other { name: name.into() });
        }
    }

    #[test]
    fn denominators() {
        assert_eq!(denominator(&axis(13, "N"), None, false), Denominator::Force { to_si: 1.0 });
        assert_eq!(denominator(&axis(0, "NONE"), None, false), Denominator::Unused);
        assert_eq!(denominator(&axis(0, "NONE"), None, true), Denominator::Force { to_si: 1.0 });
        assert_eq!(denominator(&axis(1, "kN"), None, false), Denominator::Force { to_si: 1e3 });
        assert_eq!(denominator(&axis(1, "V"), None, false).ir_unit(), "m/s per V");
    }
}
