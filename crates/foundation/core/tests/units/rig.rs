use metaplate_core::rig::*;

fn wiring() -> Wiring {
    Wiring {
        actuator_channels: (0..8).collect(),
        loopback_channel: 8,
        audio_channels: 9,
        audio_sample_rate_hz: 48_000.0,
        velocity_input: 0,
        loopback_input: 1,
        daq_range_v: 10.0,
        daq_sample_rate_hz: 24_000.0,
        loopback_volts_per_full_scale: 1.0,
    }
}

#[test]
fn wiring_checks_say_what_is_wrong() {
    assert_eq!(wiring().validate(), Ok(()));
    let mut w = wiring();
    w.actuator_channels[3] = 8;
    assert!(w.validate().unwrap_err().contains("actuator 3"));
    let mut w = wiring();
    w.audio_channels = 8;
    assert!(w.validate().unwrap_err().contains("channel 8 is beyond"));
    let mut w = wiring();
    w.loopback_input = 0;
    assert!(w.validate().unwrap_err().contains("share DAQ input 0"));
    let mut w = wiring();
    w.daq_sample_rate_hz = f64::NAN;
    assert!(w.validate().unwrap_err().contains("daq_sample_rate_hz"));
}
