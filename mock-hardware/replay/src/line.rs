//! The serial line (LDV controller): recording and replay.

use std::io::Write;

use metaplate_cassette::{Body, Cassette, DeviceKind};
use metaplate_ldv::{LineError, SerialLine};

use crate::dialect::PolytecDialect;
use crate::engine::{ByteReplay, ReplayStats};
use crate::failure::Failure;
use crate::faults::ReplayFaults;
use crate::load::ReplayError;
use crate::mismatch::Mismatch;
use crate::recorder::Recorder;
use crate::script::{EP_CONTROL, EP_IN, EP_OUT};

impl From<&LineError> for Failure {
    fn from(e: &LineError) -> Self {
        match e {
            LineError::Timeout => Failure::Timeout(String::new()),
            LineError::Disconnected { reason } => Failure::Disconnected(reason.clone()),
        }
    }
}

/// A serial line has timeouts and disconnects only: a stall reads as a timeout, and any other failure (a replay
/// mismatch) as a disconnect, so that the driver stops at once.
fn line_error(failure: Failure) -> LineError {
    match failure {
        Failure::Timeout(_) | Failure::Stall => LineError::Timeout,
        Failure::Disconnected(reason) => LineError::Disconnected { reason },
        Failure::Other { detail, .. } => LineError::Disconnected { reason: detail },
    }
}

/// A [`SerialLine`] that passes every call to `L` and records it: each write as a host-to-device record, each
/// read's bytes as a device-to-host record (or its timeout or disconnect), each reopen as a reconnect event; see
/// [`crate::script`] for the endpoints. The read timeout asked for is not recorded (replay answers at once).
pub struct RecordingLine<L: SerialLine, W: Write + Send> {
    inner: L,
    recorder: Recorder<W>,
}

impl<L: SerialLine, W: Write + Send> RecordingLine<L, W> {
    /// Records the session on `inner` into `recorder` (started with an LDV header).
    pub fn new(inner: L, recorder: Recorder<W>) -> Self {
        Self { inner, recorder }
    }

    /// The recorder, to finish the cassette once the session is over.
    pub fn recorder(&self) -> &Recorder<W> {
        &self.recorder
    }

    /// The line being recorded.
    pub fn inner(&self) -> &L {
        &self.inner
    }
}

impl<L: SerialLine, W: Write + Send> SerialLine for RecordingLine<L, W> {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        let result = self.inner.write_all(bytes);
        let mut bodies = vec![Body::HostToDevice(bytes.to_vec())];
        if let Err(e) = &result {
            bodies.extend(Failure::from(e).to_bodies());
        }
        self.recorder.record(EP_OUT, bodies);
        result
    }

    fn read(&mut self, buf: &mut [u8], timeout_s: f64) -> Result<usize, LineError> {
        let result = self.inner.read(buf, timeout_s);
        let bodies = match &result {
            Ok(n) => vec![Body::DeviceToHost(buf.get(..*n).unwrap_or(buf).to_vec())],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_IN, bodies);
        result
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        let result = self.inner.reopen();
        let bodies = match &result {
            Ok(()) => vec![Body::Event(metaplate_cassette::Event::Reconnect)],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_CONTROL, bodies);
        result
    }
}

/// A [`SerialLine`] that plays an LDV cassette back to a driver: it checks each write against the recording
/// and answers each read with the recorded bytes (or failure), with [`ReplayFaults`] injected (see the crate
/// documentation for the semantics). A deviation stops the driver with a disconnect whose reason is the
/// [`Mismatch`], also kept for [`mismatch`](Self::mismatch).
pub struct ReplayLine {
    engine: ByteReplay,
    /// Bytes of a replayed read that did not fit the driver's buffer.
    carry: Vec<u8>,
}

impl std::fmt::Debug for ReplayLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReplayLine").field("stats", self.engine.stats()).finish_non_exhaustive()
    }
}

impl ReplayLine {
    /// A replay of `cassette` with `faults`.
    ///
    /// # Errors
    /// [`ReplayError::WrongDevice`] unless the cassette is an LDV serial session.
    pub fn new(cassette: &Cassette, faults: ReplayFaults) -> Result<Self, ReplayError> {
        let engine = ByteReplay::for_cassette(cassette, DeviceKind::LdvSerial, faults, Box::new(PolytecDialect))?;
        Ok(Self { engine, carry: Vec::new() })
    }

    /// The first deviation of the driver from the recording, if any.
    pub fn mismatch(&self) -> Option<&Mismatch> {
        self.engine.mismatch()
    }

    /// What the replay did so far.
    pub fn stats(&self) -> &ReplayStats {
        self.engine.stats()
    }

    /// Whether every recorded call has been played.
    pub fn is_finished(&self) -> bool {
        self.engine.is_finished()
    }
}

impl SerialLine for ReplayLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        self.engine.write(bytes).map_err(line_error)
    }

    fn read(&mut self, buf: &mut [u8], _timeout_s: f64) -> Result<usize, LineError> {
        if self.carry.is_empty() {
            self.carry = self.engine.read().map_err(line_error)?;
        }
        let n = self.carry.len().min(buf.len());
        if n == 0 {
            // An empty replayed read (a truncated one-byte reply) or an empty buffer: nothing arrived.
            return Err(LineError::Timeout);
        }
        buf[..n].copy_from_slice(&self.carry[..n]);
        self.carry.drain(..n);
        Ok(n)
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        self.carry.clear();
        self.engine.reopen().map_err(line_error)
    }
}
