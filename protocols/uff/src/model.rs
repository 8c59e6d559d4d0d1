//! The records this crate reads and writes, in memory.

use num_complex::Complex64;

/// One dataset of a universal file.
#[derive(Debug, Clone, PartialEq)]
pub enum UffRecord {
    /// Dataset 151: the file's header (names and programs, as text; boxed, as the function's header).
    Header(Box<Header151>),
    /// Dataset 164: the file's units.
    Units(Units164),
    /// Dataset 2411: nodes with double-precision coordinates.
    Nodes(Nodes2411),
    /// Dataset 58 or 58b: a function (time response or frequency response) at a nodal degree of freedom (boxed:
    /// its header is ten times the size of the other records).
    Function(Box<Function58>),
    /// A dataset of another number, stepped over whole (decoder only: the encoder refuses it).
    Other(OtherDataset),
}

/// Dataset 151, header: the model's name and description, the programs that made the model and the file, and
/// when, as text. Each field holds at most 80 printable Latin-1 characters (dates and times 10), "NONE" for blank.
///
/// The decoder never refuses an ASCII dataset 151 for its content: writers fill it as they like (some leave records
/// out), so each record is read as the text of its line, cut to its columns, a missing record "NONE"; record 4's
/// two version fields and file type are not kept (the encoder writes 0, as pyuff does).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header151 {
    /// Record 1: the model file's name.
    pub model_name: String,
    /// Record 2: the model file's description.
    pub description: String,
    /// Record 3: the program that created the database.
    pub db_program: String,
    /// Record 4, fields 1 and 2: the date (DD-MMM-YY) and time (HH:MM:SS) the database was created.
    pub db_created: [String; 2],
    /// Record 5: the date and time the database was last saved.
    pub db_saved: [String; 2],
    /// Record 6: the program that wrote the universal file.
    pub program: String,
    /// Record 7: the date and time the universal file was written.
    pub file_written: [String; 2],
}

/// Dataset 164, units: the factors that convert the file's units to SI.
///
/// To convert a value from the file's units to SI, divide it by the factor (the specification's convention).
#[derive(Debug, Clone, PartialEq)]
pub struct Units164 {
    /// Units code: 1 SI (metre, newton), 2 BG, 3 MG, 4 BA, 5 MM, 6 CM, 7 IN, 8 GM, 9 user-defined.
    pub units_code: u32,
    /// Free description (at most 20 printable Latin-1 characters; documentation only).
    pub description: String,
    /// Temperature mode: 1 absolute, 2 relative; `None` when the file leaves it blank (LMS Test.Lab writes
    /// `         9USER_DEFINED` and no mode).
    pub temperature_mode: Option<u32>,
    /// File length units per metre.
    pub length_per_m: f64,
    /// File force units per newton.
    pub force_per_n: f64,
    /// File temperature units per kelvin.
    pub temperature_per_k: f64,
    /// Temperature offset, in file temperature units.
    pub temperature_offset: f64,
}

impl Units164 {
    /// SI units (metre, newton, kelvin; offset 273.15 as I-DEAS writes for SI): what metaplate writes.
    pub fn si() -> Self {
        Self {
            units_code: 1,
            description: "SI: Meter (newton)".to_owned(),
            temperature_mode: Some(2),
            length_per_m: 1.0,
            force_per_n: 1.0,
            temperature_per_k: 1.0,
            temperature_offset: 273.15,
        }
    }
}

/// Dataset 2411, nodes with double-precision coordinates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Nodes2411 {
    /// The nodes, in file order.
    pub nodes: Vec<Node>,
}

/// One node of dataset 2411.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Node label (metaplate: grid points from 1, actuators after them).
    pub label: u32,
    /// Export (definition) coordinate system number.
    pub export_coordinate_system: u32,
    /// Displacement coordinate system number.
    pub displacement_coordinate_system: u32,
    /// Colour code.
    pub color: u32,
    /// Coordinates x, y, z in the file's length unit: metres when dataset 164 says SI.
    pub position_m: [f64; 3],
}

