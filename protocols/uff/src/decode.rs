//! The incremental decoder: bytes in (split anywhere), records out, with bounded lines and records.

use num_complex::Complex64;

use crate::encode::{ByteOrder, Precision};
use crate::error::{DecodeError, Location, Malformed, excerpt};
use crate::fortran::{columns, parse_int, parse_real, parse_text, trim};
use crate::model::{
    AxisCharacteristics, Dof, Function58, FunctionHeader, FunctionType, Node, Nodes2411, Ordinate, OtherDataset,
    UffRecord, Units164,
};

/// The decoder's bounds on hostile input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Longest line, bytes without its line end (the format's lines are 80 columns; writers pad some to more).
    pub max_line_bytes: usize,
    /// Most real numbers in one function (a complex value counts two): bounds a record's memory to 8 bytes each.
    pub max_values: u64,
    /// Most nodes in one dataset 2411.
    pub max_nodes: u64,
}

impl Default for Limits {
    /// 1024-byte lines; 2^24 values (128 MiB as `f64`); 2^20 nodes.
    fn default() -> Self {
        Self { max_line_bytes: 1024, max_values: 1 << 24, max_nodes: 1 << 20 }
    }
}

/// The shape of a dataset 58's values, from its identifier line and record 7.
#[derive(Debug, Clone, Copy)]
struct Layout {
    complex: bool,
    precision: Precision,
    /// Real numbers to read (a complex value counts two).
    reals: u64,
}

/// The 58b fields of an identifier line.
#[derive(Debug, Clone, Copy)]
struct BinaryHeader {
    byte_order: ByteOrder,
    ascii_lines: u64,
    bytes: u64,
}

#[derive(Debug, Clone)]
enum State {
    /// Between datasets: expecting an opening delimiter. `garbage` once other lines have been reported.
    Between {
        garbage: bool,
    },
    /// After the `-1` that ended a skip: either that was a closing delimiter (an opening one follows), or it
    /// opened a dataset (its identifier line follows).
    AfterSkip,
    /// After an opening delimiter: expecting the identifier line (dataset number, `b` for binary).
    Identifier,
    Units {
        record1: Option<(u32, String, u32)>,
        factors: Vec<f64>,
    },
    Nodes {
        nodes: Vec<Node>,
        pending: Option<[u32; 4]>,
    },
    FunctionHeader {
        binary: Option<BinaryHeader>,
        lines: Vec<Vec<u8>>,
    },
    AsciiValues {
        header: Box<FunctionHeader>,
        layout: Layout,
        reals: Vec<f64>,
    },
    BinaryValues {
        header: Box<FunctionHeader>,
        layout: Layout,
        byte_order: ByteOrder,
        reals: Vec<f64>,
    },
    /// Expecting the closing delimiter, then `record` is complete; a blank line first is allowed after binary
    /// data (a common departure from the 58b description).
    Closing {
        record: Box<UffRecord>,
        blank_allowed: bool,
    },
    OtherAscii {
        other: OtherDataset,
    },
    OtherBinary {
        other: OtherDataset,
        ascii_lines: u64,
        bytes: u64,
    },
    /// Binary bytes to discard after an error, then skip to the closing delimiter.
    SkipBytes {
        bytes: u64,
    },
    /// ASCII lines, then binary bytes, to discard after an error in a 58b identifier line.
    SkipCounted {
        ascii_lines: u64,
        bytes: u64,
    },
    /// After an error inside a dataset: skipping to its closing delimiter.
    Skip,
}

impl State {
    fn expected(&self) -> &'static str {
        match self {
            State::Between { .. } | State::AfterSkip | State::Skip => "the delimiter `    -1`",
            State::Identifier => "the identifier line (dataset number)",
            State::Units { .. } => "the records of dataset 164",
            State::Nodes { .. } => "the records of dataset 2411",
            State::FunctionHeader { .. } => "the header records of dataset 58",
            State::AsciiValues { .. } => "more values of dataset 58",
            State::BinaryValues { .. }
            | State::OtherBinary { .. }
            | State::SkipBytes { .. }
            | State::SkipCounted { .. } => "the binary bytes the identifier line states",
            State::Closing { .. } | State::OtherAscii { .. } => "the delimiter `    -1` that closes the dataset",
        }
    }
}

