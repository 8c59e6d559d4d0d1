//! A byte device's cassette as the sequence of transport calls it recorded.
//!
//! Endpoints: [`EP_OUT`] for host writes (a `HostToDevice` record, or stream blocks for audio), [`EP_IN`] for
//! reads (a `DeviceToHost` record, or a failure), [`EP_STREAM`] for reads of a second IN endpoint (the U6's stream
//! data), [`EP_CONTROL`] for open, close and reopen. A failed call is
//! recorded as described in [`crate::Failure`], on the call's endpoint, right after the call's own record.

use metaplate_cassette::{Body, Event, Record};

use crate::failure::Failure;

/// Endpoint of host-to-device writes (and of submitted audio blocks).
pub const EP_OUT: u16 = 0;
/// Endpoint of device-to-host reads (and of audio waits).
pub const EP_IN: u16 = 1;
/// Endpoint of session control: open, close, reopen.
pub const EP_CONTROL: u16 = 2;
/// Endpoint of reads from a device's second IN endpoint (the U6's StreamData). Replay serves reads of both IN
/// endpoints in recorded order (a driver's calls are sequential); it does not check which endpoint a read asked.
pub const EP_STREAM: u16 = 3;

/// One recorded call of a byte transport.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// The host wrote `bytes`; `failure` if the write failed.
    Write {
        /// Index of its record in the cassette.
        record: usize,
        /// What the host wrote.
        bytes: Vec<u8>,
        /// How the write failed, if it did.
        failure: Option<Failure>,
    },
    /// The host read: bytes or a failure.
    Read {
        /// Index of its record in the cassette.
        record: usize,
        /// What the read returned.
        result: Result<Vec<u8>, Failure>,
    },
    /// The host reopened the transport.
    Reopen {
        /// Index of its record in the cassette.
        record: usize,
        /// How the reopen failed, if it did.
        failure: Option<Failure>,
    },
}

impl Step {
    /// The cassette index of the step's record.
    pub fn record(&self) -> usize {
        match self {
            Step::Write { record, .. } | Step::Read { record, .. } | Step::Reopen { record, .. } => *record,
        }
    }
}

/// The failure recorded right after `records[i]` on the same endpoint, and how many records it took.
fn failure_after(records: &[Record], i: usize, endpoint: u16) -> Option<(Failure, usize)> {
    let rest = records.get(i + 1..)?;
    Failure::from_bodies(rest.iter().take_while(|r| r.endpoint == endpoint).map(|r| &r.body))
}

/// The failure starting at `records[i]`, and how many records it took.
fn failure_at(records: &[Record], i: usize) -> Option<(Failure, usize)> {
    let endpoint = records.get(i)?.endpoint;
    let rest = records.get(i..)?;
    Failure::from_bodies(rest.iter().take_while(|r| r.endpoint == endpoint).map(|r| &r.body))
}

/// The calls of a byte transport (serial line or bulk endpoints) in a cassette's records, and the number of
/// records that are no call (session notes, open and close events, stream blocks), which replay ignores.
pub fn byte_steps(records: &[Record]) -> (Vec<Step>, usize) {
    let mut steps = Vec::new();
    let mut ignored = 0;
    let mut i = 0;
    while i < records.len() {
        let record = &records[i];
        let (step, taken) = match (&record.body, record.endpoint) {
            (Body::HostToDevice(bytes), EP_OUT) => {
                let (failure, extra) = failure_after(records, i, EP_OUT).map_or((None, 0), |(f, n)| (Some(f), n));
                (Some(Step::Write { record: i, bytes: bytes.clone(), failure }), 1 + extra)
            }
            (Body::DeviceToHost(bytes), EP_IN | EP_STREAM) => {
                (Some(Step::Read { record: i, result: Ok(bytes.clone()) }), 1)
            }
            (Body::Event(Event::Reconnect), EP_CONTROL) => (Some(Step::Reopen { record: i, failure: None }), 1),
            (Body::Event(_), EP_IN | EP_STREAM) => match failure_at(records, i) {
                Some((failure, n)) => (Some(Step::Read { record: i, result: Err(failure) }), n),
                None => (None, 1),
            },
            (Body::Event(_), EP_CONTROL) => match failure_at(records, i) {
                Some((failure, n)) => (Some(Step::Reopen { record: i, failure: Some(failure) }), n),
                None => (None, 1),
            },
            _ => (None, 1),
        };
        match step {
            Some(step) => steps.push(step),
            None => ignored += 1,
        }
        i += taken;
    }
    (steps, ignored)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(endpoint: u16, body: Body) -> Record {
        Record { t_ns: 0, endpoint, body }
    }

    #[test]
    fn calls_and_their_failures_are_grouped() {
        let records = vec![
            rec(EP_CONTROL, Body::Event(Event::Open)),
            rec(EP_OUT, Body::HostToDevice(b"Q\r".to_vec())),
            rec(EP_IN, Body::DeviceToHost(b"OK\r".to_vec())),
            rec(EP_OUT, Body::HostToDevice(b"R\r".to_vec())),
            rec(EP_OUT, Body::Event(Event::Disconnect)),
            rec(EP_OUT, Body::Event(Event::Note("gone".into()))),
            rec(EP_IN, Body::Event(Event::Timeout)),
            rec(EP_IN, Body::Event(Event::Note(String::new()))),
            rec(EP_CONTROL, Body::Event(Event::Reconnect)),
        ];
        let (steps, ignored) = byte_steps(&records);
        assert_eq!(ignored, 1, "the open event");
        assert_eq!(
            steps,
            vec![
                Step::Write { record: 1, bytes: b"Q\r".to_vec(), failure: None },
                Step::Read { record: 2, result: Ok(b"OK\r".to_vec()) },
                Step::Write { record: 3, bytes: b"R\r".to_vec(), failure: Some(Failure::Disconnected("gone".into())) },
                Step::Read { record: 6, result: Err(Failure::Timeout(String::new())) },
                Step::Reopen { record: 8, failure: None },
            ]
        );
    }
}
