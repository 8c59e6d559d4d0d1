//! A session's directory: the plan, stored before the first trial, and the append-only journal of what happened.
//!
//! - `plan.json` ([`SessionHeader`]): the experiment's name, the participant, the experiment file's hash, the plan's
//!   hash and the plan itself; written durably (the store's `write_bytes`: temporary name, fsync, rename,
//!   directory fsync) before the first trial, never rewritten;
//! - `journal.jsonl`: one JSON object per line ([`Entry`]), each written and fsync'd as it happens. Nothing is ever
//!   overwritten: a correction, an undo or a void is a new line. Reading tolerates a torn last line (a kill while
//!   writing it): that line is ignored, and cut off before the next append.
//! - `writer.json`: the pid and host of the process holding the session's lock ([`crate::lock`]); a journal that
//!   answers a trial twice (two writers, before the lock) is read as [`crate::duplicates`] says.
//!
//! Times (`scheduled_onset_s`, `measured_onset_s`, `response_entered_s`) are seconds on the session's clock (the
//! rig's: virtual on the mock lab), `trial_time_s` from the first onset to the response.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::duplicates::DuplicateAnswer;
use crate::error::ExperimentError;
use crate::file::Experiment;
pub use crate::lock::JOURNAL_FILE;
use crate::lock::SessionLock;
use crate::plan::{Phase, Plan, PlannedTrial};

/// The plan file of a session directory.
pub const PLAN_FILE: &str = "plan.json";

/// What `plan.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionHeader {
    /// The experiment's name.
    pub experiment: String,
    /// The participant's id (`P01`, `sim:seed=3`).
    pub participant: String,
    /// Chance level of the experiment (copied so that a report needs only the directory).
    pub chance: f64,
    /// Response labels, in the file's order.
    pub labels: Vec<String>,
    /// Whether trial times are reported.
    pub record_trial_times: bool,
    /// [`Experiment::file_hash`].
    pub file_hash: String,
    /// [`Plan::hash`].
    pub plan_hash: String,
    /// The plan.
    pub plan: Plan,
}

/// One completed trial, as journalled when it ends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    /// Index into the plan.
    pub trial: u32,
    /// The stimulus presented (as planned).
    pub stimulus_id: String,
    /// Hash of the drive signals played (whatever identifies them to the runner, e.g. `fnv1a64:...`).
    pub drive_hash: String,
    /// When the first play was scheduled, s on the session clock.
    pub scheduled_onset_s: f64,
    /// When it started as measured on the loopback, s; `None` when the rig has no loopback.
    pub measured_onset_s: Option<f64>,
    /// Repeats of the stimulus requested by the participant (beyond the planned plays).
    pub repeats_requested: u32,
    /// The response label entered.
    pub response: String,
    /// When the response was entered, s on the session clock.
    pub response_entered_s: f64,
    /// From the first onset to the response, s.
    pub trial_time_s: f64,
}

/// One line of the journal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "kebab-case")]
pub enum Entry {
    /// A trial ended with a response.
    Trial(TrialRecord),
    /// The response of an answered trial is corrected (the experimenter mistyped it).
    Correction {
        /// The trial.
        trial: u32,
        /// The corrected response label.
        response: String,
        /// When the correction was entered, s on the session clock.
        entered_s: f64,
    },
    /// The last answer of a trial is taken back: the trial is asked again, now.
    Undo {
        /// The trial.
        trial: u32,
        /// When, s on the session clock.
        entered_s: f64,
    },
    /// The trial is void (a cough, a finger lifted): its answer, if any, is discarded and it is re-queued at the end.
    Void {
        /// The trial.
        trial: u32,
        /// Why.
        reason: String,
        /// When, s on the session clock.
        entered_s: f64,
    },
    /// The session was resumed with a different plan or experiment file, forced; it continues with the stored plan.
    Forced {
        /// The plan hash given when forcing.
        given_plan_hash: String,
        /// The experiment file hash given when forcing.
        given_file_hash: String,
    },
}

