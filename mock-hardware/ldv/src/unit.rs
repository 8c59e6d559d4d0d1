//! What a mock Polytec unit carries: its names and versions, its decoders at their indices, its head's autofocus.

/// One velocity decoder of a unit, at its index (`VeloDec,<index>`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecoderSpec {
    /// Its name (`VD-09`), as `GetDevInfo,VeloDec,<i>,Name` gives it.
    pub name: String,
    /// Its ranges as the unit spells them, as `GetDevInfo,VeloDec,<i>,Range` lists them.
    pub ranges: Vec<String>,
    /// The range at power-on (an index into `ranges`).
    pub default_range: usize,
    /// Its tracking filter settings (`Off`, `Slow`, `Fast`); empty: it has none (`Not Available`).
    pub tracking: Vec<String>,
    /// Its low-pass filter settings (`Off`, `20kHz`, ...); empty: it has none.
    pub low_pass: Vec<String>,
}

/// A unit: controller, sensor head and decoders (which decoders, and at which indices, differ from unit to unit).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnitSpec {
    /// `GetDevInfo,Controller,0,Name` (PLACE: `OFV-5000 Vibrometer Controller`, `OFV-5000Xtra Vibrometer Controller`).
    pub controller_name: String,
    /// `Get,Controller,0,Version`.
    pub controller_version: String,
    /// `Get,SensorHead,0,Name`.
    pub head_name: String,
    /// `Get,SensorHead,0,Version`.
    pub head_version: String,
    /// Whether the head has autofocus (`GetDevInfo,SensorHead,0,AutoFocus` lists its states, or `Not Available`).
    pub autofocus: bool,
    /// Velocity decoders, `VeloDec,0` first.
    pub velocity_decoders: Vec<DecoderSpec>,
    /// Displacement decoders' names, `DisplDec,0` first (listed, never used by the driver).
    pub displacement_decoders: Vec<String>,
    /// The largest signal level, `GetDevInfo,SignalLevel,0,Value` = `0,<max>`.
    pub signal_max: u32,
    /// Whether the interface echoes each line at power-up.
    pub echo_at_power_up: bool,
}

impl UnitSpec {
    /// The mock lab's unit: an OFV-5000 with an OFV-505 head (autofocus) and one velocity decoder at `VeloDec,0`
    /// whose ranges are 1, 5, 25, 125 and 1000 mm/s/V (the velocity decoder table of the OFV-3001 manual, appendix
    /// E.2.4, for its OVD-02), at 25 mm/s/V at power-on, with tracking and low-pass filters, and a DD-300 at
    /// `DisplDec,0`. The signal level reads 0 to 100.
    pub fn lab_default() -> Self {
        let ranges = ["1mm/s/V", "5mm/s/V", "25mm/s/V", "125mm/s/V", "1000mm/s/V"];
        Self {
            controller_name: "OFV-5000 Vibrometer Controller".into(),
            controller_version: "3.4".into(),
            head_name: "OFV-505".into(),
            head_version: "1.2".into(),
            autofocus: true,
            velocity_decoders: vec![DecoderSpec {
                name: "VD-02".into(),
                ranges: ranges.iter().map(|r| (*r).to_owned()).collect(),
                default_range: 2,
                tracking: ["Off", "Slow", "Medium", "Fast"].iter().map(|r| (*r).to_owned()).collect(),
                low_pass: ["Off", "1.5kHz", "20kHz", "100kHz"].iter().map(|r| (*r).to_owned()).collect(),
            }],
            displacement_decoders: vec!["DD-300".into()],
            signal_max: 100,
            echo_at_power_up: false,
        }
    }

    /// A unit laid out as PLACE's example configuration has it: DD-300 at `DisplDec,0`, DD-900 at `DisplDec,1`,
    /// VD-08 at `VeloDec,0` and VD-09 at `VeloDec,1` (`place/plugins/polytec/polytec.py`'s module note), with the
    /// VD-08's and VD-09's ranges of PLACE's menus (`elm/plugins/PolytecOFV5000.elm`), no filters, echo on at
    /// power-up.
    pub fn place_example() -> Self {
        let owned = |v: &[&str]| v.iter().map(|r| (*r).to_owned()).collect::<Vec<_>>();
        Self {
            velocity_decoders: vec![
                DecoderSpec {
                    name: "VD-08".into(),
                    ranges: owned(&[
                        "0.2mm/s/V",
                        "0.5mm/s/V",
                        "1mm/s/V",
                        "2mm/s/V",
                        "5mm/s/V",
                        "10mm/s/V",
                        "20mm/s/V",
                        "50mm/s/V",
                    ]),
                    default_range: 4,
                    tracking: Vec::new(),
                    low_pass: Vec::new(),
                },
                DecoderSpec {
                    name: "VD-09".into(),
                    ranges: owned(&[
                        "1m/s/V",
                        "1m/s/V LP",
                        "500mm/s/V",
                        "500mm/s/V LP",
                        "200mm/s/V",
                        "200mm/s/V LP",
                        "100mm/s/V",
                        "100mm/s/V LP",
                        "50mm/s/V",
                        "50mm/s/V LP",
                        "20mm/s/V",
                        "20mm/s/V LP",
                        "10mm/s/V",
                        "5mm/s/V",
                    ]),
                    default_range: 13,
                    tracking: Vec::new(),
                    low_pass: Vec::new(),
                },
            ],
            displacement_decoders: vec!["DD-300".into(), "DD-900".into()],
            echo_at_power_up: true,
            ..Self::lab_default()
        }
    }
}
