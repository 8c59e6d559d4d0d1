//! The stand-in rig's DAQ: the socket the stand-in NI-DAQmx library asks for its analog inputs
//! (`nidaqmx_standin::lab`, one connection per acquisition), answered from the lab's chain, and tells its analog
//! outputs' voltages, which drive the lab's galvo mirrors.
//!
//! Pacing: sample `n` of an acquisition is handed out once `n / rate / speed` has passed on the wall clock since
//! its start, plus [`LAG`], and never while a playback is arriving (it is scheduled first). Until the
//! acquisition's first playback has been scheduled, or [`WAIT_FOR_PLAYBACK`] has passed, nothing is handed out: that
//! playback then sounds at the lab's time then (the acquisition's start, unless the vibrometer's link moved the
//! lab's clock) plus the interface's latency, however long the host took to start it, as on an interface and a DAQ
//! started together (`Timing::arrival_s`). An acquisition starts after every playback scheduled or arriving before
//! it has sounded, so an earlier acquisition's sweep (one stopped early, or that overflowed) is not heard in it.

use std::io::BufReader;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use metaplate_core::aim::MirrorOutputs;
use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::scene::FaultKind;
use metaplate_mock_audio::FaultWindows;
use nidaqmx_standin::lab::{MAX_READ_VALUES, Reply, Request, read_line};

use super::{Acquisition, IDLE_POLL, LAG, Timing, WAIT_FOR_PLAYBACK};
use crate::chain::Shared;
use crate::mirrors::MockMirrors;
use crate::{LabError, MockLab};

/// How long a start waits for the previous acquisition's connection to end and an arriving playback to be
/// scheduled.
const HANDOVER: Duration = Duration::from_secs(2);

/// Listens at `socket` (a stale socket of a rig that is gone is replaced).
///
/// # Errors
/// [`LabError::Serve`] when the socket cannot be bound (a rig serving there included) or the thread cannot start.
pub(super) fn serve(
    lab: &MockLab,
    socket: &Path,
    timing: Arc<Timing>,
    stop: Arc<AtomicBool>,
) -> Result<JoinHandle<()>, LabError> {
    let fail = |what: &str, e: std::io::Error| LabError::Serve { what: format!("{what} {}: {e}", socket.display()) };
    if socket.exists() && UnixStream::connect(socket).is_err() {
        let _ = std::fs::remove_file(socket);
    }
    let listener = UnixListener::bind(socket).map_err(|e| fail("listening at", e))?;
    listener.set_nonblocking(true).map_err(|e| fail("listening at", e))?;
    let shared = lab.shared.clone();
    let clock = Arc::clone(&lab.clock);
    let windows = lab.windows.clone();
    let mirrors = lab.mirrors();
    std::thread::Builder::new()
        .name("stand-in-daq".into())
        .spawn(move || {
            let next = AtomicU64::new(1);
            let generations = Arc::new(AtomicU64::new(1));
            while !stop.load(Ordering::Acquire) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        let id = next.fetch_add(1, Ordering::Relaxed);
                        let (shared, clock, timing, stop) =
                            (shared.clone(), Arc::clone(&clock), Arc::clone(&timing), Arc::clone(&stop));
                        let (windows, mirrors, generations) =
                            (windows.clone(), mirrors.clone(), Arc::clone(&generations));
                        let connection = Connection { id, shared, clock, timing, windows, mirrors, generations };
                        let _ = std::thread::Builder::new()
                            .name("stand-in-daq-connection".into())
                            .spawn(move || connection.serve(stream, &stop));
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(5)),
                }
            }
        })
        .map_err(|e| fail("starting the thread of", e))
}

/// One acquisition's connection.
struct Connection {
    id: u64,
    shared: Shared,
    clock: Arc<VirtualClock>,
    timing: Arc<Timing>,
    /// The scene's faults: a `daq_overrun` window overflows the device's buffer.
    windows: FaultWindows,
    /// The lab's galvo mirrors, which the outputs drive (shared by every connection).
    mirrors: MockMirrors,
    /// The next acquisition's generation (shared by every connection).
    generations: Arc<AtomicU64>,
}

/// Ends a connection's acquisition when the connection ends, however it ends.
struct Release<'a>(&'a Connection);

impl Drop for Release<'_> {
    fn drop(&mut self) {
        if let Ok(mut acquisition) = self.0.timing.acquisition.lock()
            && acquisition.is_some_and(|a| a.connection == self.0.id)
        {
            *acquisition = None;
        }
    }
}

