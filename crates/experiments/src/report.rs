//! The report of session directories of one experiment (`metaplate experiment report`): per participant and
//! condition, accuracy with a Wilson 95 % interval, the exact one-sided binomial p against chance, the confusion
//! matrix, trial times where recorded, pooled over participants; as JSON, text tables, Parquet (one row per scored
//! trial, [`crate::trials_parquet`]) and the accuracy figure.
//!
//! The JSON keys are in alphabetical order (every struct here declares its fields so).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::duplicates::DuplicateAnswer;
use crate::error::ExperimentError;
use crate::journal::{SessionRecord, TrialRecord};
use crate::plan::PlannedTrial;
use crate::stats::{Confusion, binomial_p_at_least, wilson_95};

/// The report of one experiment's sessions.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SessionReport {
    /// Accuracy by guessing.
    pub chance: f64,
    /// The experiment's name.
    pub experiment: String,
    /// The experiment file's hash.
    pub file_hash: String,
    /// One row per session directory, in the order given.
    pub participants: Vec<ParticipantRow>,
    /// Every session's scored trials together.
    pub pooled: PooledRow,
    /// Whether trial times are reported (the plan's `record_trial_times`).
    #[serde(skip)]
    pub times: bool,
}

/// Accuracy statistics of a set of scored trials; accuracy, interval and p are `None` without scored trials.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Score {
    accuracy: Option<f64>,
    correct: u64,
    log10_p_value: Option<f64>,
    p_value: Option<f64>,
    scored_trials: u64,
    wilson_95: Option<[f64; 2]>,
}

/// One participant's session.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParticipantRow {
    /// Fraction correct.
    pub accuracy: Option<f64>,
    /// Every planned trial answered.
    pub complete: bool,
    /// Per condition.
    pub conditions: Vec<ConditionRow>,
    /// Presented by answered.
    pub confusion: ConfusionCounts,
    /// Scored trials answered correctly.
    pub correct: u64,
    /// The session directory.
    pub dir: String,
    /// Trials journalled more than once (two writers at once, before sessions were locked): every answer, the first
    /// the one counted unless a later correction settled it. Absent when there are none.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub duplicated_trials: Vec<DuplicateRow>,
    /// The participant's id.
    pub id: String,
    /// log10 of `p_value` (finite where `p_value` underflows).
    pub log10_p_value: Option<f64>,
    /// Exact one-sided binomial p against chance.
    pub p_value: Option<f64>,
    /// Scored trials in the plan.
    pub planned_scored_trials: usize,
    /// Scored trials answered.
    pub scored_trials: u64,
    /// Wilson 95 % interval of the accuracy.
    pub wilson_95: Option<[f64; 2]>,
}

/// A trial journalled more than once, in a participant's row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DuplicateRow {
    /// The answer the report counts (`None`: the trial has no answer now, undone or void).
    pub counted: Option<String>,
    /// Every answer journalled, in order.
    pub responses: Vec<String>,
    /// A correction, undo or void after the duplicates settled it.
    pub settled: bool,
    /// The trial (index into the plan).
    pub trial: u32,
}

/// Every session's scored trials together.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PooledRow {
    /// Fraction correct.
    pub accuracy: Option<f64>,
    /// Per condition.
    pub conditions: Vec<ConditionRow>,
    /// Presented by answered.
    pub confusion: ConfusionCounts,
    /// Scored trials answered correctly.
    pub correct: u64,
    /// log10 of `p_value`.
    pub log10_p_value: Option<f64>,
    /// Exact one-sided binomial p against chance.
    pub p_value: Option<f64>,
    /// Scored trials answered.
    pub scored_trials: u64,
    /// Wilson 95 % interval.
    pub wilson_95: Option<[f64; 2]>,
}

/// One condition (stimulus) of a row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionRow {
    /// Fraction correct.
    pub accuracy: Option<f64>,
    /// Answered correctly.
    pub correct: u64,
    /// The right answer.
    pub correct_response: String,
    /// log10 of `p_value`.
    pub log10_p_value: Option<f64>,
    /// Exact one-sided binomial p against chance.
    pub p_value: Option<f64>,
    /// Scored trials answered.
    pub scored_trials: u64,
    /// The stimulus.
    pub stimulus_id: String,
    /// Trial times, s (only where the plan records them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trial_time_s: Option<TrialTimes>,
    /// Wilson 95 % interval.
    pub wilson_95: Option<[f64; 2]>,
}

/// Trial-time statistics of a condition, s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrialTimes {
    /// Longest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: Option<f64>,
    /// Shortest.
    pub min: f64,
}

/// A confusion matrix: rows presented, columns answered, in the labels' order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConfusionCounts {
    /// The response labels.
    pub labels: Vec<String>,
    /// Counts, `[presented][answered]`.
    pub presented_by_answered: Vec<Vec<u64>>,
}

type Scored<'a> = (&'a PlannedTrial, &'a TrialRecord);

