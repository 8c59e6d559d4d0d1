//! Trials a journal answers more than once: what two processes writing one session at once left behind (before
//! sessions were locked, [`crate::lock`]). Reading keeps the first answer of a trial and notes every later one; a
//! correction, undo or void of the trial after its duplicates settles it (the answer that counts is then the
//! corrected one, or none). A session whose duplicates agree (one response) continues; one whose unsettled
//! duplicates disagree is refused until each is settled ([`crate::settle::correct`]). Reading them is the
//! journal's (`SessionRecord::read`).

use serde::Serialize;

/// A trial journalled more than once.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DuplicateAnswer {
    /// The trial (index into the plan).
    pub trial: u32,
    /// Every answer journalled for it, in order (the first is the one kept).
    pub responses: Vec<String>,
    /// A correction, undo or void after the duplicates settled it.
    pub settled: bool,
}

impl DuplicateAnswer {
    /// Whether the answers disagree and nothing settled them.
    pub fn conflicts(&self) -> bool {
        !self.settled && self.responses.iter().any(|r| *r != self.responses[0])
    }
}
