//! Where a recipe's dataset goes, and opening it fresh or for resumption.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use metaplate_store::{BATCH_DIR, DatasetMeta, DatasetWriter, IfExists, MANIFEST_FILE, SceneId};

use crate::error::RecipeError;
use crate::events::RunControl;
use crate::preflight::PREFLIGHT_KEY;

/// The output of a run: a dataset directory and how to treat what is already there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Output {
    /// The dataset directory.
    pub dir: PathBuf,
    /// The plate (scene or hardware) the run measures.
    pub scene: SceneId,
    /// Version of the software writing it.
    pub software_version: String,
    /// Continue a previous run in `dir` instead of refusing a non-empty directory.
    pub resume: bool,
    /// With `resume`: continue even when the configuration changed (the change is still reported).
    pub force: bool,
    /// The report of the pre-flight check that ran before this run (`metaplate check --report`), if any: its
    /// verdict is recorded in the configuration ([`crate::preflight::manifest_record`]). A resume keeps the one
    /// recorded when the run started.
    pub preflight: Option<serde_json::Value>,
}

/// An open dataset: the writer and the (point, actuator) keys already committed.
pub(crate) struct Opened {
    pub writer: DatasetWriter,
    pub committed: BTreeSet<(u32, u16)>,
    /// What the store found on resume (`None` for a fresh dataset).
    #[allow(dead_code)] // For the CLI's resume message, once it reports quarantines.
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
