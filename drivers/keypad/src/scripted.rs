//! [`ScriptedHid`]: a keypad that plays a script of reports on a virtual clock, the fake device of the tests (as
//! probe-rs has a fake probe) and of rehearsals without a pad. It goes through the same [`Keypad`] driver as a
//! real device.
//!
//! [`Keypad`]: crate::Keypad

use std::collections::VecDeque;
use std::sync::Arc;

use metaplate_core::clock::VirtualClock;

use crate::transport::{HidInput, TransportError};

/// What the scripted device does on one read.
#[derive(Debug)]
pub enum ScriptStep {
    /// Deliver `bytes` (one raw report) `after_s` seconds after the previous step; a read with a shorter timeout
    /// times out, and the rest of the wait carries over to the next read.
    Report {
        /// Delay from the previous step, s.
        after_s: f64,
        /// The raw report.
        bytes: Vec<u8>,
    },
    /// Fail the read with this error (for example a disconnection, which suggests a reopen).
    Fail(TransportError),
}

impl ScriptStep {
    /// A boot keyboard report (modifiers, reserved, six key slots) `after_s` seconds after the previous step.
    pub fn boot_report(after_s: f64, bytes: [u8; 8]) -> Self {
        Self::Report { after_s, bytes: bytes.to_vec() }
    }
}

/// A transport that plays a script, advancing a virtual clock as time passes on the device side. Once the script
/// is played, every read times out after its full timeout.
#[derive(Debug)]
pub struct ScriptedHid {
    clock: Arc<VirtualClock>,
    script: VecDeque<ScriptStep>,
    /// Timeouts the driver asked for, s, in order.
    pub timeouts_s: Vec<f64>,
    /// How many times the driver reopened the device.
    pub reopens: usize,
}

impl ScriptedHid {
    /// A device playing `script` on `clock`.
    pub fn new(clock: &Arc<VirtualClock>, script: Vec<ScriptStep>) -> Self {
        Self { clock: Arc::clone(clock), script: script.into(), timeouts_s: Vec::new(), reopens: 0 }
    }
}

impl HidInput for ScriptedHid {
    fn describe(&self) -> (String, String, String) {
        ("Scripted".into(), "Pad".into(), "0001".into())
    }

    fn read_report(&mut self, timeout_s: f64) -> Result<Option<Vec<u8>>, TransportError> {
        self.timeouts_s.push(timeout_s);
        match self.script.pop_front() {
            Some(ScriptStep::Report { after_s, bytes }) if after_s <= timeout_s => {
                self.clock.advance(after_s);
                Ok(Some(bytes))
            }
            Some(ScriptStep::Report { after_s, bytes }) => {
                // Not yet: the report stays in the script, later by the time waited.
                self.script.push_front(ScriptStep::Report { after_s: after_s - timeout_s, bytes });
                self.clock.advance(timeout_s);
                Ok(None)
            }
            Some(ScriptStep::Fail(error)) => Err(error),
            None => {
                self.clock.advance(timeout_s);
                Ok(None)
            }
        }
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.reopens += 1;
        Ok(())
    }
}
