//! One trial of a session: played on the rig, answered by the simulated participant or at the experimenter's
//! console, journalled (see [`crate::runner`]).

use std::io::Write;
use std::time::{Duration, Instant};

use metaplate_core::rig::Rig;
use serde::Serialize;

use crate::error::ExperimentError;
use crate::file::{Experiment, Presentation};
use crate::journal::{Entry, Session, TrialRecord};
use crate::participant::SimParticipant;
use crate::plan::PlannedTrial;
use crate::stimulus::PreparedStimulus;

/// Console keys of the experimenter's actions (response keys must differ from them).
pub const REPEAT_KEY: &str = "r";
/// Undo the last answer.
pub const UNDO_KEY: &str = "u";
/// Void the current trial.
pub const VOID_KEY: &str = "v";
/// Pause.
pub const PAUSE_KEY: &str = "p";

/// What the experimenter's console gave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ConsoleEntry {
    /// One entry (a line, or a keypad key).
    Line(String),
    /// Nothing within the time asked.
    TimedOut,
    /// The input ended: the session stops (resumable).
    Closed,
}

/// The experimenter's console: where entries come from (the binary reads the terminal and the keypad).
pub trait Console {
    /// The next entry, waiting at most `timeout` (`None`: until one comes or the input ends).
    fn next_entry(&mut self, timeout: Option<Duration>) -> ConsoleEntry;
}

/// Where a session's messages go: one JSON object per event on `events` when asked, the console's text on `log`.
pub struct SessionOutput<'a> {
    /// Standard output: JSON events (with `json`).
    pub events: &'a mut dyn Write,
    /// Print the JSON events.
    pub json: bool,
    /// Standard error: the console's text, progress and warnings.
    pub log: &'a mut dyn Write,
}

/// One JSON event of a session (keys in alphabetical order).
#[derive(Serialize)]
pub(crate) struct TrialEvent<'a> {
    drive_hash: &'a str,
    event: &'static str,
    measured_onset_s: Option<f64>,
    number: usize,
    of: usize,
    repeats_requested: u32,
    response: &'a str,
    scheduled_onset_s: f64,
    trial: u32,
    trial_time_s: f64,
}

#[derive(Serialize)]
struct EntryEvent {
    event: &'static str,
    trial: u32,
}

/// One trial being run.
pub(crate) struct TrialRun<'s> {
    pub(crate) session: &'s mut Session,
    pub(crate) rig: &'s mut Rig,
    pub(crate) trial: &'s PlannedTrial,
    pub(crate) stimulus: &'s PreparedStimulus,
    /// 1-based position among the trials (answered so far + 1).
    pub(crate) number: usize,
    pub(crate) total: usize,
}

