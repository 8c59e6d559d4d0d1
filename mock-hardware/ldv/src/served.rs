//! What a pseudo-terminal server needs of a mock device: bytes in, bytes out, and a link that may drop. The mock
//! Polytec controller implements it, and so does the mock Zaber chain (`metaplate-mock-zaber`), which serves itself
//! through this crate's [`crate::PtyServer`].

use crate::device::MockDevice;

/// A mock device served on a byte link.
pub trait ServedDevice: Send + 'static {
    /// Whether the device's link is up.
    fn is_connected(&self) -> bool;
    /// Brings the link back up (the host reopened the port), if the device allows it.
    fn reconnect(&mut self);
    /// Receives host bytes and answers what they complete.
    fn receive(&mut self, bytes: &[u8]);
    /// Takes the bytes queued for the host.
    fn take_output(&mut self) -> Vec<u8>;
}

impl ServedDevice for MockDevice {
    fn is_connected(&self) -> bool {
        MockDevice::is_connected(self)
    }

    fn reconnect(&mut self) {
        MockDevice::reconnect(self);
    }

    fn receive(&mut self, bytes: &[u8]) {
        MockDevice::receive(self, bytes);
    }

    fn take_output(&mut self) -> Vec<u8> {
        MockDevice::take_output(self)
    }
}
