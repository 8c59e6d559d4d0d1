//! The encoder: records to bytes, appended to the caller's buffer.

use crate::error::EncodeError;
use crate::fortran::{latin1, push_exp, push_int, push_left, push_right};
use crate::model::{AxisCharacteristics, Dof, FunctionHeader, Header151, Nodes2411, OrdinateRef, UffRecord, Units164};

/// Byte order of 58b binary data (field 3 of the 58b identifier line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ByteOrder {
    /// Code 1: least significant byte first.
    LittleEndian,
    /// Code 2: most significant byte first.
    BigEndian,
}

impl ByteOrder {
    /// The code in the 58b identifier line.
    pub fn code(self) -> u32 {
        match self {
            ByteOrder::LittleEndian => 1,
            ByteOrder::BigEndian => 2,
        }
    }
}

/// How dataset 58 values are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// Dataset 58: 80-column text lines (`6E13.5` single, `4E20.12` double precision).
    Ascii,
    /// Dataset 58b: the same header lines, then IEEE 754 values in `byte_order`.
    Binary {
        /// The byte order of the values.
        byte_order: ByteOrder,
    },
}

/// Precision of dataset 58 ordinate values (record 7, ordinate data type 2/5 single, 4/6 double).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Precision {
    /// Single: binary `f32`, or text with 6 significant digits (`%13.5e`).
    Single,
    /// Double: binary `f64`, or text with 12 significant digits (`%20.11e`).
    Double,
}

impl Precision {
    fn name(self) -> &'static str {
        match self {
            Precision::Single => "single precision",
            Precision::Double => "double precision",
        }
    }
}

/// The encoder: writes records as pyuff 2.5.8 writes them, column for column (its C formats, `%13.5e` where
/// the specification says `E13.5`), with two deliberate differences in 58b: the byte count is the true one for
/// complex values (pyuff states half), and single precision writes `f32` values (pyuff writes `f64` always).
///
/// `format` and `precision` apply to dataset 58; datasets 151, 164 and 2411 are ASCII (164 and
/// 2411 in double precision) always.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UffEncoder {
    /// ASCII 58 or binary 58b.
    pub format: Format,
    /// Single or double precision.
    pub precision: Precision,
}

const DELIMITER: &[u8] = b"    -1\n";

impl UffEncoder {
    /// An encoder writing dataset 58 in `format` and `precision`.
    pub fn new(format: Format, precision: Precision) -> Self {
        Self { format, precision }
    }

    /// Appends `record` to `out`. On error nothing is appended.
    pub fn encode(&self, record: &UffRecord, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        match record {
            UffRecord::Header(header) => all_or_nothing(out, |out| write_header(header, out)),
            UffRecord::Units(units) => all_or_nothing(out, |out| write_units(units, out)),
            UffRecord::Nodes(nodes) => all_or_nothing(out, |out| write_nodes(nodes, out)),
            UffRecord::Function(function) => self.encode_function(&function.header, function.ordinate.as_ref(), out),
            UffRecord::Other(other) => Err(EncodeError::NotWritable { dataset_number: other.dataset_number }),
        }
    }

    /// Appends a dataset 58 made of `header` and `ordinate` to `out`, without the caller assembling a
    /// [`Function58`](crate::Function58): an exporter streams each response from its own buffer. On error nothing is
    /// appended.
    pub fn encode_function(
        &self,
        header: &FunctionHeader,
        ordinate: OrdinateRef<'_>,
        out: &mut Vec<u8>,
    ) -> Result<(), EncodeError> {
        all_or_nothing(out, |out| self.write_function(header, ordinate, out))
    }

