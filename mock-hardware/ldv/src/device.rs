//! The controller on its serial link: bytes in, faults applied, bytes out. Shared by the in-process line and the
//! pseudo-terminal server.

use std::sync::Arc;

use metaplate_core::clock::VirtualClock;
use metaplate_polytec_protocol::{Device, PolytecProtocolError, Reply, Request, RequestDecoder, Verb};

use crate::controller::MockController;
use crate::faults::{Fault, FaultSchedule, TimedFaults};

/// The mock controller with its link: decodes host bytes, answers each line (with the scheduled faults), queues
/// the reply bytes, and records what the host sent.
#[derive(Debug)]
pub struct MockDevice {
    controller: MockController,
    decoder: RequestDecoder,
    faults: FaultSchedule,
    lines_received: u64,
    output: Vec<u8>,
    held_back: Option<Vec<u8>>,
    link_up: bool,
    host_log: Vec<u8>,
    clock: Option<Arc<VirtualClock>>,
    timed: Option<Box<dyn TimedFaults>>,
    charge_read_timeouts: bool,
}

impl MockDevice {
    /// `controller` on a working link with `faults`.
    pub fn new(controller: MockController, faults: FaultSchedule) -> Self {
        Self {
            controller,
            decoder: RequestDecoder::new(),
            faults,
            lines_received: 0,
            output: Vec::new(),
            held_back: None,
            link_up: true,
            host_log: Vec::new(),
            clock: None,
            timed: None,
            charge_read_timeouts: false,
        }
    }

    /// Adds faults keyed by simulated time (read from the clock given by [`MockDevice::with_clock`]; without a
    /// clock they are looked up at 0 s). A line-keyed fault of the [`FaultSchedule`] takes precedence.
    pub fn with_timed_faults(mut self, timed: Box<dyn TimedFaults>) -> Self {
        self.timed = Some(timed);
        self
    }

    /// Makes a read that finds no reply cost its timeout in simulated time ([`MockDevice::charge_timeout`]), as
    /// a real port's read would, so that a time-keyed fault window ends while a driver retries.
    pub fn charging_read_timeouts(mut self) -> Self {
        self.charge_read_timeouts = true;
        self
    }

    /// Advances the clock by `timeout_s` if [`MockDevice::charging_read_timeouts`] was set (a read that found
    /// nothing waited that long). Negative or non-finite timeouts advance nothing.
    pub fn charge_timeout(&mut self, timeout_s: f64) {
        if let (true, Some(clock)) = (self.charge_read_timeouts, &self.clock) {
            clock.advance(timeout_s);
        }
    }

    fn now_s(&self) -> f64 {
        use metaplate_core::clock::Clock;
        self.clock.as_ref().map_or(0.0, |c| c.now_s())
    }

    /// Advances `clock` by each request's response time (20 ms for a signal level or a range change, 1 ms for the
    /// rest), so that a session takes about its real duration in simulated time and none in wall time.
    pub fn with_clock(mut self, clock: Arc<VirtualClock>) -> Self {
        self.clock = Some(clock);
        self
    }

    /// The controller, to inspect its state.
    pub fn controller(&self) -> &MockController {
        &self.controller
    }

    /// The controller, to change its state (the beam, a dropout).
    pub fn controller_mut(&mut self) -> &mut MockController {
        &mut self.controller
    }

    /// Every byte the host has written, in order (bytes written while the link was down are not received).
    pub fn host_log(&self) -> &[u8] {
        &self.host_log
    }

    /// Non-empty lines received so far (the index the next line's fault is looked up by).
    pub fn lines_received(&self) -> u64 {
        self.lines_received
    }

    /// Whether the link is up.
    pub fn is_connected(&self) -> bool {
        self.link_up
    }

    /// Brings the link back up (the host reopened the port); bytes in flight are lost. With time-keyed faults, the
    /// link stays down while the device is still absent ([`TimedFaults::may_reconnect`]).
    pub fn reconnect(&mut self) {
        let now_s = self.now_s();
        if self.timed.as_mut().is_some_and(|t| !t.may_reconnect(now_s)) {
            return;
        }
        if !self.link_up {
            self.link_up = true;
            self.decoder.clear();
            self.output.clear();
            self.held_back = None;
        }
    }