/// The kind of function a dataset 58 holds (record 6, field 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FunctionType {
    /// Code 1: a time response (metaplate's impulse responses); the abscissa is time in seconds.
    TimeResponse,
    /// Code 4: a frequency response function; the abscissa is frequency in hertz.
    FrequencyResponse,
    /// Any other code of the specification (0 and 2 to 27), kept as read.
    Other(u32),
}

impl FunctionType {
    /// The code written in the file.
    pub fn code(self) -> u32 {
        match self {
            FunctionType::TimeResponse => 1,
            FunctionType::FrequencyResponse => 4,
            FunctionType::Other(code) => code,
        }
    }

    /// The type of a code read from a file.
    pub fn from_code(code: u32) -> Self {
        match code {
            1 => FunctionType::TimeResponse,
            4 => FunctionType::FrequencyResponse,
            other => FunctionType::Other(other),
        }
    }
}

/// A nodal degree of freedom: an entity name, a node label and a direction (record 6).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Dof {
    /// Entity name (at most 10 printable Latin-1 characters; "NONE" if unused).
    pub entity: String,
    /// Node label (metaplate: the grid point for the response, the actuator for the reference). Writers use 0
    /// and negative labels for "no node" (LMS Test.Lab's throughput records have reference node -1), so any I10.
    pub node: i64,
    /// Direction: 0 scalar, ±1..±3 translation along ±X, ±Y, ±Z, ±4..±6 rotation about them.
    pub direction: i8,
}

impl Dof {
    /// The degree of freedom `+Z` translation of `node` with no entity name: a plate's out-of-plane motion.
    pub fn z(node: u32) -> Self {
        Self { entity: "NONE".to_owned(), node: i64::from(node), direction: 3 }
    }
}

/// Data characteristics of an axis (records 8 to 11): what the values are and in what unit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AxisCharacteristics {
    /// Specific data type: 0 unknown, 1 general, 8 displacement, 11 velocity, 12 acceleration, 13 excitation
    /// force, 17 time, 18 frequency, and the other codes of the specification.
    pub data_type: u32,
    /// Length units exponent (relevant for data type general).
    pub length_exponent: i32,
    /// Force units exponent.
    pub force_exponent: i32,
    /// Temperature units exponent.
    pub temperature_exponent: i32,
    /// Axis label (at most 20 printable Latin-1 characters; "NONE" if unused).
    pub label: String,
    /// Axis units label (at most 20 printable Latin-1 characters; "NONE" if unused).
    pub units_label: String,
}

impl AxisCharacteristics {
    /// Characteristics with the given data type code and labels, all exponents zero.
    pub fn new(data_type: u32, label: &str, units_label: &str) -> Self {
        Self {
            data_type,
            length_exponent: 0,
            force_exponent: 0,
            temperature_exponent: 0,
            label: label.to_owned(),
            units_label: units_label.to_owned(),
        }
    }

    /// An unused axis (data type 0, labels "NONE").
    pub fn unused() -> Self {
        Self::new(0, "NONE", "NONE")
    }
}

/// The ordinate values of a function, in the ordinate's unit over the denominator's (metaplate: m/s per N).
#[derive(Debug, Clone, PartialEq)]
pub enum Ordinate {
    /// Real values.
    Real(Vec<f64>),
    /// Complex values.
    Complex(Vec<Complex64>),
}

