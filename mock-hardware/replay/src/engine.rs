//! The replay engine shared by the serial line and the bulk transport: recorded calls in, the driver's calls
//! checked against them, with faults.

use std::collections::VecDeque;

use crate::failure::Failure;
use crate::faults::{FaultKind, ReplayFaults};
use metaplate_cassette::{Cassette, DeviceKind};

use crate::load::{ReplayError, check_kind};
use crate::mismatch::{Deviation, Mismatch};
use crate::script::{Step, byte_steps};

/// What a device's protocol lets the replay do beyond byte equality, once an injected fault has made the driver
/// retry: recognise a resent command whose per-attempt fields changed, answer commands the recording cannot
/// answer, and rewrite recorded replies to match.
pub trait Dialect: Send {
    /// Whether the driver's write `got` is the recorded write `recorded`. `recovering` is true after an injected
    /// fault, until the driver is back in step. On a match the dialect may update its translation state.
    ///
    /// # Errors
    /// The driver's bytes in the recording's terms (for the mismatch report), when they differ.
    fn matches(&mut self, recorded: &[u8], got: &[u8], recovering: bool) -> Result<(), Vec<u8>>;

    /// Whether `got` repeats an earlier recorded write exactly enough to be answered with that exchange's
    /// recorded replies, as they were (no state change). Byte equality by default; a dialect whose commands
    /// carry per-attempt fields (the DAQ's sequence numbers) keeps the default, so its earlier exchanges are
    /// never answered again (their replies would name the old sequence number).
    fn same_command(&self, recorded: &[u8], got: &[u8]) -> bool {
        recorded == got
    }

    /// A reply to a command that is in no recorded exchange (such as a resynchronisation), or `None`.
    fn synthesize(&mut self, got: &[u8]) -> Option<Vec<u8>>;

    /// A recorded read, rewritten for the driver (identity unless the dialect translates).
    fn translate_read(&self, recorded: &[u8]) -> Vec<u8>;
}

/// Plain byte equality, no synthesis, no translation.
#[derive(Debug, Clone, Copy, Default)]
pub struct ExactDialect;

impl Dialect for ExactDialect {
    fn matches(&mut self, recorded: &[u8], got: &[u8], _recovering: bool) -> Result<(), Vec<u8>> {
        if recorded == got { Ok(()) } else { Err(got.to_vec()) }
    }

    fn synthesize(&mut self, _got: &[u8]) -> Option<Vec<u8>> {
        None
    }

    fn translate_read(&self, recorded: &[u8]) -> Vec<u8> {
        recorded.to_vec()
    }
}

pub(crate) fn first_difference<T: PartialEq>(a: &[T], b: &[T]) -> Option<usize> {
    a.iter().zip(b).position(|(x, y)| x != y).or((a.len() != b.len()).then(|| a.len().min(b.len())))
}

/// What a replay did, for summaries and tests.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReplayStats {
    /// Recorded calls (writes, reads, reopens) in the cassette.
    pub steps: usize,
    /// Records that are no call (notes, open and close events), ignored.
    pub ignored_records: usize,
    /// Recorded calls played so far (a call replayed again after a retry counts again).
    pub played: usize,
    /// Driver writes matched against recorded ones.
    pub writes_matched: usize,
    /// Faults that fired, with their record index, in order.
    pub faults_applied: Vec<(usize, FaultKind)>,
    /// Driver writes that resent the previous recorded command (a retry), answered again from the recording.
    pub retries_replayed: usize,
    /// Replies the dialect made up for commands in no recorded exchange (resynchronisations).
    pub synthesized: usize,
    /// Reads answered "nothing" (timeout) while the driver recovered from a fault.
    pub quiet_reads: usize,
}

/// The replay state machine over recorded calls (see the crate documentation for the semantics).
pub(crate) struct ByteReplay {
    steps: Vec<Step>,
    records: usize,
    cursor: usize,
    faults: ReplayFaults,
    dialect: Box<dyn Dialect>,
    recovering: bool,
    /// Set by a rewind: the reads of the replayed exchange that the driver does not consume before its next
    /// write (it may have read their like already, while it waited) are skipped.
    skip_unread: bool,
    link_down: bool,
    /// Index (in `steps`) of the last recorded write the driver matched.
    last_write: Option<usize>,
    synthesized: VecDeque<Vec<u8>>,
    mismatch: Option<Mismatch>,
    stats: ReplayStats,
}

impl ByteReplay {
    /// The replay of `cassette`, which must be a session of `kind` (the one constructor of the byte replays: the
    /// LDV line's and the DAQ transport's).
    ///
    /// # Errors
    /// [`ReplayError::WrongDevice`] when the cassette is of another device.
    pub(crate) fn for_cassette(
        cassette: &Cassette,
        kind: DeviceKind,
        faults: ReplayFaults,
        dialect: Box<dyn Dialect>,
    ) -> Result<Self, ReplayError> {
        check_kind(cassette, kind)?;
        let (steps, ignored) = byte_steps(&cassette.records);
        Ok(Self::new(steps, ignored, cassette.records.len(), faults, dialect))
    }