/// Where a session stands: each trial's current answer and the queue of what remains.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Progress {
    /// Per plan trial, its current record (corrections applied), `None` while unanswered, undone or void.
    pub results: Vec<Option<TrialRecord>>,
    /// The order trials are asked in: the plan's, then each voided trial again at the end.
    pub queue: Vec<u32>,
}

impl Progress {
    /// Replays `entries` over `plan`.
    ///
    /// # Errors
    /// [`ExperimentError::BadEntry`] for an entry the plan refuses (see [`Progress::apply`]).
    pub fn replay(plan: &Plan, labels: &[String], entries: &[Entry]) -> Result<Self, ExperimentError> {
        let mut p = Self { results: vec![None; plan.trials.len()], queue: (0..plan.trials.len() as u32).collect() };
        for e in entries {
            p.apply(plan, labels, e)?;
        }
        Ok(p)
    }

    /// Checks `entry` against the plan and the current state and applies it.
    ///
    /// # Errors
    /// [`ExperimentError::BadEntry`]: a trial the plan does not have, a stimulus other than planned, a response
    /// that is not an option, an answer to a trial already answered, a correction or undo of an unanswered trial.
    pub fn apply(&mut self, plan: &Plan, labels: &[String], entry: &Entry) -> Result<(), ExperimentError> {
        let bad = |reason: String| Err(ExperimentError::BadEntry { reason });
        let check_trial = |t: u32| -> Result<&PlannedTrial, ExperimentError> {
            plan.trials.get(t as usize).ok_or_else(|| ExperimentError::BadEntry {
                reason: format!("trial {t} is not in the plan (it has {})", plan.trials.len()),
            })
        };
        let check_label = |r: &str| -> Result<(), ExperimentError> {
            if labels.iter().any(|l| l == r) {
                Ok(())
            } else {
                Err(ExperimentError::BadEntry {
                    reason: format!("`{r}` is not a response option ({})", labels.join(", ")),
                })
            }
        };
        match entry {
            Entry::Trial(r) => {
                let planned = check_trial(r.trial)?;
                if planned.stimulus_id != r.stimulus_id {
                    return bad(format!(
                        "trial {} plays `{}` in the plan, not `{}`",
                        r.trial, planned.stimulus_id, r.stimulus_id
                    ));
                }
                check_label(&r.response)?;
                let slot = &mut self.results[r.trial as usize];
                if slot.is_some() {
                    return bad(format!("trial {} is already answered: correct it, or undo it first", r.trial));
                }
                *slot = Some(r.clone());
            }
            Entry::Correction { trial, response, .. } => {
                check_trial(*trial)?;
                check_label(response)?;
                match &mut self.results[*trial as usize] {
                    Some(r) => r.response.clone_from(response),
                    None => return bad(format!("trial {trial} has no answer to correct")),
                }
            }
            Entry::Undo { trial, .. } => {
                check_trial(*trial)?;
                if self.results[*trial as usize].take().is_none() {
                    return bad(format!("trial {trial} has no answer to undo"));
                }
            }
            Entry::Void { trial, .. } => {
                check_trial(*trial)?;
                self.results[*trial as usize] = None;
                self.queue.push(*trial);
            }
            Entry::Forced { .. } => {}
        }
        Ok(())
    }

    /// The next trial to run, or `None` when the session is complete: the first unanswered trial in queue order,
    /// skipping a queue position that a later void of the same trial superseded.
    pub fn next_trial(&self) -> Option<u32> {
        self.queue.iter().enumerate().find_map(|(pos, &t)| {
            let last = self.queue.iter().rposition(|&q| q == t)?;
            (last == pos && self.results[t as usize].is_none()).then_some(t)
        })
    }
}

/// An open session: its directory, header, journal and progress.
#[derive(Debug)]
pub struct Session {
    dir: PathBuf,
    header: SessionHeader,
    journal: File,
    progress: Progress,
}

