//! Property tests: every message round-trips through encode and a decoder fed at random split points, and the
//! decoder's results do not depend on how its input is split, even for corrupted input.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use crate::common;

use common::{decode_all, decode_split};
use metaplate_daq_protocol::{
    ChannelConfig, Configure, DeviceInfo, DeviceMessage, ErrorCode, ErrorReport, Frame, HostCommand, MAX_SAMPLE_VALUES,
    SampleFlags, SamplePacket, StopReason, encode,
};
use proptest::prelude::*;

fn text() -> impl Strategy<Value = String> {
    // Up to 60 chars of any Unicode: at most 240 bytes, within the 255-byte limit.
    "\\PC{0,60}"
}

fn configure() -> impl Strategy<Value = Configure> {
    (any::<u32>(), any::<u16>(), prop::collection::vec((any::<u8>(), any::<u16>()), 0..=255)).prop_map(
        |(sample_rate_hz, samples_per_packet, chans)| Configure {
            sample_rate_hz,
            samples_per_packet,
            channels: chans.into_iter().map(|(index, range_mv)| ChannelConfig { index, range_mv }).collect(),
        },
    )
}

fn host_command() -> impl Strategy<Value = HostCommand> {
    prop_oneof![
        Just(HostCommand::GetInfo),
        configure().prop_map(HostCommand::Configure),
        Just(HostCommand::Start),
        Just(HostCommand::Stop),
        Just(HostCommand::Reset),
    ]
}

fn sample_packet() -> impl Strategy<Value = SamplePacket> {
    (1u8..=255)
        .prop_flat_map(|n_channels| {
            let max_samples = MAX_SAMPLE_VALUES / usize::from(n_channels);
            // Mostly small packets, sometimes up to the largest that fits a frame.
            let n_samples = prop_oneof![3 => 1..=max_samples.min(8), 1 => 1..=max_samples];
            (Just(n_channels), n_samples)
        })
        .prop_flat_map(|(n_channels, n_samples)| {
            (
                any::<u32>(),
                any::<u64>(),
                any::<(bool, bool)>(),
                prop::collection::vec(any::<i16>(), usize::from(n_channels) * n_samples),
            )
                .prop_map(move |(packet_seq, first_sample_index, (overrun, clipped), samples)| {
                    SamplePacket {
                        packet_seq,
                        first_sample_index,
                        flags: SampleFlags { overrun, clipped },
                        n_channels,
                        samples,
                    }
                })
        })
}

fn device_message() -> impl Strategy<Value = DeviceMessage> {
    let info = (
        any::<u32>(),
        any::<u8>(),
        any::<u32>(),
        prop::collection::vec(any::<u16>(), 0..=255),
        (text(), text(), text(), text()),
    )
        .prop_map(|(of_seq, n_channels, max_aggregate_rate_hz, ranges_mv, (vendor, model, serial, firmware))| {
            DeviceInfo { of_seq, n_channels, max_aggregate_rate_hz, ranges_mv, vendor, model, serial, firmware }
        });
    let error = (prop::option::of(any::<u32>()), prop::sample::select(ErrorCode::ALL.to_vec()), text())
        .prop_map(|(of_seq, code, detail)| ErrorReport { of_seq, code, detail });
    prop_oneof![
        info.prop_map(DeviceMessage::Info),
        any::<u32>().prop_map(|of_seq| DeviceMessage::Ack { of_seq }),
        error.prop_map(DeviceMessage::Error),
        sample_packet().prop_map(DeviceMessage::Samples),
        (prop::sample::select(StopReason::ALL.to_vec()), any::<u32>())
            .prop_map(|(reason, next_packet_seq)| DeviceMessage::Stopped { reason, next_packet_seq }),
    ]
}

fn encode_all<M: metaplate_daq_protocol::Message>(frames: &[(u32, M)]) -> Vec<u8> {
    frames.iter().flat_map(|(seq, m)| encode(*seq, m).unwrap()).collect()
}

fn expected<M: Clone>(frames: &[(u32, M)]) -> Vec<Result<Frame<M>, metaplate_daq_protocol::DaqError>> {
    frames.iter().map(|(seq, message)| Ok(Frame { seq: *seq, message: message.clone() })).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn host_commands_round_trip_at_random_splits(
        frames in prop::collection::vec((any::<u32>(), host_command()), 1..6),
        cuts in prop::collection::vec(any::<prop::sample::Index>(), 0..8),
    ) {
        let bytes = encode_all(&frames);
        let cuts: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
        prop_assert_eq!(decode_split::<HostCommand>(&bytes, &cuts), expected(&frames));
    }

    #[test]
    fn device_messages_round_trip_at_random_splits(
        frames in prop::collection::vec((any::<u32>(), device_message()), 1..6),
        cuts in prop::collection::vec(any::<prop::sample::Index>(), 0..8),
    ) {
        let bytes = encode_all(&frames);
        let cuts: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
        prop_assert_eq!(decode_split::<DeviceMessage>(&bytes, &cuts), expected(&frames));
    }

    /// Corrupt a valid stream (flip, insert or delete bytes): whatever the decoder makes of it, it makes the same of
    /// it however the input is split, and every frame it still decodes is one that was sent.
    #[test]
    fn corrupted_streams_decode_the_same_at_any_split(
        frames in prop::collection::vec((any::<u32>(), device_message()), 1..6),
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..3, any::<u8>()), 1..6),
        cuts in prop::collection::vec(any::<prop::sample::Index>(), 0..8),
    ) {
        let mut bytes = encode_all(&frames);
        for (at, kind, value) in edits {
            let i = at.index(bytes.len());
            match kind {
                0 => bytes[i] ^= value | 1,
                1 => bytes.insert(i, value),
                _ => { bytes.remove(i); }
            }
            if bytes.is_empty() { break; }
        }
        let whole = decode_all::<DeviceMessage>(&bytes);
        let cuts: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
        prop_assert_eq!(&decode_split::<DeviceMessage>(&bytes, &cuts), &whole);
        let sent = expected(&frames);
        for frame in whole.iter().filter(|r| r.is_ok()) {
            prop_assert!(sent.contains(frame), "decoded a frame that was never sent: {:?}", frame);
        }
    }
}