    fn new(
        steps: Vec<Step>,
        ignored_records: usize,
        records: usize,
        faults: ReplayFaults,
        dialect: Box<dyn Dialect>,
    ) -> Self {
        let stats = ReplayStats { steps: steps.len(), ignored_records, ..ReplayStats::default() };
        Self {
            steps,
            records,
            cursor: 0,
            faults,
            dialect,
            recovering: false,
            skip_unread: false,
            link_down: false,
            last_write: None,
            synthesized: VecDeque::new(),
            mismatch: None,
            stats,
        }
    }

    pub(crate) fn mismatch(&self) -> Option<&Mismatch> {
        self.mismatch.as_ref()
    }

    pub(crate) fn stats(&self) -> &ReplayStats {
        &self.stats
    }

    /// Whether every recorded call has been played.
    pub(crate) fn is_finished(&self) -> bool {
        self.cursor >= self.steps.len()
    }

    /// Whether the next recorded call is a read.
    pub(crate) fn next_is_read(&self) -> bool {
        matches!(self.steps.get(self.cursor), Some(Step::Read { .. }))
    }

    /// Takes the fault at `record` (each fault fires once, so a replayed exchange is not faulted again).
    fn take_fault(&mut self, record: usize) -> Option<FaultKind> {
        let kind = self.faults.at(record)?;
        self.faults = std::mem::take(&mut self.faults).without(record);
        self.stats.faults_applied.push((record, kind));
        Some(kind)
    }

    fn fail(&mut self, mismatch: Mismatch) -> Failure {
        let failure = Failure::Other { kind: "replay".into(), detail: mismatch.to_string() };
        self.mismatch.get_or_insert(mismatch);
        failure
    }

    /// A call after a mismatch or while the link is down.
    fn blocked(&self) -> Option<Failure> {
        if let Some(m) = &self.mismatch {
            return Some(Failure::Other { kind: "replay".into(), detail: m.to_string() });
        }
        self.link_down.then(|| Failure::Disconnected("injected disconnect (replay)".into()))
    }

    fn deviation(&self, deviation: Deviation, got: Vec<u8>) -> Mismatch {
        let record = self.steps.get(self.cursor).map_or(self.records, Step::record);
        let deviation = if self.cursor >= self.steps.len() { Deviation::PastEnd } else { deviation };
        Mismatch { deviation, record, expected: Vec::new(), got, first_difference: None }
    }

    pub(crate) fn write(&mut self, got: &[u8]) -> Result<(), Failure> {
        if let Some(failure) = self.blocked() {
            return Err(failure);
        }
        if let Some(Step::Write { record, .. }) = self.steps.get(self.cursor) {
            let record = *record;
            match self.faults.at(record) {
                Some(FaultKind::Disconnect) => {
                    self.take_fault(record);
                    self.link_down = true;
                    return Err(Failure::Disconnected("injected disconnect (replay)".into()));
                }
                // The device did not take the bytes: the recorded write stays next, for the driver's resend.
                Some(kind @ (FaultKind::Timeout | FaultKind::Stall)) => {
                    self.take_fault(record);
                    self.recovering = true;
                    return Err(if kind == FaultKind::Stall {
                        Failure::Stall
                    } else {
                        Failure::Timeout("injected timeout (replay)".into())
                    });
                }
                _ => {}
            }
        }
        if self.recovering {
            // A retry: the driver resent the command of the last exchange; play that exchange's reads again.
            // Checked first, so that a command recorded twice in a row is not mistaken for the next exchange.
            if let Some(index) = self.last_write
                && let Some(Step::Write { bytes, .. }) = self.steps.get(index)
                && self.dialect.matches(bytes, got, true).is_ok()
            {
                self.cursor = index + 1;
                self.recovering = false;
                self.skip_unread = true;
                self.synthesized.clear();
                self.stats.retries_replayed += 1;
                return Ok(());
            }
        }
        // In step: the next recorded call must be this write.
        let next_write = if self.recovering || self.skip_unread {
            // Recorded reads still pending (late or superseded replies, or a replayed exchange's) are skipped.
            self.steps[self.cursor..].iter().position(|s| matches!(s, Step::Write { .. })).map(|p| self.cursor + p)
        } else {
            Some(self.cursor).filter(|&c| matches!(self.steps.get(c), Some(Step::Write { .. })))
        };
        let mut refused = None;
        if let Some(index) = next_write
            && let Some(Step::Write { bytes, failure, .. }) = self.steps.get(index)
        {
            match self.dialect.matches(bytes, got, self.recovering) {
                Ok(()) => {
                    let failure = failure.clone();
                    self.cursor = index + 1;
                    self.last_write = Some(index);
                    self.recovering = false;
                    self.skip_unread = false;
                    self.synthesized.clear();
                    self.stats.played += 1;
                    self.stats.writes_matched += 1;
                    return failure.map_or(Ok(()), Err);
                }
                Err(normalised) => refused = Some((index, bytes.clone(), normalised)),
            }
        }
        if self.recovering {
            // A command the recording made earlier (a setting re-applied after a reconnect): its recorded
            // replies again, without moving the replay.
            if let Some(replies) = self.earlier_exchange(got) {
                self.synthesized.extend(replies);
                self.stats.synthesized += 1;
                return Ok(());
            }
            if let Some(reply) = self.dialect.synthesize(got) {
                self.synthesized.push_back(reply);
                self.stats.synthesized += 1;
                return Ok(());
            }
        }
        let mismatch = match refused {
            Some((index, expected, normalised)) => Mismatch {
                deviation: Deviation::Bytes,
                record: self.steps[index].record(),
                first_difference: first_difference(&expected, &normalised),
                expected,
                got: normalised,
            },
            None => self.deviation(Deviation::UnexpectedWrite, got.to_vec()),
        };
        Err(self.fail(mismatch))
    }

