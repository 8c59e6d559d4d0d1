//! `metaplate experiment list|report`: the built-ins listed with the paper's counts, and the report of sessions
//! written through the library by simulated participants (no rig: the field at the pixels is given).

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common::metaplate_bare as metaplate;
use std::path::Path;
use std::process::Command;

use metaplate_experiment::journal::TrialRecord;
use metaplate_experiment::{Entry, FieldAtPixels, Plan, Session, SimParticipant, builtin};
use serde_json::Value;

/// Runs a whole session of `experiment` in `dir` with a simulated participant answering a field of the given
/// contrast; returns the number of correct scored answers.
fn simulate_session(dir: &Path, experiment: &str, participant: &str, other_peak_m_s: f64) -> u64 {
    let e = builtin::builtin(experiment).unwrap();
    let sim = SimParticipant::parse(participant).unwrap();
    let plan = Plan::new(&e, e.order.seed);
    let labels: Vec<String> = e.labels().iter().map(|l| (*l).to_owned()).collect();
    let field = FieldAtPixels { target_peak_m_s: vec![5e-3], other_peak_m_s: vec![other_peak_m_s; 4] };
    let mut session = Session::start(dir, &e, participant, plan, false).unwrap();
    let mut clock_s = 0.0;
    let mut correct = 0;
    while let Some(t) = session.next_trial().cloned() {
        let answer = sim.answer(t.index, &t.correct, &labels, &field).unwrap().to_owned();
        let time_s = sim.response_time_s(t.index, e.record_trial_times);
        if t.phase == metaplate_experiment::Phase::Trials && answer == t.correct {
            correct += 1;
        }
        session
            .append(&Entry::Trial(TrialRecord {
                trial: t.index,
                stimulus_id: t.stimulus_id.clone(),
                drive_hash: "fnv1a64:0000000000000000".into(),
                scheduled_onset_s: clock_s,
                measured_onset_s: Some(clock_s + 0.005),
                repeats_requested: 0,
                response: answer,
                response_entered_s: clock_s + time_s,
                trial_time_s: time_s,
            }))
            .unwrap();
        clock_s += time_s + 1.0;
    }
    correct
}

