//! The in-process transport: the driver talks to a [`MockDevice`] through a shared handle, with no I/O and no
//! waiting.

use std::sync::{Arc, Mutex, MutexGuard};

use metaplate_ldv::{LineError, SerialLine};

use crate::device::MockDevice;

/// A [`SerialLine`] wired straight to a [`MockDevice`]. A read returns the bytes the device has queued, or
/// [`LineError::Timeout`] at once when it has none (the device has decided not to answer), so faults cost no wall
/// time. While the device's link is down, every call but a successful [`SerialLine::reopen`] is
/// [`LineError::Disconnected`].
#[derive(Debug, Clone)]
pub struct MockLine {
    device: Arc<Mutex<MockDevice>>,
}

impl MockLine {
    /// A line to `device`; keep a clone of the handle to inspect the device during a test.
    pub fn new(device: Arc<Mutex<MockDevice>>) -> Self {
        Self { device }
    }

    fn device(&self) -> Result<MutexGuard<'_, MockDevice>, LineError> {
        // A panic in another holder poisons the lock; report it as a lost line rather than panicking again.
        self.device.lock().map_err(|_| LineError::Disconnected { reason: "mock device lock poisoned".into() })
    }
}

fn down() -> LineError {
    LineError::Disconnected { reason: "mock link is down".into() }
}

impl SerialLine for MockLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        let mut device = self.device()?;
        if !device.is_connected() {
            return Err(down());
        }
        device.receive(bytes);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout_s: f64) -> Result<usize, LineError> {
        let mut device = self.device()?;
        if !device.is_connected() {
            return Err(down());
        }
        let mut output = device.take_output();
        if output.is_empty() {
            device.charge_timeout(timeout_s);
            return Err(LineError::Timeout);
        }
        let n = output.len().min(buf.len());
        let rest = output.split_off(n);
        buf.get_mut(..n).ok_or(LineError::Timeout)?.copy_from_slice(&output);
        // Put back what did not fit, ahead of anything newer.
        if !rest.is_empty() {
            device.unread(rest);
        }
        Ok(n)
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        let mut device = self.device()?;
        device.reconnect();
        // A device that is still absent (a time-keyed disconnect) cannot be reopened yet.
        if device.is_connected() { Ok(()) } else { Err(down()) }
    }
}
