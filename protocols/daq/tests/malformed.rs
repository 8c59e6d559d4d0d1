//! Every class of malformed input gives its typed error, and the decoder carries on behind it.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use crate::common;

use common::{decode_all, decode_split};
use metaplate_daq_protocol::{
    ChannelConfig, Configure, DaqError, DeviceDecoder, DeviceInfo, DeviceMessage, Direction, ErrorCode, ErrorReport,
    Frame, HEADER_LEN, HostCommand, HostDecoder, MAX_FRAME_LEN, MAX_PAYLOAD_LEN, MAX_SAMPLE_VALUES, SampleFlags,
    SamplePacket, encode, encode_into,
};

fn ack(of_seq: u32) -> DeviceMessage {
    DeviceMessage::Ack { of_seq }
}

fn ack_frame(seq: u32) -> Result<Frame<DeviceMessage>, DaqError> {
    Ok(Frame { seq, message: ack(seq) })
}

/// A frame with arbitrary header fields and payload and a correct CRC, as a buggy or future sender would make.
fn raw_frame(version: u8, msg_type: u8, flags: u16, payload: &[u8]) -> Vec<u8> {
    let mut f = b"MD".to_vec();
    f.push(version);
    f.push(msg_type);
    f.extend_from_slice(&flags.to_le_bytes());
    f.extend_from_slice(&9u32.to_le_bytes());
    f.extend_from_slice(&u16::try_from(payload.len()).unwrap().to_le_bytes());
    f.extend_from_slice(payload);
    let crc = crc32fast::hash(&f);
    f.extend_from_slice(&crc.to_le_bytes());
    f
}

/// Decodes `bad` followed by a good Ack (seq 1), and checks that the Ack still comes out last.
fn errors_before_good_frame(bad: &[u8]) -> Vec<DaqError> {
    let mut bytes = bad.to_vec();
    bytes.extend(encode(1, &ack(1)).unwrap());
    let mut results = decode_all::<DeviceMessage>(&bytes);
    assert_eq!(results.pop(), Some(ack_frame(1)), "the frame behind the bad one was lost");
    results.into_iter().map(|r| r.unwrap_err()).collect()
}

#[test]
fn leading_garbage_is_reported_once_with_its_length() {
    // Includes a lone first magic byte, which must not start a frame.
    let garbage = [0x00, 0x4d, 0x00, 0xff, 0x44, 0x4d];
    assert_eq!(errors_before_good_frame(&garbage), vec![DaqError::Garbage { skipped_bytes: 6 }]);
    // The same, fed a byte at a time: the count does not depend on the chunking.
    let mut bytes = garbage.to_vec();
    bytes.extend(encode(1, &ack(1)).unwrap());
    let cuts: Vec<usize> = (0..bytes.len()).collect();
    assert_eq!(
        decode_split::<DeviceMessage>(&bytes, &cuts),
        vec![Err(DaqError::Garbage { skipped_bytes: 6 }), ack_frame(1)]
    );
}

#[test]
fn a_corrupted_byte_is_a_crc_mismatch_and_the_next_frame_survives() {
    let mut bad = encode(0, &ack(0)).unwrap();
    bad[HEADER_LEN] ^= 0x01; // first payload byte
    let errors = errors_before_good_frame(&bad);
    assert!(matches!(errors[0], DaqError::CrcMismatch { .. }), "{errors:?}");
    // After the mismatch, the rest of the bad frame (all but its first byte) is skipped as garbage.
    assert_eq!(errors[1..], [DaqError::Garbage { skipped_bytes: bad.len() - 1 }]);
}

#[test]
fn a_frame_hidden_inside_an_overlong_corrupted_frame_is_recovered() {
    // The first frame's length field is corrupted to swallow the second frame: the decoder reports the CRC
    // mismatch, then rescans from inside the bad frame and finds the second and third frames.
    let mut bad = encode(0, &ack(0)).unwrap();
    bad[10] = 30;
    let mut bytes = bad.clone();
    bytes.extend(encode(1, &ack(1)).unwrap());
    bytes.extend(encode(2, &ack(2)).unwrap());
    let results = decode_all::<DeviceMessage>(&bytes);
    assert!(matches!(results[0], Err(DaqError::CrcMismatch { .. })), "{results:?}");
    assert_eq!(results[1..], [Err(DaqError::Garbage { skipped_bytes: bad.len() - 1 }), ack_frame(1), ack_frame(2)]);
}

