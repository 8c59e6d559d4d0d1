//! The ALSA capture backend through the real libasound, with no sound card: ALSA's `file` plugin reads a capture
//! stream's samples from a file (`infile`) over its `null` PCM. The test writes that file and an ALSA configuration
//! naming the PCM, and runs the capture in a child process of this test binary with `ALSA_CONFIG_PATH` set (alsa-lib
//! reads its configuration once per process).
#![cfg(all(feature = "alsa", target_os = "linux"))]

use std::path::PathBuf;
use std::process::Command;

use metaplate_audio::AlsaCaptureDaq;
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};

/// The PCM the written configuration defines.
const PCM: &str = "metaplate_capture_test";
const RATE_HZ: f64 = 48_000.0;
const CHANNELS: usize = 3;
const FRAMES: usize = 4_800;
const FULL_SCALE_V: f64 = 1.74;

/// Interleaved full-scale samples: input k is a sine of its own frequency and amplitude.
fn signal() -> Vec<f32> {
    (0..FRAMES)
        .flat_map(|n| {
            (0..CHANNELS).map(move |k| {
                let f_hz = 100.0 * (k + 1) as f64;
                (0.3 * (k + 1) as f64 * (2.0 * std::f64::consts::PI * f_hz * n as f64 / RATE_HZ).sin()) as f32
            })
        })
        .collect()
}

#[test]
fn the_interfaces_inputs_are_read_as_volts_through_libasound() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("metaplate-alsa-capture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let infile = dir.join("in.raw");
    // FLOAT_LE, the backend's first choice, which the null PCM accepts.
    let bytes: Vec<u8> = signal().iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(&infile, bytes).unwrap();
    let config = dir.join("asound.conf");
    std::fs::write(
        &config,
        format!(
            // The null PCM reports the channel map its `chmap` gives (alsa-lib's pcm_null.c), through the file
            // plugin, as an interface's driver would report its inputs' positions.
            "</usr/share/alsa/alsa.conf>\npcm.{PCM} {{\n type file\n slave.pcm {{ type null chmap [ \"FL,FR,FC\" ] }}\n \
             file \"/dev/null\"\n infile \"{}\"\n format \"raw\"\n}}\n",
            infile.display()
        ),
    )
    .unwrap();
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["alsa_capture::capture_from_the_written_pcm", "--exact", "--ignored", "--nocapture"])
        .env("ALSA_CONFIG_PATH", &config)
        .env("METAPLATE_CAPTURE_TEST_DIR", &dir)
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{text}");
    // The child ran the test (a filter that matched nothing would also succeed).
    assert!(text.contains("1 passed"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Run by the test above in a child process, with the configuration that defines its PCM.
#[test]
#[ignore = "run by the_interfaces_inputs_are_read_as_volts_through_libasound, which defines its PCM"]
fn capture_from_the_written_pcm() {
    let _dir: PathBuf = std::env::var_os("METAPLATE_CAPTURE_TEST_DIR").expect("run by its parent test").into();
    let daq = AlsaCaptureDaq::new(PCM, FULL_SCALE_V);
    // Inputs 2 and 0, in that order, in blocks of 1000.
    let channel = |input| DaqChannel { input, range_v: FULL_SCALE_V };
    let config =
        DaqConfig { channels: vec![channel(2), channel(0)], sample_rate_hz: RATE_HZ, block_len_samples: 1_000 };
    // A hardware file expecting another map has the PCM refused, naming both maps; the right one (any case) opens.
    let mut elsewhere = AlsaCaptureDaq::new(PCM, FULL_SCALE_V).expect_channel_map(vec!["FL".into(), "FR".into()]);
    let err = elsewhere.configure(&config).unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(err, DaqError::Config { .. }) && text.contains("`FL FR FC`") && text.contains("`FL FR`"),
        "{text}"
    );
    drop(elsewhere);
    let mut daq = daq.expect_channel_map(vec!["fl".into(), "fr".into(), "fc".into()]);
    daq.configure(&config).unwrap();
    // Once open, the identity names the channels.
    assert_eq!(daq.identity().model, format!("capture PCM {PCM} (channel map FL FR FC)"));
    assert_eq!(daq.sample_format(), Some(metaplate_audio::SampleFormat::F32));
    daq.start().unwrap();
    let expected = signal();
    for block_index in 0..4_usize {
        let block = daq.read_block().unwrap();
        assert_eq!(block.first_sample_index, block_index as u64 * 1_000);
        assert!(block.integrity.is_contiguous() && !block.integrity.clipped);
        for (c, input) in [2_usize, 0].into_iter().enumerate() {
            assert_eq!(block.volts[c].len(), 1_000);
            for (i, v) in block.volts[c].iter().enumerate() {
                let frame = block_index * 1_000 + i;
                let want = f64::from(expected[frame * CHANNELS + input]) * FULL_SCALE_V;
                // Floats pass through unchanged: only the scaling's rounding.
                assert!((v - want).abs() < 1e-12, "input {input}, frame {frame}: {v} V, want {want} V");
            }
        }
    }
    daq.stop().unwrap();
    // A range the inputs do not have is refused before anything opens, naming both.
    let wrong = DaqConfig { channels: vec![DaqChannel { input: 0, range_v: 10.0 }], ..config.clone() };
    let err = daq.configure(&wrong).unwrap_err();
    assert!(matches!(err, DaqError::Config { .. }) && err.to_string().contains("1.74"), "{err}");
    // A rate that is not a whole number of frames per second is refused: ALSA cannot run at it.
    let fractional = DaqConfig { sample_rate_hz: 44_100.5, ..config };
    assert!(matches!(daq.configure(&fractional), Err(DaqError::Config { .. })));
}

#[test]
fn a_capture_pcm_that_does_not_exist_is_a_typed_error_and_reading_unstarted_is_refused() {
    let mut daq = AlsaCaptureDaq::new("metaplate_no_such_capture_pcm", FULL_SCALE_V);
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })));
    assert!(matches!(daq.start(), Err(DaqError::Protocol { .. })));
    let config = DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: FULL_SCALE_V }],
        sample_rate_hz: RATE_HZ,
        block_len_samples: 100,
    };
    let err = daq.configure(&config).unwrap_err();
    assert!(matches!(err, DaqError::Disconnected { .. }), "{err:?}");
    assert!(err.to_string().contains("metaplate_no_such_capture_pcm"), "{err}");
}

