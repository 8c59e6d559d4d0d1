//! Round trips: every command through the device-side decoder, every response through the host side, stream
//! packets through the decoder at random split points; the configuration check at its limits.

use metaplate_u6_protocol::{
    Command, DeviceInfo, Errorcode, Gain, Response, ResponseBody, StreamChannel, StreamClock, StreamConfig,
    StreamDecoder, StreamPacket, U6Error,
};
use proptest::prelude::*;

fn channel() -> impl Strategy<Value = StreamChannel> {
    (0u8..14, 0u8..4, any::<bool>()).prop_map(|(positive, g, differential)| StreamChannel {
        positive,
        gain: Gain::from_index(g).unwrap(),
        differential,
    })
}

fn config() -> impl Strategy<Value = StreamConfig> {
    (
        any::<u8>(),
        any::<u8>(),
        any::<u8>(),
        any::<bool>(),
        any::<bool>(),
        any::<u16>(),
        prop::collection::vec(channel(), 0..=25),
    )
        .prop_map(
            |(resolution_index, samples_per_packet, settling_factor, fast, divide_by_256, scan_interval, channels)| {
                StreamConfig {
                    resolution_index,
                    samples_per_packet,
                    settling_factor,
                    clock: if fast { StreamClock::Mhz48 } else { StreamClock::Mhz4 },
                    divide_by_256,
                    scan_interval,
                    channels,
                }
            },
        )
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        Just(Command::ConfigU6),
        Just(Command::StreamStart),
        Just(Command::StreamStop),
        (any::<bool>(), any::<u8>()).prop_map(|(calibration, block)| Command::ReadMem { calibration, block }),
        config().prop_map(Command::StreamConfig),
    ]
}

proptest! {
    #[test]
    fn commands_round_trip(c in command()) {
        let bytes = c.encode().unwrap();
        prop_assert_eq!(Command::decode(&bytes).unwrap(), c);
    }

    #[test]
    fn responses_round_trip(c in command(), e in any::<u8>(), data in any::<[u8; 32]>(), serial in any::<u32>(), v in any::<[u8; 8]>()) {
        let body = match &c {
            Command::ConfigU6 => ResponseBody::ConfigU6(DeviceInfo {
                firmware: (v[0], v[1]), bootloader: (v[2], v[3]), hardware: (v[4], v[5]), serial,
                product_id: 6, local_id: v[6], version_info: v[7],
            }),
            Command::StreamConfig(_) => ResponseBody::StreamConfig,
            Command::StreamStart => ResponseBody::StreamStart,
            Command::StreamStop => ResponseBody::StreamStop,
            Command::ReadMem { calibration, .. } => ResponseBody::ReadMem { calibration: *calibration, data },
        };
        let r = Response { errorcode: Errorcode(e), body };
        prop_assert_eq!(Response::decode_for(&c, &r.encode()).unwrap(), r);
    }

    #[test]
    fn stream_packets_decode_in_any_chunking(
        spp in 1u8..=25,
        headers in prop::collection::vec((any::<u32>(), any::<u8>(), any::<u8>()), 1..6),
        seed in any::<u16>(),
        cuts in prop::collection::vec(any::<usize>(), 0..8),
    ) {
        let packets: Vec<StreamPacket> = headers.iter().enumerate().map(|(i, &(timestamp, errorcode, backlog))| StreamPacket {
            timestamp,
            packet_number: i as u8,
            errorcode: Errorcode(errorcode),
            samples: (0..spp).map(|k| seed.wrapping_mul(u16::from(k) + 1)).collect(),
            backlog,
        }).collect();
        let bytes: Vec<u8> = packets.iter().flat_map(|p| p.encode().unwrap()).collect();
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c % (bytes.len() + 1)).collect();
        cuts.push(bytes.len());
        cuts.sort_unstable();
        let mut d = StreamDecoder::new(spp);
        let mut got = Vec::new();
        let mut start = 0;
        for cut in cuts {
            d.push(&bytes[start..cut]);
            start = cut;
            while let Some(p) = d.poll() {
                got.push(p.unwrap());
            }
            prop_assert!(d.buffered_len() < d.packet_len());
        }
        prop_assert_eq!(got, packets);
    }
}

proptest! {
    #[test]
    fn hostile_stream_bytes_decode_the_same_in_any_chunking(
        spp in 1u8..=25,
        bytes in prop::collection::vec(prop_oneof![any::<u8>(), Just(0xf9u8), Just(0xc0u8)], 0..400),
        cuts in prop::collection::vec(any::<usize>(), 0..8),
    ) {
        let mut whole = StreamDecoder::new(spp);
        whole.push(&bytes);
        let at_once: Vec<_> = std::iter::from_fn(|| whole.poll()).collect();
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c % (bytes.len() + 1)).collect();
        cuts.push(bytes.len());
        cuts.sort_unstable();
        let mut d = StreamDecoder::new(spp);
        let mut chunked = Vec::new();
        let mut start = 0;
        for cut in cuts {
            d.push(&bytes[start..cut]);
            start = cut;
            chunked.extend(std::iter::from_fn(|| d.poll()));
            prop_assert!(d.buffered_len() < d.packet_len());
        }
        prop_assert_eq!(chunked, at_once);
    }
}

fn valid() -> StreamConfig {
    crate::two_channels()
}

fn refused(c: &StreamConfig) -> Errorcode {
    match c.check() {
        Err(U6Error::ConfigRejected { errorcode, .. }) => errorcode,
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn the_configuration_check_at_its_limits() {
    assert_eq!(valid().check(), Ok(()));
    let mut c = valid();
    c.channels.clear();
    assert_eq!(refused(&c), Errorcode::STREAM_CONFIG_INVALID);
    c.channels = vec![StreamChannel { positive: 13, gain: Gain::X1, differential: false }];
    assert_eq!(c.check(), Ok(()));
    c.channels[0].positive = 14;
    assert_eq!(refused(&c), Errorcode::STREAM_CONFIG_INVALID);
    c.channels[0] = StreamChannel { positive: 1, gain: Gain::X10, differential: true };
    assert_eq!(refused(&c), Errorcode::STREAM_CONFIG_INVALID);
    c.channels[0].positive = 12;
    assert_eq!(c.check(), Ok(()));
    let mut c = valid();
    c.resolution_index = 9;
    assert_eq!(refused(&c), Errorcode::STREAM_CONFIG_INVALID);
    let mut c = valid();
    c.samples_per_packet = 26;
    assert_eq!(refused(&c), Errorcode::STREAM_SAMPLE_NUM_INVALID);
    c.samples_per_packet = 0;
    assert_eq!(refused(&c), Errorcode::STREAM_SAMPLE_NUM_INVALID);
    // 2 channels x 25 000 scans/s = 50 kS/s: the limit; 48 MHz / 1919 is just over it.
    let mut c = valid();
    c.scan_interval = 1920;
    assert_eq!(c.check(), Ok(()));
    c.scan_interval = 1919;
    assert_eq!(refused(&c), Errorcode::STREAM_SCAN_RATE_INVALID);
    c.scan_interval = 0;
    assert_eq!(refused(&c), Errorcode::STREAM_SCAN_RATE_INVALID);
}
