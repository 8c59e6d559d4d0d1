//! `metaplate design search`: a grid of unit-cell designs judged against objectives, durable and shardable.
//!
//! - [`SearchSpec`]: the search file (base design, values of each varied parameter, objectives, band options).
//! - [`run`]: computes the designs of one shard (`--shard I/N`: the indices equal to `I` modulo `N`), each written
//!   to its own Parquet file as soon as it is computed ([`parts`]); a run killed at any moment and started again on
//!   the same folder skips every design already written, so none is lost or computed twice. An unsharded run
//!   gathers its results into `results.parquet` when it finishes; shards are gathered by [`merge`], which gives
//!   the same file.
//! - The trade-off front: the feasible designs no other feasible design beats on every goal.
//!
//! A cluster's own scheduler runs the shards (a Slurm job array, a Kubernetes indexed job): docs/design.md.

mod evaluate;
pub mod parts;
mod spec;

use std::path::{Path, PathBuf};

pub use evaluate::{DesignResult, evaluate, mark_front};
pub use parts::{RESULTS_FILE, merge};
pub use spec::{Candidate, Goal, MATERIALS, MAX_DESIGNS, Material, Objectives, SearchSpec};

use crate::error::DesignError;

/// The part of a search one process computes: the designs whose index is `index` modulo `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0-based (`0 <= index < count`).
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole search.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (0-based `I`, as Slurm's `SLURM_ARRAY_TASK_ID` with `--array=0-(N-1)` and Kubernetes'
    /// `JOB_COMPLETION_INDEX` count).
    ///
    /// # Errors
    /// [`DesignError::Option`] unless `0 <= I < N`.
    pub fn parse(text: &str) -> Result<Self, DesignError> {
        let bad = || DesignError::Option(format!("--shard takes I/N with 0 <= I < N (0-based), got `{text}`"));
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether design `index` is this shard's.
    pub fn owns(&self, index: usize) -> bool {
        index % self.count == self.index
    }
}

/// Progress of a run, after each design.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchProgress {
    /// Designs of this shard finished, including those found done when it started.
    pub done: usize,
    /// Designs of this shard in all.
    pub total: usize,
    /// Designs found done when the run started (resumed).
    pub resumed: usize,
    /// The design just computed (`None` for the first report, before any is computed).
    pub last: Option<DesignResult>,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchOutcome {
    /// Designs of this shard computed by this run.
    pub computed: Vec<usize>,
    /// Designs of this shard found done when it started.
    pub resumed: usize,
    /// Parts found unreadable and computed again.
    pub recomputed: Vec<PathBuf>,
    /// The gathered results (an unsharded run only), in index order.
    pub results: Option<Vec<DesignResult>>,
}

/// Computes `shard` of `spec` into `dir` (made when missing), calling `progress` before the first design and after
/// each; `stop` is polled between designs (Ctrl-C: what is written stays, a later run resumes).
///
/// # Errors
/// [`DesignError::Results`] when `dir` holds another search's parts, or a part or the results cannot be written;
/// [`DesignError::Stopped`] when stopped (nothing lost).
pub fn run(
    spec: &SearchSpec,
    dir: &Path,
    shard: Shard,
    progress: &mut dyn FnMut(&SearchProgress),
    stop: &dyn Fn() -> bool,
) -> Result<SearchOutcome, DesignError> {
    let count = spec.count();
    let (done, recomputed) = parts::finished(dir, &spec.fingerprint)?;
    let mine: Vec<usize> = (0..count).filter(|&i| shard.owns(i)).collect();
    let resumed = mine.iter().filter(|i| done.contains_key(i)).count();
    let mut state = SearchProgress { done: resumed, total: mine.len(), resumed, last: None };
    progress(&state);
    let mut computed = Vec::new();
    for &index in mine.iter().filter(|i| !done.contains_key(i)) {
        if stop() {
            return Err(DesignError::Stopped { done: state.done, total: state.total });
        }
        let candidate = spec.candidate(index).ok_or_else(|| DesignError::Option(format!("no design {index}")))?;
        let result = evaluate(spec, &candidate);
        parts::write_part(dir, &result, &spec.fingerprint)?;
        computed.push(index);
        state.done += 1;
        state.last = Some(result);
        progress(&state);
    }
    let results =
        if shard.count == 1 { Some(merge(spec, &[dir.to_path_buf()], &dir.join(RESULTS_FILE))?) } else { None };
    Ok(SearchOutcome { computed, resumed, recomputed, results })
}
