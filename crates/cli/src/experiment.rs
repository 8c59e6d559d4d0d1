//! `metaplate experiment list|report`: the built-in behavioural experiments, and the report of session directories
//! (per participant and condition: accuracy, Wilson 95 %, exact binomial p against chance, confusion matrix, trial
//! times; JSON, Parquet, figures).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, bail};
use arrow_array::{ArrayRef, BooleanArray, Float64Array, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{DataType, Field, Schema};
use clap::{Args, Subcommand};
use metaplate_experiment::stats::{Confusion, binomial_p_at_least, wilson_95};
use metaplate_experiment::{PlannedTrial, SessionRecord, TrialRecord, builtin};
use serde_json::{Value, json};

/// Arguments of `metaplate experiment`.
#[derive(Args)]
pub struct ExperimentArgs {
    #[command(subcommand)]
    command: ExperimentCommand,
}

#[derive(Subcommand)]
enum ExperimentCommand {
    /// List the built-in experiments (the paper's four): conditions, repeats, trials, chance.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Run one participant's session on the rig (the mock lab of --scene, or --hardware FILE): the plan stored
    /// before the first trial, every trial journalled as it ends, resumed after a crash at the next trial.
    Run(Box<crate::experiment_run::RunArgs>),
    /// How a scan renders experiments' stimuli: each stimulus's predicted peak velocity at its target, null and
    /// other pixels at the drive level, and the suppression (weakest target over strongest null, dB).
    Stimuli(Box<crate::experiment_stimuli::StimuliArgs>),
    /// Report session directories of one experiment: per participant and condition, accuracy with a Wilson 95 %
    /// interval, the exact one-sided binomial p against chance, the confusion matrix, trial times where recorded;
    /// pooled over participants.
    Report {
        /// Session directories (each holds plan.json and journal.jsonl), one per participant.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Write every scored trial as one Parquet file (one row per trial; readable by polars and pyarrow).
        #[arg(long, value_name = "FILE")]
        parquet: Option<PathBuf>,
        /// Write the per-participant accuracy figure (with the chance line) into this directory, PNG and SVG.
        #[arg(long, value_name = "DIR")]
        figures: Option<PathBuf>,
    },
}

/// Runs `metaplate experiment ...`.
pub fn run(args: &ExperimentArgs) -> anyhow::Result<()> {
    match &args.command {
        ExperimentCommand::List { json } => list(*json),
        ExperimentCommand::Run(args) => crate::experiment_run::run(args),
        ExperimentCommand::Stimuli(args) => crate::experiment_stimuli::run(args),
        ExperimentCommand::Report { dirs, json, parquet, figures } => {
            report(dirs, *json, parquet.as_deref(), figures.as_deref())
        }
    }
}

fn list(as_json: bool) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    let mut rows = Vec::new();
    for name in builtin::names() {
        let e = builtin::builtin(name)?;
        let familiarisation = if e.phases.familiarisation { e.stimuli.len() } else { 0 };
        let scored = e.stimuli.len() * e.phases.repeats as usize;
        rows.push(json!({
            "name": name,
            "description": e.description,
            "conditions": e.stimuli.len(),
            "repeats": e.phases.repeats,
            "familiarisation_trials": familiarisation,
            "scored_trials": scored,
            "chance": e.chance,
            "responses": e.labels(),
            "pixels": e.pixels.iter().map(|p| json!({"name": p.name, "x_m": p.x_m, "y_m": p.y_m})).collect::<Vec<_>>(),
            "file_hash": e.file_hash(),
        }));
        if !as_json {
            writeln!(
                out,
                "{name:<25} {:>2} conditions x {:>2} + {:>2} familiarisation = {:>3} trials, chance {:>2.0} %  {}",
                e.stimuli.len(),
                e.phases.repeats,
                familiarisation,
                scored + familiarisation,
                e.chance * 100.0,
                e.description
            )?;
        }
    }
    if as_json {
        writeln!(out, "{}", serde_json::to_string_pretty(&Value::Array(rows))?)?;
    }
    Ok(())
}

/// Accuracy statistics of a set of scored trials.
struct Score {
    scored: u64,
    correct: u64,
}

