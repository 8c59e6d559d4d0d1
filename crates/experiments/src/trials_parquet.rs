//! The scored trials of sessions as one Parquet file (`experiment report --parquet`): one row per scored, answered
//! trial, readable by polars and pyarrow; the experiment's name in the file's metadata (`metaplate.experiment`).

use std::path::Path;
use std::sync::Arc;

use arrow_array::{ArrayRef, BooleanArray, Float64Array, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{DataType, Field, Schema};

use crate::error::ExperimentError;
use crate::journal::SessionRecord;

/// Writes one row per scored, answered trial of every session as a Parquet file (readable by polars and pyarrow).
///
/// # Errors
/// Creating or writing `path`.
pub fn write_parquet(path: &Path, sessions: &[SessionRecord]) -> Result<(), ExperimentError> {
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
    let failed = |e: &dyn std::fmt::Display| ExperimentError::Output(format!("writing {}: {e}", path.display()));
    let batch = RecordBatch::try_new(schema, columns).map_err(|e| failed(&e))?;
    metaplate_store::write_table(path, &batch, &[("metaplate.experiment", &experiment)]).map_err(|e| failed(&e))?;
    Ok(())
}