#[test]
fn a_payload_length_above_the_maximum_is_refused_without_waiting_for_it() {
    let mut bad = encode(0, &ack(0)).unwrap();
    bad[10..12].copy_from_slice(&u16::try_from(MAX_PAYLOAD_LEN + 1).unwrap().to_le_bytes());
    // The header alone is enough to refuse it.
    let results = decode_all::<DeviceMessage>(&bad[..HEADER_LEN]);
    assert_eq!(results, vec![Err(DaqError::PayloadTooLong { len: MAX_PAYLOAD_LEN + 1, max: MAX_PAYLOAD_LEN })]);
    let errors = errors_before_good_frame(&bad);
    assert_eq!(errors[0], DaqError::PayloadTooLong { len: MAX_PAYLOAD_LEN + 1, max: MAX_PAYLOAD_LEN });
}

#[test]
fn well_formed_frames_with_bad_headers_are_skipped_whole() {
    let payload = 5u32.to_le_bytes();
    let cases = [
        (raw_frame(2, 0x82, 0, &payload), DaqError::VersionMismatch { received: 2, supported: 1 }),
        (raw_frame(1, 0x82, 0x0100, &payload), DaqError::ReservedFlags { flags: 0x0100 }),
        (raw_frame(1, 0x99, 0, &payload), DaqError::UnknownType { msg_type: 0x99, direction: Direction::DeviceToHost }),
        // A host command arriving at the host: the wrong direction.
        (raw_frame(1, 0x03, 0, &[]), DaqError::UnknownType { msg_type: 0x03, direction: Direction::DeviceToHost }),
    ];
    for (bad, error) in cases {
        // Exactly one error: no garbage, since the whole frame is consumed.
        assert_eq!(errors_before_good_frame(&bad), vec![error]);
    }
    // And a device reply arriving at the device.
    let results = decode_all::<HostCommand>(&encode(0, &ack(0)).unwrap());
    assert_eq!(results, vec![Err(DaqError::UnknownType { msg_type: 0x82, direction: Direction::HostToDevice })]);
}

#[test]
fn payloads_of_the_wrong_length_are_refused() {
    let cases: Vec<(u8, Vec<u8>)> = vec![
        (0x82, vec![1, 0, 0]),                   // Ack: 3 bytes of 4
        (0x82, vec![1, 0, 0, 0, 0]),             // Ack: trailing byte
        (0x85, vec![1, 0, 0, 0]),                // Stopped: 4 bytes of 5
        (0x83, vec![1, 1, 0, 0, 0, 0, 5, b'a']), // Error: detail says 5 bytes, 1 present
        // Samples: 1 channel x 2 samples announced, 1 sample present.
        (0x84, [&[0u8; 12][..], &[0, 1, 2, 0], &[7, 0]].concat()),
        (0x81, vec![0; 8]), // Info cut short
    ];
    for (msg_type, payload) in cases {
        let errors = errors_before_good_frame(&raw_frame(1, msg_type, 0, &payload));
        assert!(matches!(errors[..], [DaqError::BadPayloadLength { .. }]), "type {msg_type:#x}: {errors:?}");
    }
    let mut decoder = DeviceDecoder::new();
    for (msg_type, payload) in [(0x01, vec![0]), (0x02, vec![0xc0, 0x5d, 0, 0, 240, 0, 1, 0, 0x10]), (0x04, vec![1])] {
        decoder.push(&raw_frame(1, msg_type, 0, &payload));
        let results: Vec<_> = decoder.decoded().collect();
        assert!(matches!(results[..], [Err(DaqError::BadPayloadLength { .. })]), "type {msg_type:#x}: {results:?}");
    }
}

#[test]
fn fields_outside_their_range_are_refused() {
    let samples = |flags: u8, n_channels: u8, n_samples: u16| {
        [&[0u8; 12][..], &[flags, n_channels], &n_samples.to_le_bytes(), &[0, 0]].concat()
    };
    let cases: Vec<(u8, Vec<u8>, &str)> = vec![
        (0x83, vec![0, 0, 0, 0, 0, 0, 0], "code"),
        (0x83, vec![9, 0, 0, 0, 0, 0, 0], "code"),
        (0x83, vec![1, 2, 0, 0, 0, 0, 0], "has_of_seq"),
        (0x83, vec![1, 0, 7, 0, 0, 0, 0], "of_seq"),
        (0x85, vec![0, 0, 0, 0, 0], "reason"),
        (0x85, vec![5, 0, 0, 0, 0], "reason"),
        (0x84, samples(0x04, 1, 1), "flags"),
        (0x84, samples(0x00, 0, 1), "n_channels"),
        (0x84, samples(0x00, 1, 0), "n_samples"),
    ];
    for (msg_type, payload, field) in cases {
        let errors = errors_before_good_frame(&raw_frame(1, msg_type, 0, &payload));
        assert!(
            matches!(&errors[..], [DaqError::InvalidField { field: f, .. }] if *f == field),
            "type {msg_type:#x}, {field}: {errors:?}"
        );
    }
}

