//! The stream tracker: every anomaly class, sequence wrap-around, and conversion to volts.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use metaplate_daq_protocol::{
    ChannelConfig, Configure, DUPLICATE_WINDOW, DaqError, SampleFlags, SamplePacket, StreamEvent, StreamTracker,
};

const SPP: u16 = 4;

fn config() -> Configure {
    Configure {
        sample_rate_hz: 24_000,
        samples_per_packet: SPP,
        channels: vec![ChannelConfig { index: 0, range_mv: 10_000 }, ChannelConfig { index: 3, range_mv: 200 }],
    }
}

/// A full packet of two channels whose codes are small (off the rails), at the index implied by `seq`.
fn packet(packet_seq: u32) -> SamplePacket {
    packet_at(packet_seq, u64::from(packet_seq) * u64::from(SPP))
}

fn packet_at(packet_seq: u32, first_sample_index: u64) -> SamplePacket {
    SamplePacket {
        packet_seq,
        first_sample_index,
        flags: SampleFlags::default(),
        n_channels: 2,
        samples: vec![1, -1, 2, -2, 3, -3, 4, -4],
    }
}

fn tracker() -> StreamTracker {
    StreamTracker::new(&config()).unwrap()
}

#[test]
fn a_clean_stream_is_fresh_silent_and_contiguous() {
    let mut t = tracker();
    for seq in 0..10 {
        let out = t.track(&packet(seq));
        assert!(out.fresh && out.events.is_empty(), "{seq}: {out:?}");
    }
    // A short last packet (as on Stop) is still clean.
    let mut last = packet(10);
    last.samples.truncate(2);
    assert!(t.track(&last).events.is_empty());
    assert_eq!(t.finish(11), None);
    let s = t.stats();
    assert_eq!((s.packets, s.samples), (11, 41));
    assert!(s.is_contiguous() && s.is_clean());
}

#[test]
fn a_gap_in_packet_seq_reports_the_lost_packets_and_the_missing_samples() {
    let mut t = tracker();
    t.track(&packet(0));
    t.track(&packet(1));
    let out = t.track(&packet(4));
    assert!(out.fresh);
    assert_eq!(
        out.events,
        vec![
            StreamEvent::PacketsLost { first_missing_seq: 2, count: 2 },
            StreamEvent::Discontinuity { packet_seq: 4, expected_index: 8, got_index: 16 },
        ]
    );
    assert!(out.events.iter().all(StreamEvent::is_loss));
    let s = t.stats();
    assert_eq!((s.packets_lost, s.samples_missing, s.discontinuities), (2, 8, 1));
    assert!(!s.is_contiguous());
    // The stream continues cleanly after the gap.
    assert!(t.track(&packet(5)).events.is_empty());
}

#[test]
fn a_missing_first_packet_is_a_loss() {
    let mut t = tracker();
    let out = t.track(&packet(1));
    assert_eq!(out.events[0], StreamEvent::PacketsLost { first_missing_seq: 0, count: 1 });
}

#[test]
fn duplicates_are_dropped_without_breaking_contiguity() {
    let mut t = tracker();
    t.track(&packet(0));
    t.track(&packet(1));
    t.track(&packet(2));
    for seq in [2, 0] {
        let out = t.track(&packet(seq));
        assert!(!out.fresh);
        assert_eq!(out.events, vec![StreamEvent::Duplicate { packet_seq: seq }]);
        assert!(!out.events[0].is_loss());
    }
    let s = t.stats();
    assert_eq!((s.duplicates, s.packets), (2, 3));
    assert!(s.is_contiguous() && !s.is_clean());
}

#[test]
fn a_late_packet_is_out_of_order_once_and_a_duplicate_after() {
    let mut t = tracker();
    t.track(&packet(0));
    t.track(&packet(2)); // 1 counted lost
    let late = t.track(&packet(1));
    assert!(!late.fresh);
    assert_eq!(late.events, vec![StreamEvent::OutOfOrder { packet_seq: 1, expected_seq: 3 }]);
    assert_eq!(t.track(&packet(1)).events, vec![StreamEvent::Duplicate { packet_seq: 1 }]);
    assert_eq!((t.stats().out_of_order, t.stats().packets_lost), (1, 1));
}