impl Score {
    fn of<'a>(trials: impl Iterator<Item = &'a (&'a PlannedTrial, &'a TrialRecord)>) -> Self {
        let (mut scored, mut correct) = (0, 0);
        for (p, r) in trials {
            scored += 1;
            correct += u64::from(p.correct == r.response);
        }
        Self { scored, correct }
    }

    /// The JSON keys every level of the report shares; accuracy, interval and p are null without scored trials.
    fn json(&self, chance: f64) -> anyhow::Result<Value> {
        if self.scored == 0 {
            return Ok(json!({"scored_trials": 0, "correct": 0, "accuracy": null, "wilson_95": null,
                "p_value": null, "log10_p_value": null}));
        }
        let (accuracy, wilson) = wilson_95(self.correct, self.scored)?;
        let (p, log10_p) = binomial_p_at_least(self.correct, self.scored, chance)?;
        Ok(json!({"scored_trials": self.scored, "correct": self.correct, "accuracy": accuracy,
            "wilson_95": wilson, "p_value": p, "log10_p_value": log10_p}))
    }
}

/// The per-condition, confusion and trial-time part of a participant's (or the pool's) report.
fn detail(
    trials: &[(&PlannedTrial, &TrialRecord)],
    labels: &[String],
    chance: f64,
    times: bool,
) -> anyhow::Result<Value> {
    let mut by_condition: BTreeMap<(u32, &str), Vec<(&PlannedTrial, &TrialRecord)>> = BTreeMap::new();
    for &(p, r) in trials {
        by_condition.entry((p.condition, p.stimulus_id.as_str())).or_default().push((p, r));
    }
    let mut conditions = Vec::new();
    for ((_, id), list) in &by_condition {
        let mut row = Score::of(list.iter()).json(chance)?;
        row["stimulus_id"] = json!(id);
        row["correct_response"] = json!(list[0].0.correct);
        if times {
            let mut t: Vec<f64> = list.iter().map(|(_, r)| r.trial_time_s).collect();
            t.sort_by(f64::total_cmp);
            row["trial_time_s"] = json!({"median": median(&t), "mean": t.iter().sum::<f64>() / t.len() as f64,
                "min": t.first(), "max": t.last()});
        }
        conditions.push(row);
    }
    let mut confusion = Confusion::new(labels);
    for (p, r) in trials {
        confusion.add(&p.correct, &r.response)?;
    }
    Ok(json!({"conditions": conditions,
        "confusion": {"labels": confusion.labels, "presented_by_answered": confusion.counts}}))
}

fn median(sorted: &[f64]) -> Option<f64> {
    match sorted.len() {
        0 => None,
        n if n % 2 == 1 => Some(sorted[n / 2]),
        n => Some((sorted[n / 2 - 1] + sorted[n / 2]) / 2.0),
    }
}

fn report(dirs: &[PathBuf], as_json: bool, parquet: Option<&Path>, figures: Option<&Path>) -> anyhow::Result<()> {
    let sessions: Vec<SessionRecord> = dirs
        .iter()
        .map(|d| SessionRecord::read(d).with_context(|| format!("reading the session in {}", d.display())))
        .collect::<anyhow::Result<_>>()?;
    let first = &sessions[0].header;
    for (s, d) in sessions.iter().zip(dirs) {
        if s.header.experiment != first.experiment || s.header.file_hash != first.file_hash {
            bail!(
                "{} is a session of `{}` ({}), not of `{}` ({}): report one experiment at a time",
                d.display(),
                s.header.experiment,
                s.header.file_hash,
                first.experiment,
                first.file_hash
            );
        }
    }
    let (chance, labels, times) = (first.chance, &first.labels, first.record_trial_times);
    let mut participants = Vec::new();
    let mut pooled: Vec<(&PlannedTrial, &TrialRecord)> = Vec::new();
    for (s, d) in sessions.iter().zip(dirs) {
        let scored = s.scored();
        let mut row = Score::of(scored.iter()).json(chance)?;
        row["id"] = json!(s.header.participant);
        row["dir"] = json!(d.display().to_string());
        row["planned_scored_trials"] = json!(s.header.plan.scored());
        row["complete"] = json!(s.progress.next_trial().is_none());
        merge(&mut row, detail(&scored, labels, chance, times)?);
        participants.push(row);
        pooled.extend(scored);
    }
    let mut pooled_row = Score::of(pooled.iter()).json(chance)?;
    merge(&mut pooled_row, detail(&pooled, labels, chance, times)?);
    let report = json!({"experiment": first.experiment, "file_hash": first.file_hash, "chance": chance,
        "participants": participants, "pooled": pooled_row});

    if let Some(path) = parquet {
        write_parquet(path, &sessions)?;
    }
    if let Some(dir) = figures {
        write_figures(dir, &report)?;
    }
    let mut out = std::io::stdout().lock();
    if as_json {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        print_tables(&mut out, &report, times)?;
    }
    Ok(())
}

