//! metaplate's DAQ USB bulk streaming protocol, version 1: specification and sans-IO codec (host and device sides).
//!
//! A DAQ that speaks this protocol (and the mock DAQ) exchanges binary frames with the host over one USB bulk OUT
//! endpoint (host to device: commands) and one bulk IN endpoint (device to host: replies, samples, notifications).
//! This crate does no I/O: [`encode`] turns a message into bytes; a [`Decoder`] turns bytes, pushed in any chunking,
//! back into messages ([`HostDecoder`] reads the device's frames, [`DeviceDecoder`] the host's); a
//! [`StreamTracker`] checks a stream of sample packets for losses and converts codes to volts.
//!
//! # Frames
//!
//! All integers are little-endian. A frame is a 12-byte header, a payload of 0 to [`MAX_PAYLOAD_LEN`] (16384)
//! bytes, and a CRC trailer; the largest frame is [`MAX_FRAME_LEN`] (16400) bytes. A USB transfer may carry several
//! frames, or part of one; frames carry no padding and need not align with transfers.
//!
//! | offset | size | field | value |
//! |---|---|---|---|
//! | 0 | 2 | magic | `4d 44` (ASCII `"MD"`), [`MAGIC`] |
//! | 2 | 1 | version | 1, [`PROTOCOL_VERSION`] |
//! | 3 | 1 | message type | see below; `0x01..=0x05` host to device, `0x81..=0x85` device to host |
//! | 4 | 2 | flags | reserved, must be 0 |
//! | 6 | 4 | sequence number | the sender's frame counter (see *Sequencing*) |
//! | 10 | 2 | payload length `n` | 0 to 16384 |
//! | 12 | `n` | payload | per message type |
//! | 12 + `n` | 4 | CRC-32 | CRC-32/ISO-HDLC (zlib's `crc32`, polynomial `0x04c11db7` reflected) of bytes `0 .. 12 + n` |
//!
//! The header layout and the CRC are the same in every protocol version, so a receiver checks the length and the CRC
//! first and only then the version, flags and type. A receiver resynchronises after corruption by scanning for the
//! next magic (see [`Decoder`]).
//!
//! # Messages
//!
//! Payload offsets below are from the start of the payload. Text fields are a u8 byte length followed by that many
//! bytes of UTF-8 (at most [`MAX_TEXT_LEN`], 255). A payload must have exactly the length its fields imply.
//!
//! Host to device ([`HostCommand`]):
//!
//! | type | message | payload |
//! |---|---|---|
//! | `0x01` | `GetInfo` | empty |
//! | `0x02` | `Configure` | 0: `sample_rate_hz` u32 (per channel, Hz); 4: `samples_per_packet` u16 (per channel); 6: channel count `c` u8; 7: `c` times { `index` u8 (analog input), `range_mv` u16 (+/- range, mV) } |
//! | `0x03` | `Start` | empty |
//! | `0x04` | `Stop` | empty |
//! | `0x05` | `Reset` | empty |
//!
//! Device to host ([`DeviceMessage`]):
//!
//! | type | message | payload |
//! |---|---|---|
//! | `0x81` | `Info` | 0: `of_seq` u32; 4: `n_channels` u8 (analog inputs); 5: `max_aggregate_rate_hz` u32; 9: range count `r` u8; 10: `r` times `range_mv` u16; then text `vendor`, `model`, `serial`, `firmware` |
//! | `0x82` | `Ack` | 0: `of_seq` u32 |
//! | `0x83` | `Error` | 0: `code` u8 (below); 1: `has_of_seq` u8 (0 or 1); 2: `of_seq` u32 (0 when `has_of_seq` is 0); 6: text `detail` |
//! | `0x84` | `Samples` | 0: `packet_seq` u32; 4: `first_sample_index` u64; 12: `flags` u8 (bit 0 overrun, bit 1 clipped, others 0); 13: `n_channels` u8 (>= 1); 14: `n_samples` u16 (>= 1); 16: `n_channels * n_samples` i16 codes, interleaved by sample (all channels of sample 0, in configuration order, then sample 1, ...) |
//! | `0x85` | `Stopped` | 0: `reason` u8 (below); 1: `next_packet_seq` u32 |
//!
//! A `Samples` payload is at most 16384 bytes, so a packet carries at most [`MAX_SAMPLE_VALUES`] (8184) codes:
//! `samples_per_packet * channels` must not exceed it. A code `c` on a channel of range `R` V is `c * R / 32768` V;
//! codes -32768 and 32767 are the rails (see [`scale`]).
//!
//! Error codes ([`ErrorCode`]): 1 bad config, 2 rate out of range, 3 not configured, 4 already running, 5 buffer
//! overrun, 6 hardware fault, 7 unsupported command (well-formed, but an unknown type or version), 8 malformed
//! command (failed CRC, or a bad payload). Stop reasons ([`StopReason`]): 1 host request (`Stop`), 2 buffer overrun,
//! 3 hardware fault, 4 reset. Code 0 is invalid in both.
//!
//! # Sequencing
//!
//! - Each side numbers its own frames in the header: 0 for its first frame after power-on, then +1 per frame,
//!   wrapping at 2^32. The two counters are independent.
//! - The device answers every command with exactly one reply whose `of_seq` is the command's sequence number:
//!   `Info` for `GetInfo`, `Ack` for an accepted `Configure`, `Start`, `Stop` or `Reset`, otherwise `Error`.
//!   A command whose frame fails its CRC is answered by `Error` with code 8 and no `of_seq` (its sequence number
//!   cannot be trusted); one with a good CRC but an unknown type or version by code 7, a malformed payload by code 8,
//!   both with `of_seq`. Bytes skipped while looking for a magic are not answered.
//! - `Configure` is accepted only while idle (else code 4) and only if [`Configure::check`] passes against the
//!   device's `Info` (else code 1 or 2). It stays in force until the next `Configure` or `Reset`.
//! - `Start` needs a configuration (else code 3) and an idle device (else code 4). After its `Ack`, the device sends
//!   `Samples` with `packet_seq` 0, 1, 2, ... (+1 per packet sent, wrapping; never skipped) and `first_sample_index`
//!   counting samples per channel from 0 at the first sample. Every packet holds `samples_per_packet` samples except
//!   possibly the last of an acquisition, which may hold fewer.
//! - If the device's buffer overflows, the samples it cannot keep are lost but its sample clock keeps counting: the
//!   next packet it sends has the overrun flag and a `first_sample_index` that skips the lost samples. Its
//!   `packet_seq` does not skip: a `packet_seq` gap always means packets lost after the device sent them. A packet
//!   with a sample on a rail has the clipped flag.
//! - `Stop` while running: the device sends the remaining samples (a possibly short last packet), then `Stopped`
//!   (reason 1), then the `Ack`. `Stop` while idle is acknowledged and does nothing.
//! - `Reset`: the device stops any acquisition (sending `Stopped` with reason 4), forgets the configuration, then
//!   sends the `Ack`.
//! - A fault during an acquisition that ends it (an overrun the device cannot recover from, a hardware fault): the
//!   device sends `Error` without `of_seq` (code 5 or 6), then `Stopped` (reason 2 or 3).
//! - No `Samples` follow a `Stopped` until the next `Start` is acknowledged. `Stopped.next_packet_seq` is the number
//!   of packets sent (modulo 2^32), so the host learns of lost final packets ([`StreamTracker::finish`]).
//!
//! # Example exchange
//!
//! Byte-exact (the crate's tests check every line): the host asks for the device's identity, configures two
//! channels at +/-10 V and 24 kHz with 240 samples per packet (the LDV velocity and the audio loopback), starts,
//! receives a packet (shown with only 2 samples, one pair on the rails so the clipped flag is set), stops, resets
//! (which forgets the configuration) and tries to start again.
//!
//! ```text
//! host   GetInfo   seq 0  4d 44 01 01 00 00 00 00 00 00 00 00 61 65 31 4b
//! device Info      seq 0  4d 44 01 81 00 00 00 00 00 00 33 00 00 00 00 00 10 90 d0 03 00 04 10 27 88 13 e8 03
//!                         c8 00 09 6d 65 74 61 70 6c 61 74 65 09 6d 6f 63 6b 2d 36 32 31 31 06 53 4e 30 30 30
//!                         31 05 31 2e 30 2e 30 06 3f 59 01
//!                         (of_seq 0, 16 inputs, 250 kHz aggregate, ranges 10/5/1/0.2 V,
//!                          "metaplate" "mock-6211" "SN0001" "1.0.0")
//! host   Configure seq 1  4d 44 01 02 00 00 01 00 00 00 0d 00 c0 5d 00 00 f0 00 02 00 10 27 01 10 27 3b 99 9f fc
//! device Ack       seq 1  4d 44 01 82 00 00 01 00 00 00 04 00 01 00 00 00 8f de de 1a
//! host   Start     seq 2  4d 44 01 03 00 00 02 00 00 00 00 00 ec ec 0f 28
//! device Ack       seq 2  4d 44 01 82 00 00 02 00 00 00 04 00 02 00 00 00 62 ca 5c e3
//! device Samples   seq 3  4d 44 01 84 00 00 03 00 00 00 18 00 00 00 00 00 00 00 00 00 00 00 00 00 02 02 02 00
//!                         e8 03 18 fc ff 7f 00 80 0b 49 82 0b
//!                         (packet 0, sample 0, clipped, 2 x 2 codes: 1000 -1000 32767 -32768)
//! host   Stop      seq 3  4d 44 01 04 00 00 03 00 00 00 00 00 80 52 32 87
//! device Stopped   seq 4  4d 44 01 85 00 00 04 00 00 00 05 00 01 01 00 00 00 b1 c5 4e a5
//! device Ack       seq 5  4d 44 01 82 00 00 05 00 00 00 04 00 03 00 00 00 7e b6 3c b9
//! host   Reset     seq 4  4d 44 01 05 00 00 04 00 00 00 00 00 7b 76 4c 8d
//! device Ack       seq 6  4d 44 01 82 00 00 06 00 00 00 04 00 04 00 00 00 c4 35 dc cf
//! host   Start     seq 5  4d 44 01 03 00 00 05 00 00 00 00 00 54 dc 0a 35
//! device Error     seq 7  4d 44 01 83 00 00 07 00 00 00 16 00 03 01 05 00 00 00 0f 63 6f 6e 66 69 67 75 72 65
//!                         20 66 69 72 73 74 19 08 f8 dc
//!                         (not configured, of_seq 5, "configure first")
//! ```
//!
//! # Limits of this codec
//!
//! The sequence numbers in frame headers are carried, not checked: matching replies to commands is the driver's job,
//! and sample-packet losses are the [`StreamTracker`]'s.
//!
//! # Codec properties and tests
//!
//! Like every codec in `protocols/`, this one is sans-IO, incremental (bytes pushed in any chunking decode the same)
//! and bounded: a frame is at most [`MAX_FRAME_LEN`] bytes; a corrupt or oversized one is a typed error, and the
//! decoder resynchronises on the next magic. The crate's tests check round trips of every message through a decoder fed
//! at random split points (proptest), the example exchange above byte for byte (the expected bytes made independently,
//! with Python's `struct` and `zlib.crc32`), [`Configure::check`] at the edges of every limit, the [`StreamTracker`]'s
//! anomaly classes, and every class of malformed input. Two fuzz targets in `fuzz/`, `daq_host_decoder` and
//! `daq_device_decoder`, feed the decoders hostile bytes; run one with `cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run
//! <target> -- -max_total_time=300` (`RUSTC_BOOTSTRAP` lets cargo-fuzz use its sanitizer flags on a stable toolchain).

mod codes;
mod command;
mod decoder;
mod error;
mod frame;
mod reply;
pub mod scale;
pub mod tracker;
mod wire;

pub use codes::{ErrorCode, SampleFlags, StopReason};
pub use command::{
    ChannelConfig, Configure, HostCommand, TYPE_CONFIGURE, TYPE_GET_INFO, TYPE_RESET, TYPE_START, TYPE_STOP,
};
pub use decoder::{Decoder, DeviceDecoder, HostDecoder};
pub use error::DaqError;
pub use frame::{
    CRC_LEN, Direction, Frame, HEADER_LEN, MAGIC, MAX_FRAME_LEN, MAX_PAYLOAD_LEN, Message, PROTOCOL_VERSION, encode,
    encode_into,
};
pub use reply::{
    DeviceInfo, DeviceMessage, ErrorReport, MAX_SAMPLE_VALUES, MAX_TEXT_LEN, SAMPLES_HEADER_LEN, SamplePacket,
    TYPE_ACK, TYPE_ERROR, TYPE_INFO, TYPE_SAMPLES, TYPE_STOPPED,
};
pub use tracker::{DUPLICATE_WINDOW, StreamEvent, StreamStats, StreamTracker, Tracked};
