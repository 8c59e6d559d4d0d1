//! The LabJack U6's low-level USB functions as a sans-IO codec, host and device sides.
//!
//! The U6 (LabJack Corporation; USB vendor id `0x0CD5`, product id `0x0006`) takes commands on bulk OUT endpoint
//! 1, answers them on bulk IN endpoint 2 (`0x82`) and streams on bulk IN endpoint 3 (`0x83`) (the Exodriver's
//! `labjackusb.h`: `U6_PIPE_EP1_OUT`, `U6_PIPE_EP2_IN`, `U6_PIPE_EP3_IN`). Every packet layout here is the one in the
//! U6 User's Guide, section 5.2, "Low-level Function Reference", as LabJackPython's `u6.py` and `LabJackPython.py`
//! build and read them; each module cites its section. This crate does no I/O.
//!
//! - [`checksum`]: Checksum8 and the extended Checksum16 (section 5.1).
//! - [`Command`] / [`Response`]: ConfigU6 (identity: serial number, firmware, product id), StreamConfig (scan list
//!   with gain and differential per channel, resolution index, settling, scan clock and interval), StreamStart,
//!   StreamStop, ReadMem/ReadCal (32-byte memory blocks); `B8 B8` for a command with bad checksums.
//! - [`StreamPacket`] and [`StreamDecoder`]: StreamData packets (PacketNumber, Errorcode, samples, Backlog), decoded
//!   from bytes in any chunking, resynchronising after corruption.
//! - [`Calibration`]: the constants of calibration memory blocks 0-3 (fixed point 32.32) and code <-> volts per
//!   gain.
//! - [`ScanAssembler`]: a stream on the host: missed packets, auto-recovery (errorcodes 59 and 60), errorcodes that
//!   end the stream, volts by scan.
//! - [`StreamConfig::check`]: what the device refuses, with the errorcode it refuses with.
//!
//! # Example exchange
//!
//! Byte-exact (the crate's tests check every line; the expected bytes were made independently with LabJackPython's
//! own `setChecksum8`/`setChecksum16` and the byte lists of `u6.py`): the host reads the identity of U6 serial
//! 360012345 (firmware 1.43), reads calibration block 0, configures AIN0 and AIN1 at +/-10 V, 24 samples per
//! packet, 24 000 scans/s (48 MHz clock, ScanInterval 2000), starts, receives a packet, stops.
//!
//! ```text
//! host   ConfigU6      0b f8 0a 08 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00
//! device ConfigU6      7d f8 10 08 6b 01 00 00 00 2b 01 0f 06 00 02 39 5a 75 15 06 00 01 00 00 00 00 00 00
//!                      00 00 00 00 00 00 00 00 00 04
//!                      (firmware 1.43, bootloader 6.15, hardware 2.00, serial 360012345, product 6, local id 1)
//! host   ReadCal 0     27 f8 01 2d 00 00 00 00   (then blocks 1-3: the calibration constants)
//! host   StreamConfig  0b f8 06 11 fa 00 02 00 18 00 00 08 d0 07 00 00 01 00
//!                      (2 channels, resolution 0, 24 samples per packet, settling auto, 48 MHz, interval 2000,
//!                       AIN0 and AIN1 single-ended at gain x1)
//! device StreamConfig  0b f8 01 11 00 00 00 00
//! host   StreamStart   a8 a8
//! device StreamStart   a9 a9 00 00
//! device StreamData    d6 f9 08 c0 11 03 00 00 00 00 00 00 00 80 10 80 00 00 ff ff 03 00
//!                      (shown with 4 samples per packet: packet 0, codes 0x8000 0x8010 0x0000 0xffff, backlog 3)
//! host   StreamStop    b0 b0
//! device StreamStop    b1 b1 00 00
//! ```
//!
//! # Codec properties and tests
//!
//! Bounded and panic-free on hostile bytes: every function has a fixed length; the stream decoder holds less than
//! one packet after draining. The crate's tests check the example exchange byte for byte, round trips of every
//! packet, the checksums against LabJackPython's docstring example, the calibration's fixed point and conversion,
//! the assembler's loss and auto-recovery accounting, and malformed input. Two fuzz targets in `fuzz/`,
//! `u6_command_decoder` (device side) and `u6_stream_decoder` (host side: responses and stream packets), run with
//! `cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run <target> -- -max_total_time=300`.

pub mod calibration;
pub mod checksum;
mod command;
pub mod config;
mod error;
mod errorcode;
mod scan;
mod stream;

pub use calibration::{Calibration, RangeCalibration};
pub use command::{BAD_CHECKSUM_RESPONSE, Command, DeviceInfo, Response, ResponseBody};
pub use config::{Gain, StreamChannel, StreamClock, StreamConfig, scan_timing};
pub use error::U6Error;
pub use errorcode::Errorcode;
pub use scan::{PacketScans, ScanAssembler, StreamEvent, StreamStats};
pub use stream::{StreamDecoder, StreamPacket, packet_len};

/// LabJack's USB vendor id.
pub const VENDOR_ID: u16 = 0x0cd5;
/// The U6's USB product id (also ConfigU6's ProductID).
pub const PRODUCT_ID: u16 = 0x0006;
/// The bulk OUT endpoint of commands.
pub const ENDPOINT_COMMAND_OUT: u8 = 0x01;
/// The bulk IN endpoint of responses.
pub const ENDPOINT_RESPONSE_IN: u8 = 0x82;
/// The bulk IN endpoint of StreamData.
pub const ENDPOINT_STREAM_IN: u8 = 0x83;
