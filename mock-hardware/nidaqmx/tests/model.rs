//! The simulated NI-DAQmx on its own state (a fresh [`StandIn`] per test): what NI's C reference says each call
//! does, and the faults it names.

use std::time::{Duration, Instant};

use nidaqmx_standin::device::{
    VAL_CONT_SAMPS, VAL_DIFF, VAL_GROUP_BY_CHANNEL, VAL_GROUP_BY_SCAN_NUMBER, VAL_PSEUDO_DIFF, VAL_RISING, VAL_RSE,
    VAL_VOLTS, codes,
};
use nidaqmx_standin::{ReadOutcome, StandIn, model};

#[test]
fn identity_and_unknown_devices_use_nis_codes() {
    assert_eq!(model::product_type("dev3").unwrap(), "USB-6211", "NI device names are case-insensitive");
    assert_eq!(model::serial_number("Dev1").unwrap(), 0x01A2_B3C1);
    assert!(model::sys_dev_names().starts_with("Dev1, Dev2"));
    let e = model::product_type("Dev9").unwrap_err();
    assert_eq!(e.code, codes::INVALID_DEVICE_ID);
    assert!(
        e.message.contains("Device Specified: Dev9") && e.message.ends_with("Status Code: -200220"),
        "{}",
        e.message
    );
}

#[test]
fn terminal_configuration_is_kept_and_pseudo_differential_refused() {
    let mut ni = StandIn::new();
    let task = ni.create_task("").unwrap();
    ni.create_ai_voltage_chan(task, "Dev1/ai0:1", VAL_DIFF, -5.0, 5.0, VAL_VOLTS).unwrap();
    ni.create_ai_voltage_chan(task, "Dev1/ai9", VAL_RSE, -1.0, 1.0, VAL_VOLTS).unwrap();
    assert_eq!(ni.ai_term_cfg(task, "Dev1/ai1").unwrap(), VAL_DIFF);
    assert_eq!(ni.ai_term_cfg(task, "Dev1/ai9").unwrap(), VAL_RSE);
    // A USB-6211 has no pseudo-differential mode; ai8-15 are the negative inputs of a differential pair.
    let e = ni.create_ai_voltage_chan(task, "Dev1/ai2", VAL_PSEUDO_DIFF, -1.0, 1.0, VAL_VOLTS).unwrap_err();
    assert_eq!(e.code, codes::INVALID_ATTRIBUTE_VALUE);
    assert_eq!(
        ni.create_ai_voltage_chan(task, "Dev1/ai10", VAL_DIFF, -1.0, 1.0, VAL_VOLTS).unwrap_err().code,
        codes::INVALID_ATTRIBUTE_VALUE
    );
    assert_eq!(
        ni.create_ai_voltage_chan(task, "Dev1/ai3", VAL_RSE, -20.0, 20.0, VAL_VOLTS).unwrap_err().code,
        codes::INVALID_ATTRIBUTE_VALUE
    );
    assert_eq!(
        ni.create_ai_voltage_chan(task, "Dev1/ai16", VAL_RSE, -1.0, 1.0, VAL_VOLTS).unwrap_err().code,
        codes::PHYSICAL_CHAN_DOES_NOT_EXIST
    );
}