impl Session {
    /// Starts a session of `experiment` for `participant` with `plan` in `dir`, or resumes the one there.
    ///
    /// A new directory gets `plan.json` (durably) and an empty journal before this returns. An existing one is
    /// resumed when its stored participant, plan hash and experiment file hash equal these; otherwise the resume is
    /// refused, unless `force`, which appends a [`Entry::Forced`] line and continues with the **stored** plan.
    ///
    /// # Errors
    /// [`ExperimentError::SessionMismatch`] (a different plan or file, not forced); [`ExperimentError::Io`],
    /// [`ExperimentError::Store`], [`ExperimentError::Corrupt`] reading or writing the directory;
    /// [`ExperimentError::BadEntry`] when the stored journal contradicts its plan.
    pub fn start(
        dir: &Path,
        experiment: &Experiment,
        participant: &str,
        plan: Plan,
        force: bool,
    ) -> Result<Self, ExperimentError> {
        Self::start_locked(SessionLock::acquire_existing(dir)?, dir, experiment, participant, plan, force)
    }

    /// As [`Session::start`], with the session's lock taken already (`None`: take it now, creating `dir` for a new
    /// session). A resumed session whose duplicated answers conflict is refused
    /// ([`SessionRecord::check_duplicates`]).
    ///
    /// # Errors
    /// As [`Session::start`]; [`ExperimentError::Locked`]; [`ExperimentError::ConflictingDuplicates`].
    pub fn start_locked(
        lock: Option<SessionLock>,
        dir: &Path,
        experiment: &Experiment,
        participant: &str,
        plan: Plan,
        force: bool,
    ) -> Result<Self, ExperimentError> {
        let lock = match lock {
            Some(lock) => lock,
            None => SessionLock::create(dir)?,
        };
        let journal = lock.into_journal();
        let plan_path = dir.join(PLAN_FILE);
        if !plan_path.exists() {
            let header = SessionHeader {
                experiment: experiment.name.clone(),
                participant: participant.to_owned(),
                chance: experiment.chance,
                labels: experiment.labels().iter().map(|l| (*l).to_owned()).collect(),
                record_trial_times: experiment.record_trial_times,
                file_hash: experiment.file_hash(),
                plan_hash: plan.hash(),
                plan,
            };
            let json = serde_json::to_vec_pretty(&header)
                .map_err(|e| ExperimentError::Store { reason: format!("encoding the plan: {e}") })?;
            // The journal first (the lock created it): a directory with a plan always has a journal next to it.
            let journal_path = dir.join(JOURNAL_FILE);
            journal.sync_all().map_err(ExperimentError::io("fsync", &journal_path))?;
            metaplate_store::write_bytes(dir, PLAN_FILE, &json)?;
            let progress = Progress::replay(&header.plan, &header.labels, &[])?;
            return Ok(Self { dir: dir.to_path_buf(), header, journal, progress });
        }
        let record = SessionRecord::read(dir)?;
        record.check_duplicates(dir)?;
        let given_plan_hash = plan.hash();
        let given_file_hash = experiment.file_hash();
        let mismatch = if record.header.participant != participant {
            Some(("participant", record.header.participant.clone(), participant.to_owned()))
        } else if record.header.file_hash != given_file_hash {
            Some(("experiment file hash", record.header.file_hash.clone(), given_file_hash.clone()))
        } else if record.header.plan_hash != given_plan_hash {
            Some(("plan hash", record.header.plan_hash.clone(), given_plan_hash.clone()))
        } else {
            None
        };
        let journal_path = dir.join(JOURNAL_FILE);
        // Cut a torn last line, so the next entry starts on a line of its own.
        journal.set_len(record.journal_len).map_err(ExperimentError::io("truncate", &journal_path))?;
        let mut session = Self { dir: dir.to_path_buf(), header: record.header, journal, progress: record.progress };
        if let Some((what, stored, given)) = mismatch {
            if !force {
                return Err(ExperimentError::SessionMismatch { dir: dir.to_path_buf(), what, stored, given });
            }
            session.append(&Entry::Forced { given_plan_hash, given_file_hash })?;
        }
        Ok(session)
    }