    /// Receives host bytes and answers every complete line. Ignored while the link is down.
    pub fn receive(&mut self, bytes: &[u8]) {
        if !self.is_connected() {
            return;
        }
        self.host_log.extend_from_slice(bytes);
        self.decoder.push(bytes);
        while let Some(line) = self.decoder.poll() {
            self.answer(line);
            if !self.is_connected() {
                break;
            }
        }
    }

    /// Takes the bytes queued for the host (empty when there are none or the link is down).
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.output)
    }

    /// Puts bytes back at the front of the output queue (a reader that took more than it could use).
    pub fn unread(&mut self, mut bytes: Vec<u8>) {
        bytes.extend_from_slice(&self.output);
        self.output = bytes;
    }

    fn answer(&mut self, line: Result<Request, PolytecProtocolError>) {
        let index = self.lines_received;
        self.lines_received += 1;
        if let (Some(clock), Ok(request)) = (&self.clock, &line) {
            clock.advance(response_time_s(request));
        }
        let now_s = self.now_s();
        let timed = match self.timed.as_mut().and_then(|t| t.fault_at_time(now_s)) {
            Some(Fault::Dropout { queries }) => {
                // A dropout in progress: this line's own signal query already reads low.
                self.controller.start_dropout(queries);
                None
            }
            other => other,
        };
        let fault = self.faults.fault_at(index).or(timed);
        match fault {
            Some(Fault::Disconnect { power_cycle }) => {
                if power_cycle {
                    self.controller.power_cycle();
                }
                self.link_up = false;
                self.output.clear();
                return;
            }
            // The line is lost on the way: not carried out, not echoed, not answered.
            Some(Fault::NoReply) => return,
            _ => {}
        }
        // With the interface's echo on, the line comes back first (as received, before it takes effect).
        let mut reply = Vec::new();
        if self.controller.echo()
            && let Ok(request) = &line
        {
            reply.extend_from_slice(&Reply::encode(&request.to_string()));
        }
        // A line that does not decode is ignored, as the manual says of invalid settings (OFV-3001 E.2.4).
        if let Some(text) = line.ok().and_then(|request| self.controller.answer(&request)) {
            reply.extend_from_slice(&Reply::encode(&text));
        }
        // A reply held back from the previous line goes out first: it is now stale.
        if let Some(late) = self.held_back.take() {
            self.output.extend_from_slice(&late);
        }
        if reply.is_empty() {
            if let Some(Fault::Dropout { queries }) = fault {
                self.controller.start_dropout(queries);
            }
            return;
        }
        let draw = self.faults.draw(index);
        match fault {
            Some(Fault::LateReply) => self.held_back = Some(reply),
            Some(Fault::GarbledReply) => self.output.extend_from_slice(&garble(reply, draw)),
            Some(Fault::PartialReply) => self.output.extend_from_slice(cut(&reply, draw)),
            Some(Fault::Dropout { queries }) => {
                self.controller.start_dropout(queries);
                self.output.extend_from_slice(&reply);
            }
            None | Some(Fault::NoReply) | Some(Fault::Disconnect { .. }) => self.output.extend_from_slice(&reply),
        }
    }
}

/// Sets the top bit of one byte before the terminator (LF), chosen by `draw`: a lone byte of 0x80 or more is never
/// valid UTF-8, so the line cannot decode.
fn garble(mut reply: Vec<u8>, draw: u64) -> Vec<u8> {
    let content = reply.len().saturating_sub(1).max(1) as u64;
    if let Some(byte) = usize::try_from(draw % content).ok().and_then(|i| reply.get_mut(i)) {
        *byte |= 0x80;
    }
    reply
}

/// A prefix of the reply without its terminator: 1 to (content length) bytes, chosen by `draw`.
fn cut(reply: &[u8], draw: u64) -> &[u8] {
    let content = reply.len().saturating_sub(1).max(1) as u64;
    let len = usize::try_from(1 + draw % content).unwrap_or(1);
    reply.get(..len).unwrap_or(reply)
}

/// The time from a request's terminator to its effect or reply, s: a signal level or range change 20 ms (the
/// decoder settles), anything else 1 ms (a few characters at 115200 baud and the controller's turn-around). The
/// manual gives no figures; these are the order of magnitude a host waits.
fn response_time_s(request: &Request) -> f64 {
    match (request.verb(), request.device(), request.attribute()) {
        (Verb::Get, Device::SignalLevel, _) | (Verb::Set, Device::VeloDec, "Range") => 0.02,
        _ => 0.001,
    }
}
