//! Full acquisitions from the mock U6: known signals come back in volts within half a calibrated code.

use crate::common;

use common::{SERIAL, mock_driver, sine_at, two_channels};
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use metaplate_daq::{DriverSettings, U6Driver};
use metaplate_mock_daq::{FaultSchedule, MockTransport, MockU6, u6_info};
use metaplate_u6_protocol::{Calibration, Gain};

#[test]
fn sines_come_back_within_half_a_code() {
    let config = two_channels();
    let mut daq = mock_driver(FaultSchedule::none());
    assert_eq!(daq.identity().serial, SERIAL.to_string());
    daq.configure(&config).unwrap();
    // 2 channels: 24 samples (12 scans) per packet, whole scans in every packet.
    assert_eq!(daq.stream_config().unwrap().samples_per_packet, 24);
    daq.start().unwrap();
    let mut next = 0u64;
    // The constants read from the device (the nominal ones, as fixed point holds them).
    let cal = *daq.calibration();
    // One second at 24 kHz: 100 blocks of 240.
    for _ in 0..100 {
        let block = daq.read_block().unwrap();
        assert_eq!(block.first_sample_index, next, "blocks follow each other");
        assert!(block.integrity.is_contiguous() && !block.integrity.clipped);
        for (ch, volts) in config.channels.iter().zip(&block.volts) {
            assert_eq!(volts.len(), 240);
            // Rounding to the nearest code errs by at most half a step (the gain's slope, the larger of the two
            // nominal slopes); 1e-12 V covers the f64 rounding of the sine and the conversion.
            let r = cal.ranges[usize::from(Gain::for_range_v(ch.range_v).unwrap().index())];
            let tolerance_v = 0.5 * r.slope_v.max(-r.neg_slope_v) + 1e-12;
            for (i, &v) in volts.iter().enumerate() {
                let expected = sine_at(ch.input, next + i as u64, config.sample_rate_hz);
                assert!((v - expected).abs() <= tolerance_v, "input {} scan {}: {v} vs {expected}", ch.input, i);
            }
        }
        next += 240;
    }
    daq.stop().unwrap();
    assert!(!daq.transport().device().is_running());
    assert_eq!(daq.stats().retries, 0);
    assert_eq!(daq.stats().stream.packets, 2000);
}

#[test]
fn inputs_beyond_the_range_are_flagged_clipped() {
    // 7 V amplitude on input 0 read on the +/-1 V range.
    let config = DaqConfig { channels: vec![DaqChannel { input: 0, range_v: 1.0 }], ..two_channels() };
    let mut daq = mock_driver(FaultSchedule::none());
    daq.configure(&config).unwrap();
    daq.start().unwrap();
    // The 440 Hz peak (scan 13.6 at 24 kHz) falls in the first 240-scan block.
    let block = daq.read_block().unwrap();
    assert!(block.integrity.clipped);
    let max = block.volts[0].iter().copied().fold(f64::MIN, f64::max);
    assert_eq!(max, daq.calibration().volts(Gain::X10, u16::MAX), "held at the top rail");
}

#[test]
fn block_lengths_need_not_be_whole_packets() {
    for block_len_samples in [1, 7, 12, 1000] {
        let mut daq = mock_driver(FaultSchedule::none());
        daq.configure(&DaqConfig { block_len_samples, ..two_channels() }).unwrap();
        daq.start().unwrap();
        let mut next = 0;
        for _ in 0..5 {
            let block = daq.read_block().unwrap();
            assert_eq!(block.len_samples(), block_len_samples as usize);
            assert_eq!(block.first_sample_index, next);
            next += u64::from(block_len_samples);
        }
    }
}

#[test]
fn rates_and_ranges_are_checked_against_the_u6() {
    let mut daq = mock_driver(FaultSchedule::none());
    // 2 channels x 25 kHz = 50 kS/s, the U6's most; 48 MHz / 1919 is over it.
    daq.configure(&DaqConfig { sample_rate_hz: 25_000.0, ..two_channels() }).unwrap();
    for sample_rate_hz in [48.0e6 / 1919.0, 0.0, 24_000.5, 7.0, f64::NAN, f64::INFINITY, -1.0] {
        let err = daq.configure(&DaqConfig { sample_rate_hz, ..two_channels() }).unwrap_err();
        assert!(matches!(err, DaqError::Config { .. }), "{sample_rate_hz} Hz: {err:?}");
    }
    // 0.01 V is offered (x1000); 5 V, 0.2 V, 0 V and NaN are not.
    daq.configure(&DaqConfig { channels: vec![DaqChannel { input: 13, range_v: 0.01 }], ..two_channels() }).unwrap();
    for range_v in [5.0, 0.2, 0.0, f64::NAN] {
        let config = DaqConfig { channels: vec![DaqChannel { input: 0, range_v }], ..two_channels() };
        let err = daq.configure(&config).unwrap_err();
        assert!(matches!(&err, DaqError::Config { detail } if detail.contains("not one of")), "{range_v} V: {err:?}");
    }
    let missing = DaqConfig { channels: vec![DaqChannel { input: 14, range_v: 10.0 }], ..two_channels() };
    assert!(matches!(daq.configure(&missing), Err(DaqError::Config { .. })));
    let none = DaqConfig { channels: vec![], ..two_channels() };
    assert!(matches!(daq.configure(&none), Err(DaqError::Config { .. })));
}

#[test]
fn a_non_finite_input_ends_the_stream_with_a_typed_error() {
    let source = |_: u8, first: u64, _: f64, out: &mut [f64]| {
        for (i, v) in out.iter_mut().enumerate() {
            *v = if first + i as u64 == 3000 { f64::NAN } else { 0.0 };
        }
    };
    let device = MockU6::new(u6_info(7), Calibration::nominal(), Box::new(source));
    let mut daq = U6Driver::open(MockTransport::new(device, FaultSchedule::none()), DriverSettings::default()).unwrap();
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let err = (0..20).find_map(|_| daq.read_block().err()).unwrap();
    assert!(matches!(&err, DaqError::Overrun { detail } if detail.contains("STREAM_AUTORECOVER_OVERFLOW")), "{err:?}");
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })), "the acquisition has ended");
}

#[test]
fn a_stream_left_running_is_stopped_when_opening() {
    let mut first = mock_driver(FaultSchedule::none());
    first.configure(&two_channels()).unwrap();
    first.start().unwrap();
    first.read_block().unwrap();
    // A new session takes over the device while it still streams (the first session crashed).
    let spare = MockTransport::new(common::sine_device(), FaultSchedule::none());
    let transport = std::mem::replace(first.transport_mut(), spare);
    assert!(transport.device().is_running());
    let mut second = U6Driver::open(transport, common::settings()).unwrap();
    assert!(!second.transport().device().is_running());
    second.configure(&two_channels()).unwrap();
    second.start().unwrap();
    let block = second.read_block().unwrap();
    assert_eq!(block.first_sample_index, 0, "a fresh acquisition");
    assert!(block.integrity.is_contiguous());
}