    /// Opens the existing session in `dir` to append to it, whatever its plan (what `experiment correct` does),
    /// taking its lock.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] for a directory without a session; [`ExperimentError::Locked`]; reading errors.
    pub fn open(dir: &Path) -> Result<Self, ExperimentError> {
        let Some(lock) = SessionLock::acquire_existing(dir)? else {
            return Err(ExperimentError::Refused(format!("{} holds no session", dir.display())));
        };
        let journal = lock.into_journal();
        let record = SessionRecord::read(dir)?;
        let journal_path = dir.join(JOURNAL_FILE);
        journal.set_len(record.journal_len).map_err(ExperimentError::io("truncate", &journal_path))?;
        Ok(Self { dir: dir.to_path_buf(), header: record.header, journal, progress: record.progress })
    }

    /// The session's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The stored header (plan included).
    pub fn header(&self) -> &SessionHeader {
        &self.header
    }

    /// Where the session stands.
    pub fn progress(&self) -> &Progress {
        &self.progress
    }

    /// The next trial to run, `None` when complete.
    pub fn next_trial(&self) -> Option<&PlannedTrial> {
        self.progress.next_trial().and_then(|t| self.header.plan.trials.get(t as usize))
    }

    /// Checks `entry` against the plan, writes it as one line and fsyncs it: when this returns `Ok`, the entry
    /// survives a power cut.
    ///
    /// # Errors
    /// [`ExperimentError::BadEntry`] (nothing is written); [`ExperimentError::Io`] writing or syncing.
    pub fn append(&mut self, entry: &Entry) -> Result<(), ExperimentError> {
        let mut next = self.progress.clone();
        next.apply(&self.header.plan, &self.header.labels, entry)?;
        let mut line = serde_json::to_string(entry)
            .map_err(|e| ExperimentError::BadEntry { reason: format!("cannot encode: {e}") })?;
        line.push('\n');
        let path = self.dir.join(JOURNAL_FILE);
        self.journal.write_all(line.as_bytes()).map_err(ExperimentError::io("append to", &path))?;
        self.journal.sync_data().map_err(ExperimentError::io("fsync", &path))?;
        self.progress = next;
        Ok(())
    }
}

/// A session directory read back (for a report, or to resume).
#[derive(Debug, Clone, PartialEq)]
pub struct SessionRecord {
    /// The stored header.
    pub header: SessionHeader,
    /// Every journal entry, in order (a torn last line left out).
    pub entries: Vec<Entry>,
    /// The progress they make.
    pub progress: Progress,
    /// Whether the journal ended in a torn line.
    pub torn_tail: bool,
    /// Trials journalled more than once (two writers at once, before sessions were locked), in journal order.
    pub duplicates: Vec<DuplicateAnswer>,
    /// Length of the journal's complete lines, bytes.
    journal_len: u64,
}

impl SessionRecord {
    /// Reads `dir`'s plan and journal.
    ///
    /// # Errors
    /// [`ExperimentError::Io`]; [`ExperimentError::Corrupt`] for an unreadable plan or a bad line other than the
    /// last; [`ExperimentError::BadEntry`] when the journal contradicts the plan.
    pub fn read(dir: &Path) -> Result<Self, ExperimentError> {
        let plan_path = dir.join(PLAN_FILE);
        let text = std::fs::read_to_string(&plan_path).map_err(ExperimentError::io("read", &plan_path))?;
        let header: SessionHeader = serde_json::from_str(&text).map_err(|e| ExperimentError::Corrupt {
            path: plan_path.clone(),
            line: e.line(),
            reason: e.to_string(),
        })?;
        let journal_path = dir.join(JOURNAL_FILE);
        let text = std::fs::read(&journal_path).map_err(ExperimentError::io("read", &journal_path))?;
        let (entries, journal_len, torn_tail) = parse_journal(&text, &journal_path)?;
        let (progress, duplicates) = replay_reading(&header.plan, &header.labels, &entries)?;
        Ok(Self { header, entries, progress, torn_tail, duplicates, journal_len })
    }

