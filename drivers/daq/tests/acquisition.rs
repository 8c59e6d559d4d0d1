//! Full acquisitions from the mock DAQ: known signals come back in volts within the quantisation step.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{mock_driver, sine_at, two_channels};
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use metaplate_daq::{DaqDriver, DriverSettings};
use metaplate_daq_protocol::MAX_SAMPLE_VALUES;
use metaplate_mock_daq::{FaultSchedule, MockDaq, MockTransport, usb6211_info};

#[test]
fn sines_come_back_within_half_a_code() {
    let config = two_channels();
    let mut daq = mock_driver(FaultSchedule::none());
    daq.configure(&config).unwrap();
    daq.start().unwrap();
    let mut next = 0u64;
    // One second at 24 kHz: 100 blocks of 240.
    for _ in 0..100 {
        let block = daq.read_block().unwrap();
        assert_eq!(block.first_sample_index, next, "blocks follow each other");
        assert!(block.integrity.is_contiguous() && !block.integrity.clipped);
        for (ch, volts) in config.channels.iter().zip(&block.volts) {
            assert_eq!(volts.len(), 240);
            // Rounding to the nearest code errs by at most half a step (range / 32768 / 2); 1e-12 V covers the
            // f64 rounding of the sine and of the scaling.
            let tolerance_v = ch.range_v / 32768.0 / 2.0 + 1e-12;
            for (i, &v) in volts.iter().enumerate() {
                let expected = sine_at(ch.input, next + i as u64, config.sample_rate_hz);
                assert!((v - expected).abs() <= tolerance_v, "input {} sample {}: {v} vs {expected}", ch.input, i);
            }
        }
        next += 240;
    }
    daq.stop().unwrap();
    assert!(!daq.transport().device().is_running());
    assert_eq!(daq.stats().retries, 0);
}

#[test]
fn inputs_beyond_the_range_are_flagged_clipped() {
    // 7 V amplitude on input 0 read on the +/-5 V range.
    let config = DaqConfig { channels: vec![DaqChannel { input: 0, range_v: 5.0 }], ..two_channels() };
    let mut daq = mock_driver(FaultSchedule::none());
    daq.configure(&config).unwrap();
    daq.start().unwrap();
    // The 440 Hz peak (sample 13.6 at 24 kHz) falls in the first 240-sample block.
    let block = daq.read_block().unwrap();
    assert!(block.integrity.clipped);
    let max = block.volts[0].iter().copied().fold(f64::MIN, f64::max);
    assert_eq!(max, 5.0 * 32767.0 / 32768.0, "held at the top rail");
}

#[test]
fn block_length_extremes() {
    let n = 2;
    for block_len_samples in [1, (MAX_SAMPLE_VALUES / n) as u32] {
        let mut daq = mock_driver(FaultSchedule::none());
        daq.configure(&DaqConfig { block_len_samples, ..two_channels() }).unwrap();
        daq.start().unwrap();
        let block = daq.read_block().unwrap();
        assert_eq!(block.len_samples(), block_len_samples as usize);
    }
    let mut daq = mock_driver(FaultSchedule::none());
    let too_long = DaqConfig { block_len_samples: (MAX_SAMPLE_VALUES / n) as u32 + 1, ..two_channels() };
    assert!(matches!(daq.configure(&too_long), Err(DaqError::Config { .. })));
}

#[test]
fn rates_and_ranges_are_checked_at_their_limits() {
    let mut daq = mock_driver(FaultSchedule::none());
    // 250 kHz aggregate over 2 channels: 125 kHz is the most, 125001 Hz too much.
    daq.configure(&DaqConfig { sample_rate_hz: 125_000.0, ..two_channels() }).unwrap();
    for sample_rate_hz in [125_001.0, 0.0, 0.5, 24_000.5, f64::NAN, f64::INFINITY, -1.0] {
        let err = daq.configure(&DaqConfig { sample_rate_hz, ..two_channels() }).unwrap_err();
        assert!(matches!(err, DaqError::Config { .. }), "{sample_rate_hz} Hz: {err:?}");
    }
    // 0.2 V is offered (and is not exactly 200 mV in f64); 0.3 V, 0 V and NaN are not.
    daq.configure(&DaqConfig { channels: vec![DaqChannel { input: 15, range_v: 0.2 }], ..two_channels() }).unwrap();
    for range_v in [0.3, 0.0, f64::NAN, 1e6] {
        let config = DaqConfig { channels: vec![DaqChannel { input: 0, range_v }], ..two_channels() };
        assert!(matches!(daq.configure(&config), Err(DaqError::Config { .. })), "{range_v} V");
    }
    // Input 16 does not exist on a 16-input device; a duplicated input is refused.
    let missing = DaqConfig { channels: vec![DaqChannel { input: 16, range_v: 10.0 }], ..two_channels() };
    assert!(matches!(daq.configure(&missing), Err(DaqError::Config { .. })));
    let twice = DaqChannel { input: 1, range_v: 10.0 };
    let duplicated = DaqConfig { channels: vec![twice, twice], ..two_channels() };
    assert!(matches!(daq.configure(&duplicated), Err(DaqError::Config { .. })));
    let none = DaqConfig { channels: vec![], ..two_channels() };
    assert!(matches!(daq.configure(&none), Err(DaqError::Config { .. })));
}

#[test]
fn a_non_finite_input_is_a_device_fault_not_a_nan() {
    let source = |_: u8, first: u64, _: f64, out: &mut [f64]| {
        for (i, v) in out.iter_mut().enumerate() {
            *v = if first + i as u64 == 300 { f64::NAN } else { 0.0 };
        }
    };
    let device = MockDaq::new(usb6211_info("SN0002"), Box::new(source)).unwrap();
    let mut daq =
        DaqDriver::open(MockTransport::new(device, FaultSchedule::none()), DriverSettings::default()).unwrap();
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    assert!(daq.read_block().is_ok(), "samples 0..240 are finite");
    let err = daq.read_block().unwrap_err();
    assert!(matches!(err, DaqError::Device { code: 6, .. }), "{err:?}");
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })), "the acquisition has ended");
}

#[test]
fn a_device_left_running_is_stopped_before_configuring() {
    let mut first = mock_driver(FaultSchedule::none());
    first.configure(&two_channels()).unwrap();
    first.start().unwrap();
    first.read_block().unwrap();
    // A new session takes over the device while it still streams (the first session crashed).
    let spare = MockTransport::new(common::sine_device(), FaultSchedule::none());
    let transport = std::mem::replace(first.transport_mut(), spare);
    assert!(transport.device().is_running());
    let mut second = DaqDriver::open(transport, common::settings()).unwrap();
    second.configure(&two_channels()).unwrap();
    second.start().unwrap();
    let block = second.read_block().unwrap();
    assert_eq!(block.first_sample_index, 0, "a fresh acquisition");
    assert!(block.integrity.is_contiguous());
}