enum Step {
    Emit(Result<UffRecord, DecodeError>),
    Again,
    Wait,
}

enum Line {
    Text(Vec<u8>),
    TooLong,
    Wait,
}

/// The incremental decoder of universal files: [`push`](Self::push) bytes as they arrive, split anywhere, then
/// [`poll`](Self::poll) until it returns `None`; call [`finish`](Self::finish) at the end of the input and poll once
/// more.
///
/// It yields datasets 164, 2411 and 58/58b as [`UffRecord`]s and steps over datasets of other numbers
/// ([`UffRecord::Other`]). Each error names the record (the dataset's ordinal in the file), its dataset number and
/// the line; after an error the decoder skips to the dataset's closing delimiter and goes on with the next
/// dataset, so one bad dataset costs only itself. Results do not depend on how the input was split.
///
/// Memory: the buffer holds at most one line ([`Limits::max_line_bytes`]) beyond the bytes of the last push, and a
/// record in progress grows only with the values actually read (never by what a header claims), up to
/// [`Limits::max_values`] or [`Limits::max_nodes`].
#[derive(Debug, Clone)]
pub struct UffDecoder {
    limits: Limits,
    buf: Vec<u8>,
    pos: usize,
    eof: bool,
    /// Lines consumed so far: the number of the last line read.
    lines: u64,
    /// Opening delimiters met: the current dataset's ordinal.
    record: u64,
    dataset_number: Option<u32>,
    /// Discarding the rest of an overlong line up to its line end.
    overlong: bool,
    truncation_reported: bool,
    state: State,
}

impl Default for UffDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl UffDecoder {
    /// A decoder at the start of a file, with the default [`Limits`].
    pub fn new() -> Self {
        Self::with_limits(Limits::default())
    }

    /// A decoder at the start of a file, with `limits`.
    pub fn with_limits(limits: Limits) -> Self {
        Self {
            limits,
            buf: Vec::new(),
            pos: 0,
            eof: false,
            lines: 0,
            record: 0,
            dataset_number: None,
            overlong: false,
            truncation_reported: false,
            state: State::Between { garbage: false },
        }
    }

    /// Feeds the next bytes of the file. Bytes pushed after [`finish`](Self::finish) are ignored.
    pub fn push(&mut self, bytes: &[u8]) {
        if self.eof {
            return;
        }
        if self.pos > 0 && self.pos >= self.buf.len() / 2 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(bytes);
    }

    /// Marks the end of the input: a last line without a line end is read, and input that ends inside a dataset
    /// gives one [`Malformed::Truncated`].
    pub fn finish(&mut self) {
        self.eof = true;
    }

    /// The next record or error, or `None` when more input (or [`finish`](Self::finish)) is needed or the input
    /// is exhausted.
    pub fn poll(&mut self) -> Option<Result<UffRecord, DecodeError>> {
        loop {
            match self.step() {
                Step::Emit(result) => return Some(result),
                Step::Again => {}
                Step::Wait => {
                    let idle = matches!(self.state, State::Between { .. } | State::AfterSkip | State::Skip);
                    if self.eof && !idle && !self.truncation_reported {
                        self.truncation_reported = true;
                        let expected = self.state.expected();
                        self.state = State::Skip;
                        return Some(Err(self.error(Malformed::Truncated { expected })));
                    }
                    return None;
                }
            }
        }
    }