impl Score {
    fn of(trials: &[Scored<'_>], chance: f64) -> Result<Self, ExperimentError> {
        let scored = trials.len() as u64;
        let correct = trials.iter().filter(|(p, r)| p.correct == r.response).count() as u64;
        if scored == 0 {
            return Ok(Self {
                accuracy: None,
                correct: 0,
                log10_p_value: None,
                p_value: None,
                scored_trials: 0,
                wilson_95: None,
            });
        }
        let (accuracy, wilson) = wilson_95(correct, scored)?;
        let (p, log10_p) = binomial_p_at_least(correct, scored, chance)?;
        Ok(Self {
            accuracy: Some(accuracy),
            correct,
            log10_p_value: Some(log10_p),
            p_value: Some(p),
            scored_trials: scored,
            wilson_95: Some(wilson),
        })
    }
}

/// The per-condition rows and the confusion matrix of `trials`.
fn detail(
    trials: &[Scored<'_>],
    labels: &[String],
    chance: f64,
    times: bool,
) -> Result<(Vec<ConditionRow>, ConfusionCounts), ExperimentError> {
    let mut by_condition: BTreeMap<(u32, &str), Vec<Scored<'_>>> = BTreeMap::new();
    for &(p, r) in trials {
        by_condition.entry((p.condition, p.stimulus_id.as_str())).or_default().push((p, r));
    }
    let mut conditions = Vec::new();
    for ((_, id), list) in &by_condition {
        let s = Score::of(list, chance)?;
        let trial_time_s = times.then(|| {
            let mut t: Vec<f64> = list.iter().map(|(_, r)| r.trial_time_s).collect();
            t.sort_by(f64::total_cmp);
            TrialTimes {
                max: t[t.len() - 1],
                mean: t.iter().sum::<f64>() / t.len() as f64,
                median: metaplate_dsp::stats::median(&mut t.clone()),
                min: t[0],
            }
        });
        conditions.push(ConditionRow {
            accuracy: s.accuracy,
            correct: s.correct,
            correct_response: list[0].0.correct.clone(),
            log10_p_value: s.log10_p_value,
            p_value: s.p_value,
            scored_trials: s.scored_trials,
            stimulus_id: (*id).to_owned(),
            trial_time_s,
            wilson_95: s.wilson_95,
        });
    }
    let mut confusion = Confusion::new(labels);
    for (p, r) in trials {
        confusion.add(&p.correct, &r.response)?;
    }
    Ok((conditions, ConfusionCounts { labels: confusion.labels, presented_by_answered: confusion.counts }))
}

impl SessionReport {
    /// Reads the sessions in `dirs` (one experiment's) and reports them.
    ///
    /// # Errors
    /// No directory; an unreadable session (naming it); sessions of different experiments; the statistics' errors.
    pub fn read(dirs: &[PathBuf]) -> Result<(Self, Vec<SessionRecord>), ExperimentError> {
        let sessions: Vec<SessionRecord> = dirs
            .iter()
            .map(|d| {
                SessionRecord::read(d)
                    .map_err(|e| ExperimentError::Refused(format!("reading the session in {}: {e}", d.display())))
            })
            .collect::<Result<_, _>>()?;
        let first = &sessions.first().ok_or_else(|| ExperimentError::invalid_argument("dirs", "none given"))?.header;
        for (s, d) in sessions.iter().zip(dirs) {
            if s.header.experiment != first.experiment || s.header.file_hash != first.file_hash {
                return Err(ExperimentError::Refused(format!(
                    "{} is a session of `{}` ({}), not of `{}` ({}): report one experiment at a time",
                    d.display(),
                    s.header.experiment,
                    s.header.file_hash,
                    first.experiment,
                    first.file_hash
                )));
            }
        }
        let (chance, labels, times) = (first.chance, &first.labels, first.record_trial_times);
        let mut participants = Vec::new();
        let mut pooled: Vec<Scored<'_>> = Vec::new();
        for (s, d) in sessions.iter().zip(dirs) {
            let scored = s.scored();
            let score = Score::of(&scored, chance)?;
            let (conditions, confusion) = detail(&scored, labels, chance, times)?;
            participants.push(ParticipantRow {
                accuracy: score.accuracy,
                complete: s.progress.next_trial().is_none(),
                conditions,
                confusion,
                correct: score.correct,
                dir: d.display().to_string(),
                duplicated_trials: s.duplicates.iter().map(|dup| duplicate_row(s, dup)).collect(),
                id: s.header.participant.clone(),
                log10_p_value: score.log10_p_value,
                p_value: score.p_value,
                planned_scored_trials: s.header.plan.scored(),
                scored_trials: score.scored_trials,
                wilson_95: score.wilson_95,
            });
            pooled.extend(scored);
        }
        let score = Score::of(&pooled, chance)?;
        let (conditions, confusion) = detail(&pooled, labels, chance, times)?;
        let pooled = PooledRow {
            accuracy: score.accuracy,
            conditions,
            confusion,
            correct: score.correct,
            log10_p_value: score.log10_p_value,
            p_value: score.p_value,
            scored_trials: score.scored_trials,
            wilson_95: score.wilson_95,
        };
        let report = Self {
            chance,
            experiment: first.experiment.clone(),
            file_hash: first.file_hash.clone(),
            participants,
            pooled,
            times,
        };
        Ok((report, sessions))
    }

    /// Writes the report as text tables: participants, conditions (pooled), the confusion matrix (pooled), and
    /// each trial journalled more than once.
    ///
    /// # Errors
    /// Writing to `out`.
    pub fn write_tables(&self, out: &mut dyn Write) -> Result<(), ExperimentError> {
        let pct = |v: Option<f64>| v.map_or("-".to_owned(), |x| format!("{:.1} %", x * 100.0));
        let interval = |v: Option<[f64; 2]>| {
            v.map_or("-".to_owned(), |[lo, hi]| format!("[{:.1}, {:.1}] %", lo * 100.0, hi * 100.0))
        };
        let p = |p: Option<f64>, l: Option<f64>| match (p, l) {
            (Some(p), _) if p > 0.0 => format!("{p:.3e}"),
            (Some(_), Some(l)) => format!("1e{l:.1}"),
            _ => "-".to_owned(),
        };
        writeln!(out, "experiment {} (chance {:.0} %)", self.experiment, self.chance * 100.0)?;
        writeln!(
            out,
            "{:<16} {:>9} {:>8} {:>20} {:>12}",
            "participant", "correct", "accuracy", "Wilson 95 %", "p vs chance"
        )?;
        let rows = self
            .participants
            .iter()
            .map(|r| (r.id.as_str(), r.correct, r.scored_trials, r.accuracy, r.wilson_95, r.p_value, r.log10_p_value));
        let q = &self.pooled;
        let pooled = ("pooled", q.correct, q.scored_trials, q.accuracy, q.wilson_95, q.p_value, q.log10_p_value);
        for (id, correct, scored, accuracy, wilson, p_value, log10_p) in rows.chain([pooled]) {
            writeln!(
                out,
                "{id:<16} {:>9} {:>8} {:>20} {:>12}",
                format!("{correct}/{scored}"),
                pct(accuracy),
                interval(wilson),
                p(p_value, log10_p)
            )?;
        }
        writeln!(out, "\nper condition (pooled):")?;
        for c in &q.conditions {
            let time = match (self.times, c.trial_time_s) {
                (true, Some(t)) => format!("  trial time median {:.2} s", t.median.unwrap_or(f64::NAN)),
                _ => String::new(),
            };
            writeln!(
                out,
                "  {:<22} {:>9} {:>8} {:>20}{time}",
                c.stimulus_id,
                format!("{}/{}", c.correct, c.scored_trials),
                pct(c.accuracy),
                interval(c.wilson_95)
            )?;
        }
        writeln!(out, "\nconfusion (pooled; rows presented, columns answered):")?;
        write!(out, "  {:<10}", "")?;
        for l in &q.confusion.labels {
            write!(out, " {l:>9}")?;
        }
        writeln!(out)?;
        for (l, row) in q.confusion.labels.iter().zip(&q.confusion.presented_by_answered) {
            write!(out, "  {l:<10}")?;
            for n in row {
                write!(out, " {:>9}", n.to_string())?;
            }
            writeln!(out)?;
        }
        for r in self.participants.iter().filter(|r| !r.duplicated_trials.is_empty()) {
            writeln!(out, "\n{} ({}): trials journalled more than once (two writers at once):", r.id, r.dir)?;
            for d in &r.duplicated_trials {
                let counted = d.counted.as_deref().unwrap_or("no answer");
                let how = if d.settled {
                    "settled"
                } else if d.responses.iter().all(|x| *x == d.responses[0]) {
                    "agree"
                } else {
                    "CONFLICT"
                };
                writeln!(out, "  trial {}: answers {} ({how}); counts: {counted}", d.trial, d.responses.join(", "))?;
            }
        }
        Ok(())
    }

    /// Writes the per-participant accuracy figure (with the chance line) into `dir`, PNG and SVG.
    ///
    /// # Errors
    /// Creating `dir`; the figure's errors.
    pub fn write_figure(&self, dir: &Path) -> Result<(), ExperimentError> {
        std::fs::create_dir_all(dir).map_err(ExperimentError::io("create", dir))?;
        let rows = self.participants.iter().map(|r| (r.id.as_str(), r.accuracy, r.wilson_95));
        let bars: Vec<metaplate_figures::AccuracyBar> = rows
            .chain([("all", self.pooled.accuracy, self.pooled.wilson_95)])
            .filter_map(|(label, accuracy, wilson_95)| {
                Some(metaplate_figures::AccuracyBar {
                    label: label.to_owned(),
                    accuracy: accuracy?,
                    wilson_95: wilson_95?,
                })
            })
            .collect();
        let title = format!("{}: accuracy per participant", self.experiment);
        metaplate_figures::accuracy(dir, &title, &bars, self.chance)
            .map_err(|e| ExperimentError::Output(e.to_string()))?;
        Ok(())
    }
}

fn duplicate_row(s: &SessionRecord, d: &DuplicateAnswer) -> DuplicateRow {
    let counted = s.progress.results.get(d.trial as usize).and_then(|r| r.as_ref()).map(|r| r.response.clone());
    DuplicateRow { counted, responses: d.responses.clone(), settled: d.settled, trial: d.trial }
}
