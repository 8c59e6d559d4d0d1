//! The lab's fault injection on the device links, keyed by the scene's fault windows in virtual time.

use std::sync::Arc;
use std::time::Duration;

use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::scene::FaultKind;
use metaplate_daq::{BulkTransport, TransportError};
use metaplate_mock_audio::{DisconnectTracker, FaultWindows};
use metaplate_mock_daq::MockTransport;
use metaplate_mock_ldv::{Fault, TimedFaults};

use crate::chain::Shared;

/// The LDV's time-keyed faults: `serial_timeout` (no reply), `garbled_reply`, `partial_reply` for every line
/// answered inside their windows; `ldv_dropout` (signal queries read low); `disconnect` (the serial adapter drops
/// off the bus and cannot be reopened before the window's end).
#[derive(Debug)]
pub(crate) struct LdvFaults {
    windows: FaultWindows,
    disconnects: DisconnectTracker,
    dropped: bool,
}

impl LdvFaults {
    pub fn new(windows: &FaultWindows) -> Self {
        Self { windows: windows.clone(), disconnects: DisconnectTracker::new(windows), dropped: false }
    }
}

impl TimedFaults for LdvFaults {
    fn fault_at_time(&mut self, now_s: f64) -> Option<Fault> {
        if self.disconnects.is_away(now_s) {
            if !self.dropped {
                self.dropped = true;
                return Some(Fault::Disconnect { power_cycle: false });
            }
            return None;
        }
        let active = |kind| self.windows.active(kind, now_s).is_some();
        if active(FaultKind::SerialTimeout) {
            Some(Fault::NoReply)
        } else if active(FaultKind::GarbledReply) {
            Some(Fault::GarbledReply)
        } else if active(FaultKind::PartialReply) {
            Some(Fault::PartialReply)
        } else if active(FaultKind::LdvDropout) {
            Some(Fault::Dropout { queries: 1 })
        } else {
            None
        }
    }

    fn may_reconnect(&mut self, now_s: f64) -> bool {
        let back = self.disconnects.reopen(now_s);
        if back {
            self.dropped = false;
        }
        back
    }
}

/// The mock U6's USB link with the scene's faults: `usb_stall` (every read inside the window times out, costing
/// its timeout in virtual time), `daq_overrun` (once per window: the U6's buffer overflows and auto-recovery
/// discards the window's worth of scans, at least one, reported by errorcodes 59 and 60), `disconnect` (the device
/// power-cycles and leaves the bus; reopening fails until the window's end). It also tells the lab when a stream
/// starts (its scan 0 time).
pub(crate) struct LabDaqLink {
    inner: MockTransport,
    clock: Arc<VirtualClock>,
    windows: FaultWindows,
    disconnects: DisconnectTracker,
    dropped: bool,
    overruns_done: Vec<f64>,
    shared: Shared,
}

impl std::fmt::Debug for LabDaqLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LabDaqLink").field("inner", &self.inner).finish_non_exhaustive()
    }
}

impl LabDaqLink {
    pub fn new(inner: MockTransport, clock: Arc<VirtualClock>, windows: &FaultWindows, shared: Shared) -> Self {
        Self {
            inner,
            clock,
            windows: windows.clone(),
            disconnects: DisconnectTracker::new(windows),
            dropped: false,
            overruns_done: Vec::new(),
            shared,
        }
    }

    /// Fails with `Disconnected` while the device is off the bus (power-cycling it when it leaves).
    fn check_bus(&mut self) -> Result<(), TransportError> {
        if self.disconnects.is_away(self.clock.now_s()) {
            if !self.dropped {
                self.dropped = true;
                self.inner.device_mut().power_cycle();
            }
            return Err(TransportError::Disconnected("mock U6 is off the bus".into()));
        }
        Ok(())
    }

    /// A read on either IN endpoint: the bus, a stall, and the overflow due, before the transfer itself.
    fn before_read(&mut self, timeout: Duration) -> Result<(), TransportError> {
        self.check_bus()?;
        let now_s = self.clock.now_s();
        if self.windows.active(FaultKind::UsbStall, now_s).is_some() {
            self.clock.advance(timeout.as_secs_f64());
            return Err(TransportError::Timeout);
        }
        if let Some(fault) = self.windows.active(FaultKind::DaqOverrun, now_s).copied()
            && !self.overruns_done.contains(&fault.at_s)
            && self.inner.device().is_running()
        {
            self.overruns_done.push(fault.at_s);
            if let Some(rate_hz) = self.inner.device().config().map(|c| c.scan_rate_hz()) {
                let scans = (fault.duration_s * rate_hz).ceil().max(1.0);
                // Saturating: a window longer than 2^64 scans is not a scene anyone writes.
                self.inner.device_mut().overflow(scans as u64);
            }
        }
        Ok(())
    }
}

impl BulkTransport for LabDaqLink {
    fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), TransportError> {
        self.check_bus()?;
        let was_running = self.inner.device().is_running();
        self.inner.write(bytes, timeout)?;
        if !was_running && self.inner.device().is_running() {
            // Sample 0 of the new acquisition is taken now.
            let mut state = self.shared.lock().map_err(|e| TransportError::Other(e.to_string()))?;
            state.daq_started();
        }
        Ok(())
    }

    fn read(&mut self, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.before_read(timeout)?;
        self.inner.read(timeout)
    }

    fn read_stream(&mut self, max_len: usize, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.before_read(timeout)?;
        self.inner.read_stream(max_len, timeout)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        if !self.disconnects.reopen(self.clock.now_s()) {
            return Err(TransportError::Disconnected("mock U6 is still off the bus".into()));
        }
        self.dropped = false;
        self.inner.reopen()
    }
}