#[test]
fn text_that_is_not_utf8_is_refused() {
    let payload = [&[1u8, 0, 0, 0, 0, 0][..], &[2, 0xc3, 0x28]].concat(); // Error detail: invalid 2-byte sequence
    assert_eq!(
        errors_before_good_frame(&raw_frame(1, 0x83, 0, &payload)),
        vec![DaqError::InvalidUtf8 { message: "Error", field: "detail" }]
    );
}

#[test]
fn a_truncated_frame_waits_in_a_bounded_buffer_and_clear_discards_it() {
    let whole = encode(0, &ack(0)).unwrap();
    let mut decoder = HostDecoder::new();
    decoder.push(&whole[..whole.len() - 1]);
    assert_eq!(decoder.poll(), None);
    assert_eq!(decoder.buffered_len(), whole.len() - 1);
    decoder.clear();
    assert_eq!(decoder.buffered_len(), 0);
    decoder.push(&encode(1, &ack(1)).unwrap());
    assert_eq!(decoder.poll(), Some(ack_frame(1)));
    assert_eq!(decoder.poll(), None);
}

#[test]
fn a_maximum_frame_decodes_and_a_huge_push_leaves_a_bounded_buffer() {
    let packet = SamplePacket {
        packet_seq: 0,
        first_sample_index: 0,
        flags: SampleFlags::default(),
        n_channels: 1,
        samples: (0..MAX_SAMPLE_VALUES).map(|i| i16::try_from(i % 30_000).unwrap()).collect(),
    };
    let max = encode(0, &DeviceMessage::Samples(packet.clone())).unwrap();
    assert_eq!(max.len(), MAX_FRAME_LEN);
    // 100 maximum frames and a truncated one in one push (1.6 MB): all decode, and what stays buffered is the
    // truncated frame only.
    let mut bytes: Vec<u8> = max.iter().copied().cycle().take(100 * max.len()).collect();
    bytes.extend_from_slice(&max[..MAX_FRAME_LEN - 1]);
    let mut decoder = HostDecoder::new();
    decoder.push(&bytes);
    let n = decoder
        .decoded()
        .inspect(|r| assert_eq!(r.as_ref().unwrap().message, DeviceMessage::Samples(packet.clone())))
        .count();
    assert_eq!(n, 100);
    assert_eq!(decoder.buffered_len(), MAX_FRAME_LEN - 1);
}

#[test]
fn messages_beyond_the_wire_limits_do_not_encode_and_leave_the_output_untouched() {
    let long = "x".repeat(256);
    let info = DeviceInfo {
        of_seq: 0,
        n_channels: 1,
        max_aggregate_rate_hz: 1,
        ranges_mv: vec![10_000],
        vendor: String::new(),
        model: String::new(),
        serial: long.clone(),
        firmware: String::new(),
    };
    let packet = |n_channels: u8, len: usize| {
        DeviceMessage::Samples(SamplePacket {
            packet_seq: 0,
            first_sample_index: 0,
            flags: SampleFlags::default(),
            n_channels,
            samples: vec![0; len],
        })
    };
    let device_cases = [
        DeviceMessage::Info(info.clone()),
        DeviceMessage::Info(DeviceInfo { serial: String::new(), ranges_mv: vec![1; 256], ..info }),
        DeviceMessage::Error(ErrorReport { of_seq: None, code: ErrorCode::HardwareFault, detail: long }),
        packet(0, 0),
        packet(2, 0),
        packet(2, 3),
        packet(1, MAX_SAMPLE_VALUES + 1),
    ];
    for message in device_cases {
        let mut out = vec![0xaa];
        assert!(matches!(encode_into(0, &message, &mut out), Err(DaqError::Unencodable { .. })), "{message:?}");
        assert_eq!(out, vec![0xaa]);
    }
    // The largest packet does encode: the limit is exact.
    assert!(encode(0, &packet(1, MAX_SAMPLE_VALUES)).is_ok());
    let config = Configure {
        sample_rate_hz: 1,
        samples_per_packet: 1,
        channels: vec![ChannelConfig { index: 0, range_mv: 1 }; 256],
    };
    assert!(matches!(encode(0, &HostCommand::Configure(config)), Err(DaqError::Unencodable { .. })));
}
