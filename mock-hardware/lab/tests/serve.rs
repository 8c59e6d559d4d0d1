//! The stand-in rig's signal path in process, spoken to as a host does (its FIFO written as ALSA's `file` PCM
//! writes it, its socket through the NI-DAQmx stand-in's own link): a playback is heard in the acquisition it
//! arrives in, and an acquisition that ends in the middle of one leaves nothing of it to the next. The binary's
//! `lab serve` runs the whole rig through the real backends in `tests/standin.rs`.
#![cfg(unix)]

use std::io::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

use metaplate_lab::serve::{PLAYBACK_FIFO, RigAim, ServeOptions, StandInRig};
use nidaqmx_standin::lab::{LabLink, Reply, SOCKET_NAME};

use crate::common;

/// The DAQ's rate, Hz, and the rig's speed (the test need not wait in real time).
const RATE_HZ: f64 = 24_000.0;
const SPEED: f64 = 20.0;

/// Interleaved FLOAT_LE frames of `channels`, silent but for `seconds` of a 0.5 full-scale 200 Hz tone on
/// `channel`, as ALSA's raw `file` PCM writes them.
fn tone_bytes(channels: usize, channel: usize, seconds: f64) -> Vec<u8> {
    let frames = (seconds * 48_000.0) as usize;
    let mut bytes = Vec::with_capacity(frames * channels * 4);
    for n in 0..frames {
        for c in 0..channels {
            let v = if c == channel { 0.5 * (std::f64::consts::TAU * 200.0 * n as f64 / 48_000.0).sin() } else { 0.0 };
            bytes.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    bytes
}

/// The loopback's (input 1's) peak over samples `first .. first + count` of the link's acquisition, V.
fn loopback_peak_v(link: &mut LabLink, first: u64, count: u64) -> f64 {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        match link.read(first, count).unwrap() {
            Reply::Wait { ms } => std::thread::sleep(Duration::from_millis(ms)),
            Reply::Data(values) => return values.iter().skip(1).step_by(2).fold(0.0, |m: f64, v| m.max(v.abs())),
            other => panic!("{other:?}"),
        }
        assert!(Instant::now() < deadline, "the rig never handed the samples out");
    }
}

fn play(fifo: &Path, bytes: &[u8]) {
    std::fs::OpenOptions::new().write(true).open(fifo).unwrap().write_all(bytes).unwrap();
}

#[test]
fn an_acquisition_hears_its_own_playbacks_and_none_an_aborted_one_left() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let channels = lab.wiring().audio_channels as usize;
    let loopback = lab.wiring().loopback_channel as usize;
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("serve-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // The library is only copied for hosts to load; this test speaks the protocol itself.
    let library = dir.join("library.so");
    std::fs::write(&library, b"not loaded here").unwrap();
    let options =
        ServeOptions { speed: SPEED, nidaqmx_library: library, plate: "homogeneous".into(), aim: RigAim::Galvo };
    let rig = StandInRig::start(lab, &dir.join("rig"), &options).unwrap();
    let (socket, fifo) = (rig.dir().join(SOCKET_NAME), rig.dir().join(PLAYBACK_FIFO));

    // Acquisition A: a 1 s tone arrives in two pieces 100 ms apart (the second continues the first); the host
    // reads 0.1 s, hears it, and hangs up in the middle of it.
    let mut a = LabLink::start(&socket, RATE_HZ, &[0, 1]).unwrap();
    let tone = tone_bytes(channels, loopback, 1.0);
    let half = tone.len() / 2 / (channels * 4) * (channels * 4);
    play(&fifo, &tone[..half]);
    std::thread::sleep(Duration::from_millis(100));
    play(&fifo, &tone[half..]);
    std::thread::sleep(Duration::from_millis(100));
    let heard_v = loopback_peak_v(&mut a, 0, 2_400);
    assert!((heard_v - 0.5).abs() < 0.02, "the tone at 0.5 V on the loopback: {heard_v} V");
    drop(a);

    // Acquisition B, with no playback of its own: 3 s of silence (its 2 s wait for one passes first), none of A's
    // tone. (Its second piece arrived 100 ms after the first, 2 s later at the rig's speed: without the rig's
    // moving on past what was scheduled, it would sound 2 s into B.)
    let mut b = LabLink::start(&socket, RATE_HZ, &[0, 1]).unwrap();
    let left_v = loopback_peak_v(&mut b, 0, 72_000);
    assert!(left_v < 1e-9, "B hears {left_v} V of A's tone");
    drop(b);

    // Acquisition C hears its own.
    let mut c = LabLink::start(&socket, RATE_HZ, &[0, 1]).unwrap();
    play(&fifo, &tone_bytes(channels, loopback, 0.2));
    let own_v = loopback_peak_v(&mut c, 0, 4_800);
    assert!((own_v - 0.5).abs() < 0.02, "C's own tone: {own_v} V");
    drop(c);
    drop(rig);
    assert!(!dir.join("rig").join(PLAYBACK_FIFO).exists(), "the rig takes its FIFO with it");
    std::fs::remove_dir_all(&dir).unwrap();
}
