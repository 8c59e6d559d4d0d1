//! The dataset records the decoder reads: header (151), units (164), nodes (2411) and functions at nodal DOF (58 and
//! 58b): each step takes one line (or the binary block) of its dataset and says what the state machine does next.

use num_complex::Complex64;

use super::{BinaryHeader, Layout, State, Step, UffDecoder};
use crate::encode::{ByteOrder, Precision};
use crate::error::{DecodeError, Location, Malformed, excerpt};
use crate::fortran::{columns, parse_line_text, parse_real, parse_text, trim};
use crate::model::{
    AxisCharacteristics, Dof, Function58, FunctionHeader, FunctionType, Header151, Node, Nodes2411, Ordinate,
    UffRecord, Units164,
};

impl UffDecoder {
    /// Dataset 151: each of the 7 records is the text of its line, whatever it holds (lines after the seventh are
    /// stepped over); at the closing delimiter, the records missing are "NONE".
    pub(super) fn step_header(&mut self, mut records: Vec<Vec<u8>>, line: &[u8], is_delimiter: bool) -> Step {
        if !is_delimiter {
            if records.len() < 7 {
                records.push(columns(line, 0, 80).to_vec());
            }
            self.state = State::Header { records };
            return Step::Again;
        }
        self.state = State::Between { garbage: false };
        Step::Emit(Ok(UffRecord::Header(Box::new(header151(&records)))))
    }

    pub(super) fn step_units(
        &mut self,
        record1: Option<(u32, String, Option<u32>)>,
        mut factors: Vec<f64>,
        line: &[u8],
        is_delimiter: bool,
    ) -> Step {
        let Some(record1) = record1 else {
            // UffRecord 1: Format(I10,20A1,I10); LMS Test.Lab leaves the temperature mode out.
            let parsed = self.u32_field("units code", line, 0, 10).and_then(|code| {
                let mode = if trim(columns(line, 30, 10)).is_empty() {
                    None
                } else {
                    Some(self.u32_field("temperature mode", line, 30, 10)?)
                };
                Ok((code, parse_text(columns(line, 10, 20)), mode))
            });
            return match parsed {
                Ok(record1) => {
                    self.state = State::Units { record1: Some(record1), factors };
                    Step::Again
                }
                Err(kind) => self.fail(kind),
            };
        };
        if is_delimiter {
            self.state = State::Between { garbage: false };
            let found = factors.len() as u64;
            return Step::Emit(Err(self.error(Malformed::TooFewValues { expected: 4, found })));
        }
        // UffRecord 2: Format(3D25.17), the fourth factor on the next line; read as words, as pyuff does.
        for word in line.split(|&b| b == b' ' || b == b'\t').filter(|w| !w.is_empty()) {
            let Some(value) = parse_real(word) else {
                let expected = "a unit factor (D25.17)";
                return self.fail(Malformed::Unexpected { expected, found: excerpt(word) });
            };
            if !value.is_finite() {
                return self.fail(Malformed::NonFinite { index: factors.len() as u64, value });
            }
            if factors.len() == 4 {
                return self.fail(Malformed::TooManyValues { expected: 4 });
            }
            factors.push(value);
        }
        if let [length_per_m, force_per_n, temperature_per_k, temperature_offset] = factors[..] {
            let (units_code, description, temperature_mode) = record1;
            let units = Units164 {
                units_code,
                description,
                temperature_mode,
                length_per_m,
                force_per_n,
                temperature_per_k,
                temperature_offset,
            };
            self.state = State::Closing { record: Box::new(UffRecord::Units(units)), blank_allowed: false };
        } else {
            self.state = State::Units { record1: Some(record1), factors };
        }
        Step::Again
    }