fn merge(into: &mut Value, from: Value) {
    if let (Some(a), Value::Object(b)) = (into.as_object_mut(), from) {
        a.extend(b);
    }
}

fn print_tables(out: &mut impl Write, report: &Value, times: bool) -> anyhow::Result<()> {
    let pct = |v: &Value| v.as_f64().map_or("-".to_owned(), |x| format!("{:.1} %", x * 100.0));
    let interval = |v: &Value| match (v[0].as_f64(), v[1].as_f64()) {
        (Some(lo), Some(hi)) => format!("[{:.1}, {:.1}] %", lo * 100.0, hi * 100.0),
        _ => "-".to_owned(),
    };
    let p = |v: &Value| match (v["p_value"].as_f64(), v["log10_p_value"].as_f64()) {
        (Some(p), _) if p > 0.0 => format!("{p:.3e}"),
        (Some(_), Some(l)) => format!("1e{l:.1}"),
        _ => "-".to_owned(),
    };
    writeln!(
        out,
        "experiment {} (chance {:.0} %)",
        report["experiment"].as_str().unwrap_or(""),
        report["chance"].as_f64().unwrap_or(0.0) * 100.0
    )?;
    writeln!(
        out,
        "{:<16} {:>9} {:>8} {:>20} {:>12}",
        "participant", "correct", "accuracy", "Wilson 95 %", "p vs chance"
    )?;
    let empty = Vec::new();
    let rows = report["participants"].as_array().unwrap_or(&empty);
    for (r, id) in rows.iter().map(|r| (r, r["id"].as_str().unwrap_or("?"))).chain([(&report["pooled"], "pooled")]) {
        writeln!(
            out,
            "{id:<16} {:>9} {:>8} {:>20} {:>12}",
            format!("{}/{}", r["correct"], r["scored_trials"]),
            pct(&r["accuracy"]),
            interval(&r["wilson_95"]),
            p(r)
        )?;
    }
    let pooled = &report["pooled"];
    writeln!(out, "\nper condition (pooled):")?;
    for c in pooled["conditions"].as_array().unwrap_or(&empty) {
        let time = if times {
            format!("  trial time median {:.2} s", c["trial_time_s"]["median"].as_f64().unwrap_or(f64::NAN))
        } else {
            String::new()
        };
        writeln!(
            out,
            "  {:<22} {:>9} {:>8} {:>20}{time}",
            c["stimulus_id"].as_str().unwrap_or("?"),
            format!("{}/{}", c["correct"], c["scored_trials"]),
            pct(&c["accuracy"]),
            interval(&c["wilson_95"])
        )?;
    }
    writeln!(out, "\nconfusion (pooled; rows presented, columns answered):")?;
    let labels: Vec<&str> =
        pooled["confusion"]["labels"].as_array().unwrap_or(&empty).iter().filter_map(Value::as_str).collect();
    write!(out, "  {:<10}", "")?;
    for l in &labels {
        write!(out, " {l:>9}")?;
    }
    writeln!(out)?;
    for (l, row) in labels.iter().zip(pooled["confusion"]["presented_by_answered"].as_array().unwrap_or(&empty)) {
        write!(out, "  {l:<10}")?;
        for n in row.as_array().unwrap_or(&empty) {
            write!(out, " {:>9}", n.to_string())?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// One row per scored, answered trial of every session.
fn write_parquet(path: &Path, sessions: &[SessionRecord]) -> anyhow::Result<()> {
    let mut participant = Vec::new();
    let mut trial = Vec::new();
    let mut stimulus = Vec::new();
    let mut condition = Vec::new();
    let mut correct_response = Vec::new();
    let mut response = Vec::new();
    let mut is_correct = Vec::new();
    let mut trial_time = Vec::new();
    let mut scheduled = Vec::new();
    let mut measured = Vec::new();
    let mut repeats = Vec::new();
    let mut drive_hash = Vec::new();
    for s in sessions {
        for (p, r) in s.scored() {
            participant.push(s.header.participant.clone());
            trial.push(p.index);
            stimulus.push(p.stimulus_id.clone());
            condition.push(p.condition);
            correct_response.push(p.correct.clone());
            response.push(r.response.clone());
            is_correct.push(p.correct == r.response);
            trial_time.push(r.trial_time_s);
            scheduled.push(r.scheduled_onset_s);
            measured.push(r.measured_onset_s);
            repeats.push(r.repeats_requested);
            drive_hash.push(r.drive_hash.clone());
        }
    }
    let experiment = sessions.first().map(|s| s.header.experiment.clone()).unwrap_or_default();
    let schema = Arc::new(Schema::new(vec![
        Field::new("participant", DataType::Utf8, false),
        Field::new("trial", DataType::UInt32, false),
        Field::new("condition", DataType::UInt32, false),
        Field::new("stimulus_id", DataType::Utf8, false),
        Field::new("correct_response", DataType::Utf8, false),
        Field::new("response", DataType::Utf8, false),
        Field::new("correct", DataType::Boolean, false),
        Field::new("trial_time_s", DataType::Float64, false),
        Field::new("scheduled_onset_s", DataType::Float64, false),
        Field::new("measured_onset_s", DataType::Float64, true),
        Field::new("repeats_requested", DataType::UInt32, false),
        Field::new("drive_hash", DataType::Utf8, false),
    ]));
    let columns: Vec<ArrayRef> = vec![
        Arc::new(StringArray::from(participant)),
        Arc::new(UInt32Array::from(trial)),
        Arc::new(UInt32Array::from(condition)),
        Arc::new(StringArray::from(stimulus)),
        Arc::new(StringArray::from(correct_response)),
        Arc::new(StringArray::from(response)),
        Arc::new(BooleanArray::from(is_correct)),
        Arc::new(Float64Array::from(trial_time)),
        Arc::new(Float64Array::from(scheduled)),
        Arc::new(Float64Array::from(measured)),
        Arc::new(UInt32Array::from(repeats)),
        Arc::new(StringArray::from(drive_hash)),
    ];
    let batch = RecordBatch::try_new(schema.clone(), columns)?;
    let props = parquet::file::properties::WriterProperties::builder()
        .set_compression(parquet::basic::Compression::SNAPPY)
        .set_key_value_metadata(Some(vec![parquet::file::metadata::KeyValue::new(
            "metaplate.experiment".to_owned(),
            experiment,
        )]))
        .build();
    let file = std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut writer = parquet::arrow::ArrowWriter::try_new(file, schema, Some(props))?;
    writer.write(&batch)?;
    writer.close()?;
    Ok(())
}

fn write_figures(dir: &Path, report: &Value) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let empty = Vec::new();
    let bars: Vec<metaplate_figures::AccuracyBar> = report["participants"]
        .as_array()
        .unwrap_or(&empty)
        .iter()
        .chain([&report["pooled"]])
        .zip(report["participants"].as_array().unwrap_or(&empty).iter().map(|r| r["id"].as_str()).chain([Some("all")]))
        .filter_map(|(r, id)| {
            Some(metaplate_figures::AccuracyBar {
                label: id?.to_owned(),
                accuracy: r["accuracy"].as_f64()?,
                wilson_95: [r["wilson_95"][0].as_f64()?, r["wilson_95"][1].as_f64()?],
            })
        })
        .collect();
    let title = format!("{}: accuracy per participant", report["experiment"].as_str().unwrap_or(""));
    metaplate_figures::accuracy(dir, &title, &bars, report["chance"].as_f64().unwrap_or(0.0))?;
    Ok(())
}