impl TrialRun<'_> {
    /// One play on the rig: (scheduled, measured) onset, s on the rig's clock.
    fn play_once(&mut self, log: &mut dyn Write) -> Result<(f64, f64), ExperimentError> {
        let t0 = self.rig.clock.now_s();
        let played = self.stimulus.pattern.play(self.rig)?;
        if played.underruns > 0 || played.gap {
            writeln!(log, "warning: {} audio underrun(s), recording gap: {}", played.underruns, played.gap)?;
        }
        Ok((t0 + played.scheduled_onset_s, t0 + played.measured_onset_s))
    }

    /// Appends a trial's record and prints its event.
    fn journal(&mut self, record: TrialRecord, out: &mut SessionOutput<'_>) -> Result<(), ExperimentError> {
        self.session.append(&Entry::Trial(record.clone()))?;
        if out.json {
            let event = TrialEvent {
                drive_hash: &record.drive_hash,
                event: "trial",
                measured_onset_s: record.measured_onset_s,
                number: self.number,
                of: self.total,
                repeats_requested: record.repeats_requested,
                response: &record.response,
                scheduled_onset_s: record.scheduled_onset_s,
                trial: record.trial,
                trial_time_s: record.trial_time_s,
            };
            print_event(out, &event)?;
        }
        Ok(())
    }

    fn record(&self, scheduled: f64, measured: f64, repeats: u32, response: String, at_s: f64) -> TrialRecord {
        TrialRecord {
            trial: self.trial.index,
            stimulus_id: self.trial.stimulus_id.clone(),
            drive_hash: self.stimulus.drive_hash.clone(),
            scheduled_onset_s: scheduled,
            measured_onset_s: Some(measured),
            repeats_requested: repeats,
            response,
            response_entered_s: at_s,
            trial_time_s: at_s - measured,
        }
    }

    /// The simulated participant's trial; always goes on (true).
    pub(crate) fn sim(
        &mut self,
        sim: &SimParticipant,
        e: &Experiment,
        out: &mut SessionOutput<'_>,
    ) -> Result<bool, ExperimentError> {
        writeln!(out.log, "trial {} of {}", self.number, self.total)?;
        let (scheduled, measured) = self.play_once(out.log)?;
        let field = self.stimulus.field.as_ref().ok_or_else(|| {
            ExperimentError::Refused("internal: no predicted field for the simulated participant".into())
        })?;
        let labels = self.session.header().labels.clone();
        let response = sim.answer(self.trial.index, &self.trial.correct, &labels, field)?.to_owned();
        let trial_time_s = sim.response_time_s(self.trial.index, e.presentation == Presentation::UntilResponse);
        let entered_s = measured + trial_time_s;
        self.rig.clock.sleep_s((entered_s - self.rig.clock.now_s()).max(0.0));
        let mut record = self.record(scheduled, measured, 0, response, entered_s);
        record.trial_time_s = trial_time_s;
        self.journal(record, out)?;
        Ok(true)
    }

    /// The console's trial: false when the console's input ended (stop, resumable).
    pub(crate) fn console(
        &mut self,
        console: &mut dyn Console,
        answered: &mut Vec<u32>,
        e: &Experiment,
        on_mock_lab: bool,
        out: &mut SessionOutput<'_>,
    ) -> Result<bool, ExperimentError> {
        let options: Vec<String> = e.responses.iter().map(|r| format!("{} {}", r.key, r.label)).collect();
        // Blind: the trial number and the options, never the stimulus or the answer.
        writeln!(
            out.log,
            "trial {} of {}: {}   ({REPEAT_KEY} repeat, {UNDO_KEY} undo last, {VOID_KEY} void, {PAUSE_KEY} pause)",
            self.number,
            self.total,
            options.join("  ")
        )?;
        let (scheduled, first_onset) = self.play_once(out.log)?;
        let mut repeats = 0u32;
        let replay_every = (e.presentation == Presentation::UntilResponse)
            .then(|| Duration::from_secs_f64(e.repeat_pause_s.max(0.0) + self.stimulus.pattern.playback.duration_s));
        loop {
            let waiting = Instant::now();
            let line = match console.next_entry(replay_every) {
                ConsoleEntry::Line(line) => line,
                ConsoleEntry::TimedOut => {
                    self.play_once(out.log)?;
                    continue;
                }
                ConsoleEntry::Closed => return Ok(false),
            };
            if on_mock_lab {
                self.rig.clock.sleep_s(waiting.elapsed().as_secs_f64());
            }
            let key = line.trim();
            let now_s = self.rig.clock.now_s();
            if let Some(option) = e.responses.iter().find(|r| r.key == key) {
                let record = self.record(scheduled, first_onset, repeats, option.label.clone(), now_s);
                self.journal(record, out)?;
                answered.push(self.trial.index);
                return Ok(true);
            }
            match key {
                "" => {}
                REPEAT_KEY => {
                    self.rig.clock.sleep_s(e.repeat_pause_s);
                    self.play_once(out.log)?;
                    repeats += 1;
                }
                UNDO_KEY => {
                    let Some(last) = answered.pop() else {
                        writeln!(out.log, "nothing to undo")?;
                        continue;
                    };
                    self.session.append(&Entry::Undo { trial: last, entered_s: now_s })?;
                    writeln!(out.log, "the last answer is undone: that trial is asked again")?;
                    if out.json {
                        print_event(out, &EntryEvent { event: "undo", trial: last })?;
                    }
                    return Ok(true);
                }
                VOID_KEY => {
                    let reason = "voided at the console".into();
                    self.session.append(&Entry::Void { trial: self.trial.index, reason, entered_s: now_s })?;
                    writeln!(out.log, "trial {} of {} void: it is asked again at the end", self.number, self.total)?;
                    if out.json {
                        print_event(out, &EntryEvent { event: "void", trial: self.trial.index })?;
                    }
                    return Ok(true);
                }
                PAUSE_KEY => {
                    writeln!(out.log, "paused: Enter to go on")?;
                    if console.next_entry(None) == ConsoleEntry::Closed {
                        return Ok(false);
                    }
                }
                other => writeln!(
                    out.log,
                    "`{other}` is not a key here: {}, or {REPEAT_KEY} {UNDO_KEY} {VOID_KEY} {PAUSE_KEY}",
                    options.join(", ")
                )?,
            }
        }
    }
}

pub(crate) fn print_event(out: &mut SessionOutput<'_>, event: &impl Serialize) -> Result<(), ExperimentError> {
    let line = serde_json::to_string(event).map_err(|e| ExperimentError::Output(e.to_string()))?;
    writeln!(out.events, "{line}")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    #[test]
    fn trial_events_print_their_keys_in_alphabetical_order() {
        let event = TrialEvent {
            drive_hash: "h",
            event: "trial",
            measured_onset_s: Some(1.0),
            number: 1,
            of: 2,
            repeats_requested: 0,
            response: "left",
            scheduled_onset_s: 0.5,
            trial: 0,
            trial_time_s: 0.25,
        };
        let json = serde_json::to_string(&event).unwrap();
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(serde_json::to_string(&value).unwrap(), json);
    }
}
