//! One participant's session on the rig: what `metaplate experiment run` does.
//!
//! Before the first trial the full plan is drawn (the seed given, default the file's `order.seed`), hashed and stored
//! ([`Session::start`]: a resume needs the same plan and experiment file, unless forced), and every stimulus is
//! rendered once through the calibration ([`prepare_stimulus`]: pixels snapped to the scan's points, refused off the
//! plate, in a gap or when a drive would clip), its drive hash recorded with each trial. Each trial plays its
//! stimulus on the rig (the onset measured on the loopback), takes a response and is journalled (fsync'd) as it
//! ends. A session killed at any moment resumes at the next trial with the same plan. One process writes a session
//! at a time ([`crate::lock`]): an existing session is locked before anything is rendered, a new one when its
//! directory is created.
//!
//! Times in the journal are on the rig's clock (virtual on the mock lab, where the console's waits for the
//! experimenter are added to it): `scheduled_onset_s` and `measured_onset_s` are the clock at the play's start plus
//! the playback's scheduled and loopback-measured onsets.
//!
//! Responses:
//! - the simulated participant (`sim[:opts]`, [`SimParticipant`]) answers from the predicted peak velocities at the
//!   pixels: the stimulus's target pixels against the others, with the odd pattern of an odd-one-out stimulus
//!   rendered alone (the others null) for that prediction. It plays each presentation once and takes its model's
//!   response time on the rig's clock.
//! - any other id: the experimenter's [`Console`], line-based: the trial number and the response options only
//!   (never the answer); a response key, `r` repeat the stimulus, `u` undo the last answer (an undo entry; that
//!   trial is asked again), `v` void the trial (re-queued at the end), `p` pause. An `until-response` experiment
//!   replays the stimulus every `repeat_pause_s` until an entry. End of input stops the session (resumable).

use std::collections::BTreeMap;
use std::path::Path;

use metaplate_core::audio::AudioConfig;
use metaplate_core::rig::Rig;
use metaplate_store::Dataset;
use serde::Serialize;

use crate::error::ExperimentError;
use crate::file::Experiment;
use crate::journal::{Entry, Session, SessionRecord};
use crate::lock::SessionLock;
use crate::participant::SimParticipant;
use crate::plan::Plan;
use crate::stimulus::{DriveOptions, PreparedStimulus, prepare_stimulus};
use crate::trial::{TrialRun, print_event};

pub use crate::trial::{Console, ConsoleEntry, PAUSE_KEY, REPEAT_KEY, SessionOutput, UNDO_KEY, VOID_KEY};

/// Who answers a session.
pub enum Responder<'a> {
    /// The simulated participant.
    Sim(SimParticipant),
    /// A person, through the experimenter's console.
    Console(&'a mut dyn Console),
}

/// How a session run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionEnd {
    /// Trials answered now.
    pub answered: usize,
    /// Trials in the plan.
    pub trials: usize,
    /// The console's input ended before the session was complete.
    pub stopped: bool,
}

/// A session about to run: its checks done and, for an existing session, its lock held.
pub struct SessionRunner<'a> {
    experiment: &'a Experiment,
    participant: String,
    dataset: &'a Dataset,
    drive: DriveOptions,
    dir: &'a Path,
    plan: Plan,
    seed: u64,
    force: bool,
    sim: Option<SimParticipant>,
    lock: Option<SessionLock>,
}

#[derive(Serialize)]
struct EndEvent<'a> {
    answered: usize,
    dir: &'a Path,
    event: &'static str,
    trials: usize,
}

