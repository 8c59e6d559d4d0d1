//! Byte-exact exchanges of the driver with a scripted device: the frames are the protocol crate's documented
//! example (protocols/daq/src/lib.rs, "Example exchange"), so the driver's OUT bytes are checked against the spec.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{Scripted, hex};
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use metaplate_daq::{DaqDriver, DriverSettings};
use metaplate_daq_protocol::{DeviceMessage, ErrorCode, ErrorReport, SampleFlags, SamplePacket, encode};

const GET_INFO_0: &str = "4d 44 01 01 00 00 00 00 00 00 00 00 61 65 31 4b";
const INFO_0: &str = "4d 44 01 81 00 00 00 00 00 00 33 00 00 00 00 00 10 90 d0 03 00 04 10 27 88 13 e8 03 \
    c8 00 09 6d 65 74 61 70 6c 61 74 65 09 6d 6f 63 6b 2d 36 32 31 31 06 53 4e 30 30 30 \
    31 05 31 2e 30 2e 30 06 3f 59 01";
const CONFIGURE_1: &str = "4d 44 01 02 00 00 01 00 00 00 0d 00 c0 5d 00 00 f0 00 02 00 10 27 01 10 27 3b 99 9f fc";
const ACK_1: &str = "4d 44 01 82 00 00 01 00 00 00 04 00 01 00 00 00 8f de de 1a";
const START_2: &str = "4d 44 01 03 00 00 02 00 00 00 00 00 ec ec 0f 28";
const ACK_2: &str = "4d 44 01 82 00 00 02 00 00 00 04 00 02 00 00 00 62 ca 5c e3";
const SAMPLES_3: &str = "4d 44 01 84 00 00 03 00 00 00 18 00 00 00 00 00 00 00 00 00 00 00 00 00 02 02 02 00 \
    e8 03 18 fc ff 7f 00 80 0b 49 82 0b";
const STOP_3: &str = "4d 44 01 04 00 00 03 00 00 00 00 00 80 52 32 87";
const STOPPED_4: &str = "4d 44 01 85 00 00 04 00 00 00 05 00 01 01 00 00 00 b1 c5 4e a5";
const ACK_5: &str = "4d 44 01 82 00 00 05 00 00 00 04 00 03 00 00 00 7e b6 3c b9";

/// The configuration of the documented example: inputs 0 and 1 at +/-10 V, 24 kHz, 240 samples per packet.
fn example_config() -> DaqConfig {
    DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 1, range_v: 10.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 240,
    }
}

fn open(replies: Vec<Vec<Vec<u8>>>) -> DaqDriver<Scripted> {
    let mut all = vec![vec![hex(INFO_0)]];
    all.extend(replies);
    DaqDriver::open(Scripted::new(all), DriverSettings::default()).unwrap()
}

fn frame(seq: u32, message: DeviceMessage) -> Vec<u8> {
    encode(seq, &message).unwrap()
}

#[test]
fn documented_exchange_is_byte_exact() {
    // Ack of Start and the first packet arrive in one transfer: the packet must be kept for read_block.
    let mut start_reply = hex(ACK_2);
    start_reply.extend(hex(SAMPLES_3));
    let mut daq = open(vec![vec![hex(ACK_1)], vec![start_reply], vec![hex(STOPPED_4), hex(ACK_5)]]);
    let id = daq.identity().clone();
    assert_eq!(
        (id.vendor.as_str(), id.model.as_str(), id.serial.as_str(), id.firmware.as_str()),
        ("metaplate", "mock-6211", "SN0001", "1.0.0")
    );
    daq.configure(&example_config()).unwrap();
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    daq.stop().unwrap();

    let written = &daq.transport().written;
    let expected: Vec<Vec<u8>> = [GET_INFO_0, CONFIGURE_1, START_2, STOP_3].iter().map(|h| hex(h)).collect();
    assert_eq!(written, &expected);

    // Codes 1000, -1000, 32767, -32768 on +/-10 V are code * 10 / 32768 V: exact in f64 (a 16-bit code times a
    // power-of-two scale), so equality is the right check.
    let v = |code: f64| code * 10.0 / 32768.0;
    assert_eq!(block.first_sample_index, 0);
    assert_eq!(block.volts, vec![vec![v(1000.0), v(32767.0)], vec![v(-1000.0), v(-32768.0)]]);
    assert!(block.integrity.clipped, "a pair on the rails is clipping");
    assert!(block.integrity.is_contiguous());
}