    pub(super) fn step_nodes(
        &mut self,
        mut nodes: Vec<Node>,
        pending: Option<[u32; 4]>,
        line: &[u8],
        is_delimiter: bool,
    ) -> Step {
        let Some([label, export, displacement, color]) = pending else {
            if is_delimiter {
                self.state = State::Between { garbage: false };
                return Step::Emit(Ok(UffRecord::Nodes(Nodes2411 { nodes })));
            }
            if nodes.len() as u64 >= self.limits.max_nodes {
                let max = self.limits.max_nodes;
                return self.fail(Malformed::TooLarge {
                    what: "nodes in dataset 2411",
                    count: max.saturating_add(1),
                    max,
                });
            }
            // UffRecord 1: Format(4I10).
            let mut fields = [0u32; 4];
            let names = ["node label", "export coordinate system", "displacement coordinate system", "color"];
            for (i, name) in names.into_iter().enumerate() {
                match self.u32_field(name, line, 10 * i, 10) {
                    Ok(value) => fields[i] = value,
                    Err(kind) => return self.fail(kind),
                }
            }
            self.state = State::Nodes { nodes, pending: Some(fields) };
            return Step::Again;
        };
        // UffRecord 2: Format(1P3D25.16).
        let mut position_m = [0.0; 3];
        for (axis, value_m) in position_m.iter_mut().enumerate() {
            let value = match parse_real(columns(line, 25 * axis, 25)) {
                Some(value) => value,
                None => return self.fail(self.field_error("node coordinate", line, 25 * axis, 25, "D25.16")),
            };
            if !value.is_finite() {
                let index = 3 * nodes.len() as u64 + axis as u64;
                return self.fail(Malformed::NonFinite { index, value });
            }
            *value_m = value;
        }
        if !trim(columns(line, 75, usize::MAX)).is_empty() {
            return self.fail(self.field_error("end of record 2", line, 75, line.len().saturating_sub(75), "blank"));
        }
        nodes.push(Node {
            label,
            export_coordinate_system: export,
            displacement_coordinate_system: displacement,
            color,
            position_m,
        });
        self.state = State::Nodes { nodes, pending: None };
        Step::Again
    }

    pub(super) fn start_values(&mut self, binary: Option<BinaryHeader>, lines: &[Vec<u8>]) -> Step {
        let first_line = self.lines - 10;
        let (header, layout) = match self.function_header(lines) {
            Ok(parsed) => parsed,
            Err((index, kind)) => {
                let location = Location { line: first_line + index as u64, ..self.location() };
                self.state = match binary {
                    Some(binary) => State::SkipBytes { bytes: binary.bytes },
                    None => State::Skip,
                };
                return Step::Emit(Err(DecodeError { location, kind }));
            }
        };
        let header = Box::new(header);
        if layout.reals > self.limits.max_values {
            let (count, max) = (layout.reals, self.limits.max_values);
            return self.fail(Malformed::TooLarge { what: "values in dataset 58", count, max });
        }
        let Some(binary) = binary else {
            self.state = State::AsciiValues { header, layout, reals: Vec::new() };
            return Step::Again;
        };
        let bytes_per_real: u64 = match layout.precision {
            Precision::Single => 4,
            Precision::Double => 8,
        };
        let expected = layout.reals.saturating_mul(bytes_per_real);
        if binary.ascii_lines != 11 {
            let kind = Malformed::Unexpected {
                expected: "11 ASCII lines before the binary data of dataset 58b",
                found: binary.ascii_lines.to_string(),
            };
            self.state = State::SkipBytes { bytes: binary.bytes };
            return Step::Emit(Err(self.error(kind)));
        }
        // pyuff up to 2.5 (at least) states the bytes of the real parts only for complex values: accepted, since
        // the values the header announces are what is read.
        let pyuff_complex = layout.complex && binary.bytes * 2 == expected;
        if binary.bytes != expected && !pyuff_complex {
            // One of the two counts is wrong: skip the smaller, then search for the closing delimiter.
            self.state = State::SkipBytes { bytes: binary.bytes.min(expected) };
            return Step::Emit(Err(self.error(Malformed::ByteCount { stated: binary.bytes, expected })));
        }
        self.state = State::BinaryValues { header, layout, byte_order: binary.byte_order, reals: Vec::new() };
        Step::Again
    }