#[test]
fn an_input_triggered_by_the_output_reads_the_waveform_from_its_first_sample() {
    let mut ni = StandIn::new();
    let ao = ni.create_task("ao").unwrap();
    ni.create_ao_voltage_chan(ao, "Dev1/ao0", -10.0, 10.0, VAL_VOLTS).unwrap();
    ni.cfg_samp_clk_timing(ao, "", 10_000.0, VAL_RISING, VAL_CONT_SAMPS, 100).unwrap();
    let wave: Vec<f64> = (0..100).map(|i| 1.0 + f64::from(i) * 0.01).collect();
    ni.write_analog_f64(ao, 100, false, VAL_GROUP_BY_CHANNEL, &wave, Instant::now()).unwrap();
    let ai = ni.create_task("ai").unwrap();
    ni.create_ai_voltage_chan(ai, "Dev1/ai0", VAL_RSE, -5.0, 5.0, VAL_VOLTS).unwrap();
    ni.cfg_samp_clk_timing(ai, "", 10_000.0, VAL_RISING, VAL_CONT_SAMPS, 1000).unwrap();
    ni.cfg_dig_edge_start_trig(ai, "/Dev1/ao/StartTrigger", VAL_RISING).unwrap();
    let t = Instant::now();
    ni.start(ai, t).unwrap();
    let mut out = vec![0.0; 150];
    // Armed: no samples until the output starts.
    assert_eq!(
        ni.try_read(ai, 150, VAL_GROUP_BY_SCAN_NUMBER, &mut out, t + Duration::from_secs(1)).unwrap(),
        ReadOutcome::Wait(None)
    );
    ni.start(ao, t + Duration::from_millis(2)).unwrap();
    let done = ni.try_read(ai, 150, VAL_GROUP_BY_SCAN_NUMBER, &mut out, t + Duration::from_millis(30)).unwrap();
    assert_eq!(done, ReadOutcome::Done(150));
    let expected: Vec<f64> = (0..150).map(|i| wave[i % 100]).collect();
    assert_eq!(out, expected, "the loopback ai0 <- ao0 reads the regenerated waveform sample for sample");
}

#[test]
fn resources_are_reserved_by_started_tasks() {
    let mut ni = StandIn::new();
    let now = Instant::now();
    let a = ni.create_task("").unwrap();
    ni.create_ao_voltage_chan(a, "Dev2/ao0:1", -10.0, 10.0, VAL_VOLTS).unwrap();
    ni.start(a, now).unwrap();
    ni.write_analog_f64(a, 1, false, VAL_GROUP_BY_CHANNEL, &[2.5, -1.5], now).unwrap();
    assert_eq!(ni.output_v("Dev2", 0, now), 2.5);
    assert_eq!(ni.output_v("Dev2", 1, now), -1.5);
    let b = ni.create_task("").unwrap();
    ni.create_ao_voltage_chan(b, "Dev2/ao1", -10.0, 10.0, VAL_VOLTS).unwrap();
    let e = ni.start(b, now).unwrap_err();
    assert_eq!(e.code, codes::RESOURCE_RESERVED);
    assert!(e.message.contains("Reserved by Task: _unnamedTask<0>"), "{}", e.message);
    ni.clear(a, now).unwrap();
    ni.start(b, now).unwrap();
    assert_eq!(ni.output_v("Dev2", 1, now), -1.5, "an output holds its voltage after its task is cleared");
}

#[test]
fn an_unread_buffer_overruns_and_a_short_wait_times_out() {
    let mut ni = StandIn::new();
    let task = ni.create_task("").unwrap();
    ni.create_ai_voltage_chan(task, "Dev3/ai2", VAL_RSE, -1.0, 1.0, VAL_VOLTS).unwrap();
    ni.cfg_samp_clk_timing(task, "", 1000.0, VAL_RISING, VAL_CONT_SAMPS, 0).unwrap();
    let t = Instant::now();
    ni.start(task, t).unwrap();
    let mut out = vec![0.0; 100];
    // 1 kS/s: 100 samples are due at 100 ms.
    let wait = ni.try_read(task, 100, VAL_GROUP_BY_SCAN_NUMBER, &mut out, t + Duration::from_millis(50)).unwrap();
    assert!(
        matches!(wait, ReadOutcome::Wait(Some(at)) if at.duration_since(t) == Duration::from_millis(100)),
        "{wait:?}"
    );
    assert_eq!(
        ni.try_read(task, 100, VAL_GROUP_BY_SCAN_NUMBER, &mut out, t + Duration::from_millis(100)).unwrap(),
        ReadOutcome::Done(100)
    );
    // ai2: 0.5 V at 1 kHz sampled at 1 kS/s is 0 at every sample (sin of whole turns).
    assert!(out.iter().all(|v| v.abs() < 1e-9));
    // NI's default buffer at 1 kS/s is 10 kS: 11 s of samples unread overwrite it.
    let e = ni.try_read(task, 100, VAL_GROUP_BY_SCAN_NUMBER, &mut out, t + Duration::from_secs(11)).unwrap_err();
    assert_eq!(e.code, codes::SAMPLES_NO_LONGER_AVAILABLE);
    assert!(e.message.contains("no longer available"), "{}", e.message);
}