#[test]
fn list_gives_the_papers_four_with_their_counts() {
    let out = metaplate(&["experiment", "list", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let list: Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = list.as_array().unwrap();
    let counts: Vec<(&str, u64, u64, f64)> = rows
        .iter()
        .map(|r| {
            (
                r["name"].as_str().unwrap(),
                r["familiarisation_trials"].as_u64().unwrap(),
                r["scored_trials"].as_u64().unwrap(),
                r["chance"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        counts,
        [
            ("pixel-identification", 5, 50, 0.2),
            ("odd-one-out-exploration", 10, 50, 0.2),
            ("motion-direction", 8, 80, 0.5),
            ("multi-touch-odd-one-out", 5, 50, 0.2),
        ]
    );
    let text = String::from_utf8(metaplate(&["experiment", "list"]).stdout).unwrap();
    assert!(text.contains("motion-direction") && text.contains("chance 50 %"), "{text}");
}

#[test]
fn report_pools_participants_with_intervals_p_values_parquet_and_figures() {
    let root = tempfile::tempdir().unwrap();
    let (a, b, blurred) = (root.path().join("p1"), root.path().join("p2"), root.path().join("p3"));
    // Two well-focused participants (20 dB contrast) and one given a badly focused field (2 dB).
    let correct_a = simulate_session(&a, "odd-one-out-exploration", "sim:seed=1", 5e-4);
    let correct_b = simulate_session(&b, "odd-one-out-exploration", "sim:seed=2", 5e-4);
    let correct_blurred = simulate_session(&blurred, "odd-one-out-exploration", "sim:seed=3", 4e-3);
    assert!(correct_blurred + 10 < correct_a.min(correct_b), "{correct_blurred} vs {correct_a}, {correct_b}");

    let parquet = root.path().join("trials.parquet");
    let figures = root.path().join("figures");
    let dirs: Vec<&str> = [&a, &b, &blurred].iter().map(|d| d.to_str().unwrap()).collect();
    let mut args = vec!["experiment", "report", "--json", "--parquet", parquet.to_str().unwrap()];
    args.extend(["--figures", figures.to_str().unwrap()]);
    args.extend(&dirs);
    let out = metaplate(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["experiment"], "odd-one-out-exploration");
    assert_eq!(report["chance"], 0.2);
    let participants = report["participants"].as_array().unwrap();
    assert_eq!(participants.len(), 3);
    for (p, (id, correct)) in
        participants.iter().zip([("sim:seed=1", correct_a), ("sim:seed=2", correct_b), ("sim:seed=3", correct_blurred)])
    {
        assert_eq!(p["id"], id);
        assert_eq!(p["scored_trials"], 50);
        assert_eq!(p["correct"], correct);
        let acc = p["accuracy"].as_f64().unwrap();
        assert_eq!(acc, correct as f64 / 50.0);
        let (lo, hi) = (p["wilson_95"][0].as_f64().unwrap(), p["wilson_95"][1].as_f64().unwrap());
        assert!(lo <= acc && acc <= hi);
        assert!(p["p_value"].as_f64().unwrap() <= 1.0);
        assert_eq!(p["conditions"].as_array().unwrap().len(), 10);
        // Experiment 2 records trial times: each condition reports them.
        assert!(p["conditions"][0]["trial_time_s"]["median"].as_f64().unwrap() > 3.5);
        let confusion = &p["confusion"]["presented_by_answered"];
        let total: u64 =
            confusion.as_array().unwrap().iter().flat_map(|r| r.as_array().unwrap()).map(|n| n.as_u64().unwrap()).sum();
        assert_eq!(total, 50);
    }
    let pooled = &report["pooled"];
    assert_eq!(pooled["scored_trials"], 150);
    assert_eq!(pooled["correct"], correct_a + correct_b + correct_blurred);
    // Far above chance: the exact p is tiny, its logarithm exact.
    assert!(pooled["log10_p_value"].as_f64().unwrap() < -30.0);

    // The Parquet file: one row per scored trial of every participant.
    let file = std::fs::File::open(&parquet).unwrap();
    let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file).unwrap().build().unwrap();
    let rows: usize = reader.map(|b| b.unwrap().num_rows()).sum();
    assert_eq!(rows, 150);
    assert!(figures.join("accuracy.png").exists() && figures.join("accuracy.svg").exists());

    // The text report names the pool; a mix of experiments is refused.
    let text = String::from_utf8(metaplate(&["experiment", "report", dirs[0], dirs[1]]).stdout).unwrap();
    assert!(text.contains("pooled") && text.contains("confusion"), "{text}");
    let other = root.path().join("other");
    simulate_session(&other, "motion-direction", "sim", 5e-4);
    let out = metaplate(&["experiment", "report", dirs[0], other.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("one experiment at a time"));
}

/// polars and pyarrow read the report's Parquet: one row per scored trial, the columns named, the `correct` column
/// summing to the report's count.
#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with polars and pyarrow: run by .ci/run"]
fn polars_reads_the_trials_parquet() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("p1");
    let correct = simulate_session(&dir, "motion-direction", "sim:seed=5", 5e-4);
    let parquet = root.path().join("trials.parquet");
    let out = metaplate(&["experiment", "report", "--parquet", parquet.to_str().unwrap(), dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let script = format!(
        "import sys, polars as pl, pyarrow.parquet as pq\n\
         df = pl.read_parquet(sys.argv[1])\n\
         assert df.height == 80, df.height\n\
         assert df['correct'].sum() == {correct}, df['correct'].sum()\n\
         assert set(df['stimulus_id'].unique().to_list()) >= {{'rightward-640ms', 'leftward-80ms'}}\n\
         assert pq.read_table(sys.argv[1]).num_rows == 80\n\
         assert pq.read_metadata(sys.argv[1]).metadata[b'metaplate.experiment'] == b'motion-direction'\n\
         print('ok')\n"
    );
    let out = Command::new(metaplate_fixtures::python()).arg("-c").arg(script).arg(&parquet).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && stdout.contains("ok"), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
}
