//! Universal files (UFF), sans-IO: the datasets a modal-analysis tool needs to place and read metaplate's
//! responses, and to bring a lab's measurements in.
//!
//! A universal file is a sequence of datasets, each opened and closed by a line `    -1` (I6) and identified by
//! its number on the line after the opening one. This crate reads and writes:
//!
//! - **58** (function at nodal DOF), ASCII, and **58b**, its binary variant: the 11 header records (ID lines 1 to
//!   5; DOF identification, record 6; data form, record 7; abscissa, ordinate, denominator and z-axis data
//!   characteristics, records 8 to 11), then the values. Supported: any function type (metaplate writes 1, time
//!   response, and 4, frequency response function); real and complex ordinates; single and double precision;
//!   **even abscissa only** (uneven spacing is reported as [`Malformed::Unsupported`]); 58b in either byte order
//!   with IEEE 754 values (the identifier line `    58b     1     2          11        NNNN     0     0 ...`:
//!   byte order 1 little or 2 big endian, floating-point format 2, 11 ASCII lines, `NNNN` bytes of data).
//! - **164** (units): units code, description, temperature mode and the four factors to SI.
//! - **2411** (nodes, double precision): label, coordinate systems, colour and x, y, z.
//! - **151** (header): the model's and the file's names, descriptions and programs, as text ([`Header151`]: read
//!   line by line whatever a writer put there, never refused for its content).
//!
//! Other datasets are stepped over ([`UffRecord::Other`]), ASCII to their closing delimiter, binary by the byte count
//! of their identifier line.
//!
//! [`sample_rate_from_step`] is the one rule that turns a 6-digit abscissa step back into a sample rate (the whole
//! hertz within 10⁻⁵, see below). `metaplate-interchange` is this crate's user: the binary's `export` and `import`
//! go through it.
//!
//! # Layout and precision
//!
//! The [`UffEncoder`] writes what pyuff 2.5.8 writes, column for column (checked against its files in the tests),
//! which follows the specification's Fortran formats with C's `%e` in place of Fortran's `E`:
//!
//! | values | format | significant digits | relative error of a round trip |
//! |---|---|---|---|
//! | 58 ASCII single (cases 1, 3) | `6E13.5`, written `%13.5e` | 6 | ≤ 5 × 10⁻⁶ |
//! | 58 ASCII double (cases 5, 7) | `4E20.12`, written `%20.11e` | 12 | ≤ 5 × 10⁻¹² |
//! | 58b single | `f32` | 24 bits | ≤ 2⁻²⁴ ≈ 6 × 10⁻⁸ |
//! | 58b double | `f64` | 53 bits | exact |
//! | record 7: abscissa start and step, z value | `3E13.5`, written `%13.5e` | 6 | ≤ 5 × 10⁻⁶ |
//! | 164 factors | `3D25.17`, written `%25.16e` with `D` | 17 | exact |
//! | 2411 coordinates | `1P3D25.16`, written `%25.16e` | 17 | exact |
//!
//! The abscissa step carries 6 significant digits in every variant (record 7 is text): a 48 kHz time step
//! (20.8333… µs) is written `2.08333e-05` and reads back as 48000.08 Hz, so an importer rounds the sample rate
//! it derives. Values in single precision must lie within `f32` range. NaN and infinities are refused by the
//! encoder ([`EncodeError::Value`]) and reported by the decoder ([`Malformed::NonFinite`]): a decoded record holds
//! only finite numbers.
//!
//! Text fields are printable Latin-1, one character a byte (the encoder refuses anything else, which would shift
//! the columns; the decoder shows control bytes as `?`), trimmed on reading, with "NONE" for blank (the
//! specification's word for unused).
//!
//! # What other writers write
//!
//! The decoder reads these departures, each seen in public files: dataset 164 without its temperature mode (LMS
//! Test.Lab); zeros past the count record 7 announces on the line that completes it; reference (and response) nodes
//! 0 or negative; CR, LF or CRLF line ends (which, learnt at the first line end, so that a CR-only 58b's data may
//! begin with a line feed byte); numbers separated by blanks, of any width, or fixed-width with none between them;
//! Latin-1 text. [`UffDecoder::only_functions`] steps over datasets 58 of other function types (coherence, PSD) as
//! soon as record 6 is read, unchecked, so that an importer is not failed by a record it does not use.
//!
//! # 58b byte counts
//!
//! The 58b description puts the binary data right after the line end of record 11 and the closing `    -1`
//! right after the data, with no line end between. The encoder writes exactly that, with the true byte count
//! (values × 4 or 8, a complex value counting two). The decoder reads the values record 7 announces and checks
//! the identifier line's count against them ([`Malformed::ByteCount`]), with two known departures accepted: a line
//! end between the data and the closing delimiter (written by some commercial software; pyuff's `fix_58b` is for
//! these files), and a complex dataset stating half its bytes (pyuff 2.5.8 writes `num_pts × 8`).
//!
//! # Streaming
//!
//! The encoder appends one record to a caller's buffer ([`UffEncoder::encode_function`] takes a borrowed
//! [`OrdinateRef`], so a response goes from a dataset's buffer to the file without a copy into a [`Function58`]);
//! an exporter writes the buffer out and clears it after each record. The [`UffDecoder`] takes bytes split anywhere,
//! holds at most one line beyond the last push plus the record being read, grows a record only with the values it
//! has read, and bounds lines, values and nodes ([`Limits`]). Every [`DecodeError`] names the record (the dataset's
//! ordinal in the file), the dataset number and the line, and what was expected there.
//!
//! # Example
//!
//! An exporter appends each response to a buffer and writes it out; a reader pushes what it reads:
//!
//! ```
//! use metaplate_uff::{
//!     ByteOrder, Format, FunctionHeader, FunctionType, OrdinateRef, Precision, UffDecoder, UffEncoder, UffRecord,
//!     Units164,
//! };
//!
//! let encoder = UffEncoder::new(Format::Binary { byte_order: ByteOrder::LittleEndian }, Precision::Single);
//! let mut file = Vec::new();
//! encoder.encode(&UffRecord::Units(Units164::si()), &mut file)?;
//! // The impulse response of grid point 7 to actuator 1001, sampled at 48 kHz (m/s per N).
//! let ir = [0.0, 1.5e-3, -2.25e-4];
//! let header = FunctionHeader::velocity_over_force(FunctionType::TimeResponse, 7, 1001, 0.0, 1.0 / 48e3, "point 7");
//! encoder.encode_function(&header, OrdinateRef::Real(&ir), &mut file)?;
//!
//! let mut decoder = UffDecoder::new();
//! for piece in file.chunks(100) {
//!     decoder.push(piece);
//! }
//! decoder.finish();
//! let records: Vec<UffRecord> = decoder.records().collect::<Result<_, _>>()?;
//! let UffRecord::Function(function) = &records[1] else { unreachable!() };
//! assert_eq!(function.header.response.node, 7);
//! assert_eq!(function.ordinate.len(), 3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Tests
//!
//! Round trips of every combination (ASCII 58 and binary 58b in both byte orders, single and double precision, real and
//! complex ordinates, datasets 164 and 2411) through the encoder and a decoder fed at any split (proptest); files pyuff
//! 2.5.8 wrote decode here, and the same records encoded here match them byte for byte; pyuff reads what this crate
//! writes, value by value (the `#[ignore]`d module `pyuff_reads`, which needs a Python with pyuff and which
//! `scripts/test.sh` runs); every malformed input gives a typed error naming the record and line. The fuzz target
//! `uff_reader` in `fuzz/` feeds the decoder hostile bytes; run it with `cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run
//! uff_reader -- -max_total_time=300` (`RUSTC_BOOTSTRAP` lets cargo-fuzz use its sanitizer flags on a stable
//! toolchain).

