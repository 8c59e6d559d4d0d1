//! The U6's bulk endpoints (commands, responses, stream): recording and replay.

use std::io::Write;
use std::time::Duration;

use metaplate_cassette::{Body, Cassette, DeviceKind, Event};
use metaplate_daq::{BulkTransport, TransportError};

use crate::dialect::U6Dialect;
use crate::engine::{ByteReplay, ReplayStats};
use crate::failure::Failure;
use crate::faults::ReplayFaults;
use crate::load::ReplayError;
use crate::mismatch::Mismatch;
use crate::recorder::Recorder;
use crate::script::{EP_CONTROL, EP_IN, EP_OUT, EP_STREAM};

impl From<&TransportError> for Failure {
    fn from(e: &TransportError) -> Self {
        match e {
            TransportError::Timeout => Failure::Timeout(String::new()),
            TransportError::Stall => Failure::Stall,
            TransportError::Disconnected(detail) => Failure::Disconnected(detail.clone()),
            TransportError::Other(detail) => Failure::Other { kind: "other".into(), detail: detail.clone() },
        }
    }
}

fn transport_error(failure: Failure) -> TransportError {
    match failure {
        Failure::Timeout(_) => TransportError::Timeout,
        Failure::Stall => TransportError::Stall,
        Failure::Disconnected(detail) => TransportError::Disconnected(detail),
        Failure::Other { detail, .. } => TransportError::Other(detail),
    }
}

/// A [`BulkTransport`] that passes every call to `T` and records it: each OUT transfer as a host-to-device
/// record, each IN transfer as a device-to-host record (on [`EP_IN`] for responses, [`EP_STREAM`] for stream data), failures (timeout, stall, disconnect, other) as in
/// [`Failure`], reopens as reconnect events. Timeouts asked for are not recorded.
pub struct RecordingTransport<T: BulkTransport, W: Write + Send> {
    inner: T,
    recorder: Recorder<W>,
}

impl<T: BulkTransport, W: Write + Send> RecordingTransport<T, W> {
    /// Records the session on `inner` into `recorder` (started with a DAQ header).
    pub fn new(inner: T, recorder: Recorder<W>) -> Self {
        Self { inner, recorder }
    }

    /// The recorder, to finish the cassette once the session is over.
    pub fn recorder(&self) -> &Recorder<W> {
        &self.recorder
    }

    /// The transport being recorded.
    pub fn inner(&self) -> &T {
        &self.inner
    }
}

impl<T: BulkTransport, W: Write + Send> BulkTransport for RecordingTransport<T, W> {
    fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), TransportError> {
        let result = self.inner.write(bytes, timeout);
        let mut bodies = vec![Body::HostToDevice(bytes.to_vec())];
        if let Err(e) = &result {
            bodies.extend(Failure::from(e).to_bodies());
        }
        self.recorder.record(EP_OUT, bodies);
        result
    }

    fn read(&mut self, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        let result = self.inner.read(timeout);
        let bodies = match &result {
            Ok(bytes) => vec![Body::DeviceToHost(bytes.clone())],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_IN, bodies);
        result
    }

    fn read_stream(&mut self, max_len: usize, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        let result = self.inner.read_stream(max_len, timeout);
        let bodies = match &result {
            Ok(bytes) => vec![Body::DeviceToHost(bytes.clone())],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_STREAM, bodies);
        result
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        let result = self.inner.reopen();
        let bodies = match &result {
            Ok(()) => vec![Body::Event(Event::Reconnect)],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_CONTROL, bodies);
        result
    }
}

/// A [`BulkTransport`] that plays a U6 cassette back to a driver, with [`ReplayFaults`]; commands are matched
/// through [`U6Dialect`] (byte for byte). A deviation stops the driver with
/// `TransportError::Other` carrying the [`Mismatch`], also kept for [`mismatch`](Self::mismatch).
pub struct ReplayTransport {
    engine: ByteReplay,
}

impl std::fmt::Debug for ReplayTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReplayTransport").field("stats", self.engine.stats()).finish_non_exhaustive()
    }
}

impl ReplayTransport {
    /// A replay of `cassette` with `faults`.
    ///
    /// # Errors
    /// [`ReplayError::WrongDevice`] unless the cassette is a DAQ USB session.
    pub fn new(cassette: &Cassette, faults: ReplayFaults) -> Result<Self, ReplayError> {
        let engine = ByteReplay::for_cassette(cassette, DeviceKind::DaqUsb, faults, Box::new(U6Dialect))?;
        Ok(Self { engine })
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

    /// Whether the next recorded call is an IN transfer (the session was reading there).
    pub fn next_is_read(&self) -> bool {
        self.engine.next_is_read()
    }
}

impl BulkTransport for ReplayTransport {
    fn write(&mut self, bytes: &[u8], _timeout: Duration) -> Result<(), TransportError> {
        self.engine.write(bytes).map_err(transport_error)
    }

    fn read(&mut self, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.engine.read().map_err(transport_error)
    }

    fn read_stream(&mut self, _max_len: usize, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.engine.read().map_err(transport_error)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.engine.reopen().map_err(transport_error)
    }
}