#[test]
fn duplicates_are_recognised_exactly_within_the_window() {
    let mut t = tracker();
    for seq in 0..=DUPLICATE_WINDOW {
        t.track(&packet(seq));
    }
    // next_seq is WINDOW + 1: packet 1 is WINDOW back (remembered), packet 0 is WINDOW + 1 back (forgotten).
    assert_eq!(t.track(&packet(1)).events, vec![StreamEvent::Duplicate { packet_seq: 1 }]);
    assert_eq!(
        t.track(&packet(0)).events,
        vec![StreamEvent::OutOfOrder { packet_seq: 0, expected_seq: DUPLICATE_WINDOW + 1 }]
    );
}

#[test]
fn packet_seq_wraps_around_without_a_false_loss() {
    let mut t = tracker();
    // Two jumps of just under half the sequence space take the tracker to the top of the u32 range.
    let mut index = 0u64;
    let mut feed = |t: &mut StreamTracker, seq: u32, skipped: u64| {
        index += skipped * u64::from(SPP);
        let out = t.track(&packet_at(seq, index));
        index += u64::from(SPP);
        out
    };
    feed(&mut t, 0, 0);
    let jump = (1u32 << 31) - 2;
    let out = feed(&mut t, jump + 1, u64::from(jump));
    // Lost packets also show as a forward jump of the sample clock.
    let got_index = u64::from(jump + 1) * u64::from(SPP);
    assert_eq!(
        out.events,
        vec![
            StreamEvent::PacketsLost { first_missing_seq: 1, count: jump },
            StreamEvent::Discontinuity { packet_seq: jump + 1, expected_index: u64::from(SPP), got_index },
        ]
    );
    let out = feed(&mut t, u32::MAX - 1, u64::from(u32::MAX - 1 - (jump + 2)));
    assert!(matches!(out.events[..], [StreamEvent::PacketsLost { .. }, StreamEvent::Discontinuity { .. }]), "{out:?}");
    for seq in [u32::MAX, 0, 1] {
        let out = feed(&mut t, seq, 0);
        assert!(out.fresh && out.events.is_empty(), "{seq}: {out:?}");
    }
    // A repeat of the pre-wrap packet is a duplicate, not a jump forward.
    assert_eq!(t.track(&packet_at(u32::MAX, 0)).events, vec![StreamEvent::Duplicate { packet_seq: u32::MAX }]);
}

#[test]
fn an_overrun_reports_the_samples_the_device_lost() {
    let mut t = tracker();
    t.track(&packet(0));
    let mut p = packet_at(1, 4 + 10);
    p.flags.overrun = true;
    let out = t.track(&p);
    assert!(out.fresh);
    assert_eq!(
        out.events,
        vec![
            StreamEvent::Overrun { packet_seq: 1 },
            StreamEvent::Discontinuity { packet_seq: 1, expected_index: 4, got_index: 14 },
        ]
    );
    assert_eq!((t.stats().overruns, t.stats().samples_missing), (1, 10));
    // The next packet is expected where this one ended.
    assert!(t.track(&packet_at(2, 18)).events.is_empty());
}

#[test]
fn an_overrun_flag_alone_still_breaks_contiguity() {
    let mut t = tracker();
    let mut p = packet(0);
    p.flags.overrun = true;
    assert_eq!(t.track(&p).events, vec![StreamEvent::Overrun { packet_seq: 0 }]);
    assert!(!t.stats().is_contiguous());
}

#[test]
fn a_sample_clock_that_goes_back_is_a_discontinuity_without_missing_samples() {
    let mut t = tracker();
    t.track(&packet(0));
    t.track(&packet(1));
    let out = t.track(&packet_at(2, 2));
    assert_eq!(out.events, vec![StreamEvent::Discontinuity { packet_seq: 2, expected_index: 8, got_index: 2 }]);
    assert_eq!((t.stats().discontinuities, t.stats().samples_missing), (1, 0));
}

