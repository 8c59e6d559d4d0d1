//! Byte-exact checks of the example exchange documented in the crate's specification. The expected bytes were
//! produced independently of this crate (Python's `struct` and `zlib.crc32`), so they test the wire format itself.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use crate::common;

use common::{decode_all, decode_split, hex};
use metaplate_daq_protocol::{
    ChannelConfig, Configure, DeviceInfo, DeviceMessage, ErrorCode, ErrorReport, Frame, HostCommand, SampleFlags,
    SamplePacket, StopReason, encode,
};

fn host_examples() -> Vec<(u32, HostCommand, &'static str)> {
    vec![
        (0, HostCommand::GetInfo, "4d 44 01 01 00 00 00 00 00 00 00 00 61 65 31 4b"),
        (
            1,
            HostCommand::Configure(Configure {
                sample_rate_hz: 24_000,
                samples_per_packet: 240,
                channels: vec![
                    ChannelConfig { index: 0, range_mv: 10_000 },
                    ChannelConfig { index: 1, range_mv: 10_000 },
                ],
            }),
            "4d 44 01 02 00 00 01 00 00 00 0d 00 c0 5d 00 00 f0 00 02 00 10 27 01 10 27 3b 99 9f fc",
        ),
        (2, HostCommand::Start, "4d 44 01 03 00 00 02 00 00 00 00 00 ec ec 0f 28"),
        (3, HostCommand::Stop, "4d 44 01 04 00 00 03 00 00 00 00 00 80 52 32 87"),
        (4, HostCommand::Reset, "4d 44 01 05 00 00 04 00 00 00 00 00 7b 76 4c 8d"),
        (5, HostCommand::Start, "4d 44 01 03 00 00 05 00 00 00 00 00 54 dc 0a 35"),
    ]
}

fn device_examples() -> Vec<(u32, DeviceMessage, &'static str)> {
    vec![
        (
            0,
            DeviceMessage::Info(DeviceInfo {
                of_seq: 0,
                n_channels: 16,
                max_aggregate_rate_hz: 250_000,
                ranges_mv: vec![10_000, 5_000, 1_000, 200],
                vendor: "metaplate".into(),
                model: "mock-6211".into(),
                serial: "SN0001".into(),
                firmware: "1.0.0".into(),
            }),
            "4d 44 01 81 00 00 00 00 00 00 33 00 00 00 00 00 10 90 d0 03 00 04 10 27 88 13 e8 03 \
             c8 00 09 6d 65 74 61 70 6c 61 74 65 09 6d 6f 63 6b 2d 36 32 31 31 06 53 4e 30 30 30 \
             31 05 31 2e 30 2e 30 06 3f 59 01",
        ),
        (1, DeviceMessage::Ack { of_seq: 1 }, "4d 44 01 82 00 00 01 00 00 00 04 00 01 00 00 00 8f de de 1a"),
        (2, DeviceMessage::Ack { of_seq: 2 }, "4d 44 01 82 00 00 02 00 00 00 04 00 02 00 00 00 62 ca 5c e3"),
        (
            3,
            DeviceMessage::Samples(SamplePacket {
                packet_seq: 0,
                first_sample_index: 0,
                flags: SampleFlags { overrun: false, clipped: true },
                n_channels: 2,
                samples: vec![1000, -1000, 32767, -32768],
            }),
            "4d 44 01 84 00 00 03 00 00 00 18 00 00 00 00 00 00 00 00 00 00 00 00 00 02 02 02 00 \
             e8 03 18 fc ff 7f 00 80 0b 49 82 0b",
        ),
        (
            4,
            DeviceMessage::Stopped { reason: StopReason::HostRequest, next_packet_seq: 1 },
            "4d 44 01 85 00 00 04 00 00 00 05 00 01 01 00 00 00 b1 c5 4e a5",
        ),
        (5, DeviceMessage::Ack { of_seq: 3 }, "4d 44 01 82 00 00 05 00 00 00 04 00 03 00 00 00 7e b6 3c b9"),
        (6, DeviceMessage::Ack { of_seq: 4 }, "4d 44 01 82 00 00 06 00 00 00 04 00 04 00 00 00 c4 35 dc cf"),
        (
            7,
            DeviceMessage::Error(ErrorReport {
                of_seq: Some(5),
                code: ErrorCode::NotConfigured,
                detail: "configure first".into(),
            }),
            "4d 44 01 83 00 00 07 00 00 00 16 00 03 01 05 00 00 00 0f 63 6f 6e 66 69 67 75 72 65 \
             20 66 69 72 73 74 19 08 f8 dc",
        ),
        (
            7,
            DeviceMessage::Error(ErrorReport { of_seq: None, code: ErrorCode::HardwareFault, detail: String::new() }),
            "4d 44 01 83 00 00 07 00 00 00 07 00 06 00 00 00 00 00 00 f0 de 5f 99",
        ),
    ]
}

#[test]
fn host_commands_encode_to_the_documented_bytes() {
    for (seq, command, bytes) in host_examples() {
        assert_eq!(encode(seq, &command).unwrap(), hex(bytes), "{command:?}");
    }
}

#[test]
fn device_messages_encode_to_the_documented_bytes() {
    for (seq, message, bytes) in device_examples() {
        assert_eq!(encode(seq, &message).unwrap(), hex(bytes), "{message:?}");
    }
}

#[test]
fn documented_bytes_decode_to_the_documented_messages() {
    for (seq, command, bytes) in host_examples() {
        assert_eq!(decode_all::<HostCommand>(&hex(bytes)), vec![Ok(Frame { seq, message: command })]);
    }
    for (seq, message, bytes) in device_examples() {
        assert_eq!(decode_all::<DeviceMessage>(&hex(bytes)), vec![Ok(Frame { seq, message })]);
    }
}

#[test]
fn the_device_stream_decodes_identically_at_every_split_point() {
    let stream: Vec<u8> = device_examples().iter().flat_map(|(_, _, b)| hex(b)).collect();
    let expected: Vec<_> = device_examples().into_iter().map(|(seq, message, _)| Ok(Frame { seq, message })).collect();
    // Every single cut, and byte-at-a-time.
    for cut in 0..=stream.len() {
        assert_eq!(decode_split::<DeviceMessage>(&stream, &[cut]), expected, "cut at {cut}");
    }
    let every_byte: Vec<usize> = (0..stream.len()).collect();
    assert_eq!(decode_split::<DeviceMessage>(&stream, &every_byte), expected);
}