    /// The recorded reads (bytes only, translated) of the latest recorded exchange before the cursor whose
    /// write matches `got`, if any.
    fn earlier_exchange(&self, got: &[u8]) -> Option<Vec<Vec<u8>>> {
        let end = self.cursor.min(self.steps.len());
        let index = (0..end).rev().find(|&i| match &self.steps[i] {
            Step::Write { bytes, failure: None, .. } => self.dialect.same_command(bytes, got),
            _ => false,
        })?;
        let replies = self.steps[index + 1..]
            .iter()
            .take_while(|s| matches!(s, Step::Read { .. }))
            .filter_map(|s| match s {
                Step::Read { result: Ok(bytes), .. } => Some(self.dialect.translate_read(bytes)),
                _ => None,
            })
            .collect();
        Some(replies)
    }

    pub(crate) fn read(&mut self) -> Result<Vec<u8>, Failure> {
        if let Some(failure) = self.blocked() {
            return Err(failure);
        }
        if let Some(reply) = self.synthesized.pop_front() {
            return Ok(reply);
        }
        loop {
            let Some(Step::Read { record, result }) = self.steps.get(self.cursor) else {
                if self.recovering {
                    // The device has nothing more to say until the driver sends again.
                    self.stats.quiet_reads += 1;
                    return Err(Failure::Timeout("nothing to replay while the driver recovers".into()));
                }
                let mismatch = self.deviation(Deviation::UnexpectedRead, Vec::new());
                return Err(self.fail(mismatch));
            };
            let (record, result) = (*record, result.clone());
            let fault = self.take_fault(record);
            if fault.is_some() {
                self.recovering = true;
            }
            match fault {
                Some(FaultKind::Timeout) => return Err(Failure::Timeout("injected timeout (replay)".into())),
                Some(FaultKind::Stall) => return Err(Failure::Stall),
                Some(FaultKind::Disconnect) => {
                    self.link_down = true;
                    return Err(Failure::Disconnected("injected disconnect (replay)".into()));
                }
                Some(FaultKind::Drop) => {
                    self.cursor += 1;
                    continue;
                }
                _ => {}
            }
            self.cursor += 1;
            self.stats.played += 1;
            let mut bytes = self.dialect.translate_read(&result?);
            match fault {
                Some(FaultKind::Garble) => {
                    let middle = bytes.len() / 2;
                    if let Some(b) = bytes.get_mut(middle) {
                        *b ^= 0x80;
                    }
                }
                Some(FaultKind::Truncate) => bytes.truncate(bytes.len() / 2),
                _ => {}
            }
            return Ok(bytes);
        }
    }

    pub(crate) fn reopen(&mut self) -> Result<(), Failure> {
        if let Some(m) = &self.mismatch {
            return Err(Failure::Other { kind: "replay".into(), detail: m.to_string() });
        }
        if self.link_down {
            // The injected disconnect ends; the driver recovers against the recording from the last exchange.
            self.link_down = false;
            self.recovering = true;
            return Ok(());
        }
        match self.steps.get(self.cursor) {
            Some(Step::Reopen { failure, .. }) => {
                let failure = failure.clone();
                self.cursor += 1;
                self.stats.played += 1;
                failure.map_or(Ok(()), Err)
            }
            _ if self.recovering => Ok(()),
            _ => {
                let mismatch = self.deviation(Deviation::UnexpectedReopen, Vec::new());
                Err(self.fail(mismatch))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mismatch::escape;

    #[test]
    fn first_difference_finds_the_byte_or_the_shorter_length() {
        assert_eq!(first_difference(b"abc", b"abc"), None);
        assert_eq!(first_difference(b"abc", b"abd"), Some(2));
        assert_eq!(first_difference(b"ab", b"abc"), Some(2));
        assert_eq!(first_difference(b"", b"x"), Some(0));
        assert_eq!(escape(b"OK\r\x80"), "\"OK\\r\\x80\"");
    }
}
