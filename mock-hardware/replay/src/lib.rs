//! Record and replay of device sessions: transports that write cassettes, and transports that play them back
//! (with faults), so that the real drivers run against a session recorded from a real or a mock device.
//!
//! # Recording
//!
//! [`RecordingLine`] (serial line, LDV), [`RecordingTransport`] (bulk endpoints, DAQ) and [`RecordingSink`]
//! (PCM stream, audio) wrap a real or mock transport, pass every call through unchanged, and write each call and
//! its result to a cassette (`metaplate-cassette`) through a [`Recorder`], stamped with a `Clock`, flushed record
//! by record so that a crash leaves a readable prefix. Endpoints and the encoding of failures: [`script`],
//! [`Failure`].
//!
//! # Replay
//!
//! [`ReplayLine`], [`ReplayTransport`] and [`ReplaySink`] implement the same transport traits from a cassette,
//! so the real driver runs against the recording. Without faults the replay is strict: each driver write must be
//! the next recorded write, byte for byte (a [`Mismatch`] names the record, the expected and received bytes and
//! the first differing byte), and each read gets the next recorded read's bytes or failure; a read where the
//! recording writes (or past its end) is a mismatch too. The mismatch reaches the driver as a disconnect (serial
//! line) or `TransportError::Other` (bulk), so it stops at once.
//!
//! # Faults
//!
//! [`ReplayFaults`] name a cassette record index (counted over the good records, from 0) and a kind. A fault
//! fires once, on the call whose record it names:
//! - on a read: `timeout` / `stall` return that failure and leave the recorded bytes for the next read (a late
//!   reply); `drop` loses the recorded read (the read gets what follows); `garble` flips the top bit of the
//!   middle byte; `truncate` delivers the first half (rounded down) and loses the rest;
//! - on a write: `timeout` / `stall` return that failure, and the recorded write stays next, for the resend;
//! - `disconnect` (read or write): that call and every later one report a disconnect until the driver reopens;
//!   the reopen succeeds without consuming the recording;
//! - on a record that is neither (an event, a note), or one never reached, it does not fire
//!   ([`ReplayStats::faults_applied`] lists those that did).
//!
//! After a fault fires, the replay *recovers*: it expects the driver to retry. While recovering,
//! 1. a driver write that is the last matched recorded write again (a resend) rewinds the replay to just after that write, so the retry gets the recorded reply
//!    again ([`ReplayStats::retries_replayed`]); recovery ends, and recorded reads of that exchange the driver
//!    has not consumed by its next write are skipped (while it waited for the faulted reply it may have read
//!    their like already: a DAQ reads the sample stream while it waits for `Start`'s acknowledgement);
//! 2. else a write that is the next recorded write (skipping recorded reads still pending: late replies the
//!    driver has given up on) continues the session; recovery ends;
//! 3. else a write that repeats an earlier recorded write byte for byte (a setting the LDV driver re-applies
//!    after a reconnect) gets that exchange's recorded replies again, without moving the replay;
//! 4. else the device's [`Dialect`] may answer a command in no recorded exchange ([`ReplayStats::synthesized`];
//!    a Polytec controller's [`PolytecDialect`] makes nothing up);
//! 5. else it is a mismatch;
//! 6. a read with no recorded read next gets a timeout (the device is quiet until the driver sends again)
//!    instead of a mismatch.
//!
//! So a fault the driver's retry logic absorbs (an LDV reply timed out, garbled or cut short: discard what is waiting
//! and resend; a DAQ reply stalled or lost: drain and resend) ends in the same results as the clean replay, and a
//! fault it cannot absorb shows as the driver's typed error (a disconnect; a dropped sample packet as
//! `packets_lost` in the next block's integrity, and one read short at the end of the stream). A U6 command
//! carries no sequence number: a resend is the recorded bytes again ([`U6Dialect`]).
//!
//! # Sessions
//!
//! [`session`] re-runs a recorded LDV, DAQ or audio session through its real driver from the recorded commands
//! alone ([`session::replay`], what `metaplate replay` does), and records short demo sessions against the mock
//! devices. [`summary`] is what `metaplate replay` prints of it: a text summary ([`summary_text`]), the same as one
//! JSON object ([`ReplaySummary`]), and a cassette's records one a line ([`list_text`]). A cassette is read from
//! bytes or a file by [`load_bytes`] / [`load_file`].

mod audio;
mod bulk;
mod dialect;
mod engine;
mod failure;
mod faults;
mod line;
mod load;
mod mismatch;
mod recorder;
pub mod script;
pub mod session;
pub mod summary;

pub use audio::{RecordingSink, ReplaySink};
pub use bulk::{RecordingTransport, ReplayTransport};
pub use dialect::{PolytecDialect, U6Dialect};
pub use engine::{Dialect, ExactDialect, ReplayStats};
pub use failure::Failure;
pub use faults::{FaultKind, FaultSpecError, ReplayFaults};
pub use line::{RecordingLine, ReplayLine};
pub use load::{LoadedCassette, ReplayError, load_bytes, load_file};
pub use mismatch::{Deviation, Mismatch, escape};
pub use recorder::{RecordError, Recorder};
pub use summary::{ReplaySummary, list_text, summary_text};