impl Connection {
    fn serve(&self, stream: UnixStream, stop: &AtomicBool) {
        // Blocking reads without a timeout: a timeout in the middle of a line would lose its start. The thread ends
        // when the host hangs up (its task stopped, or its process ended).
        let (Ok(()), Ok(read_half)) = (stream.set_nonblocking(false), stream.try_clone()) else {
            return;
        };
        let _release = Release(self);
        let mut reader = BufReader::new(read_half);
        let mut writer = stream;
        let mut inputs: Vec<u8> = Vec::new();
        while !stop.load(Ordering::Acquire) {
            let Ok(line) = read_line(&mut reader) else { break };
            let reply = match Request::parse(&line) {
                Err(text) => Reply::Error(text),
                Ok(Request::Start { rate_hz, inputs: asked }) => {
                    let reply = self.start(rate_hz);
                    if reply == Reply::Ok {
                        inputs = asked;
                    }
                    reply
                }
                Ok(Request::Read { first, count }) => self.read(&inputs, first, count),
                Ok(Request::Outputs { x_v, y_v }) => match self.mirrors.clone().set_volts(x_v, y_v) {
                    Ok(()) => Reply::Ok,
                    Err(e) => Reply::Error(e.to_string()),
                },
            };
            if reply.write_to(&mut writer).is_err() {
                break;
            }
        }
    }

    fn start(&self, rate_hz: f64) -> Reply {
        // The previous task's connection ends a moment after its host stopped it, and a playback still arriving is
        // scheduled first (it belongs before this acquisition): wait for both, a little.
        let deadline = Instant::now() + HANDOVER;
        while Instant::now() < deadline
            && (self.timing.acquisition().is_some_and(|a| a.connection != self.id)
                || self.timing.receiving.load(Ordering::Acquire))
        {
            std::thread::sleep(IDLE_POLL);
        }
        let Ok(mut acquisition) = self.timing.acquisition.lock() else {
            return Reply::Error("the rig's acquisition lock is poisoned".into());
        };
        if acquisition.is_some_and(|a| a.connection != self.id) {
            return Reply::Error("another acquisition is running on this rig (one input task at a time)".into());
        }
        // Time has passed since the last playback sounded (an acquisition that stopped early, or overflowed, left
        // its end ahead of the clock): none of it belongs to this acquisition.
        let until_s = self.timing.sounding_until_s();
        if until_s > self.clock.now_s() {
            self.clock.advance(until_s - self.clock.now_s());
        }
        match self.shared.lock() {
            Ok(mut state) => state.daq_started(),
            Err(e) => return Reply::Error(e.to_string()),
        }
        *acquisition = Some(Acquisition {
            connection: self.id,
            generation: self.generations.fetch_add(1, Ordering::Relaxed),
            wall_t0: Instant::now(),
            virtual_t0_s: self.clock.now_s(),
            rate_hz,
        });
        Reply::Ok
    }

    fn read(&self, inputs: &[u8], first: u64, count: u64) -> Reply {
        let Some(acquisition) = self.timing.acquisition().filter(|a| a.connection == self.id) else {
            return Reply::Error("read before start".into());
        };
        if count.saturating_mul(inputs.len() as u64) > MAX_READ_VALUES {
            return Reply::Error(format!(
                "{count} samples of {} inputs is over {MAX_READ_VALUES} values",
                inputs.len()
            ));
        }
        let now = Instant::now();
        let waited = now.saturating_duration_since(acquisition.wall_t0);
        let played = self.timing.played(&acquisition);
        if self.timing.receiving.load(Ordering::Acquire) || (!played && waited < WAIT_FOR_PLAYBACK) {
            return Reply::Wait { ms: 2 };
        }
        let end = first.saturating_add(count);
        // A hostile rate or index gives an instant that never comes, not a panic.
        let due = Duration::try_from_secs_f64(end as f64 / acquisition.rate_hz / self.timing.speed)
            .unwrap_or(Duration::MAX)
            .saturating_add(LAG);
        if waited < due {
            return Reply::Wait { ms: (due - waited).as_millis().clamp(1, 1_000) as u64 };
        }
        let end_s = acquisition.virtual_t0_s + end as f64 / acquisition.rate_hz;
        if self.windows.active(FaultKind::DaqOverrun, end_s).is_some() {
            return Reply::Overrun;
        }
        let n = usize::try_from(count).unwrap_or(0);
        let mut by_scan = vec![0.0; n * inputs.len()];
        let mut column = vec![0.0; n];
        let Ok(mut state) = self.shared.lock() else {
            return Reply::Error("the lab's state lock is poisoned".into());
        };
        for (c, &input) in inputs.iter().enumerate() {
            if let Err(e) = state.fill(input, first, acquisition.rate_hz, &mut column) {
                return Reply::Error(format!("the lab's chain: {e}"));
            }
            if column.iter().any(|v| !v.is_finite()) {
                return Reply::Error(format!("a non-finite voltage on ai{input}"));
            }
            for (i, v) in column.iter().enumerate() {
                by_scan[i * inputs.len() + c] = *v;
            }
        }
        Reply::Data(by_scan)
    }
}
