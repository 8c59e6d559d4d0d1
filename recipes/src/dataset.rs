//! Where a recipe's dataset goes, and opening it fresh or for resumption.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use metaplate_store::{BATCH_DIR, DatasetMeta, DatasetWriter, IfExists, MANIFEST_FILE, SceneId};

use crate::error::RecipeError;

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

/// Opens `out` for `meta`: a fresh dataset, or with `out.resume` the previous one in the directory.
///
/// # Errors
/// [`RecipeError::Store`] as the store says (a non-empty directory without `resume`, a changed configuration without
/// `force`, corruption it cannot quarantine); [`RecipeError::Config`] for a resume the store cannot do.
pub(crate) fn open(out: &Output, meta: DatasetMeta) -> Result<Opened, RecipeError> {
    if out.resume && has_dataset(&out.dir) {
        return resume(out, meta);
    }
    let writer = DatasetWriter::create(&out.dir, meta, IfExists::Refuse)?;
    Ok(Opened { writer, committed: BTreeSet::new(), report: None })
}

/// Resumption through the store's journal: it verifies the configuration (refusing a change unless `force`,
/// saying what changed), the committed files (quarantining a corrupt one, whose points are then measured again) and
/// returns the keys committed.
fn resume(out: &Output, meta: DatasetMeta) -> Result<Opened, RecipeError> {
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
