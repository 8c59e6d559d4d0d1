//! Shared test fixtures: hex packets, a scripted transport, sine sources and a mock-backed driver.
#![allow(dead_code)]

use std::collections::VecDeque;
use std::f64::consts::PI;
use std::time::Duration;

use metaplate_core::daq::{DaqChannel, DaqConfig};
use metaplate_daq::{BulkTransport, DriverSettings, TransportError, U6Driver};
use metaplate_mock_daq::{FaultSchedule, MockTransport, MockU6, u6_info};
use metaplate_u6_protocol::Calibration;

/// Bytes from space-separated hex, as the protocol crate documents its example packets.
pub fn hex(text: &str) -> Vec<u8> {
    text.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

/// A transport that answers the n-th OUT transfer with the n-th list of response transfers, serves `stream`
/// transfers in order, and records what was written.
#[derive(Debug, Default)]
pub struct Scripted {
    pub replies: VecDeque<Vec<Vec<u8>>>,
    pub pending: VecDeque<Vec<u8>>,
    pub stream: VecDeque<Vec<u8>>,
    pub written: Vec<Vec<u8>>,
}

impl Scripted {
    pub fn new(replies: Vec<Vec<Vec<u8>>>, stream: Vec<Vec<u8>>) -> Self {
        Self { replies: replies.into(), stream: stream.into(), ..Self::default() }
    }
}

impl BulkTransport for Scripted {
    fn write(&mut self, bytes: &[u8], _timeout: Duration) -> Result<(), TransportError> {
        self.written.push(bytes.to_vec());
        if let Some(r) = self.replies.pop_front() {
            self.pending.extend(r);
        }
        Ok(())
    }
    fn read(&mut self, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.pending.pop_front().ok_or(TransportError::Timeout)
    }
    fn read_stream(&mut self, _max_len: usize, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        // Stream data flows once StreamStart was sent (the drains of opening find the endpoint quiet).
        if !self.written.iter().any(|w| w == &[0xa8, 0xa8]) {
            return Err(TransportError::Timeout);
        }
        self.stream.pop_front().ok_or(TransportError::Timeout)
    }
    fn reopen(&mut self) -> Result<(), TransportError> {
        Ok(())
    }
}

/// Sine amplitude (V) and frequency (Hz) per analog input, as used by the acquisition tests.
pub fn sine_of(input: u8) -> (f64, f64) {
    match input {
        0 => (7.0, 440.0),
        3 => (0.8, 1000.0),
        _ => (0.0, 0.0),
    }
}

/// The analytic input voltage at scan `index`, V.
pub fn sine_at(input: u8, index: u64, rate_hz: f64) -> f64 {
    let (a, f) = sine_of(input);
    a * (2.0 * PI * f * index as f64 / rate_hz).sin()
}

/// The serial number of the test U6.
pub const SERIAL: u32 = 360_012_345;

/// A mock U6 with the nominal calibration (LabJackPython's defaults) whose inputs carry [`sine_of`].
pub fn sine_device() -> MockU6 {
    let source = |input: u8, first: u64, rate_hz: f64, out: &mut [f64]| {
        for (i, v) in out.iter_mut().enumerate() {
            *v = sine_at(input, first + i as u64, rate_hz);
        }
    };
    MockU6::new(u6_info(SERIAL), Calibration::nominal(), Box::new(source))
}

/// Two channels: input 0 at +/-10 V, input 3 at +/-1 V; 24 kHz; 240-scan blocks.
pub fn two_channels() -> DaqConfig {
    DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 3, range_v: 1.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 240,
    }
}

/// Settings for the mock: it never blocks, so the timeouts only matter to a real transport.
pub fn settings() -> DriverSettings {
    DriverSettings { retries: 2, max_drain_transfers: 8, max_transfers_per_attempt: 64, ..DriverSettings::default() }
}

/// A driver opened on a mock U6 with sine inputs and `faults`.
pub fn mock_driver(faults: FaultSchedule) -> U6Driver<MockTransport> {
    U6Driver::open(MockTransport::new(sine_device(), faults), settings()).unwrap()
}