    fn write_function(
        &self,
        header: &FunctionHeader,
        ordinate: OrdinateRef<'_>,
        out: &mut Vec<u8>,
    ) -> Result<(), EncodeError> {
        if ordinate.is_empty() {
            return Err(EncodeError::Empty);
        }
        check_values(ordinate, self.precision)?;
        for (field, value) in [
            ("abscissa start", header.abscissa_start),
            ("abscissa step", header.abscissa_step),
            ("z-axis value", header.z_axis_value),
        ] {
            let positive = field != "abscissa step" || value > 0.0;
            if !value.is_finite() || !positive {
                return Err(EncodeError::Header { field, value });
            }
        }
        let count = ordinate.len();
        let reals_per_value: usize = match ordinate {
            OrdinateRef::Real(_) => 1,
            OrdinateRef::Complex(_) => 2,
        };
        let value_bytes: usize = match self.precision {
            Precision::Single => 4,
            Precision::Double => 8,
        };
        let data_type: i64 = match (ordinate, self.precision) {
            (OrdinateRef::Real(_), Precision::Single) => 2,
            (OrdinateRef::Real(_), Precision::Double) => 4,
            (OrdinateRef::Complex(_), Precision::Single) => 5,
            (OrdinateRef::Complex(_), Precision::Double) => 6,
        };
        check_int("number of values", count as i64, 1, 9_999_999_999)?;

        match self.format {
            Format::Ascii => push_opening(out, 58),
            Format::Binary { byte_order } => {
                out.extend_from_slice(DELIMITER);
                // Format (I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12): 58, b, byte order, IEEE 754 (2), 11 ASCII lines,
                // the bytes of binary data, four unused zeros.
                let bytes = count.saturating_mul(reals_per_value).saturating_mul(value_bytes);
                push_int(out, 58, 6);
                out.push(b'b');
                push_int(out, i64::from(byte_order.code()), 6);
                push_int(out, 2, 6);
                push_int(out, 11, 12);
                push_int(out, bytes as i64, 12);
                for width in [6, 6, 12, 12] {
                    push_int(out, 0, width);
                }
                out.push(b'\n');
            }
        }
        for line in &header.id_lines {
            push_text(out, "ID line", line, 80, Justify::Left)?;
            out.push(b'\n');
        }
        // UffRecord 6: Format(2(I5,I10),2(1X,10A1,I10,I4)).
        push_checked_int(out, "function type", i64::from(header.function_type.code()), 0, 99_999, 5)?;
        push_checked_int(out, "function identification number", i64::from(header.function_id), 0, 9_999_999_999, 10)?;
        push_checked_int(out, "version number", i64::from(header.version), 0, 99_999, 5)?;
        push_checked_int(out, "load case", i64::from(header.load_case), 0, 9_999_999_999, 10)?;
        push_dof(out, "response", &header.response)?;
        push_dof(out, "reference", &header.reference)?;
        out.push(b'\n');
        // UffRecord 7: Format(3I10,3E13.5): data type, values, even spacing (1), start, step, z-axis value.
        push_int(out, data_type, 10);
        push_int(out, count as i64, 10);
        push_int(out, 1, 10);
        push_exp(out, header.abscissa_start, 13, 5, b'e');
        push_exp(out, header.abscissa_step, 13, 5, b'e');
        push_exp(out, header.z_axis_value, 13, 5, b'e');
        out.push(b'\n');
        for axis in [&header.abscissa, &header.ordinate, &header.denominator, &header.z_axis] {
            push_axis(out, axis)?;
        }
        match self.format {
            Format::Ascii => push_ascii_values(out, ordinate, self.precision),
            Format::Binary { byte_order } => push_binary_values(out, ordinate, self.precision, byte_order),
        }
        out.extend_from_slice(DELIMITER);
        Ok(())
    }
}

/// The opening delimiter and the identifier line of an ASCII dataset, padded to 80 columns as pyuff pads it.
fn push_opening(out: &mut Vec<u8>, dataset_number: i64) {
    out.extend_from_slice(DELIMITER);
    push_int(out, dataset_number, 6);
    push_right(out, b"", 74);
    out.push(b'\n');
}

/// Runs `write` on `out`, and removes what it appended if it fails.
fn all_or_nothing(
    out: &mut Vec<u8>,
    write: impl FnOnce(&mut Vec<u8>) -> Result<(), EncodeError>,
) -> Result<(), EncodeError> {
    let start = out.len();
    let result = write(out);
    if result.is_err() {
        out.truncate(start);
    }
    result
}

/// Every value finite, and within `f32` range for single precision.
fn check_values(ordinate: OrdinateRef<'_>, precision: Precision) -> Result<(), EncodeError> {
    let fits = |value: f64| match precision {
        Precision::Single => (value as f32).is_finite(),
        Precision::Double => value.is_finite(),
    };
    let bad = |index: usize, value: f64| EncodeError::Value { index, value, precision: precision.name() };
    match ordinate {
        OrdinateRef::Real(values) => match values.iter().position(|&v| !fits(v)) {
            Some(i) => Err(bad(i, values[i])),
            None => Ok(()),
        },
        OrdinateRef::Complex(values) => {
            for (i, value) in values.iter().enumerate() {
                if !fits(value.re) {
                    return Err(bad(2 * i, value.re));
                }
                if !fits(value.im) {
                    return Err(bad(2 * i + 1, value.im));
                }
            }
            Ok(())
        }
    }
}