#[test]
fn clipping_is_reported_from_the_flag_or_from_a_rail_code() {
    let mut t = tracker();
    let mut flagged = packet(0);
    flagged.flags.clipped = true;
    let mut on_rail = packet(1);
    on_rail.samples[5] = i16::MIN;
    let mut top_rail = packet(2);
    top_rail.samples[0] = i16::MAX;
    for p in [flagged, on_rail, top_rail] {
        let out = t.track(&p);
        assert!(out.fresh);
        assert_eq!(out.events, vec![StreamEvent::Clipped { packet_seq: p.packet_seq }]);
    }
    assert_eq!(t.stats().clipped_packets, 3);
    assert!(t.stats().is_contiguous() && !t.stats().is_clean());
}

#[test]
fn packets_of_the_wrong_shape_are_dropped_and_their_samples_count_as_lost() {
    let mut t = tracker();
    let mut three_channels = packet(0);
    three_channels.n_channels = 3;
    three_channels.samples = vec![0; 6];
    let mut too_long = packet(0);
    too_long.samples.extend([5, -5]);
    for (p, n_channels, n_samples) in [(three_channels, 3, 2), (too_long, 2, 5)] {
        assert!(matches!(t.volts(&p), Err(DaqError::PacketShape { .. })));
        let out = t.track(&p);
        assert!(!out.fresh);
        assert_eq!(out.events, vec![StreamEvent::WrongShape { packet_seq: 0, n_channels, n_samples }]);
    }
    // The good packet 1 then reveals packet 0 as lost.
    assert!(matches!(t.track(&packet(1)).events[0], StreamEvent::PacketsLost { first_missing_seq: 0, count: 1 }));
    assert_eq!(t.stats().wrong_shape, 2);
}

#[test]
fn finish_reports_packets_lost_at_the_end() {
    let mut t = tracker();
    t.track(&packet(0));
    t.track(&packet(1));
    assert_eq!(t.finish(4), Some(StreamEvent::PacketsLost { first_missing_seq: 2, count: 2 }));
    assert_eq!(t.stats().packets_lost, 2);
    assert_eq!(t.finish(4), None);
    // A Stopped count behind the packets seen (a device fault) reports nothing rather than a huge loss.
    assert_eq!(t.finish(1), None);
}

#[test]
fn volts_use_each_channels_range_and_deinterleave() {
    let t = tracker();
    let mut p = packet(0);
    p.samples = vec![i16::MIN, i16::MIN, 16_384, 16_384, 0, 0, i16::MAX, i16::MAX];
    let v = t.volts(&p).unwrap();
    // Codes times range / 32768 are exact in f64 (16-bit code times a 16-bit range), so equality is exact up to
    // the one division by 1000 in the range: allow one ulp-scale 1e-15 relative.
    let expect = [[-10.0, 5.0, 0.0, 10.0 * 32_767.0 / 32_768.0], [-0.2, 0.1, 0.0, 0.2 * 32_767.0 / 32_768.0]];
    for (got, want) in v.iter().zip(expect) {
        assert_eq!(got.len(), 4);
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 1e-15 * w.abs(), "{g} vs {w}");
        }
    }
}

#[test]
fn configurations_that_cannot_stream_are_refused() {
    let mut c = config();
    c.channels.clear();
    assert!(matches!(StreamTracker::new(&c), Err(DaqError::ConfigRejected { .. })));
    let mut c = config();
    c.channels[1].range_mv = 0;
    assert!(matches!(StreamTracker::new(&c), Err(DaqError::ConfigRejected { .. })));
    let mut c = config();
    c.samples_per_packet = 0;
    assert!(matches!(StreamTracker::new(&c), Err(DaqError::ConfigRejected { .. })));
}