    /// Polls until `None`, as an iterator.
    pub fn records(&mut self) -> impl Iterator<Item = Result<UffRecord, DecodeError>> + '_ {
        std::iter::from_fn(move || self.poll())
    }

    /// Bytes pushed and not yet decoded.
    pub fn buffered_len(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// The number of the last line read, from 1 (0 before the first).
    pub fn line(&self) -> u64 {
        self.lines
    }

    fn available(&self) -> &[u8] {
        self.buf.get(self.pos..).unwrap_or(&[])
    }

    fn consume(&mut self, n: usize) {
        self.pos = (self.pos + n).min(self.buf.len());
    }

    fn location(&self) -> Location {
        Location { record: self.record, dataset_number: self.dataset_number, line: self.lines }
    }

    fn error(&self, kind: Malformed) -> DecodeError {
        DecodeError { location: self.location(), kind }
    }

    /// Reports `kind` and skips the rest of the dataset.
    fn fail(&mut self, kind: Malformed) -> Step {
        self.state = State::Skip;
        Step::Emit(Err(self.error(kind)))
    }

    /// The next complete line without its line end (`\n` or `\r\n`).
    fn next_line(&mut self) -> Line {
        loop {
            let max = self.limits.max_line_bytes;
            let available = self.available();
            match available.iter().position(|&b| b == b'\n') {
                Some(end) => {
                    let overlong = self.overlong || end > max + 1;
                    let mut line = if overlong { Vec::new() } else { available[..end].to_vec() };
                    if line.last() == Some(&b'\r') {
                        line.pop();
                    }
                    self.consume(end + 1);
                    self.lines += 1;
                    if self.overlong {
                        // The rest of a line already reported.
                        self.overlong = false;
                        continue;
                    }
                    if overlong || line.len() > max {
                        return Line::TooLong;
                    }
                    return Line::Text(line);
                }
                None if self.overlong => {
                    let n = available.len();
                    self.consume(n);
                    return Line::Wait;
                }
                None if available.len() > max + 1 => {
                    let n = available.len();
                    self.consume(n);
                    self.overlong = true;
                    // Reported as the line it is, although its end has not arrived.
                    self.lines += 1;
                    return Line::TooLong;
                }
                None if self.eof && !available.is_empty() => {
                    let mut line = available.to_vec();
                    if line.last() == Some(&b'\r') {
                        line.pop();
                    }
                    let n = available.len();
                    self.consume(n);
                    self.lines += 1;
                    return Line::Text(line);
                }
                None => return Line::Wait,
            }
        }
    }

    fn step(&mut self) -> Step {
        let state = std::mem::replace(&mut self.state, State::Skip);
        match state {
            State::BinaryValues { header, layout, byte_order, reals } => {
                self.step_binary(header, layout, byte_order, reals)
            }
            State::OtherBinary { other, ascii_lines: 0, bytes } => {
                let bytes = self.discard(bytes);
                self.state = if bytes == 0 {
                    State::Closing { record: Box::new(UffRecord::Other(other)), blank_allowed: true }
                } else {
                    State::OtherBinary { other, ascii_lines: 0, bytes }
                };
                if bytes == 0 { Step::Again } else { Step::Wait }
            }
            State::SkipCounted { ascii_lines: 0, bytes } => {
                self.state = State::SkipBytes { bytes };
                Step::Again
            }
            State::SkipBytes { bytes } => {
                let bytes = self.discard(bytes);
                self.state = if bytes == 0 { State::Skip } else { State::SkipBytes { bytes } };
                if bytes == 0 { Step::Again } else { Step::Wait }
            }
            state => {
                let line = self.next_line();
                let line = match line {
                    Line::Wait => {
                        self.state = state;
                        return Step::Wait;
                    }
                    Line::TooLong => {
                        // Overlong lines are an error only where this crate reads the fields.
                        match state {
                            State::Skip
                            | State::OtherAscii { .. }
                            | State::OtherBinary { .. }
                            | State::SkipCounted { .. } => {
                                self.state = state;
                                return Step::Again;
                            }
                            State::Between { garbage: true } => {
                                self.state = state;
                                return Step::Again;
                            }
                            State::Between { garbage: false } | State::AfterSkip => {
                                self.state = State::Between { garbage: true };
                                let max_bytes = self.limits.max_line_bytes;
                                return Step::Emit(Err(self.error(Malformed::LineTooLong { max_bytes })));
                            }
                            _ => {
                                let max_bytes = self.limits.max_line_bytes;
                                return self.fail(Malformed::LineTooLong { max_bytes });
                            }
                        }
                    }
                    Line::Text(line) => line,
                };
                self.step_line(state, line)
            }
        }
    }

    /// Discards up to `bytes` buffered bytes; returns how many remain to discard.
    fn discard(&mut self, bytes: u64) -> u64 {
        let n = usize::try_from(bytes).unwrap_or(usize::MAX).min(self.available().len());
        self.consume(n);
        bytes - n as u64
    }

    fn step_line(&mut self, state: State, line: Vec<u8>) -> Step {
        let is_delimiter = trim(&line) == b"-1";
        match state {
            State::Between { garbage } => {
                if is_delimiter {
                    self.open();
                    Step::Again
                } else if trim(&line).is_empty() || garbage {
                    self.state = State::Between { garbage };
                    Step::Again
                } else {
                    self.state = State::Between { garbage: true };
                    let expected = "the delimiter `    -1` that opens a dataset";
                    Step::Emit(Err(self.error(Malformed::Unexpected { expected, found: excerpt(&line) })))
                }
            }
            State::AfterSkip => {
                if is_delimiter {
                    self.open();
                    Step::Again
                } else if parse_int(columns(&line, 0, 6)).is_some() {
                    // The `-1` that ended the skip opened this dataset.
                    self.record += 1;
                    self.dataset_number = None;
                    self.step_identifier(line)
                } else if trim(&line).is_empty() {
                    self.state = State::AfterSkip;
                    Step::Again
                } else {
                    self.state = State::Between { garbage: false };
                    self.step_line(State::Between { garbage: false }, line)
                }
            }
            State::Identifier => {
                if is_delimiter {
                    // The delimiter before was a closing one (of a dataset skipped as garbage) or opened an empty
                    // dataset: this one opens the next.
                    self.state = State::Identifier;
                    return Step::Again;
                }
                self.step_identifier(line)
            }
            State::Skip => {
                self.state = if is_delimiter { State::AfterSkip } else { State::Skip };
                Step::Again
            }
            State::Closing { record, blank_allowed } => {
                if is_delimiter {
                    self.state = State::Between { garbage: false };
                    Step::Emit(Ok(*record))
                } else if blank_allowed && trim(&line).is_empty() {
                    self.state = State::Closing { record, blank_allowed: false };
                    Step::Again
                } else {
                    let expected = "the delimiter `    -1` that closes the dataset";
                    self.fail(Malformed::Unexpected { expected, found: excerpt(&line) })
                }
            }
            State::OtherAscii { other } => {
                if is_delimiter {
                    self.state = State::Between { garbage: false };
                    Step::Emit(Ok(UffRecord::Other(other)))
                } else {
                    self.state = State::OtherAscii { other };
                    Step::Again
                }
            }
            State::SkipCounted { ascii_lines, bytes } => {
                self.state = State::SkipCounted { ascii_lines: ascii_lines.saturating_sub(1), bytes };
                Step::Again
            }
            State::OtherBinary { other, ascii_lines, bytes } => {
                self.state = State::OtherBinary { other, ascii_lines: ascii_lines.saturating_sub(1), bytes };
                Step::Again
            }
            State::Units { record1, factors } => self.step_units(record1, factors, &line, is_delimiter),
            State::Nodes { nodes, pending } => self.step_nodes(nodes, pending, &line, is_delimiter),
            State::FunctionHeader { binary, mut lines } => {
                if is_delimiter {
                    self.state = State::Between { garbage: false };
                    let expected = "the 11 header records of dataset 58";
                    return Step::Emit(Err(self.error(Malformed::Unexpected { expected, found: excerpt(&line) })));
                }
                lines.push(line);
                if lines.len() < 11 {
                    self.state = State::FunctionHeader { binary, lines };
                    return Step::Again;
                }
                self.start_values(binary, &lines)
            }
            State::AsciiValues { header, layout, reals } => self.step_ascii(header, layout, reals, &line, is_delimiter),
            State::BinaryValues { .. } | State::SkipBytes { .. } => {
                // Handled in `step` without reading lines.
                self.state = state;
                Step::Again
            }
        }
    }

    fn open(&mut self) {
        self.record += 1;
        self.dataset_number = None;
        self.state = State::Identifier;
    }

    fn field_error(
        &self,
        field: &'static str,
        line: &[u8],
        start: usize,
        width: usize,
        format: &'static str,
    ) -> Malformed {
        Malformed::Field {
            field,
            first_column: start + 1,
            last_column: start + width,
            format,
            found: excerpt(columns(line, start, width)),
        }
    }

    fn int_field(
        &self,
        field: &'static str,
        line: &[u8],
        start: usize,
        width: usize,
        range: std::ops::RangeInclusive<i64>,
        format: &'static str,
    ) -> Result<i64, Malformed> {
        match parse_int(columns(line, start, width)) {
            Some(value) if range.contains(&value) => Ok(value),
            _ => Err(self.field_error(field, line, start, width, format)),
        }
    }

    fn u32_field(&self, field: &'static str, line: &[u8], start: usize, width: usize) -> Result<u32, Malformed> {
        let value = self.int_field(field, line, start, width, 0..=i64::from(u32::MAX), "an integer 0 to 2^32-1")?;
        u32::try_from(value).map_err(|_| self.field_error(field, line, start, width, "an integer 0 to 2^32-1"))
    }

    fn step_identifier(&mut self, line: Vec<u8>) -> Step {
        let number = match self.u32_field("dataset number", &line, 0, 6) {
            Ok(number) => number,
            Err(kind) => return self.fail(kind),
        };
        self.dataset_number = Some(number);
        let binary = matches!(line.get(6), Some(b'b' | b'B'));
        let binary_header = if binary {
            match self.binary_header(&line) {
                Ok(header) => Some(header),
                Err((kind, Some((ascii_lines, bytes)))) => {
                    // The counts are sound: step over the dataset by them, not by searching binary data.
                    self.state = State::SkipCounted { ascii_lines, bytes };
                    return Step::Emit(Err(self.error(kind)));
                }
                Err((kind, None)) => return self.fail(kind),
            }
        } else {
            None
        };
        let other = OtherDataset { dataset_number: number, binary, line: self.lines.saturating_sub(1) };
        self.state = match (number, binary_header) {
            (58, binary) => State::FunctionHeader { binary, lines: Vec::with_capacity(11) },
            (164 | 2411, Some(_)) => {
                return self.fail(Malformed::Unsupported { what: format!("binary dataset {number}") });
            }
            (164, None) => State::Units { record1: None, factors: Vec::with_capacity(4) },
            (2411, None) => State::Nodes { nodes: Vec::new(), pending: None },
            (_, Some(header)) => State::OtherBinary { other, ascii_lines: header.ascii_lines, bytes: header.bytes },
            (_, None) => State::OtherAscii { other },
        };
        Step::Again
    }

    /// Format (I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12): number, `b`, byte order, floating-point format, ASCII lines
    /// following, bytes following them, four unused fields.
    /// On error: what, and the counts of ASCII lines and bytes to skip when they are sound.
    fn binary_header(&self, line: &[u8]) -> Result<BinaryHeader, (Malformed, Option<(u64, u64)>)> {
        let count = |field, start| {
            self.int_field(field, line, start, 12, 0..=i64::MAX, "I12").map(|v| v as u64).map_err(|kind| (kind, None))
        };
        let ascii_lines = count("number of ASCII lines following", 19)?;
        let bytes = count("number of bytes following the ASCII lines", 31)?;
        let counts = Some((ascii_lines, bytes));
        let byte_order = match self.int_field("byte ordering method", line, 7, 6, 1..=2, "1 (little) or 2 (big endian)")
        {
            Ok(1) => ByteOrder::LittleEndian,
            Ok(_) => ByteOrder::BigEndian,
            Err(kind) => return Err((kind, counts)),
        };
        match self.int_field("floating-point format", line, 13, 6, 0..=99, "I6") {
            Ok(2) => Ok(BinaryHeader { byte_order, ascii_lines, bytes }),
            Ok(other) => {
                let what = format!("floating-point format {other} (only 2, IEEE 754, is read)");
                Err((Malformed::Unsupported { what }, counts))
            }
            Err(kind) => Err((kind, counts)),
        }
    }

    fn step_units(
        &mut self,
        record1: Option<(u32, String, u32)>,
        mut factors: Vec<f64>,
        line: &[u8],
        is_delimiter: bool,
    ) -> Step {
        let Some(record1) = record1 else {
            // UffRecord 1: Format(I10,20A1,I10).
            let parsed = self.u32_field("units code", line, 0, 10).and_then(|code| {
                let mode = self.u32_field("temperature mode", line, 30, 10)?;
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

    fn step_nodes(&mut self, mut nodes: Vec<Node>, pending: Option<[u32; 4]>, line: &[u8], is_delimiter: bool) -> Step {
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

    fn start_values(&mut self, binary: Option<BinaryHeader>, lines: &[Vec<u8>]) -> Step {
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
        let id_lines = [0, 1, 2, 3, 4].map(|i| parse_text(columns(line(i), 0, 80)));
        // UffRecord 6: Format(2(I5,I10),2(1X,10A1,I10,I4)).
        let r6 = line(5);
        let at = |kind| (5, kind);
        let function_type = self.int_field("function type", r6, 0, 5, 0..=99_999, "I5").map_err(at)?;
        let function_id = self.u32_field("function identification number", r6, 5, 10).map_err(at)?;
        let version = self.u32_field("version number", r6, 15, 5).map_err(at)?;
        let load_case = self.u32_field("load case identification number", r6, 20, 10).map_err(at)?;
        let dof = |start: usize, name: &'static str| -> Result<Dof, Malformed> {
            let node = self.u32_field(name, r6, start + 11, 10)?;
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
            return Err(at(Malformed::Unsupported { what: "uneven abscissa spacing (0)".to_owned() }));
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

    fn step_ascii(
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
        // Cases 1 and 3: 6E13.5; cases 5 and 7: 4E20.12.
        let (width, format) = match layout.precision {
            Precision::Single => (13, "E13.5"),
            Precision::Double => (20, "E20.12"),
        };
        let mut start = 0;
        while start < line.len() {
            let field = columns(line, start, width);
            if trim(field).is_empty() {
                // Blank columns end the values of a line; nothing but blanks may follow.
                if !trim(columns(line, start, usize::MAX)).is_empty() {
                    return self.fail(self.field_error("data value", line, start, width, format));
                }
                break;
            }
            let Some(value) = parse_real(field) else {
                return self.fail(self.field_error("data value", line, start, width, format));
            };
            if reals.len() as u64 >= layout.reals {
                return self.fail(Malformed::TooManyValues { expected: layout.reals });
            }
            if !value.is_finite() {
                return self.fail(Malformed::NonFinite { index: reals.len() as u64, value });
            }
            reals.push(value);
            start += width;
        }
        if reals.len() as u64 == layout.reals {
            self.state = State::Closing { record: Box::new(function(*header, layout, reals)), blank_allowed: false };
        } else {
            self.state = State::AsciiValues { header, layout, reals };
        }
        Step::Again
    }

    fn step_binary(
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

fn function(header: FunctionHeader, layout: Layout, reals: Vec<f64>) -> UffRecord {
    let ordinate = if layout.complex {
        Ordinate::Complex(reals.chunks_exact(2).map(|pair| Complex64::new(pair[0], pair[1])).collect())
    } else {
        Ordinate::Real(reals)
    };
    UffRecord::Function(Box::new(Function58 { header, ordinate }))
}
