//! The NI-DAQmx backend through its real code path (run-time loading, foreign calls, NI's status codes) against
//! the stand-in library `metaplate-mock-nidaqmx` builds (`libnidaqmx_standin.so`, simulated USB-6211s `Dev1` .. `Dev8`
//! with `ao0`/`ao1` looped back to `ai0`/`ai1`, see that crate). Each test takes its own device: the stand-in's
//! state is per process, as NI-DAQmx's is, and `cargo test` runs the tests in one process.

use std::time::Duration;

use metaplate_core::aim::{AimError, MirrorOutputs};
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use metaplate_daq::{NiDaqmx, NiInput, NiMirrorOutputs, NiOutputWaveform, NiSettings, StartTrigger, TerminalConfig};
use metaplate_fixtures::nidaqmx_stand_in;

fn settings(device: &str) -> NiSettings {
    NiSettings { library: Some(nidaqmx_stand_in()), read_timeout_s: 2.0, ..NiSettings::new(device) }
}

fn config(inputs: &[u8], range_v: f64, sample_rate_hz: f64, block_len_samples: u32) -> DaqConfig {
    DaqConfig {
        channels: inputs.iter().map(|&input| DaqChannel { input, range_v }).collect(),
        sample_rate_hz,
        block_len_samples,
    }
}

#[test]
fn missing_library_is_reported_as_unavailable() {
    let settings = NiSettings { library: Some("/nonexistent/libnidaqmx.so".into()), ..NiSettings::new("Dev1") };
    match NiDaqmx::open(&settings).unwrap_err() {
        DaqError::Unavailable { detail } => {
            assert!(detail.contains("NI-DAQmx") && detail.contains("/nonexistent/libnidaqmx.so"), "{detail}")
        }
        other => panic!("expected Unavailable, got {other:?}"),
    }
}

#[test]
fn opening_records_the_product_type_and_serial_number() {
    let daq = NiDaqmx::open(&settings("Dev1")).unwrap();
    let id = daq.identity();
    assert_eq!(
        (id.vendor.as_str(), id.model.as_str(), id.serial.as_str()),
        ("National Instruments", "NI USB-6211", "01A2B3C1")
    );
    assert!(id.firmware.contains("Dev1"), "{id:?}");
}

#[test]
fn a_missing_device_is_named_with_nis_text() {
    match NiDaqmx::open(&settings("Dev9")).unwrap_err() {
        DaqError::Unavailable { detail } => {
            assert!(detail.contains("-200220") && detail.contains("device not found"), "{detail}");
            assert!(detail.contains("Device Specified: Dev9"), "NI's extended error text is kept: {detail}");
        }
        other => panic!("expected Unavailable, got {other:?}"),
    }
}

#[test]
fn terminal_configuration_and_range_per_input_reach_the_device() {
    let mut s = settings("Dev2");
    s.terminal = TerminalConfig::Rse;
    s.inputs.insert(0, NiInput { terminal: TerminalConfig::Differential, range_v: None });
    s.inputs.insert(2, NiInput { terminal: TerminalConfig::Nrse, range_v: Some(0.2) });
    let mut daq = NiDaqmx::open(&s).unwrap();
    daq.configure(&config(&[0, 2, 3], 5.0, 10_000.0, 100)).unwrap();
    let taken = daq.input_terminals();
    assert_eq!(
        taken,
        [(0, Some(TerminalConfig::Differential)), (2, Some(TerminalConfig::Nrse)), (3, Some(TerminalConfig::Rse))],
        "what the stand-in was given, read back with DAQmxGetAITermCfg"
    );
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    daq.stop().unwrap();
    // ai2 and ai3 carry 0.5 V sines (1 and 2 kHz): on its 0.2 V range ai2 clips; ai3 fits its 5 V.
    assert!(block.integrity.clipped);
    assert!(block.volts[1].iter().all(|v| v.abs() <= 0.2 + 1e-12));
    assert!(block.volts[2].iter().any(|v| v.abs() > 0.2));
    // A USB-6211 has no pseudo-differential inputs: NI refuses it, and the code and text come back.
    s.inputs.insert(3, NiInput { terminal: TerminalConfig::PseudoDifferential, range_v: None });
    let mut daq = NiDaqmx::open(&s).unwrap();
    match daq.configure(&config(&[3], 5.0, 4000.0, 100)).unwrap_err() {
        DaqError::Device { code, detail } => {
            assert_eq!(code, -200077);
            assert!(detail.contains("DAQmx_AI_TermCfg") && detail.contains("Pseudodifferential"), "{detail}");
        }
        other => panic!("expected Device, got {other:?}"),
    }
}

fn ramp(len: usize) -> Vec<f64> {
    (0..len).map(|i| 1.0 + i as f64 * 0.01).collect()
}

/// Reads the first block of ai0 (the loopback of ao0) while ao0 generates a ramp, with `trigger`.
fn loopback_first_block(device: &str, trigger: StartTrigger) -> Vec<f64> {
    let mut s = settings(device);
    s.trigger = trigger;
    let mut daq = NiDaqmx::open(&s).unwrap();
    daq.set_output_waveform(Some(NiOutputWaveform { outputs: vec![0], range_v: 10.0, samples: vec![ramp(100)] }))
        .unwrap();
    daq.configure(&config(&[0], 5.0, 20_000.0, 250)).unwrap();
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    daq.stop().unwrap();
    block.volts[0].clone()
}