/// Calls `each` with the record's real numbers in file order (complex: real part, then imaginary).
fn for_each_real(ordinate: OrdinateRef<'_>, mut each: impl FnMut(f64)) {
    match ordinate {
        OrdinateRef::Real(values) => values.iter().for_each(|&v| each(v)),
        OrdinateRef::Complex(values) => values.iter().for_each(|v| {
            each(v.re);
            each(v.im);
        }),
    }
}

fn push_ascii_values(out: &mut Vec<u8>, ordinate: OrdinateRef<'_>, precision: Precision) {
    // Cases 1, 3 (6E13.5) and 5, 7 (4E20.12) of the specification; pyuff's C formats `%13.5e` and `%20.11e`
    // give the same widths with one more significant digit than Fortran's 0.xxxxxE+yy.
    let (per_line, width, decimals) = match precision {
        Precision::Single => (6, 13, 5),
        Precision::Double => (4, 20, 11),
    };
    let mut on_line = 0;
    for_each_real(ordinate, |value| {
        push_exp(out, value, width, decimals, b'e');
        on_line += 1;
        if on_line == per_line {
            out.push(b'\n');
            on_line = 0;
        }
    });
    if on_line > 0 {
        out.push(b'\n');
    }
}

fn push_binary_values(out: &mut Vec<u8>, ordinate: OrdinateRef<'_>, precision: Precision, byte_order: ByteOrder) {
    // The values follow the last header line directly, and the closing delimiter follows them directly: no line
    // ends in or after binary data (the 58b description).
    for_each_real(ordinate, |value| match (precision, byte_order) {
        (Precision::Single, ByteOrder::LittleEndian) => out.extend_from_slice(&(value as f32).to_le_bytes()),
        (Precision::Single, ByteOrder::BigEndian) => out.extend_from_slice(&(value as f32).to_be_bytes()),
        (Precision::Double, ByteOrder::LittleEndian) => out.extend_from_slice(&value.to_le_bytes()),
        (Precision::Double, ByteOrder::BigEndian) => out.extend_from_slice(&value.to_be_bytes()),
    });
}

#[derive(Clone, Copy)]
enum Justify {
    Left,
    Right,
}

/// Appends `text` in `width` columns ("NONE" if empty), refusing what would shift the columns.
fn push_text(
    out: &mut Vec<u8>,
    field: &'static str,
    text: &str,
    width: usize,
    justify: Justify,
) -> Result<(), EncodeError> {
    let text = if text.is_empty() { "NONE" } else { text };
    if width == 80 && text.trim_matches([' ', '\t']) == "-1" {
        return Err(EncodeError::Delimiter { field });
    }
    let bytes = match latin1(text) {
        Some(bytes) if bytes.len() <= width => bytes,
        _ => return Err(EncodeError::Text { field, text: text.to_owned(), max_len: width }),
    };
    match justify {
        Justify::Left => push_left(out, &bytes, width),
        Justify::Right => push_right(out, &bytes, width),
    }
    Ok(())
}

fn check_int(field: &'static str, value: i64, min: i64, max: i64) -> Result<(), EncodeError> {
    if (min..=max).contains(&value) { Ok(()) } else { Err(EncodeError::Integer { field, value, min, max }) }
}

fn push_checked_int(
    out: &mut Vec<u8>,
    field: &'static str,
    value: i64,
    min: i64,
    max: i64,
    width: usize,
) -> Result<(), EncodeError> {
    check_int(field, value, min, max)?;
    push_int(out, value, width);
    Ok(())
}

/// `1X,10A1,I10,I4`: the entity name right-justified as pyuff writes it (`%10s`).
fn push_dof(out: &mut Vec<u8>, which: &'static str, dof: &Dof) -> Result<(), EncodeError> {
    out.push(b' ');
    push_text(out, which, &dof.entity, 10, Justify::Right)?;
    push_checked_int(out, which, dof.node, -999_999_999, 9_999_999_999, 10)?;
    push_checked_int(out, "direction", i64::from(dof.direction), -6, 6, 4)
}