impl Ordinate {
    /// Number of values (complex values count once).
    pub fn len(&self) -> usize {
        match self {
            Ordinate::Real(values) => values.len(),
            Ordinate::Complex(values) => values.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A borrowed view of the values.
    pub fn as_ref(&self) -> OrdinateRef<'_> {
        match self {
            Ordinate::Real(values) => OrdinateRef::Real(values),
            Ordinate::Complex(values) => OrdinateRef::Complex(values),
        }
    }
}

/// Borrowed ordinate values, so that an exporter encodes a response straight from its own buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OrdinateRef<'a> {
    /// Real values.
    Real(&'a [f64]),
    /// Complex values.
    Complex(&'a [Complex64]),
}

impl OrdinateRef<'_> {
    /// Number of values (complex values count once).
    pub fn len(&self) -> usize {
        match self {
            OrdinateRef::Real(values) => values.len(),
            OrdinateRef::Complex(values) => values.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Everything of a dataset 58 but its values: the ID lines, the degrees of freedom, the even abscissa and the
/// axes' characteristics.
#[derive(Debug, Clone, PartialEq)]
pub struct FunctionHeader {
    /// ID lines 1 to 5 (records 1 to 5; at most 80 printable Latin-1 characters each, "NONE" if unused). Line 1
    /// describes the function, line 3 usually holds the date.
    pub id_lines: [String; 5],
    /// Function type (record 6, field 1).
    pub function_type: FunctionType,
    /// Function identification number.
    pub function_id: u32,
    /// Version or sequence number (at most 99999).
    pub version: u32,
    /// Load case identification number (0: single point excitation).
    pub load_case: u32,
    /// The response degree of freedom (metaplate: the grid point, +Z).
    pub response: Dof,
    /// The reference degree of freedom (metaplate: the actuator, +Z).
    pub reference: Dof,
    /// First abscissa value, in the abscissa's unit: s for a time response, Hz for a frequency response (SI).
    pub abscissa_start: f64,
    /// Abscissa increment of the even abscissa, in the same unit (finite, > 0).
    pub abscissa_step: f64,
    /// Z-axis value (0 if unused).
    pub z_axis_value: f64,
    /// Abscissa data characteristics (record 8).
    pub abscissa: AxisCharacteristics,
    /// Ordinate (numerator) data characteristics (record 9).
    pub ordinate: AxisCharacteristics,
    /// Ordinate denominator data characteristics (record 10).
    pub denominator: AxisCharacteristics,
    /// Z-axis data characteristics (record 11).
    pub z_axis: AxisCharacteristics,
}

impl FunctionHeader {
    /// A metaplate response: velocity (m/s) at `response` over force (N) at `reference`, both +Z. A time response
    /// starts at `abscissa_start` s with steps of `abscissa_step` s; a frequency response at `abscissa_start` Hz
    /// with steps of `abscissa_step` Hz. ID line 1 is `description`; the others are "NONE".
    pub fn velocity_over_force(
        function_type: FunctionType,
        response_node: u32,
        reference_node: u32,
        abscissa_start: f64,
        abscissa_step: f64,
        description: &str,
    ) -> Self {
        let abscissa = match function_type {
            FunctionType::FrequencyResponse => AxisCharacteristics::new(18, "Frequency", "Hz"),
            _ => AxisCharacteristics::new(17, "Time", "s"),
        };
        let none = || "NONE".to_owned();
        Self {
            id_lines: [description.to_owned(), none(), none(), none(), none()],
            function_type,
            function_id: 0,
            version: 0,
            load_case: 0,
            response: Dof::z(response_node),
            reference: Dof::z(reference_node),
            abscissa_start,
            abscissa_step,
            z_axis_value: 0.0,
            abscissa,
            ordinate: AxisCharacteristics::new(11, "Velocity", "m/s"),
            denominator: AxisCharacteristics::new(13, "Force", "N"),
            z_axis: AxisCharacteristics::unused(),
        }
    }
}

/// Dataset 58 (ASCII) or 58b (binary): a function at a nodal degree of freedom with an even abscissa.
#[derive(Debug, Clone, PartialEq)]
pub struct Function58 {
    /// The header records.
    pub header: FunctionHeader,
    /// The values, one per abscissa step.
    pub ordinate: Ordinate,
}

/// A dataset the decoder stepped over: its number, whether it was binary, and where it started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OtherDataset {
    /// The dataset number (for example 151 header, 2412 elements, 82 trace lines).
    pub dataset_number: u32,
    /// Whether the identifier line marked it binary (`b` in column 7).
    pub binary: bool,
    /// Line number (from 1) of its opening delimiter.
    pub line: u64,
    /// For a dataset 58 stepped over by [`UffDecoder::only_functions`](crate::UffDecoder::only_functions): its
    /// function type code (record 6, field 1).
    pub function_type: Option<u32>,
}
