//! The mock U6 behind an in-process [`BulkTransport`], with scheduled faults.

use std::time::Duration;

use metaplate_daq::{BulkTransport, TransportError};

use crate::device::MockU6;
use crate::faults::{Fault, FaultSchedule};

/// An in-process bulk transport to a [`MockU6`]. It never blocks: a read with nothing to deliver returns
/// [`TransportError::Timeout`] at once, whatever the timeout, so no test waits.
///
/// A stream read returns as many whole packets as `max_len` holds (at least one). A real U6 ends a USB transfer
/// at a packet shorter than 64 bytes, so it sends several packets per transfer only at 25 samples per packet; the
/// codec and the driver take any number, and the mock's larger transfers keep the mock lab fast.
#[derive(Debug)]
pub struct MockTransport {
    device: MockU6,
    faults: FaultSchedule,
    /// IN transfers attempted so far, on either endpoint (the fault schedule's key).
    reads: u64,
    stall_reads_left: u32,
    drop_next_packet: bool,
    connected: bool,
    written: Vec<Vec<u8>>,
    reopens: u64,
}

impl MockTransport {
    /// A connected transport to `device`, injecting `faults`.
    pub fn new(device: MockU6, faults: FaultSchedule) -> Self {
        Self {
            device,
            faults,
            reads: 0,
            stall_reads_left: 0,
            drop_next_packet: false,
            connected: true,
            written: Vec::new(),
            reopens: 0,
        }
    }

    /// Replaces the fault schedule (keyed by IN-transfer number since the transport was made, so faults at
    /// transfers already made never fire).
    pub fn set_faults(&mut self, faults: FaultSchedule) {
        self.faults = faults;
    }

    /// The device (to inspect its state).
    pub fn device(&self) -> &MockU6 {
        &self.device
    }

    /// The device, mutably (to inject a fault by hand).
    pub fn device_mut(&mut self) -> &mut MockU6 {
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
        TransportError::Disconnected("mock U6 is off the bus".into())
    }

    /// Applies the faults due at this IN transfer; `Err` if the transfer fails.
    fn before_read(&mut self) -> Result<(), TransportError> {
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
                Fault::Overrun { scans } => self.device.overflow(u64::from(scans)),
                Fault::FatalOverrun => self.device.fatal_overflow(),
                Fault::DropPacket => self.drop_next_packet = true,
            }
        }
        if self.stall_reads_left > 0 {
            self.stall_reads_left -= 1;
            return Err(TransportError::Timeout);
        }
        Ok(())
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
        self.before_read()?;
        self.device.next_response().ok_or(TransportError::Timeout)
    }

    fn read_stream(&mut self, max_len: usize, _timeout: Duration) -> Result<Vec<u8>, TransportError> {
        self.before_read()?;
        let packet_len =
            self.device.config().map_or(usize::MAX, |c| metaplate_u6_protocol::packet_len(c.samples_per_packet));
        let mut bytes =
            self.device.next_stream_transfer((max_len / packet_len).max(1)).ok_or(TransportError::Timeout)?;
        if std::mem::take(&mut self.drop_next_packet) {
            bytes.drain(..packet_len.min(bytes.len()));
            if bytes.is_empty() {
                return Err(TransportError::Timeout);
            }
        }
        Ok(bytes)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.connected = true;
        self.reopens += 1;
        Ok(())
    }
}
