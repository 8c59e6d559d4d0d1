//! `Configure::check` at the edges of every limit, and the code/volt conversions at their extremes.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use metaplate_daq_protocol::scale::{is_rail, raw_to_volts, volts_to_raw};
use metaplate_daq_protocol::{ChannelConfig, Configure, DaqError, DeviceInfo, ErrorCode, MAX_SAMPLE_VALUES};
use proptest::prelude::*;

fn info() -> DeviceInfo {
    DeviceInfo {
        of_seq: 0,
        n_channels: 16,
        max_aggregate_rate_hz: 250_000,
        ranges_mv: vec![10_000, 5_000, 1_000, 200],
        vendor: "metaplate".into(),
        model: "mock-6211".into(),
        serial: "SN0001".into(),
        firmware: "1.0.0".into(),
    }
}

fn paper_config() -> Configure {
    Configure {
        sample_rate_hz: 24_000,
        samples_per_packet: 240,
        channels: vec![ChannelConfig { index: 0, range_mv: 10_000 }, ChannelConfig { index: 1, range_mv: 10_000 }],
    }
}

fn code_of(result: Result<(), DaqError>) -> Option<ErrorCode> {
    match result {
        Ok(()) => None,
        Err(DaqError::ConfigRejected { code, .. }) => Some(code),
        Err(e) => panic!("unexpected error {e}"),
    }
}

#[test]
fn the_papers_configuration_is_accepted() {
    assert_eq!(code_of(paper_config().check(&info())), None);
}

#[test]
fn channel_problems_are_bad_config() {
    let with = |f: fn(&mut Configure)| {
        let mut c = paper_config();
        f(&mut c);
        code_of(c.check(&info()))
    };
    assert_eq!(with(|c| c.channels.clear()), Some(ErrorCode::BadConfig));
    assert_eq!(with(|c| c.channels[1].index = 0), Some(ErrorCode::BadConfig)); // duplicate
    assert_eq!(with(|c| c.channels[1].index = 16), Some(ErrorCode::BadConfig)); // one past the last input
    assert_eq!(with(|c| c.channels[1].index = 15), None); // the last input
    assert_eq!(with(|c| c.channels[0].range_mv = 2_000), Some(ErrorCode::BadConfig)); // not offered
    assert_eq!(with(|c| c.channels[0].range_mv = 200), None);
}

#[test]
fn packet_size_is_bounded_by_one_frame() {
    let mut c = paper_config();
    let max = u16::try_from(MAX_SAMPLE_VALUES / 2).unwrap();
    for (spp, code) in [(0, Some(ErrorCode::BadConfig)), (1, None), (max, None), (max + 1, Some(ErrorCode::BadConfig))]
    {
        c.samples_per_packet = spp;
        assert_eq!(code_of(c.check(&info())), code, "samples_per_packet {spp}");
    }
}

#[test]
fn rate_is_bounded_by_the_aggregate_maximum() {
    let mut c = paper_config();
    for (rate, code) in [
        (0, Some(ErrorCode::RateOutOfRange)),
        (1, None),
        (125_000, None), // x 2 channels = the maximum exactly
        (125_001, Some(ErrorCode::RateOutOfRange)),
        (u32::MAX, Some(ErrorCode::RateOutOfRange)), // no overflow in rate x channels
    ] {
        c.sample_rate_hz = rate;
        assert_eq!(code_of(c.check(&info())), code, "rate {rate}");
    }
}

#[test]
fn codes_convert_to_volts_at_the_extremes() {
    // Exact: powers of two and small integers only.
    assert_eq!(raw_to_volts(i16::MIN, 10_000), -10.0);
    assert_eq!(raw_to_volts(0, 10_000), 0.0);
    assert_eq!(raw_to_volts(i16::MAX, 10_000), 10.0 * 32_767.0 / 32_768.0);
    assert_eq!(raw_to_volts(1, 65_535), 65.535 / 32_768.0);
    assert_eq!(raw_to_volts(i16::MAX, 0), 0.0);
    assert!(is_rail(i16::MIN) && is_rail(i16::MAX) && !is_rail(0) && !is_rail(i16::MAX - 1));
}

#[test]
fn volts_quantise_with_clipping_at_the_rails() {
    assert_eq!(volts_to_raw(0.0, 10_000).unwrap(), (0, false));
    assert_eq!(volts_to_raw(-10.0, 10_000).unwrap(), (i16::MIN, false)); // the bottom code is exactly -R
    assert_eq!(volts_to_raw(10.0, 10_000).unwrap(), (i16::MAX, true)); // +R is half a step past the top code
    assert_eq!(volts_to_raw(-1e300, 10_000).unwrap(), (i16::MIN, true));
    assert_eq!(volts_to_raw(1e300, 1).unwrap(), (i16::MAX, true));
    assert_eq!(volts_to_raw(f64::MIN_POSITIVE, 1).unwrap(), (0, false));
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(matches!(volts_to_raw(bad, 10_000), Err(DaqError::NonFiniteVolts { .. })));
    }
    assert!(matches!(volts_to_raw(1.0, 0), Err(DaqError::ConfigRejected { .. })));
}

proptest! {
    #[test]
    fn every_code_survives_volts_and_back(raw in any::<i16>(), range_mv in 1u16..) {
        prop_assert_eq!(volts_to_raw(raw_to_volts(raw, range_mv), range_mv).unwrap(), (raw, false));
    }

    /// Inside the codes' span, quantisation error is at most half a step, R / 65536 (plus 1e-12 relative for the
    /// rounding of the scale factor).
    #[test]
    fn quantisation_error_is_at_most_half_a_step(x in -1.0f64..(32_767.0 / 32_768.0), range_mv in 1u16..) {
        let range_v = f64::from(range_mv) / 1000.0;
        let volts = x * range_v;
        let (raw, clipped) = volts_to_raw(volts, range_mv).unwrap();
        prop_assert!(!clipped);
        prop_assert!((raw_to_volts(raw, range_mv) - volts).abs() <= range_v / 65_536.0 * (1.0 + 1e-12));
    }
}
