//! The incremental decoder: bytes in (split anywhere), records out, with bounded lines and records.

use crate::encode::{ByteOrder, Precision};
use crate::error::{DecodeError, Location, Malformed, excerpt};
use crate::fortran::{columns, parse_int, trim};
use crate::model::{FunctionHeader, FunctionType, Node, OtherDataset, UffRecord};

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

mod datasets;

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
    /// Dataset 151: the records read so far (at most 7), each cut to its 80 columns.
    Header {
        records: Vec<Vec<u8>>,
    },
    Units {
        record1: Option<(u32, String, Option<u32>)>,
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
            State::Header { .. } => "the records of dataset 151",
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
    /// The line of the current (or last) dataset's opening delimiter.
    opened_at: u64,
    dataset_number: Option<u32>,
    /// Discarding the rest of an overlong line up to its line end.
    overlong: bool,
    /// Whether the file's line ends are a lone `\r` (learnt at its first line end).
    cr_only: Option<bool>,
    /// The function types (codes) of datasets 58 to decode; others are stepped over after record 6. All if `None`.
    function_types: Option<Vec<u32>>,
    truncation_reported: bool,
    state: State,
    /// The numbers of the ASCII line being read (reused from line to line).
    line_values: Vec<f64>,
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
            opened_at: 0,
            dataset_number: None,
            overlong: false,
            cr_only: None,
            function_types: None,
            truncation_reported: false,
            line_values: Vec::new(),
            state: State::Between { garbage: false },
        }
    }

    /// This decoder, decoding only the datasets 58 and 58b of these function types (record 6, field 1): the others
    /// are stepped over as soon as their function type is read, before any other field is checked, and given as
    /// [`UffRecord::Other`] with their [`OtherDataset::function_type`]. An importer takes this so that a record it does
    /// not use (a coherence, a PSD with an uneven abscissa) cannot fail it.
    pub fn only_functions(mut self, types: &[FunctionType]) -> Self {
        self.function_types = Some(types.iter().map(|t| t.code()).collect());
        self
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

    /// The line (from 1) of the opening delimiter of the dataset being read, or of the last one [`poll`](Self::poll)
    /// returned: record `r` of a dataset 58 (ID line 1 is record 1) is on line `opened_line() + 1 + r`.
    pub fn opened_line(&self) -> u64 {
        self.opened_at
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

    /// The next complete line without its line end: `\n`, `\r\n` or `\r` alone (writers on old Macs and some
    /// DAQ software). Whether a `\r` is followed by a `\n` that belongs to it is learnt at the file's first line end:
    /// in a CR-only file a `\n` after a `\r` can be the first byte of 58b binary data.
    fn next_line(&mut self) -> Line {
        loop {
            let max = self.limits.max_line_bytes;
            let cr_only = self.cr_only;
            let available = self.available();
            match available.iter().position(|&b| b == b'\n' || b == b'\r') {
                Some(end) => {
                    let ending = match (available[end], available.get(end + 1)) {
                        (b'\r', Some(b'\n')) if cr_only != Some(true) => 2,
                        (b'\r', None) if cr_only != Some(true) && !self.eof => {
                            // The `\n` of a CRLF may be in the next push: wait for it, holding at most the line.
                            if end > max {
                                self.consume(end);
                                if !self.overlong {
                                    self.overlong = true;
                                    self.lines += 1;
                                    return Line::TooLong;
                                }
                            }
                            return Line::Wait;
                        }
                        _ => 1,
                    };
                    let lone_cr = available[end] == b'\r' && ending == 1;
                    let overlong = self.overlong || end > max;
                    let line = if overlong { Vec::new() } else { available[..end].to_vec() };
                    if cr_only.is_none() {
                        self.cr_only = Some(lone_cr);
                    }
                    self.consume(end + ending);
                    self.lines += 1;
                    if self.overlong {
                        // The rest of a line already reported.
                        self.overlong = false;
                        continue;
                    }
                    if overlong {
                        return Line::TooLong;
                    }
                    return Line::Text(line);
                }
                None if self.overlong => {
                    let n = available.len();
                    self.consume(n);
                    return Line::Wait;
                }
                None if available.len() > max => {
                    let n = available.len();
                    self.consume(n);
                    self.overlong = true;
                    // Reported as the line it is, although its end has not arrived.
                    self.lines += 1;
                    return Line::TooLong;
                }
                None if self.eof && !available.is_empty() => {
                    let line = available.to_vec();
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
                    self.opened_at = self.lines.saturating_sub(1);
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
                    self.opened_at = self.lines;
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
            State::Header { records } => self.step_header(records, &line, is_delimiter),
            State::Units { record1, factors } => self.step_units(record1, factors, &line, is_delimiter),
            State::Nodes { nodes, pending } => self.step_nodes(nodes, pending, &line, is_delimiter),
            State::FunctionHeader { binary, mut lines } => {
                if is_delimiter {
                    self.state = State::Between { garbage: false };
                    let expected = "the 11 header records of dataset 58";
                    return Step::Emit(Err(self.error(Malformed::Unexpected { expected, found: excerpt(&line) })));
                }
                lines.push(line);
                if lines.len() == 6
                    && let Some(skip) = self.skipped_function(binary, &lines[5])
                {
                    self.state = skip;
                    return Step::Again;
                }
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
        self.opened_at = self.lines;
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
        let other =
            OtherDataset { dataset_number: number, binary, line: self.lines.saturating_sub(1), function_type: None };
        self.state = match (number, binary_header) {
            (58, binary) => State::FunctionHeader { binary, lines: Vec::with_capacity(11) },
            (164 | 2411, Some(_)) => {
                return self.fail(Malformed::Unsupported { what: format!("binary dataset {number}") });
            }
            (151, None) => State::Header { records: Vec::with_capacity(7) },
            (164, None) => State::Units { record1: None, factors: Vec::with_capacity(4) },
            (2411, None) => State::Nodes { nodes: Vec::new(), pending: None },
            (_, Some(header)) => State::OtherBinary { other, ascii_lines: header.ascii_lines, bytes: header.bytes },
            (_, None) => State::OtherAscii { other },
        };
        Step::Again
    }

    /// The state that steps over a dataset 58 whose record 6 (`record6`) gives a function type this decoder does
    /// not decode, or `None` to decode it (or when the type cannot be read: the header's check reports that).
    fn skipped_function(&self, binary: Option<BinaryHeader>, record6: &[u8]) -> Option<State> {
        let wanted = self.function_types.as_ref()?;
        let code = u32::try_from(parse_int(columns(record6, 0, 5))?).ok()?;
        if wanted.contains(&code) {
            return None;
        }
        let line = self.lines.saturating_sub(7);
        let other = OtherDataset { dataset_number: 58, binary: binary.is_some(), line, function_type: Some(code) };
        Some(match binary {
            // Six of the ASCII lines the identifier line counts are read.
            Some(b) => State::OtherBinary { other, ascii_lines: b.ascii_lines.saturating_sub(6), bytes: b.bytes },
            None => State::OtherAscii { other },
        })
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
}
