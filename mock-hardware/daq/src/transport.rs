//! The mock DAQ behind an in-process [`BulkTransport`], with scheduled faults.

use std::time::Duration;

use metaplate_daq::{BulkTransport, TransportError};
use metaplate_daq_protocol::MAX_FRAME_LEN;

use crate::device::MockDaq;
use crate::faults::{Fault, FaultSchedule};

/// The largest IN transfer the mock sends, bytes: four maximum frames (a real device's bulk buffer is similar).
pub const MAX_TRANSFER_LEN: usize = 4 * MAX_FRAME_LEN;

/// An in-process bulk transport to a [`MockDaq`]. It never blocks: a read with nothing to deliver returns
/// [`TransportError::Timeout`] at once, whatever the timeout, so no test waits.
#[derive(Debug)]
pub struct MockTransport {
    device: MockDaq,
    faults: FaultSchedule,
    /// IN transfers attempted so far (the fault schedule's key).
    reads: u64,
    stall_reads_left: u32,
    connected: bool,
    written: Vec<Vec<u8>>,
    reopens: u64,
}

impl MockTransport {
    /// A connected transport to `device`, injecting `faults`.
    pub fn new(device: MockDaq, faults: FaultSchedule) -> Self {
        Self { device, faults, reads: 0, stall_reads_left: 0, connected: true, written: Vec::new(), reopens: 0 }
    }

    /// The device (to inspect its state).
    pub fn device(&self) -> &MockDaq {
        &self.device
    }

    /// The device, mutably (to inject a fault by hand).
    pub fn device_mut(&mut self) -> &mut MockDaq {
        &mut self.device
    }

    /// Every OUT transfer the host has written, in order.
    pub fn written(&self) -> &[Vec<u8>] {
        &self.written
    }

    /// IN transfers attempted so far.
    pub fn reads(&self) -> u64 {
        self.reads
    }

    /// Whether the device is on the bus.
    pub fn is_connected(&self) -> bool {
        self.connected
    }

    /// Successful reopens.
    pub fn reopens(&self) -> u64 {
        self.reopens
    }

    fn disconnected() -> TransportError {
        TransportError::Disconnected("mock DAQ is off the bus".into())
    }
}

impl BulkTransport for MockTransport {
    fn write(&mut self, bytes: &[u8], _timeout: Duration) -> Result<(), TransportError> {
        if !self.connected {
            return Err(Self::disconnected());
        }
        self.written.push(bytes.to_vec());
        self.device.receive(bytes);
        Ok(())
    }

    fn read(&mut self, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        if !self.connected {
            return Err(Self::disconnected());
        }
        let index = self.reads;
        self.reads += 1;
        let due: Vec<Fault> = self.faults.due(index).collect();
        for fault in due {
            match fault {
                Fault::Stall { reads } => self.stall_reads_left = self.stall_reads_left.max(reads),
                Fault::Disconnect => {
                    self.connected = false;
                    self.stall_reads_left = 0;
                    self.device.power_cycle();
                    return Err(Self::disconnected());
                }
                Fault::Overrun { packets } => self.device.overrun(packets),
                Fault::FatalOverrun => self.device.fatal_overrun(),
            }
        }
        if self.stall_reads_left > 0 {
            self.stall_reads_left -= 1;
            return Err(TransportError::Timeout);
        }
        self.device.next_transfer(MAX_TRANSFER_LEN).ok_or(TransportError::Timeout)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.connected = true;
        self.reopens += 1;
        Ok(())
    }
}