    /// Records 1 to 11 of dataset 58 (`lines[0]` is record 1). On error: the index of the record's line and what.
    fn function_header(&self, lines: &[Vec<u8>]) -> Result<(FunctionHeader, Layout), (usize, Malformed)> {
        let line = |i: usize| lines.get(i).map_or(&[][..], |l| l.as_slice());
        let id_lines = [0, 1, 2, 3, 4].map(|i| parse_line_text(line(i)));
        // UffRecord 6: Format(2(I5,I10),2(1X,10A1,I10,I4)).
        let r6 = line(5);
        let at = |kind| (5, kind);
        let function_type = self.int_field("function type", r6, 0, 5, 0..=99_999, "I5").map_err(at)?;
        let function_id = self.u32_field("function identification number", r6, 5, 10).map_err(at)?;
        let version = self.u32_field("version number", r6, 15, 5).map_err(at)?;
        let load_case = self.u32_field("load case identification number", r6, 20, 10).map_err(at)?;
        let dof = |start: usize, name: &'static str| -> Result<Dof, Malformed> {
            let node = self.int_field(name, r6, start + 11, 10, -999_999_999..=9_999_999_999, "I10")?;
            let direction = self.int_field("direction", r6, start + 21, 4, -6..=6, "-6 to 6")?;
            Ok(Dof { entity: parse_text(columns(r6, start + 1, 10)), node, direction: direction as i8 })
        };
        let response = dof(30, "response node").map_err(at)?;
        let reference = dof(55, "reference node").map_err(at)?;
        // UffRecord 7: Format(3I10,3E13.5).
        let r7 = line(6);
        let at = |kind| (6, kind);
        let data_type = self.int_field("ordinate data type", r7, 0, 10, 2..=6, "2, 4, 5 or 6").map_err(at)?;
        let (complex, precision) = match data_type {
            2 => (false, Precision::Single),
            4 => (false, Precision::Double),
            5 => (true, Precision::Single),
            6 => (true, Precision::Double),
            _ => return Err(at(self.field_error("ordinate data type", r7, 0, 10, "2, 4, 5 or 6"))),
        };
        let values =
            self.int_field("number of values", r7, 10, 10, 1..=i64::MAX / 2, "I10 (at least 1)").map_err(at)?;
        let spacing = self.int_field("abscissa spacing", r7, 20, 10, 0..=1, "0 or 1").map_err(at)?;
        if spacing != 1 {
            let what = "uneven abscissa spacing (record 7, columns 21-30: 0); an even abscissa (1) is read".to_owned();
            return Err(at(Malformed::Unsupported { what }));
        }
        let real = |start: usize, field: &'static str| -> Result<f64, Malformed> {
            match parse_real(columns(r7, start, 13)) {
                Some(value) if value.is_finite() => Ok(value),
                _ => Err(self.field_error(field, r7, start, 13, "E13.5, finite")),
            }
        };
        let abscissa_start = real(30, "abscissa minimum").map_err(at)?;
        let abscissa_step = real(43, "abscissa increment").map_err(at)?;
        if abscissa_step <= 0.0 {
            return Err(at(self.field_error("abscissa increment", r7, 43, 13, "E13.5, positive")));
        }
        let z_axis_value = real(56, "z-axis value").map_err(at)?;
        // Records 8 to 11: Format(I10,3I5,2(1X,20A1)).
        let axis = |i: usize| -> Result<AxisCharacteristics, (usize, Malformed)> {
            let r = line(i);
            let at = |kind| (i, kind);
            let exponent = |start: usize, field: &'static str| {
                self.int_field(field, r, start, 5, -9999..=99_999, "I5").map(|v| v as i32).map_err(at)
            };
            Ok(AxisCharacteristics {
                data_type: self.u32_field("specific data type", r, 0, 10).map_err(at)?,
                length_exponent: exponent(10, "length units exponent")?,
                force_exponent: exponent(15, "force units exponent")?,
                temperature_exponent: exponent(20, "temperature units exponent")?,
                label: parse_text(columns(r, 26, 20)),
                units_label: parse_text(columns(r, 47, 20)),
            })
        };
        let header = FunctionHeader {
            id_lines,
            function_type: FunctionType::from_code(function_type as u32),
            function_id,
            version,
            load_case,
            response,
            reference,
            abscissa_start,
            abscissa_step,
            z_axis_value,
            abscissa: axis(7)?,
            ordinate: axis(8)?,
            denominator: axis(9)?,
            z_axis: axis(10)?,
        };
        let reals = (values as u64).saturating_mul(if complex { 2 } else { 1 });
        Ok((header, Layout { complex, precision, reals }))
    }

    pub(super) fn step_ascii(
        &mut self,
        header: Box<FunctionHeader>,
        layout: Layout,
        mut reals: Vec<f64>,
        line: &[u8],
        is_delimiter: bool,
    ) -> Step {
        if is_delimiter {
            self.state = State::Between { garbage: false };
            let kind = Malformed::TooFewValues { expected: layout.reals, found: reals.len() as u64 };
            return Step::Emit(Err(self.error(kind)));
        }
        // Cases 1 and 3: 6E13.5; cases 5 and 7: 4E20.12. Writers differ in widths and digits, so a line whose
        // blank-separated words are all numbers is read as words; else by the format's columns (numbers written
        // with no space between them, Fortran's `0.12345+100`).
        let (width, format) = match layout.precision {
            Precision::Single => (13, "E13.5"),
            Precision::Double => (20, "E20.12"),
        };
        let mut values = std::mem::take(&mut self.line_values);
        if let Err(start) = parse_values(line, width, &mut values) {
            self.line_values = values;
            return self.fail(self.field_error("data value", line, start, width, format));
        }
        for &value in &values {
            if reals.len() as u64 >= layout.reals {
                // Several writers pad the last line with zeros past the count record 7 announces.
                if value == 0.0 {
                    continue;
                }
                self.line_values = values;
                return self.fail(Malformed::TooManyValues { expected: layout.reals });
            }
            if !value.is_finite() {
                self.line_values = values;
                return self.fail(Malformed::NonFinite { index: reals.len() as u64, value });
            }
            reals.push(value);
        }
        self.line_values = values;
        if reals.len() as u64 == layout.reals {
            self.state = State::Closing { record: Box::new(function(*header, layout, reals)), blank_allowed: false };
        } else {
            self.state = State::AsciiValues { header, layout, reals };
        }
        Step::Again
    }

    pub(super) fn step_binary(
        &mut self,
        header: Box<FunctionHeader>,
        layout: Layout,
        byte_order: ByteOrder,
        mut reals: Vec<f64>,
    ) -> Step {
        let size = match layout.precision {
            Precision::Single => 4,
            Precision::Double => 8,
        };
        let wanted = layout.reals - reals.len() as u64;
        let whole = (self.available().len() / size) as u64;
        let take = wanted.min(whole) as usize;
        let bytes = self.available().get(..take * size).unwrap_or(&[]);
        let start = reals.len();
        for chunk in bytes.chunks_exact(size) {
            let value = match (layout.precision, byte_order, chunk) {
                (Precision::Single, ByteOrder::LittleEndian, &[a, b, c, d]) => {
                    f64::from(f32::from_le_bytes([a, b, c, d]))
                }
                (Precision::Single, ByteOrder::BigEndian, &[a, b, c, d]) => f64::from(f32::from_be_bytes([a, b, c, d])),
                (Precision::Double, ByteOrder::LittleEndian, &[a, b, c, d, e, f, g, h]) => {
                    f64::from_le_bytes([a, b, c, d, e, f, g, h])
                }
                (Precision::Double, ByteOrder::BigEndian, &[a, b, c, d, e, f, g, h]) => {
                    f64::from_be_bytes([a, b, c, d, e, f, g, h])
                }
                _ => f64::NAN,
            };
            reals.push(value);
        }
        self.consume(take * size);
        if let Some(offset) = reals[start..].iter().position(|v| !v.is_finite()) {
            let index = start + offset;
            let remaining = (layout.reals - reals.len() as u64).saturating_mul(size as u64);
            self.state = State::SkipBytes { bytes: remaining };
            return Step::Emit(Err(self.error(Malformed::NonFinite { index: index as u64, value: reals[index] })));
        }
        if reals.len() as u64 == layout.reals {
            self.state = State::Closing { record: Box::new(function(*header, layout, reals)), blank_allowed: true };
            Step::Again
        } else {
            self.state = State::BinaryValues { header, layout, byte_order, reals };
            Step::Wait
        }
    }
}

