//! The in-process transport: the driver talks to a [`MockChain`] through a shared handle, with no I/O.

use std::sync::{Arc, Mutex, MutexGuard};

use metaplate_ldv::{LineError, SerialLine};

use crate::chain::MockChain;

/// A [`SerialLine`] wired straight to a [`MockChain`]. A read returns the bytes the chain has queued, or
/// [`LineError::Timeout`] at once when it has none; while the chain's link is down, every call but a
/// [`SerialLine::reopen`] is [`LineError::Disconnected`].
#[derive(Debug, Clone)]
pub struct ChainLine {
    chain: Arc<Mutex<MockChain>>,
    /// Bytes taken from the chain that did not fit the last read.
    held: Vec<u8>,
}

impl ChainLine {
    /// A line to `chain`; keep a clone of the handle to act on the chain during a test.
    pub fn new(chain: Arc<Mutex<MockChain>>) -> Self {
        Self { chain, held: Vec::new() }
    }

    fn chain(&self) -> Result<MutexGuard<'_, MockChain>, LineError> {
        let chain =
            self.chain.lock().map_err(|_| LineError::Disconnected { reason: "mock chain lock poisoned".into() })?;
        if chain.is_connected() {
            Ok(chain)
        } else {
            Err(LineError::Disconnected { reason: "mock link is down".into() })
        }
    }
}

impl SerialLine for ChainLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        self.chain()?.receive(bytes);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout_s: f64) -> Result<usize, LineError> {
        let output = self.chain()?.take_output();
        self.held.extend(output);
        if self.held.is_empty() {
            return Err(LineError::Timeout);
        }
        let n = self.held.len().min(buf.len());
        buf.get_mut(..n).ok_or(LineError::Timeout)?.copy_from_slice(self.held.get(..n).unwrap_or_default());
        self.held.drain(..n);
        Ok(n)
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        self.held.clear();
        self.chain
            .lock()
            .map_err(|_| LineError::Disconnected { reason: "mock chain lock poisoned".into() })?
            .reconnect();
        Ok(())
    }
}