/// Records 8 to 11: Format(I10,3I5,2(1X,20A1)).
fn push_axis(out: &mut Vec<u8>, axis: &AxisCharacteristics) -> Result<(), EncodeError> {
    push_checked_int(out, "specific data type", i64::from(axis.data_type), 0, 9_999_999_999, 10)?;
    for exponent in [axis.length_exponent, axis.force_exponent, axis.temperature_exponent] {
        push_checked_int(out, "units exponent", i64::from(exponent), -9999, 99_999, 5)?;
    }
    out.push(b' ');
    push_text(out, "axis label", &axis.label, 20, Justify::Left)?;
    out.push(b' ');
    push_text(out, "axis units label", &axis.units_label, 20, Justify::Left)?;
    out.push(b'\n');
    Ok(())
}

fn write_header(header: &Header151, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    push_opening(out, 151);
    let line = |out: &mut Vec<u8>, field, text: &str| -> Result<(), EncodeError> {
        push_text(out, field, text, 80, Justify::Left)?;
        out.push(b'\n');
        Ok(())
    };
    let stamp = |out: &mut Vec<u8>, what: [&'static str; 2], [date, time]: &[String; 2]| {
        push_text(out, what[0], date, 10, Justify::Left)?;
        push_text(out, what[1], time, 10, Justify::Left)
    };
    // Records 1 to 3: Format(80A1) each.
    line(out, "model file name", &header.model_name)?;
    line(out, "model file description", &header.description)?;
    line(out, "program which created the database", &header.db_program)?;
    // Record 4: Format(10A1,10A1,3I10): the two versions and the file type (0, universal) as pyuff writes them.
    stamp(out, ["date database created", "time database created"], &header.db_created)?;
    for _ in 0..3 {
        push_int(out, 0, 10);
    }
    out.push(b'\n');
    // Record 5: Format(10A1,10A1).
    stamp(out, ["date database saved", "time database saved"], &header.db_saved)?;
    out.push(b'\n');
    // Record 6: Format(80A1); record 7: Format(10A1,10A1).
    line(out, "program which wrote the universal file", &header.program)?;
    stamp(out, ["date file written", "time file written"], &header.file_written)?;
    out.push(b'\n');
    out.extend_from_slice(DELIMITER);
    Ok(())
}

fn write_units(units: &Units164, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    push_opening(out, 164);
    // UffRecord 1: Format(I10,20A1,I10); pyuff right-justifies the description.
    push_checked_int(out, "units code", i64::from(units.units_code), 0, 9_999_999_999, 10)?;
    push_text(out, "units description", &units.description, 20, Justify::Right)?;
    if let Some(mode) = units.temperature_mode {
        push_checked_int(out, "temperature mode", i64::from(mode), 0, 9_999_999_999, 10)?;
    }
    out.push(b'\n');
    // UffRecord 2: Format(3D25.17), then the temperature offset on its own line (as pyuff and I-DEAS write it).
    let factors = [
        ("length factor", units.length_per_m),
        ("force factor", units.force_per_n),
        ("temperature factor", units.temperature_per_k),
        ("temperature offset", units.temperature_offset),
    ];
    for (i, (field, value)) in factors.into_iter().enumerate() {
        if !value.is_finite() {
            return Err(EncodeError::Header { field, value });
        }
        push_exp(out, value, 25, 16, b'D');
        if i >= 2 {
            out.push(b'\n');
        }
    }
    out.extend_from_slice(DELIMITER);
    Ok(())
}

fn write_nodes(nodes: &Nodes2411, out: &mut Vec<u8>) -> Result<(), EncodeError> {
    push_opening(out, 2411);
    for (n, node) in nodes.nodes.iter().enumerate() {
        // UffRecord 1: Format(4I10); record 2: Format(1P3D25.16), as pyuff writes it (`%25.16e`).
        for value in [node.label, node.export_coordinate_system, node.displacement_coordinate_system, node.color] {
            push_checked_int(out, "node field", i64::from(value), 0, 9_999_999_999, 10)?;
        }
        out.push(b'\n');
        for (axis, &value) in node.position_m.iter().enumerate() {
            if !value.is_finite() {
                return Err(EncodeError::Value { index: 3 * n + axis, value, precision: "double precision" });
            }
            push_exp(out, value, 25, 16, b'e');
        }
        out.push(b'\n');
    }
    out.extend_from_slice(DELIMITER);
    Ok(())
}
