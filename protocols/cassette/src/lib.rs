//! Cassettes: the record-and-replay file format of metaplate's device sessions.
//!
//! A cassette holds one session with one device, mock or real: the bytes each way, blocks of sample streams, and
//! session events (open, close, timeout, disconnect, reconnect, notes), each stamped with its time since the
//! session start. A replayer walks a [`Cassette`] to reproduce a driver's behaviour without the device. This crate
//! is sans-IO: an [`Encoder`] that appends bytes to a buffer, an incremental [`Decoder`] that takes bytes split
//! anywhere and yields [`Frame`]s, and the in-memory [`Cassette`]. A cassette is read back from disk, so the
//! decoder treats it as hostile input: it never panics; it checks every length against its checksum and its limit
//! ([`MAX_PAYLOAD_LEN`], [`MAX_HEADER_LEN`]) before waiting or allocating for it; once polled dry, its buffer holds
//! less than one record ([`MAX_RECORD_LEN`]); and it reports every defect as a typed [`CassetteError`].
//!
//! # Byte layout (format version 1.0)
//!
//! All integers are little-endian; `f64` and `f32` are IEEE 754 little-endian; CRC-32 is the IEEE polynomial
//! (zlib's `crc32`, `crc32fast`). A file is a header, any number of records, and an end marker.
//!
//! Header (31 to 4096 bytes):
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 8 | magic `MPCASSET` |
//! | 8 | 2 | major format version (1) |
//! | 10 | 2 | minor format version (0) |
//! | 12 | 2 | header length `H`, bytes, CRC included: 31 ≤ `H` ≤ 4096 |
//! | 14 | 1 | device kind: 1 LDV serial, 2 DAQ USB, 3 audio, 4 HID |
//! | 15 | 8 | recording start, ns since the Unix epoch (`u64`, informational) |
//! | 23 | 1 + n | vendor: a length byte `n` ≤ 255, then `n` bytes of UTF-8 |
//! | … | 1 + n | model, the same way |
//! | … | 1 + n | serial number |
//! | … | 1 + n | firmware version |
//! | … | | extension bytes of later minor versions (none in 1.0; skipped) |
//! | `H` − 4 | 4 | CRC-32 of bytes 0 .. `H` − 4 |
//!
//! Record (27 + `P` bytes), at offset `r`:
//!
//! | offset | size | field |
//! |---|---|---|
//! | `r` + 0 | 4 | sync word `89 52 45 43` (`\x89REC`) |
//! | `r` + 4 | 1 | record kind: 1 host-to-device bytes, 2 device-to-host bytes, 3 stream block, 4 event |
//! | `r` + 5 | 2 | endpoint or channel id |
//! | `r` + 7 | 8 | timestamp, ns since the session start (`u64`), never less than the previous record's |
//! | `r` + 15 | 4 | payload length `P` ≤ 16 MiB ([`MAX_PAYLOAD_LEN`]) |
//! | `r` + 19 | 4 | head CRC-32 of bytes `r` .. `r` + 19 (so the length is trusted before the payload is awaited) |
//! | `r` + 23 | `P` | payload |
//! | `r` + 23 + `P` | 4 | record CRC-32 of bytes `r` .. `r` + 23 + `P` |
//!
//! Payloads: bytes records hold the bytes as they were. A stream block holds a 19-byte sub-header, channels `C`
//! (`u16`, ≥ 1), sample format (1 = `i16`, 2 = `f32`), sample rate in Hz (`f64`, finite, > 0) and the index of
//! its first frame (`u64`), then the samples interleaved frame by frame, a whole number of frames, `f32` samples
//! finite. An event holds its kind (1 open, 2 close, 3 timeout, 4 disconnect, 5 reconnect, 6 note) and, for a note
//! only, up to 64 KiB of UTF-8 text ([`MAX_NOTE_LEN`]).
//!
//! End marker (16 bytes): sync word `89 45 4e 44` (`\x89END`), the number of records written (`u64`), and the
//! CRC-32 of its first 12 bytes. A recorder writes it only when the session ends cleanly, so a file without it was
//! cut short.
//!
//! # Example
//!
//! An LDV session (vendor `Om`, model `8330`, no serial or firmware, started 1 s after the epoch) in which the host
//! sent `Q\r` on endpoint 0 at t = 0, then ended cleanly, is these 82 bytes: a 37-byte header, a 29-byte record
//! and the end marker (checked byte for byte in the tests; the CRCs were computed independently with Python's
//! `zlib.crc32`):
//!
//! ```text
//! 0000  4d 50 43 41 53 53 45 54  01 00 00 00 25 00 01 00  MPCASSET....%...
//! 0010  ca 9a 3b 00 00 00 00 02  4f 6d 04 38 33 33 30 00  ..;.....Om.8330.
//! 0020  00 5d 46 43 21 89 52 45  43 01 00 00 00 00 00 00  .]FC!.REC.......
//! 0030  00 00 00 00 02 00 00 00  0a 13 0c b2 51 0d 0b b1  ............Q...
//! 0040  d3 6c 89 45 4e 44 01 00  00 00 00 00 00 00 35 43  .l.END........5C
//! 0050  03 ee                                             ..
//! ```
//!
//! # Versioning
//!
//! Writers write version 1.0. The major version changes when an existing field changes meaning or place; a reader
//! refuses any major version but its own ([`CassetteError::UnsupportedVersion`]). The minor version changes for
//! additions an older reader can step over: header extension bytes (covered by the header CRC and skipped), and
//! new device, record, event or sample-format codes, which an older reader reports as
//! [`CassetteError::UnknownKind`] (a record with an unknown kind is skipped whole, its framing intact).
//!
//! # Errors and recovery
//!
//! A bad header is fatal ([`CassetteError::BadMagic`], [`CassetteError::UnsupportedVersion`], a header
//! checksum, [`CassetteError::UnknownKind`] of device): nothing after it is read. After the header, each defect
//! costs only what it must. A record whose payload checksum fails, whose kind is unknown, whose content is invalid
//! or whose timestamp goes back is reported and skipped, and the next record is read normally (its head checksum
//! vouched for its length). A record whose head checksum fails, or bytes that start neither a record nor the end
//! marker ([`CassetteError::LostSync`]), lose the framing: the decoder reports one error and scans for the next
//! sync word. An over-long record with a sound head is reported as [`CassetteError::Oversize`] and skipped without
//! being buffered. Input that ends before the end marker gives [`CassetteError::Truncated`] after every good
//! record; bytes after the end marker give one [`CassetteError::TrailingGarbage`]; an end marker whose record
//! count differs from the good records read gives [`CassetteError::RecordCount`].
//!
//! # Tests
//!
//! Round trips of every record type through the encoder and a decoder fed at random split points (proptest), the
//! example above and a richer session byte for byte (against bytes built independently with Python's `struct` and
//! `zlib.crc32`), the encoder's refusals at the edges of every limit, and every class of malformed input with its typed
//! error and recovery. The fuzz target `cassette_reader` in `fuzz/` feeds the decoder hostile bytes (it reseals
//! checksums so that it explores past them); run it with `cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run cassette_reader
//! -- -max_total_time=300` (`RUSTC_BOOTSTRAP` lets cargo-fuzz use its sanitizer flags on a stable toolchain).

mod cassette;
mod decode;
mod encode;
mod error;
mod layout;
mod model;
mod payload;

pub use cassette::{Cassette, Recovered};
pub use decode::{Decoder, FormatVersion, Frame};
pub use encode::Encoder;
pub use error::{CassetteError, Invalid, Section};
pub use layout::{
    END_SYNC, FORMAT_MAJOR, FORMAT_MINOR, MAGIC, MAX_HEADER_LEN, MAX_IDENTITY_FIELD_LEN, MAX_NOTE_LEN, MAX_PAYLOAD_LEN,
    MAX_RECORD_LEN, MIN_HEADER_LEN, RECORD_SYNC, TRAILER_LEN,
};
pub use model::{Body, DeviceIdentity, DeviceKind, Event, Header, Record, Samples, StreamBlock};
