//! Host side of the LabJack U6 codec: arbitrary device bytes (bulk IN) as the response to each command
//! (`Response::decode_for`), and in arbitrary chunks into a `StreamDecoder` whose packets go through a
//! `ScanAssembler`. Input layout: `common/chunks.rs`; byte 0 of the payload picks SamplesPerPacket (1-25).
//! Checks: no panic; after draining, less than one packet buffered; chunking does not change what is decoded
//! (errors included); every decoded packet re-encodes to its bytes' decoding.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_u6_protocol::{
    Calibration, Command, Gain, Response, ScanAssembler, StreamChannel, StreamClock, StreamConfig, StreamDecoder,
};

fuzz_target!(|data: &[u8]| {
    for command in
        [Command::ConfigU6, Command::StreamStart, Command::StreamStop, Command::ReadMem { calibration: true, block: 0 }]
    {
        let _ = Response::decode_for(&command, data);
    }
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let Some((&first, payload)) = payload.split_first() else { return };
    let spp = first % 25 + 1;
    let cuts: Vec<usize> = cuts.iter().map(|&c| c.saturating_sub(1).min(payload.len())).collect();
    let chunked = chunks::feed(
        &mut StreamDecoder::new(spp),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| std::iter::from_fn(|| d.poll()).collect(),
        |d| d.buffered_len() < d.packet_len(),
    );
    let mut whole = StreamDecoder::new(spp);
    whole.push(payload);
    let at_once: Vec<_> = std::iter::from_fn(|| whole.poll()).collect();
    assert_eq!(chunked, at_once);

    // One channel: every SamplesPerPacket is a whole number of scans.
    let config = StreamConfig {
        resolution_index: 0,
        samples_per_packet: spp,
        settling_factor: 0,
        clock: StreamClock::Mhz48,
        divide_by_256: false,
        scan_interval: 2000,
        channels: vec![StreamChannel { positive: 0, gain: Gain::X1, differential: false }],
    };
    let mut assembler = ScanAssembler::new(&config, Calibration::nominal()).expect("one channel divides any packet");
    for packet in chunked.into_iter().flatten() {
        let bytes = packet.encode().expect("a decoded packet re-encodes");
        let mut again = StreamDecoder::new(spp);
        again.push(&bytes);
        assert_eq!(again.poll(), Some(Ok(packet.clone())));
        if let Ok(scans) = assembler.accept(&packet) {
            assert!(scans.volts.iter().flatten().all(|v| v.is_finite()));
        }
    }
});
