//! Where a recipe's dataset goes, and opening it fresh or for resumption.

use std::collections::BTreeSet;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use metaplate_store::{BATCH_DIR, DatasetMeta, DatasetWriter, IfExists, MANIFEST_FILE, SceneId};

use serde_json::{Value, json};

use crate::error::RecipeError;
use crate::events::RunControl;

/// The output of a run: a dataset directory and how to treat what is already there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Output {
    /// The dataset directory.
    pub dir: PathBuf,
    /// The plate (scene or hardware) the run measures.
    pub scene: SceneId,
    /// Version of the software writing it.
    pub software_version: String,
    /// Continue a previous run in `dir` instead of refusing a non-empty directory. A directory that holds no run
    /// starts a new one: [`crate::Event::Started`] says `resumed: false`.
    pub resume: bool,
    /// With `resume`: continue even when the configuration changed (the change is still reported).
    pub force: bool,
    /// The report of the pre-flight check that ran before this run (`metaplate check --report`), if any: its
    /// verdict is recorded in the configuration ([`manifest_record`]). A resume keeps the one
    /// recorded when the run started.
    pub preflight: Option<serde_json::Value>,
}

/// The configuration key under which a run records its pre-flight.
pub const PREFLIGHT_KEY: &str = "preflight";

/// What a dataset records of the pre-flight `report` (a document `metaplate check --report` wrote: `verdict`,
/// `checks`, `checked_at`, `software_version`, `rig`): the verdict, when, the failed checks' names, and whether
/// the rig checked is the rig of the run (`rig_record`, identities and wiring, as
/// [`crate::rig_config`] gives it), so a verdict from another rig or cabling reads as such.
pub fn manifest_record(report: &Value, rig_record: &Value) -> Value {
    let failed: Vec<&str> = report["checks"]
        .as_array()
        .map(|checks| {
            checks.iter().filter(|c| c["passed"] != Value::Bool(true)).filter_map(|c| c["name"].as_str()).collect()
        })
        .unwrap_or_default();
    json!({
        "verdict": report["verdict"].as_str().unwrap_or("unknown"),
        "checked_at": report["checked_at"],
        "software_version": report["software_version"],
        "failed": failed,
        "same_rig": report.get("rig") == Some(rig_record),
    })
}

/// Reads the report `metaplate check --report` wrote at `path`, for [`Output::preflight`] (its verdict may be a
/// fail: the run records it and starts all the same).
///
/// # Errors
/// A sentence naming the file: it cannot be read, is not JSON, or has no `verdict`.
pub fn read_preflight_report(path: &Path) -> Result<Value, String> {
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("reading the pre-flight report {}: {e}", path.display()))?;
    let report: Value = serde_json::from_str(&text)
        .map_err(|e| format!("{} is not a pre-flight report (not JSON): {e}", path.display()))?;
    if report["verdict"].as_str().is_none() {
        return Err(format!("{} is not a pre-flight report (no `verdict`)", path.display()));
    }
    Ok(report)
}

/// A run's log file, `DIR/<recipe>.log`, created only once the dataset exists: the store refuses to create a dataset
/// in a directory that holds anything, so lines logged before that are kept in memory and written out when
/// `manifest.json` appears (and dropped if the run fails before). Appended to on resume.
pub struct RunLog {
    path: PathBuf,
    manifest: PathBuf,
    pending: Vec<u8>,
    file: Option<File>,
}