    /// Refuses a session whose duplicated answers disagree and are not settled (see [`crate::duplicates`]).
    ///
    /// # Errors
    /// [`ExperimentError::ConflictingDuplicates`] naming each such trial and its answers.
    pub fn check_duplicates(&self, dir: &Path) -> Result<(), ExperimentError> {
        let conflicts: Vec<String> = self
            .duplicates
            .iter()
            .filter(|d| d.conflicts())
            .map(|d| format!("trial {} ({})", d.trial, d.responses.join(", ")))
            .collect();
        if conflicts.is_empty() {
            return Ok(());
        }
        Err(ExperimentError::ConflictingDuplicates { dir: dir.to_path_buf(), trials: conflicts.join(", ") })
    }

    /// The scored trials that have an answer, with their plan entries, in plan order.
    pub fn scored(&self) -> Vec<(&PlannedTrial, &TrialRecord)> {
        self.header
            .plan
            .trials
            .iter()
            .zip(&self.progress.results)
            .filter(|(p, _)| p.phase == Phase::Trials)
            .filter_map(|(p, r)| r.as_ref().map(|r| (p, r)))
            .collect()
    }
}

/// Replays `entries` over `plan` as [`Progress::replay`] does, except that an answer to a trial already answered (and
/// an undo of a trial whose answer a duplicate's undo already took back) is noted rather than refused.
///
/// # Errors
/// [`ExperimentError::BadEntry`] for any other entry the plan refuses.
pub fn replay_reading(
    plan: &Plan,
    labels: &[String],
    entries: &[Entry],
) -> Result<(Progress, Vec<DuplicateAnswer>), ExperimentError> {
    let mut progress = Progress::replay(plan, labels, &[])?;
    let mut duplicates: Vec<DuplicateAnswer> = Vec::new();
    for entry in entries {
        let answered = |t: u32| progress.results.get(t as usize).and_then(Option::as_ref);
        match entry {
            Entry::Trial(r) if answered(r.trial).is_some() => {
                let first = answered(r.trial).map(|a| a.response.clone()).unwrap_or_default();
                match duplicates.iter_mut().find(|d| d.trial == r.trial) {
                    Some(d) => {
                        d.responses.push(r.response.clone());
                        d.settled = false;
                    }
                    None => duplicates.push(DuplicateAnswer {
                        trial: r.trial,
                        responses: vec![first, r.response.clone()],
                        settled: false,
                    }),
                }
                continue;
            }
            Entry::Undo { trial, .. } if answered(*trial).is_none() && duplicates.iter().any(|d| d.trial == *trial) => {
                continue;
            }
            Entry::Correction { trial, .. } | Entry::Undo { trial, .. } | Entry::Void { trial, .. } => {
                if let Some(d) = duplicates.iter_mut().find(|d| d.trial == *trial) {
                    d.settled = true;
                }
            }
            Entry::Trial(_) | Entry::Forced { .. } => {}
        }
        progress.apply(plan, labels, entry)?;
    }
    Ok((progress, duplicates))
}

