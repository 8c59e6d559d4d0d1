//! A failed transport call, device-neutral, and how it is written into a cassette.
//!
//! A failed call is recorded on the endpoint of the call, right after the call's own record (if it has one), as:
//! - `Event::Timeout` then `Event::Note(detail)` for a timeout;
//! - `Event::Disconnect` then `Event::Note(detail)` for a lost device;
//! - `Event::Note("error <kind>: <detail>")` for anything else (`stall`, `other`, `params`, `state`,
//!   `unavailable`): the cassette model has no event code for these, so the note carries them.
//!
//! The detail note is always written (possibly empty), so a reader never has to guess whether a note belongs to
//! the failure before it.

use metaplate_cassette::{Body, Event};

/// Why a transport call failed, in terms common to the serial line, the bulk transport and the PCM sink.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Failure {
    /// Nothing within the timeout.
    Timeout(String),
    /// The device is gone.
    Disconnected(String),
    /// A USB endpoint stalled.
    Stall,
    /// Any other failure: its kind (a short lowercase word) and detail.
    Other {
        /// `other`, `params`, `state`, `unavailable`, ...
        kind: String,
        /// What the transport said.
        detail: String,
    },
}

/// The prefix of a note that records a failure of another kind than timeout or disconnect.
const ERROR_NOTE: &str = "error ";

impl Failure {
    /// The records (bodies) that describe this failure, in order.
    pub(crate) fn to_bodies(&self) -> Vec<Body> {
        match self {
            Failure::Timeout(detail) => vec![Body::Event(Event::Timeout), note(detail.clone())],
            Failure::Disconnected(detail) => vec![Body::Event(Event::Disconnect), note(detail.clone())],
            Failure::Stall => vec![note(format!("{ERROR_NOTE}stall: "))],
            Failure::Other { kind, detail } => vec![note(format!("{ERROR_NOTE}{kind}: {detail}"))],
        }
    }

    /// Reads a failure from the bodies starting at `bodies[0]`; returns it and how many bodies it took, or `None`
    /// when `bodies[0]` does not start a failure.
    pub(crate) fn from_bodies<'a>(mut bodies: impl Iterator<Item = &'a Body>) -> Option<(Failure, usize)> {
        let detail_of = |next: Option<&Body>| match next {
            Some(Body::Event(Event::Note(text))) if !text.starts_with(ERROR_NOTE) => Some(text.clone()),
            _ => None,
        };
        match bodies.next()? {
            Body::Event(Event::Timeout) => {
                let detail = detail_of(bodies.next());
                let taken = 1 + usize::from(detail.is_some());
                Some((Failure::Timeout(detail.unwrap_or_default()), taken))
            }
            Body::Event(Event::Disconnect) => {
                let detail = detail_of(bodies.next());
                let taken = 1 + usize::from(detail.is_some());
                Some((Failure::Disconnected(detail.unwrap_or_default()), taken))
            }
            Body::Event(Event::Note(text)) => {
                let rest = text.strip_prefix(ERROR_NOTE)?;
                let (kind, detail) = rest.split_once(": ").unwrap_or((rest, ""));
                let failure = if kind == "stall" {
                    Failure::Stall
                } else {
                    Failure::Other { kind: kind.to_owned(), detail: detail.to_owned() }
                };
                Some((failure, 1))
            }
            _ => None,
        }
    }

    /// A one-line description for summaries.
    pub fn describe(&self) -> String {
        match self {
            Failure::Timeout(d) => format!("timeout {d}").trim_end().to_owned(),
            Failure::Disconnected(d) => format!("disconnect {d}").trim_end().to_owned(),
            Failure::Stall => "stall".into(),
            Failure::Other { kind, detail } => format!("{kind}: {detail}"),
        }
    }
}

fn note(text: String) -> Body {
    Body::Event(Event::Note(text))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_failure_reads_back_as_written() {
        let cases = [
            Failure::Timeout(String::new()),
            Failure::Timeout("no reply".into()),
            Failure::Disconnected("unplugged: error 19".into()),
            Failure::Stall,
            Failure::Other { kind: "params".into(), detail: "rate 44100 refused: a: b".into() },
        ];
        for failure in cases {
            let bodies = failure.to_bodies();
            assert_eq!(Failure::from_bodies(bodies.iter()), Some((failure.clone(), bodies.len())), "{failure:?}");
        }
        // A plain note is not a failure; a timeout without its note still is one.
        assert_eq!(Failure::from_bodies([Body::Event(Event::Note("hello".into()))].iter()), None);
        let bare = [Body::Event(Event::Timeout), Body::HostToDevice(vec![1])];
        assert_eq!(Failure::from_bodies(bare.iter()), Some((Failure::Timeout(String::new()), 1)));
    }
}