impl Write for RunLog {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.file.is_none() {
            if !self.manifest.exists() {
                self.pending.extend_from_slice(buf);
                return Ok(buf.len());
            }
            let mut file = OpenOptions::new().create(true).append(true).open(&self.path)?;
            file.write_all(&self.pending)?;
            self.pending.clear();
            self.file = Some(file);
        }
        match &mut self.file {
            Some(file) => file.write(buf),
            None => Ok(buf.len()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.as_mut().map_or(Ok(()), Write::flush)
    }
}

impl RunLog {
    /// The log of `recipe`'s run in `dir`.
    pub fn new(dir: &Path, recipe: &str) -> Self {
        Self {
            path: dir.join(format!("{recipe}.log")),
            manifest: dir.join(MANIFEST_FILE),
            pending: Vec::new(),
            file: None,
        }
    }
}

/// An open dataset: the writer and the (point, actuator) keys already committed.
pub(crate) struct Opened {
    pub writer: DatasetWriter,
    pub committed: BTreeSet<(u32, u16)>,
    /// What the store found on resume (`None` for a fresh dataset).
    pub report: Option<metaplate_store::ResumeReport>,
}

/// Whether `dir` holds anything of a dataset.
fn has_dataset(dir: &Path) -> bool {
    dir.join(MANIFEST_FILE).exists() || dir.join(BATCH_DIR).exists()
}

/// Opens `out` for `meta`: a fresh dataset, or with `out.resume` the previous one in the directory; with the write
/// budget of `control`'s test hook, if set.
///
/// # Errors
/// [`RecipeError::Store`] as the store says (a non-empty directory without `resume`, a changed configuration without
/// `force`, corruption it cannot quarantine); [`RecipeError::Config`] for a resume the store cannot do.
pub(crate) fn open(out: &Output, meta: DatasetMeta, control: &RunControl) -> Result<Opened, RecipeError> {
    let mut opened = if out.resume && has_dataset(&out.dir) {
        resume(out, meta)?
    } else {
        if out.resume {
            tracing::warn!(dir = %out.dir.display(), "nothing to resume: no run in the directory; a new run starts");
        }
        let writer = DatasetWriter::create(&out.dir, meta, IfExists::Refuse)?;
        Opened { writer, committed: BTreeSet::new(), report: None }
    };
    if let Some(bytes) = control.write_budget_bytes() {
        opened.writer = opened.writer.with_write_budget(bytes);
    }
    Ok(opened)
}

/// Resumption through the store's journal: it verifies the configuration (refusing a change unless `force`,
/// saying what changed), the committed files (quarantining a corrupt one, whose points are then measured again) and
/// returns the keys committed.
fn resume(out: &Output, mut meta: DatasetMeta) -> Result<Opened, RecipeError> {
    keep_recorded_preflight(&out.dir, &mut meta);
    let (writer, report) = DatasetWriter::resume(&out.dir, &meta, out.force)?;
    for difference in &report.forced_differences {
        tracing::warn!(%difference, "configuration changed; resuming anyway (--force)");
    }
    for q in &report.quarantined {
        tracing::warn!(file = %q.file, reason = %q.reason, "quarantined; its points will be measured again");
    }
    for issue in &report.journal_issues {
        tracing::warn!(?issue, "journal issue repaired");
    }
    tracing::info!(committed = report.committed.len(), elapsed_s = report.elapsed_s, "resumed");
    Ok(Opened { writer, committed: report.committed.clone(), report: Some(report) })
}

/// The pre-flight belongs to the run's start: a resume compares its configuration with the one recorded, pre-flight
/// included, so it takes the recorded one (or none) whatever this invocation was given.
fn keep_recorded_preflight(dir: &Path, meta: &mut DatasetMeta) {
    let recorded = metaplate_store::Manifest::read(dir).ok().and_then(|m| m.meta.config.get(PREFLIGHT_KEY).cloned());
    let given = meta.config.remove(PREFLIGHT_KEY);
    if given.is_some() && given != recorded {
        tracing::warn!("the pre-flight given is ignored: a resumed run keeps the one recorded when it started");
    }
    if let Some(recorded) = recorded {
        meta.config.insert(PREFLIGHT_KEY.into(), recorded);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_manifest_records_the_verdict_the_failures_and_whether_the_rig_is_the_same() {
        let rig = json!({"wiring": {"actuator_channels": [0, 1]}});
        let report = json!({"verdict": "fail", "checked_at": "2026-11-25T01:00:00Z", "software_version": "0.1.0",
            "checks": [{"name": "wiring", "passed": true}, {"name": "loopback", "passed": false}], "rig": rig});
        let record = manifest_record(&report, &rig);
        assert_eq!(record["verdict"], "fail");
        assert_eq!(record["failed"], json!(["loopback"]));
        assert_eq!(record["same_rig"], true);
        let recabled = json!({"wiring": {"actuator_channels": [1, 0]}});
        assert_eq!(manifest_record(&report, &recabled)["same_rig"], false);
        assert_eq!(manifest_record(&json!({}), &rig)["verdict"], "unknown");
    }
}
