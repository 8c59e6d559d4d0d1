//! Writes a cassette to any `std::io::Write` record by record, stamping records with a [`Clock`].

use std::io::Write;
use std::sync::{Arc, Mutex};

use metaplate_cassette::{Body, CassetteError, Encoder, Header, Record};
use metaplate_core::clock::Clock;

/// Why recording failed. The session being recorded is never disturbed by it: the recording wrapper keeps
/// passing calls through and reports the first error from `finish`.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Writing the file failed.
    #[error("cassette write failed: {0}")]
    Io(#[from] std::io::Error),
    /// The encoder refused a record (over-long payload, invalid stream block).
    #[error("cassette encoding failed: {0}")]
    Encode(#[from] CassetteError),
    /// The recorder's lock was poisoned by a panic elsewhere.
    #[error("recorder lock poisoned")]
    Poisoned,
}

/// The state behind a recording wrapper.
struct State<W: Write> {
    out: W,
    encoder: Encoder,
    buf: Vec<u8>,
    /// The clock reading at the session start, s.
    start_s: f64,
    last_t_ns: u64,
    /// The first error met; once set, nothing more is written.
    error: Option<RecordError>,
    finished: bool,
}

/// A cassette being written: header first, then each record as it happens, flushed to `W` at once, so that a
/// crash leaves a readable prefix (read back as truncated, every record before the cut intact). Durability
/// against power loss is the writer's business (a `File` may be synced by the caller after `finish`).
///
/// Shared by clones (the recording wrappers hold one; the caller may keep another to finish the cassette while
/// the driver owns the wrapper).
pub struct Recorder<W: Write> {
    state: Arc<Mutex<State<W>>>,
    clock: Arc<dyn Clock>,
}

impl<W: Write> Clone for Recorder<W> {
    fn clone(&self) -> Self {
        Self { state: self.state.clone(), clock: self.clock.clone() }
    }
}

impl<W: Write> std::fmt::Debug for Recorder<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder").finish_non_exhaustive()
    }
}

/// Nanoseconds from `start_s` to `now_s`, rounded, clamped to `u64` and to at least `last_t_ns` (a cassette's
/// timestamps never decrease; a non-finite clock reading repeats the last timestamp).
fn elapsed_ns(start_s: f64, now_s: f64, last_t_ns: u64) -> u64 {
    let ns = ((now_s - start_s) * 1e9).round();
    // `as` saturates: NaN gives 0, huge values u64::MAX.
    let ns = if ns.is_finite() { ns as u64 } else { last_t_ns };
    ns.max(last_t_ns)
}

impl<W: Write> Recorder<W> {
    /// Starts a cassette: writes `header` to `out` and flushes. Record times are measured on `clock` from now.
    ///
    /// # Errors
    /// [`RecordError::Encode`] for an identity field over 255 bytes; [`RecordError::Io`] when writing fails.
    pub fn start(mut out: W, header: &Header, clock: Arc<dyn Clock>) -> Result<Self, RecordError> {
        let mut encoder = Encoder::new();
        let mut buf = Vec::new();
        encoder.header(header, &mut buf)?;
        out.write_all(&buf)?;
        out.flush()?;
        buf.clear();
        let start_s = clock.now_s();
        let state = State { out, encoder, buf, start_s, last_t_ns: 0, error: None, finished: false };
        Ok(Self { state: Arc::new(Mutex::new(state)), clock })
    }

    /// Appends records with these bodies on `endpoint`, all stamped now. After an error, does nothing (the error
    /// is kept for [`finish`](Self::finish)).
    pub(crate) fn record(&self, endpoint: u16, bodies: impl IntoIterator<Item = Body>) {
        let now_s = self.clock.now_s();
        let Ok(mut guard) = self.state.lock() else { return };
        let state = &mut *guard;
        if state.error.is_some() || state.finished {
            return;
        }
        let t_ns = elapsed_ns(state.start_s, now_s, state.last_t_ns);
        state.last_t_ns = t_ns;
        state.buf.clear();
        for body in bodies {
            if let Err(e) = state.encoder.record(&Record { t_ns, endpoint, body }, &mut state.buf) {
                state.error = Some(e.into());
                return;
            }
        }
        if let Err(e) = state.out.write_all(&state.buf).and_then(|()| state.out.flush()) {
            state.error = Some(e.into());
        }
    }

    /// Records written so far.
    pub fn records(&self) -> u64 {
        self.state.lock().map(|s| s.encoder.records()).unwrap_or(0)
    }

    /// Writes the end marker and flushes: the cassette is complete. Idempotent.
    ///
    /// # Errors
    /// The first error met while recording, or while writing the end marker.
    pub fn finish(&self) -> Result<(), RecordError> {
        let mut guard = self.state.lock().map_err(|_| RecordError::Poisoned)?;
        let state = &mut *guard;
        if let Some(error) = state.error.take() {
            return Err(error);
        }
        if state.finished {
            return Ok(());
        }
        state.buf.clear();
        state.encoder.end(&mut state.buf)?;
        state.out.write_all(&state.buf)?;
        state.out.flush()?;
        state.finished = true;
        Ok(())
    }

    /// Runs `f` on the writer (for example to take an in-memory cassette's bytes, or to sync a file).
    ///
    /// # Errors
    /// [`RecordError::Poisoned`] if the lock was poisoned.
    pub fn with_writer<R>(&self, f: impl FnOnce(&mut W) -> R) -> Result<R, RecordError> {
        let mut guard = self.state.lock().map_err(|_| RecordError::Poisoned)?;
        Ok(f(&mut guard.out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_are_monotonic_and_saturate() {
        assert_eq!(elapsed_ns(1.0, 1.5, 0), 500_000_000);
        // A clock that went back, or a NaN reading, repeats the last time.
        assert_eq!(elapsed_ns(1.0, 0.5, 7), 7);
        assert_eq!(elapsed_ns(1.0, f64::NAN, 7), 7);
        assert_eq!(elapsed_ns(0.0, 1e30, 0), u64::MAX);
    }
}