#[test]
fn stale_replies_and_garbage_are_skipped() {
    // Before the Ack of Configure (seq 1): junk bytes and an Ack of a command never sent in this attempt.
    let mut transfer = b"junk".to_vec();
    transfer.extend(frame(1, DeviceMessage::Ack { of_seq: 7 }));
    transfer.extend(frame(2, DeviceMessage::Ack { of_seq: 1 }));
    let mut daq = open(vec![vec![transfer]]);
    daq.configure(&example_config()).unwrap();
    assert_eq!(daq.stats().stale_replies, 1);
    assert_eq!(daq.stats().decode_errors, 1, "one run of garbage");
    assert_eq!(daq.stats().retries, 0);
}

#[test]
fn device_refusal_is_a_device_error_with_its_code() {
    let refusal = ErrorReport { of_seq: Some(1), code: ErrorCode::RateOutOfRange, detail: "too fast".into() };
    let mut daq = open(vec![vec![frame(1, DeviceMessage::Error(refusal))]]);
    let err = daq.configure(&example_config()).unwrap_err();
    assert!(matches!(&err, DaqError::Device { code: 2, detail } if detail.contains("too fast")), "{err:?}");
    assert!(daq.wire_config().is_none(), "a refused configuration is not in force");
}

#[test]
fn unanswered_command_times_out_after_the_retry_bound() {
    let mut daq = open(vec![]);
    let err = daq.configure(&example_config()).unwrap_err();
    assert!(matches!(err, DaqError::Timeout { attempts: 3, .. }), "{err:?}");
    // GetInfo, then three Configure attempts with fresh sequence numbers 1, 2, 3.
    let seqs: Vec<u8> = daq.transport().written.iter().map(|f| f[6]).collect();
    assert_eq!(seqs, vec![0, 1, 2, 3]);
    assert_eq!(daq.stats().retries, 2);
}

#[test]
fn lost_start_ack_then_already_running_counts_as_started() {
    let running = ErrorReport { of_seq: Some(3), code: ErrorCode::AlreadyRunning, detail: String::new() };
    let mut daq = open(vec![vec![hex(ACK_1)], vec![], vec![frame(2, DeviceMessage::Error(running))]]);
    daq.configure(&example_config()).unwrap();
    daq.start().unwrap();
    assert_eq!(daq.stats().retries, 1);
}

#[test]
fn lost_and_duplicated_packets_are_reported_not_stitched() {
    let packet = |packet_seq, first_sample_index| {
        frame(
            9,
            DeviceMessage::Samples(SamplePacket {
                packet_seq,
                first_sample_index,
                flags: SampleFlags::default(),
                n_channels: 2,
                samples: vec![1, 2, 3, 4],
            }),
        )
    };
    // Packet 0, a duplicate of it, then packet 2 (packet 1 lost in transit).
    let stream = vec![hex(ACK_2), packet(0, 0), packet(0, 0), packet(2, 4)];
    let mut daq = open(vec![vec![hex(ACK_1)], stream]);
    daq.configure(&DaqConfig { block_len_samples: 2, ..example_config() }).unwrap();
    daq.start().unwrap();
    let first = daq.read_block().unwrap();
    assert_eq!(first.first_sample_index, 0);
    assert!(first.integrity.is_contiguous());
    let second = daq.read_block().unwrap();
    assert_eq!(second.first_sample_index, 4);
    assert_eq!(second.integrity.packets_lost, 1);
    assert_eq!(second.integrity.samples_missing, 2);
    assert!(!second.integrity.is_contiguous());
    // Nothing more arrives: bounded by the retries, then a typed timeout.
    assert!(matches!(daq.read_block(), Err(DaqError::Timeout { .. })));
}

#[test]
fn misuse_is_refused_before_anything_is_sent() {
    let mut daq = open(vec![]);
    assert!(matches!(daq.start(), Err(DaqError::Protocol { .. })));
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })));
    let bad_range = DaqConfig { channels: vec![DaqChannel { input: 0, range_v: 3.0 }], ..example_config() };
    assert!(matches!(daq.configure(&bad_range), Err(DaqError::Config { .. })));
    assert_eq!(daq.transport().written.len(), 1, "only GetInfo was sent");
}
