use metaplate_u6_protocol::config::*;

#[test]
fn the_papers_rate_is_exact_on_the_48_mhz_clock() {
    assert_eq!(scan_timing(24_000.0), Some((StreamClock::Mhz48, false, 2000)));
    // 61.03515625 Hz and below need the divided clocks (LabJackPython switches at 61.03515 Hz).
    assert_eq!(scan_timing(50.0), Some((StreamClock::Mhz48, true, 3750)));
    assert_eq!(scan_timing(187_500.0 / 3.0), Some((StreamClock::Mhz48, false, 768)));
    assert_eq!(scan_timing(7.0), None);
    assert_eq!(scan_timing(f64::NAN), None);
}

#[test]
fn gains_map_to_the_guides_ranges() {
    assert_eq!(Gain::for_range_v(10.0), Some(Gain::X1));
    assert_eq!(Gain::for_range_v(0.1), Some(Gain::X100));
    assert_eq!(Gain::for_range_v(5.0), None);
    let ch = StreamChannel { positive: 2, gain: Gain::X100, differential: true };
    assert_eq!(ch.options_byte(), 0xa0);
    assert_eq!(StreamChannel::from_bytes(2, 0xa0), Ok(ch));
    assert!(StreamChannel::from_bytes(2, 0x01).is_err());
}
