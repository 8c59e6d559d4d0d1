//! The U6 codec's tests: the documented exchange byte for byte, round trips, calibration, the stream assembler,
//! malformed input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod assembler;
mod calibration;
mod examples;
mod malformed;
mod roundtrip;
mod units;

/// The documented example's StreamConfig: AIN0 and AIN1 single-ended at x1, 24 samples per packet, 24 kHz.
pub fn two_channels() -> metaplate_u6_protocol::StreamConfig {
    use metaplate_u6_protocol::{Gain, StreamChannel, StreamClock, StreamConfig};
    let ch = |positive| StreamChannel { positive, gain: Gain::X1, differential: false };
    StreamConfig {
        resolution_index: 0,
        samples_per_packet: 24,
        settling_factor: 0,
        clock: StreamClock::Mhz48,
        divide_by_256: false,
        scan_interval: 2000,
        channels: vec![ch(0), ch(1)],
    }
}

/// Hex text ("0b f8 ...") as bytes.
pub fn hex(text: &str) -> Vec<u8> {
    text.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}
