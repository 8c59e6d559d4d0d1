//! The host's stream accounting: packet numbers, auto-recovery (errorcodes 59 and 60, as the User's Guide's
//! StreamData section and LabJackPython's `streamData` count them), errorcodes that end the stream, volts by scan.

use metaplate_u6_protocol::{
    Calibration, Errorcode, Gain, ScanAssembler, StreamChannel, StreamClock, StreamConfig, StreamEvent, StreamPacket,
    U6Error,
};

fn config(channels: usize, spp: u8) -> StreamConfig {
    StreamConfig {
        resolution_index: 0,
        samples_per_packet: spp,
        settling_factor: 0,
        clock: StreamClock::Mhz48,
        divide_by_256: false,
        scan_interval: 2000,
        channels: (0..channels)
            .map(|i| StreamChannel { positive: i as u8, gain: Gain::X1, differential: false })
            .collect(),
    }
}

fn packet(number: u8, errorcode: Errorcode, timestamp: u32, samples: Vec<u16>) -> StreamPacket {
    StreamPacket { timestamp, packet_number: number, errorcode, samples, backlog: 0 }
}

fn ideal() -> ScanAssembler {
    ScanAssembler::new(&config(2, 4), Calibration::ideal()).unwrap()
}

#[test]
fn packets_of_whole_scans_are_required() {
    assert!(matches!(ScanAssembler::new(&config(2, 25), Calibration::ideal()), Err(U6Error::InvalidField { .. })));
}

#[test]
fn scans_are_split_by_channel_and_converted() {
    let mut a = ideal();
    let got = a.accept(&packet(0, Errorcode::OK, 0, vec![32_768, 32_769, 0, 65_535])).unwrap();
    assert_eq!(got.first_scan_index, 0);
    assert_eq!(got.volts, vec![vec![0.0, -10.0], vec![10.0 / 32_768.0, 32_767.0 * 10.0 / 32_768.0]]);
    assert!(got.clipped);
    assert!(got.events.is_empty());
    let next = a.accept(&packet(1, Errorcode::OK, 0, vec![32_768; 4])).unwrap();
    assert_eq!(next.first_scan_index, 2);
    assert!(!next.clipped);
}

#[test]
fn a_packet_number_gap_costs_its_scans_and_wraps_at_256() {
    let mut a = ideal();
    for n in 0..=255u8 {
        a.accept(&packet(n, Errorcode::OK, 0, vec![32_768; 4])).unwrap();
    }
    // Packet 256 (number 0) and 257 (1) lost: 2 packets of 2 scans.
    let got = a.accept(&packet(2, Errorcode::OK, 0, vec![32_768; 4])).unwrap();
    assert_eq!(got.events, vec![StreamEvent::PacketsMissed { packets: 2, scans: 4 }]);
    assert_eq!(got.first_scan_index, 256 * 2 + 4);
    // A repeat of packet 2 lies behind: dropped, nothing counted.
    let stale = a.accept(&packet(2, Errorcode::OK, 0, vec![32_768; 4])).unwrap();
    assert_eq!(stale.events, vec![StreamEvent::Stale { packet_number: 2 }]);
    assert!(stale.volts.iter().all(Vec::is_empty));
    assert_eq!(a.stats().packets_missed, 2);
    assert_eq!(a.stats().stale_packets, 1);
}

#[test]
fn auto_recovery_keeps_the_sample_clock() {
    let mut a = ideal();
    a.accept(&packet(0, Errorcode::OK, 0, vec![32_768; 4])).unwrap();
    // Draining after the overflow: good samples, flagged.
    let draining = a.accept(&packet(1, Errorcode::STREAM_AUTORECOVER_ACTIVE, 0, vec![32_768; 4])).unwrap();
    assert_eq!(draining.events, vec![StreamEvent::AutoRecoverActive]);
    assert_eq!(draining.first_scan_index, 2);
    // The report: a dummy scan (0xFFFF) first, TimeStamp 10 scans discarded (the dummy included).
    let report =
        a.accept(&packet(2, Errorcode::STREAM_AUTORECOVER_REPORT, 10, vec![0xffff, 0xffff, 32_768, 32_768])).unwrap();
    assert_eq!(report.events, vec![StreamEvent::ScansDiscarded { scans: 10 }]);
    assert_eq!(report.first_scan_index, 4 + 10);
    assert_eq!(report.volts, vec![vec![0.0], vec![0.0]]);
    assert!(!report.clipped, "the dummy scan is not a sample");
    assert_eq!(a.next_scan_index(), 15);
    assert_eq!(a.stats().scans_discarded, 10);
}

#[test]
fn other_errorcodes_end_the_stream_by_name() {
    let mut a = ideal();
    let e = a.accept(&packet(0, Errorcode::STREAM_SCAN_OVERLAP, 0, vec![0; 4])).unwrap_err();
    assert_eq!(e, U6Error::StreamError { packet_number: 0, errorcode: Errorcode(55) });
    assert!(e.to_string().contains("STREAM_SCAN_OVERLAP (55)"));
    let e = a.accept(&packet(1, Errorcode::STREAM_AUTORECOVER_OVERFLOW, 0, vec![0; 4])).unwrap_err();
    assert!(e.to_string().contains("STREAM_AUTORECOVER_OVERFLOW (63)"));
}

#[test]
fn a_packet_of_the_wrong_size_is_refused() {
    let mut a = ideal();
    assert!(matches!(a.accept(&packet(0, Errorcode::OK, 0, vec![0; 2])), Err(U6Error::InvalidField { .. })));
}
