//! Settling a session's trial after the fact: a correction entry, journalled as the others are (the session's lock
//! taken), that makes one answer count (what a session whose trial two processes answered differently needs,
//! [`crate::duplicates`]).

use crate::error::ExperimentError;
use crate::journal::Entry;

/// Settles `trial` of the session in `dir` with the answer `response` (one of its labels): a correction entry,
/// journalled as the others are (the session's lock taken). Its time is the latest the journal holds.
///
/// # Errors
/// A directory without a session, [`ExperimentError::Locked`], a trial without an answer or a label the experiment
/// does not have ([`ExperimentError::BadEntry`]), writing errors.
pub fn correct(dir: &std::path::Path, trial: u32, response: &str) -> Result<(), ExperimentError> {
    let mut session = crate::journal::Session::open(dir)?;
    let entered_s = session.progress().results.iter().flatten().map(|r| r.response_entered_s).fold(0.0, f64::max);
    session.append(&Entry::Correction { trial, response: response.to_owned(), entered_s })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;
    use crate::builtin::builtin;
    use crate::journal::{Progress, TrialRecord, replay_reading};
    use crate::plan::Plan;

    fn answer(plan: &Plan, trial: u32, response: &str) -> Entry {
        Entry::Trial(TrialRecord {
            trial,
            stimulus_id: plan.trials[trial as usize].stimulus_id.clone(),
            drive_hash: "fnv1a64:0".into(),
            scheduled_onset_s: 0.0,
            measured_onset_s: None,
            repeats_requested: 0,
            response: response.into(),
            response_entered_s: 1.0,
            trial_time_s: 1.0,
        })
    }

    #[test]
    fn duplicates_keep_the_first_answer_and_conflict_until_settled() {
        let e = builtin("pixel-identification").unwrap();
        let plan = Plan::new(&e, 1);
        let labels: Vec<String> = e.labels().iter().map(|l| (*l).to_owned()).collect();
        let (a, b) = (labels[0].as_str(), labels[1].as_str());
        let entries = vec![answer(&plan, 0, a), answer(&plan, 1, a), answer(&plan, 0, a), answer(&plan, 1, b)];
        let (progress, dups) = replay_reading(&plan, &labels, &entries).unwrap();
        assert_eq!(progress.results[1].as_ref().unwrap().response, a, "the first answer counts");
        assert_eq!(dups.len(), 2);
        assert!(!dups[0].conflicts(), "trial 0's duplicates agree");
        assert!(dups[1].conflicts());
        assert_eq!(dups[1].responses, [a, b]);
        // A correction after the duplicates settles the trial; a later duplicate unsettles it again.
        let mut settled = entries.clone();
        settled.push(Entry::Correction { trial: 1, response: b.into(), entered_s: 2.0 });
        let (progress, dups) = replay_reading(&plan, &labels, &settled).unwrap();
        assert!(!dups[1].conflicts());
        assert_eq!(progress.results[1].as_ref().unwrap().response, b);
        settled.push(answer(&plan, 1, a));
        assert!(replay_reading(&plan, &labels, &settled).unwrap().1[1].conflicts());
        // Strict replay still refuses them (a live session never writes a duplicate).
        assert!(Progress::replay(&plan, &labels, &entries).is_err());
    }

    #[test]
    fn both_writers_undoing_one_trial_is_read_as_one_undo() {
        let e = builtin("pixel-identification").unwrap();
        let plan = Plan::new(&e, 1);
        let labels: Vec<String> = e.labels().iter().map(|l| (*l).to_owned()).collect();
        let undo = Entry::Undo { trial: 0, entered_s: 1.0 };
        let entries = vec![answer(&plan, 0, &labels[0]), answer(&plan, 0, &labels[0]), undo.clone(), undo];
        let (progress, dups) = replay_reading(&plan, &labels, &entries).unwrap();
        assert!(progress.results[0].is_none());
        assert!(dups[0].settled);
    }
}