impl<'a> SessionRunner<'a> {
    /// Checks a session of `experiment` for `participant` (an id, or `sim[:opts]`) in `dir`, with the plan of `seed`
    /// (default the file's), and takes the session's lock when it exists already.
    ///
    /// # Errors
    /// An empty participant, a bad `sim` spec, a response key the console keeps, another participant's session in
    /// `dir` (unless `force`), [`ExperimentError::Locked`] when another process runs the session, and a session whose
    /// journal holds conflicting duplicated answers ([`ExperimentError::ConflictingDuplicates`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        experiment: &'a Experiment,
        participant: &str,
        dataset: &'a Dataset,
        drive: DriveOptions,
        dir: &'a Path,
        seed: Option<u64>,
        force: bool,
    ) -> Result<Self, ExperimentError> {
        let participant = participant.trim().to_owned();
        if participant.is_empty() {
            return Err(ExperimentError::Refused("--participant must not be empty".into()));
        }
        let is_sim = participant == "sim" || participant.starts_with("sim:");
        let sim = if is_sim { Some(SimParticipant::parse(&participant)?) } else { None };
        if sim.is_none() {
            check_console_keys(experiment)?;
        }
        // Locked before anything is read or rendered: a second process is refused at once.
        let lock = SessionLock::acquire_existing(dir)?;
        let plan = Plan::new(experiment, seed.unwrap_or(experiment.order.seed));
        let stored = if lock.is_some() { SessionRecord::read(dir).ok() } else { None };
        if let Some(stored) = &stored {
            if stored.header.participant != participant && !force {
                return Err(ExperimentError::Refused(format!(
                    "{} holds the session of participant `{}`, not `{participant}` (--force to continue it anyway)",
                    dir.display(),
                    stored.header.participant
                )));
            }
            stored.check_duplicates(dir)?;
        }
        // The stimuli's noise is drawn from the plan's seed: a resumed session's (forced, the stored plan's) plays
        // the drives its first trials played.
        let seed = stored.as_ref().map_or(plan.seed, |s| s.header.plan.seed);
        Ok(Self { experiment, participant, dataset, drive, dir, plan, seed, force, sim, lock })
    }

    /// The simulated participant, when it answers (else the console does).
    pub fn simulated(&self) -> Option<SimParticipant> {
        self.sim.clone()
    }

    /// Renders every stimulus (a refusal comes now, with nothing of the session written), starts or resumes the
    /// session and runs its trials on `rig` until it is complete or the console's input ends.
    /// `on_mock_lab`: the rig's clock is the mock lab's virtual clock (the console's waits are added to it).
    ///
    /// # Errors
    /// A stimulus refused ([`prepare_stimulus`]), the masking outputs not opening, the session refused
    /// ([`Session::start`]), a device or journal error during a trial.
    pub fn run(
        self,
        rig: &mut Rig,
        on_mock_lab: bool,
        responder: Responder<'_>,
        out: &mut SessionOutput<'_>,
    ) -> Result<SessionEnd, ExperimentError> {
        let e = self.experiment;
        let mut prepared: BTreeMap<String, PreparedStimulus> = BTreeMap::new();
        for stimulus in &e.stimuli {
            let p =
                prepare_stimulus(self.dataset, &self.drive, e, stimulus, self.seed, &rig.wiring, self.sim.is_some())
                    .map_err(|err| {
                        ExperimentError::Playback(format!("preparing the stimulus `{}`: {err}", stimulus.id))
                    })?;
            prepared.insert(stimulus.id.clone(), p);
        }
        if let Some(m) = &e.masking {
            // The interface must open the masking pair too: asked now, so that a refusal comes with nothing written.
            let channels = prepared.values().map(|p| p.pattern.playback.channels()).max().unwrap_or(0);
            rig.audio.configure(&AudioConfig { channels, ..rig.wiring.audio_config() }).map_err(|err| {
                ExperimentError::Playback(format!(
                    "opening the masking outputs {} and {}: {err}",
                    m.channels[0], m.channels[1]
                ))
            })?;
            writeln!(
                out.log,
                "masking: pink noise on outputs {} and {} at {} dB FS RMS while each stimulus plays",
                m.channels[0], m.channels[1], m.level_dbfs
            )?;
        }
        let dir = self.dir;
        let mut session = Session::start_locked(self.lock, dir, e, &self.participant, self.plan, self.force)
            .map_err(|err| ExperimentError::Refused(format!("starting the session in {}: {err}", dir.display())))?;
        // A forced resume keeps the stored plan: it may name stimuli the given file lacks.
        if let Some(t) = session.header().plan.trials.iter().find(|t| !prepared.contains_key(&t.stimulus_id)) {
            return Err(ExperimentError::Refused(format!(
                "the stored plan plays `{}`, which the experiment file does not have",
                t.stimulus_id
            )));
        }
        let mut answered = answered_stack(&SessionRecord::read(dir)?.entries);
        let total = session.header().plan.trials.len();
        let header = session.header();
        writeln!(
            out.log,
            "{} for `{}`: plan {} ({total} trials, seed {}), session {}",
            header.experiment,
            self.participant,
            header.plan_hash,
            header.plan.seed,
            dir.display()
        )?;
        let mut responder = responder;
        let mut stopped = false;
        while let Some(trial) = session.next_trial().cloned() {
            let done = session.progress().results.iter().filter(|r| r.is_some()).count();
            let stimulus = prepared
                .get(&trial.stimulus_id)
                .ok_or_else(|| ExperimentError::Refused("internal: stimulus not prepared".into()))?;
            let mut trial_run =
                TrialRun { session: &mut session, rig: &mut *rig, trial: &trial, stimulus, number: done + 1, total };
            let next = match &mut responder {
                Responder::Sim(sim) => trial_run.sim(sim, e, out)?,
                Responder::Console(console) => trial_run.console(&mut **console, &mut answered, e, on_mock_lab, out)?,
            };
            if !next {
                stopped = true;
                break;
            }
        }
        let answered_now = session.progress().results.iter().filter(|r| r.is_some()).count();
        if out.json {
            let event = if stopped { "stopped" } else { "finished" };
            print_event(out, &EndEvent { answered: answered_now, dir, event, trials: total })?;
        }
        if stopped {
            writeln!(
                out.log,
                "stopped with {answered_now} of {total} trials answered; the same command resumes at the next trial"
            )?;
        } else {
            writeln!(
                out.log,
                "session complete: {total} trials journalled in {}; `metaplate experiment report {}` reports it",
                dir.display(),
                dir.display()
            )?;
        }
        Ok(SessionEnd { answered: answered_now, trials: total, stopped })
    }
}