/// The entries of a journal's bytes, the length of its complete lines, and whether a torn last line was left out.
fn parse_journal(bytes: &[u8], path: &Path) -> Result<(Vec<Entry>, u64, bool), ExperimentError> {
    let mut entries = Vec::new();
    let mut offset = 0usize;
    let mut line_no = 0usize;
    while offset < bytes.len() {
        line_no += 1;
        let rest = &bytes[offset..];
        let Some(end) = rest.iter().position(|&b| b == b'\n') else {
            // No newline: the last line was being written when the process died.
            return Ok((entries, offset as u64, true));
        };
        let parsed = std::str::from_utf8(&rest[..end])
            .map_err(|e| e.to_string())
            .and_then(|s| serde_json::from_str::<Entry>(s).map_err(|e| e.to_string()));
        match parsed {
            Ok(e) => entries.push(e),
            // A complete but unreadable last line is torn too (a partial write padded by the file system).
            Err(_) if offset + end + 1 == bytes.len() => return Ok((entries, offset as u64, true)),
            Err(reason) => return Err(ExperimentError::Corrupt { path: path.to_path_buf(), line: line_no, reason }),
        }
        offset += end + 1;
    }
    Ok((entries, offset as u64, false))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use std::fs::OpenOptions;

    use super::*;
    use crate::builtin::builtin;

    fn record(plan: &Plan, trial: u32, response: &str) -> Entry {
        Entry::Trial(TrialRecord {
            trial,
            stimulus_id: plan.trials[trial as usize].stimulus_id.clone(),
            drive_hash: "fnv1a64:0".into(),
            scheduled_onset_s: f64::from(trial),
            measured_onset_s: Some(f64::from(trial) + 0.005),
            repeats_requested: 0,
            response: response.into(),
            response_entered_s: f64::from(trial) + 1.0,
            trial_time_s: 1.0,
        })
    }

    #[test]
    fn resume_continues_at_the_next_trial_and_voids_are_requeued_at_the_end() {
        let dir = tempfile::tempdir().unwrap();
        let e = builtin("pixel-identification").unwrap();
        let plan = Plan::new(&e, 5);
        let mut s = Session::start(dir.path(), &e, "P01", plan.clone(), false).unwrap();
        assert_eq!(s.next_trial().unwrap().index, 0);
        s.append(&record(&plan, 0, "thumb")).unwrap();
        s.append(&record(&plan, 1, "index")).unwrap();
        s.append(&Entry::Void { trial: 1, reason: "cough".into(), entered_s: 3.0 }).unwrap();
        s.append(&record(&plan, 2, "ring")).unwrap();
        s.append(&Entry::Undo { trial: 2, entered_s: 4.0 }).unwrap();
        assert_eq!(s.next_trial().unwrap().index, 2);
        s.append(&record(&plan, 2, "middle")).unwrap();
        s.append(&Entry::Correction { trial: 0, response: "little".into(), entered_s: 5.0 }).unwrap();
        // Refused entries write nothing.
        assert!(matches!(s.append(&record(&plan, 0, "thumb")), Err(ExperimentError::BadEntry { .. })));
        assert!(matches!(s.append(&record(&plan, 3, "elbow")), Err(ExperimentError::BadEntry { .. })));
        let mut unplanned = record(&plan, 3, "thumb");
        if let Entry::Trial(r) = &mut unplanned {
            r.trial = 999;
        }
        assert!(matches!(s.append(&unplanned), Err(ExperimentError::BadEntry { .. })));
        let undo_unanswered = Entry::Undo { trial: 4, entered_s: 6.0 };
        assert!(matches!(s.append(&undo_unanswered), Err(ExperimentError::BadEntry { .. })));
        drop(s);

        let mut s = Session::start(dir.path(), &e, "P01", plan.clone(), false).unwrap();
        assert_eq!(s.next_trial().unwrap().index, 3);
        for t in 3..plan.trials.len() as u32 {
            s.append(&record(&plan, t, "thumb")).unwrap();
        }
        // The voided trial comes last.
        assert_eq!(s.next_trial().unwrap().index, 1);
        s.append(&record(&plan, 1, "index")).unwrap();
        assert!(s.next_trial().is_none());
        let r = SessionRecord::read(dir.path()).unwrap();
        assert_eq!(r.progress.results[0].as_ref().unwrap().response, "little");
        assert_eq!(r.progress.results[2].as_ref().unwrap().response, "middle");
        assert_eq!(r.scored().len(), 50);
        assert!(!r.torn_tail);
    }

    /// Runs `session` to its end (or `stop_after` trials) with a simulated participant; answers and times depend
    /// only on the trial.
    fn answer_all(session: &mut Session, stop_after: usize) {
        let sim = crate::participant::SimParticipant::parse("sim:seed=4").unwrap();
        let field = crate::participant::FieldAtPixels { target_peak_m_s: vec![1e-3], other_peak_m_s: vec![4e-4] };
        let labels = session.header().labels.clone();
        for _ in 0..stop_after {
            let Some(t) = session.next_trial().cloned() else { return };
            let mut entry =
                record(&session.header().plan, t.index, sim.answer(t.index, &t.correct, &labels, &field).unwrap());
            if let Entry::Trial(r) = &mut entry {
                r.trial_time_s = sim.response_time_s(t.index, false);
            }
            session.append(&entry).unwrap();
        }
    }

    #[test]
    fn a_session_killed_mid_write_and_resumed_equals_an_uninterrupted_one() {
        let e = builtin("multi-touch-odd-one-out").unwrap();
        let plan = Plan::new(&e, 11);
        let whole = tempfile::tempdir().unwrap();
        answer_all(&mut Session::start(whole.path(), &e, "sim", plan.clone(), false).unwrap(), usize::MAX);
        let split = tempfile::tempdir().unwrap();
        answer_all(&mut Session::start(split.path(), &e, "sim", plan.clone(), false).unwrap(), 23);
        // The kill: half a line written.
        let mut f = OpenOptions::new().append(true).open(split.path().join(JOURNAL_FILE)).unwrap();
        f.write_all(b"{\"event\":\"trial\",\"tri").unwrap();
        drop(f);
        answer_all(&mut Session::start(split.path(), &e, "sim", plan.clone(), false).unwrap(), usize::MAX);
        let (a, b) = (SessionRecord::read(whole.path()).unwrap(), SessionRecord::read(split.path()).unwrap());
        assert_eq!(a.progress, b.progress);
        assert_eq!(a.entries, b.entries);
        assert_eq!(
            std::fs::read(whole.path().join(JOURNAL_FILE)).unwrap(),
            std::fs::read(split.path().join(JOURNAL_FILE)).unwrap()
        );
        assert_eq!(a.scored().len(), 50);
    }

    #[test]
    fn a_torn_last_line_is_ignored_and_cut_before_the_next_append() {
        let dir = tempfile::tempdir().unwrap();
        let e = builtin("motion-direction").unwrap();
        let plan = Plan::new(&e, 5);
        let mut s = Session::start(dir.path(), &e, "P01", plan.clone(), false).unwrap();
        s.append(&record(&plan, 0, "leftward")).unwrap();
        drop(s);
        let path = dir.path().join(JOURNAL_FILE);
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"{\"event\":\"trial\",\"trial\":1,\"stim").unwrap();
        drop(f);
        let r = SessionRecord::read(dir.path()).unwrap();
        assert!(r.torn_tail);
        assert_eq!(r.entries.len(), 1);
        let mut s = Session::start(dir.path(), &e, "P01", plan.clone(), false).unwrap();
        assert_eq!(s.next_trial().unwrap().index, 1);
        s.append(&record(&plan, 1, "rightward")).unwrap();
        let r = SessionRecord::read(dir.path()).unwrap();
        assert!(!r.torn_tail);
        assert_eq!(r.entries.len(), 2);

        // A bad line in the middle is corruption, not a torn tail.
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, format!("garbage\n{text}")).unwrap();
        assert!(matches!(SessionRecord::read(dir.path()), Err(ExperimentError::Corrupt { line: 1, .. })));
    }

    #[test]
    fn a_different_plan_or_file_is_refused_unless_forced() {
        let dir = tempfile::tempdir().unwrap();
        let e = builtin("pixel-identification").unwrap();
        Session::start(dir.path(), &e, "P01", Plan::new(&e, 5), false).unwrap();
        let other_seed = Session::start(dir.path(), &e, "P01", Plan::new(&e, 6), false);
        assert!(matches!(other_seed, Err(ExperimentError::SessionMismatch { what: "plan hash", .. })));
        let mut changed = e.clone();
        changed.repeat_pause_s = 1.0;
        let other_file = Session::start(dir.path(), &changed, "P01", Plan::new(&changed, 5), false);
        assert!(matches!(other_file, Err(ExperimentError::SessionMismatch { what: "experiment file hash", .. })));
        let other_participant = Session::start(dir.path(), &e, "P02", Plan::new(&e, 5), false);
        assert!(matches!(other_participant, Err(ExperimentError::SessionMismatch { what: "participant", .. })));
        let forced = Session::start(dir.path(), &e, "P01", Plan::new(&e, 6), true).unwrap();
        assert_eq!(forced.header().plan, Plan::new(&e, 5));
        let r = SessionRecord::read(dir.path()).unwrap();
        assert!(matches!(r.entries[..], [Entry::Forced { .. }]));
    }
}