#[test]
#[ignore = "needs a real sound card: METAPLATE_CAPTURE_DEVICE=hw:... cargo test -p metaplate-audio --test tests alsa_capture::a_real_card -- --ignored"]
fn a_real_card_records_at_the_exact_rate() {
    let name = std::env::var("METAPLATE_CAPTURE_DEVICE")
        .expect("this test needs METAPLATE_CAPTURE_DEVICE=<ALSA capture PCM>, e.g. hw:CARD=24Ao,DEV=0");
    let rate_hz: f64 = std::env::var("METAPLATE_CAPTURE_RATE_HZ").map_or(48_000.0, |v| v.parse().unwrap());
    let full_scale_v: f64 = std::env::var("METAPLATE_CAPTURE_FULL_SCALE_V").map_or(1.0, |v| v.parse().unwrap());
    let mut daq = AlsaCaptureDaq::new(&name, full_scale_v);
    let block = (rate_hz / 10.0) as u32;
    let config = DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: full_scale_v }],
        sample_rate_hz: rate_hz,
        block_len_samples: block,
    };
    daq.configure(&config).unwrap();
    eprintln!("sample format: {:?}", daq.sample_format());
    let wall = std::time::Instant::now();
    daq.start().unwrap();
    let mut peak_v = 0.0_f64;
    for i in 0..10_u64 {
        let b = daq.read_block().unwrap();
        assert_eq!(b.first_sample_index, i * u64::from(block));
        assert!(b.integrity.is_contiguous(), "block {i}: {:?}", b.integrity);
        peak_v = b.volts[0].iter().fold(peak_v, |m, v| m.max(v.abs()));
    }
    daq.stop().unwrap();
    let elapsed_s = wall.elapsed().as_secs_f64();
    eprintln!("1 s recorded in {elapsed_s:.3} s, input 0 peak {peak_v:.4} V");
    // Ten blocks of 0.1 s take the recording's second (less the first period, plus a loaded machine's slack).
    assert!(elapsed_s > 0.9 && elapsed_s < 2.0, "recording took {elapsed_s} s");
}