#[test]
fn inputs_started_by_the_outputs_start_trigger_share_its_first_sample() {
    let wave = ramp(100);
    let expected: Vec<f64> = (0..250).map(|i| wave[i % 100]).collect();
    assert_eq!(loopback_first_block("Dev3", StartTrigger::OutputStart), expected);
    // Started in software, the input runs before the output does: its first sample is the idle output (0 V). This
    // is what the trigger prevents, and why the assertion above can fail.
    let software = loopback_first_block("Dev4", StartTrigger::Software);
    assert_eq!(software[0], 0.0);
    assert_ne!(software, expected);
    // Without an output there is nothing to start the inputs: refused before anything is armed.
    let mut s = settings("Dev4");
    s.trigger = StartTrigger::OutputStart;
    let mut daq = NiDaqmx::open(&s).unwrap();
    assert!(matches!(daq.configure(&config(&[0], 5.0, 1000.0, 10)), Err(DaqError::Config { .. })));
}

#[test]
fn an_unread_buffer_is_an_overrun() {
    let mut daq = NiDaqmx::open(&settings("Dev5")).unwrap();
    // 250 kS/s on one input: NI's default buffer for the rate (100 kS) fills in 0.4 s.
    daq.configure(&config(&[4], 1.0, 250_000.0, 1000)).unwrap();
    daq.start().unwrap();
    daq.read_block().unwrap();
    std::thread::sleep(Duration::from_millis(500));
    match daq.read_block().unwrap_err() {
        DaqError::Overrun { detail } => {
            assert!(detail.contains("-200279") && detail.contains("no longer available"), "{detail}")
        }
        other => panic!("expected Overrun, got {other:?}"),
    }
}

#[test]
fn a_trigger_that_never_comes_is_a_timeout() {
    let mut s = settings("Dev6");
    s.trigger = StartTrigger::parse("PFI0", "Dev6").unwrap();
    s.read_timeout_s = 0.1;
    let mut daq = NiDaqmx::open(&s).unwrap();
    daq.configure(&config(&[2], 1.0, 1000.0, 10)).unwrap();
    daq.start().unwrap();
    match daq.read_block().unwrap_err() {
        DaqError::Timeout { what, .. } => assert!(what.contains("-200284") && what.contains("start trigger"), "{what}"),
        other => panic!("expected Timeout, got {other:?}"),
    }
}

#[test]
fn outputs_held_by_the_mirrors_are_reserved() {
    let lib = Some(nidaqmx_stand_in());
    let mirrors = NiMirrorOutputs::open("Dev7", "ao0", "ao1", 10.0, lib.clone()).unwrap();
    match NiMirrorOutputs::open("Dev7", "ao1", "Dev7/ao0", 10.0, lib).unwrap_err() {
        AimError::Device { message } => {
            assert!(message.contains("-50103") && message.contains("reserved"), "{message}")
        }
        other => panic!("expected Device, got {other:?}"),
    }
    let mut daq = NiDaqmx::open(&settings("Dev7")).unwrap();
    daq.set_output_waveform(Some(NiOutputWaveform { outputs: vec![1], range_v: 10.0, samples: vec![ramp(10)] }))
        .unwrap();
    daq.configure(&config(&[2], 1.0, 1000.0, 10)).unwrap();
    assert!(matches!(daq.start(), Err(DaqError::Device { code: -50103, .. })));
    drop(mirrors);
    daq.start().unwrap();
}

#[test]
fn mirror_outputs_hold_the_volts_written() {
    let mut mirrors = NiMirrorOutputs::open("Dev8", "ao0", "ao1", 5.0, Some(nidaqmx_stand_in())).unwrap();
    assert_eq!(mirrors.describe(), "NI USB-6211 s/n 01A2B3C8 Dev8/ao0, Dev8/ao1");
    assert_eq!(mirrors.limit_v(), 5.0);
    mirrors.set_volts(1.25, -2.5).unwrap();
    assert!(matches!(mirrors.set_volts(5.5, 0.0), Err(AimError::InvalidArgument { .. })));
    assert!(matches!(mirrors.set_volts(f64::NAN, 0.0), Err(AimError::InvalidArgument { .. })));
    // Read back through the loopback (ai0 <- ao0, ai1 <- ao1), as a lab checks its cabling.
    let mut daq = NiDaqmx::open(&settings("Dev8")).unwrap();
    daq.configure(&config(&[0, 1], 5.0, 1000.0, 5)).unwrap();
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    assert_eq!(block.volts, [vec![1.25; 5], vec![-2.5; 5]]);
    mirrors.reconnect().unwrap();
    mirrors.set_volts(0.5, 0.25).unwrap();
}

/// On a real NI device through NI's own library: `METAPLATE_NIDAQMX_DEVICE=Dev1 cargo test -p metaplate-daq --test
/// tests nidaqmx::real_device -- --ignored --nocapture` (reads 100 samples of ai0 at 10 kS/s, +/-10 V, RSE).
#[test]
#[ignore = "needs NI-DAQmx and a device: set METAPLATE_NIDAQMX_DEVICE (an NI device name such as Dev1)"]
fn real_device() {
    let device = std::env::var("METAPLATE_NIDAQMX_DEVICE").expect("METAPLATE_NIDAQMX_DEVICE names the NI device");
    let settings = NiSettings { terminal: TerminalConfig::Rse, ..NiSettings::new(&device) };
    let mut daq = NiDaqmx::open(&settings).unwrap();
    println!("{:?}", daq.identity());
    assert!(!daq.identity().model.is_empty() && !daq.identity().serial.is_empty());
    daq.configure(&config(&[0], 10.0, 10_000.0, 100)).unwrap();
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    daq.stop().unwrap();
    assert_eq!(block.volts[0].len(), 100);
    println!("ai0: {:?} V ...", &block.volts[0][..5]);
}