mod decode;
mod encode;
mod error;
mod fortran;
mod model;

pub use decode::{Limits, UffDecoder};
pub use encode::{ByteOrder, Format, Precision, UffEncoder};
pub use error::{DecodeError, EncodeError, Location, Malformed};
pub use fortran::printable;
pub use model::{
    AxisCharacteristics, Dof, Function58, FunctionHeader, FunctionType, Header151, Node, Nodes2411, Ordinate,
    OrdinateRef, OtherDataset, UffRecord, Units164,
};
pub use num_complex::Complex64;

/// The sample rate, Hz, of an even abscissa of step `step_s` seconds as a universal file writes it (6 significant
/// digits, a relative error of at most 5 × 10⁻⁶): `1 / step_s` rounded to the nearest whole hertz when that lies
/// within 10⁻⁵ (twice the writing's error) of it, else `1 / step_s` as read. Every rate a DAQ or an audio
/// interface runs at is a whole number of hertz, so 24 kHz written `4.16667e-05` reads back as 24000 Hz exactly
/// and 48 kHz (`2.08333e-05`, 48000.08 Hz) as 48000. `None` for a step that is not finite and positive.
pub fn sample_rate_from_step(step_s: f64) -> Option<f64> {
    if !(step_s.is_finite() && step_s > 0.0) {
        return None;
    }
    let raw_hz = 1.0 / step_s;
    let whole_hz = raw_hz.round();
    let rate = if whole_hz >= 1.0 && (raw_hz - whole_hz).abs() <= 1e-5 * raw_hz { whole_hz } else { raw_hz };
    rate.is_finite().then_some(rate)
}

#[cfg(test)]
mod rate_tests {
    use super::sample_rate_from_step;

    #[test]
    fn six_digit_steps_give_whole_rates_back() {
        for rate in [8000.0, 24_000.0, 25_600.0, 44_100.0, 48_000.0, 51_200.0, 96_000.0, 192_000.0] {
            let written: f64 = format!("{:.5e}", 1.0 / rate).parse().unwrap_or(f64::NAN);
            assert_eq!(sample_rate_from_step(written), Some(rate), "{rate}");
        }
        assert_eq!(sample_rate_from_step(4.16667e-05), Some(24_000.0));
        // Not near a whole number of hertz: kept as read.
        assert_eq!(sample_rate_from_step(0.4), Some(2.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(sample_rate_from_step(bad), None);
        }
    }
}