/// The numbers of a line of ASCII values into `out` (cleared first), each parsed once: its blank-separated words when
/// they are all numbers, else fixed columns of `width` up to the first blank field, after which nothing but blanks
/// may follow. `Err` with the first column (0-based) of a field that is no number.
fn parse_values(line: &[u8], width: usize, out: &mut Vec<f64>) -> Result<(), usize> {
    out.clear();
    let mut every_word = true;
    for word in words(line) {
        match parse_real(word) {
            Some(value) => out.push(value),
            None => {
                every_word = false;
                break;
            }
        }
    }
    if every_word {
        return Ok(());
    }
    out.clear();
    let mut start = 0;
    while start < line.len() {
        let field = columns(line, start, width);
        if trim(field).is_empty() {
            // Blank columns end the values of a line; nothing but blanks may follow.
            return if trim(columns(line, start, usize::MAX)).is_empty() { Ok(()) } else { Err(start) };
        }
        out.push(parse_real(field).ok_or(start)?);
        start += width;
    }
    Ok(())
}

/// The blank-separated words of a line.
fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|&b| b == b' ' || b == b'\t').filter(|w| !w.is_empty())
}

/// Dataset 151 from its records as read (missing ones "NONE").
fn header151(records: &[Vec<u8>]) -> Header151 {
    let record = |i: usize| records.get(i).map_or(&[][..], Vec::as_slice);
    let text = |i: usize| parse_line_text(record(i));
    let stamp = |i: usize| [parse_text(columns(record(i), 0, 10)), parse_text(columns(record(i), 10, 10))];
    Header151 {
        model_name: text(0),
        description: text(1),
        db_program: text(2),
        db_created: stamp(3),
        db_saved: stamp(4),
        program: text(5),
        file_written: stamp(6),
    }
}

fn function(header: FunctionHeader, layout: Layout, reals: Vec<f64>) -> UffRecord {
    let ordinate = if layout.complex {
        Ordinate::Complex(reals.chunks_exact(2).map(|pair| Complex64::new(pair[0], pair[1])).collect())
    } else {
        Ordinate::Real(reals)
    };
    UffRecord::Function(Box::new(Function58 { header, ordinate }))
}
