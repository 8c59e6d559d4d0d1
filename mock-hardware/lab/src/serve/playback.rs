//! The stand-in rig's audio interface: the host plays through ALSA's stock `file` PCM
//! (`file:'DIR/play.fifo',raw`, over the `null` PCM, which takes frames as fast as they come; or the same behind a
//! `plug` at the scene's other rate, defined in the rig's `asound.conf`), which writes the raw
//! frames (FLOAT_LE, the audio backend's first choice, interleaved, the hardware file's channel count) into a FIFO
//! the lab reads here.
//!
//! The frames that arrive together make one playback, scheduled on the lab's chain once no byte has come for
//! [`GAP`] (or in pieces of 10 s, for a host that never pauses); it sounds from its arrival (see `Timing::
//! arrival_s`) plus the interface's latency. Frames that arrive while the previous playback of the same
//! acquisition still sounds continue it without a gap, as an interface's buffer would (a host thread paused
//! mid-write splits a playback, not its timing).

use std::io::Read;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use metaplate_audio::samples::{SampleFormat, decode};
use metaplate_core::clock::Clock;
use metaplate_mock_audio::{Playback, PlaybackObserver};
use rustix::fs::{FileType, Mode, OFlags};

use super::{IDLE_POLL, Timing};
use crate::{LabError, MockLab};

/// How long without a byte ends a playback.
const GAP: Duration = Duration::from_millis(20);

/// Makes the FIFO at `fifo` and serves it.
///
/// # Errors
/// [`LabError::Serve`] when the FIFO cannot be made or opened, or the thread cannot start. A FIFO left by a rig
/// that was killed is replaced (the caller has made sure no rig serves the folder).
pub(super) fn serve(
    lab: &MockLab,
    fifo: &Path,
    timing: Arc<Timing>,
    stop: Arc<AtomicBool>,
) -> Result<JoinHandle<()>, LabError> {
    let fail =
        |what: &str, e: &dyn std::fmt::Display| LabError::Serve { what: format!("{what} {}: {e}", fifo.display()) };
    if std::fs::symlink_metadata(fifo).is_ok_and(|m| std::os::unix::fs::FileTypeExt::is_fifo(&m.file_type())) {
        let _ = std::fs::remove_file(fifo);
    }
    rustix::fs::mknodat(rustix::fs::CWD, fifo, FileType::Fifo, Mode::from_raw_mode(0o600), 0)
        .map_err(|e| fail("making the FIFO", &e))?;
    // Non-blocking: a read finds EOF while no host has the PCM open, and nothing while it is silent.
    let fd = rustix::fs::open(fifo, OFlags::RDONLY | OFlags::NONBLOCK | OFlags::CLOEXEC, Mode::empty())
        .map_err(|e| fail("opening the FIFO", &e))?;
    let mut file = std::fs::File::from(fd);
    let channels = lab.wiring().audio_channels.max(1);
    let frame_bytes = channels as usize * SampleFormat::F32.bytes_per_sample();
    // The interface's own clock: the scene's setup may have left it at another rate than the host asks.
    let scene = lab.scene();
    let frame_rate_hz = scene.setup.audio_device_rate_hz.unwrap_or(scene.audio.sample_rate_hz)
        * (1.0 + scene.audio.clock_offset_ppm * 1e-6);
    let latency_s = lab.constants().audio_latency_s;
    let shared = lab.shared.clone();
    let clock = Arc::clone(&lab.clock);
    // A host that never pauses still has its frames scheduled, in pieces of this many bytes (10 s).
    let piece_bytes = ((frame_rate_hz * 10.0) as usize).max(1).saturating_mul(frame_bytes);
    std::thread::Builder::new()
        .name("stand-in-audio".into())
        .spawn(move || {
            let mut buffer = vec![0_u8; 1 << 16];
            let mut pending: Vec<u8> = Vec::new();
            // The open piece: where it starts sounding, lab time, and the acquisition it arrived in.
            let mut piece: Option<(f64, u64)> = None;
            let mut last_byte = Instant::now();
            while !stop.load(Ordering::Acquire) {
                match file.read(&mut buffer) {
                    Ok(n) if n > 0 => {
                        let now = Instant::now();
                        if piece.is_none() {
                            timing.receiving.store(true, Ordering::Release);
                            let (arrival_s, generation) = timing.arrival_s(clock.now_s(), now);
                            piece = Some((arrival_s + latency_s, generation));
                        }
                        pending.extend_from_slice(&buffer[..n]);
                        last_byte = now;
                        if pending.len() < piece_bytes {
                            continue;
                        }
                    }
                    // No host has the PCM open: a partial frame of the last one's will not be completed.
                    Ok(_) if piece.is_none() => pending.clear(),
                    Ok(_) => {}
                    Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted) => {}
                    // The FIFO itself failed: nothing more will come, and nothing is arriving.
                    Err(_) => {
                        timing.receiving.store(false, Ordering::Release);
                        break;
                    }
                }
                let full = pending.len() >= piece_bytes;
                if let Some((start_s, generation)) = piece.filter(|_| full || last_byte.elapsed() >= GAP) {
                    let whole = pending.len() / frame_bytes * frame_bytes;
                    // Exact: every value decoded is an f32's.
                    let samples: Vec<f32> =
                        decode(&pending[..whole], SampleFormat::F32).into_iter().map(|v| v as f32).collect();
                    // A partial frame waits for the rest of it.
                    pending.drain(..whole);
                    let playback =
                        Playback { start_s, frame_rate_hz, channels, samples: Arc::new(samples), underruns: 0 };
                    if playback.frames() > 0 {
                        timing.will_sound(generation, playback.end_s());
                        shared.on_playback(&playback);
                        timing.scheduled(generation);
                    }
                    piece = None;
                    timing.receiving.store(false, Ordering::Release);
                }
                if !full {
                    std::thread::sleep(IDLE_POLL);
                }
            }
        })
        .map_err(|e| fail("starting the thread of", &e))
}