/// Refuses an experiment whose response keys are the console's own.
fn check_console_keys(experiment: &Experiment) -> Result<(), ExperimentError> {
    for r in &experiment.responses {
        if [REPEAT_KEY, UNDO_KEY, VOID_KEY, PAUSE_KEY].contains(&r.key.as_str()) {
            return Err(ExperimentError::Refused(format!(
                "the response `{}` uses the key `{}`, which the console keeps for repeat (r), undo (u), void (v) \
                 and pause (p)",
                r.label, r.key
            )));
        }
    }
    Ok(())
}

/// The trials answered and not since undone or voided, in the order they were answered: what `u` undoes.
fn answered_stack(entries: &[Entry]) -> Vec<u32> {
    let mut stack: Vec<u32> = Vec::new();
    for e in entries {
        match e {
            Entry::Trial(r) => {
                stack.retain(|t| *t != r.trial);
                stack.push(r.trial);
            }
            Entry::Undo { trial, .. } | Entry::Void { trial, .. } => stack.retain(|t| t != trial),
            Entry::Correction { .. } | Entry::Forced { .. } => {}
        }
    }
    stack
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;
    use crate::journal::TrialRecord;

    fn answer(trial: u32) -> Entry {
        Entry::Trial(TrialRecord {
            trial,
            stimulus_id: "s".into(),
            drive_hash: "h".into(),
            scheduled_onset_s: 0.0,
            measured_onset_s: None,
            repeats_requested: 0,
            response: "a".into(),
            response_entered_s: 0.0,
            trial_time_s: 0.0,
        })
    }

    #[test]
    fn undo_takes_back_the_last_answer_still_standing() {
        let entries = [answer(0), answer(1), Entry::Undo { trial: 1, entered_s: 0.0 }, answer(2), answer(1)];
        assert_eq!(answered_stack(&entries), [0, 2, 1]);
        let voided = [answer(0), Entry::Void { trial: 0, reason: "cough".into(), entered_s: 0.0 }];
        assert!(answered_stack(&voided).is_empty());
    }

    #[test]
    fn the_console_keys_are_refused_as_response_keys() {
        let mut e = crate::builtin::builtin("pixel-identification").unwrap();
        assert!(check_console_keys(&e).is_ok());
        e.responses[0].key = UNDO_KEY.into();
        let err = check_console_keys(&e).unwrap_err().to_string();
        assert!(err.contains("the key `u`"), "{err}");
    }
}
