//! The run skeleton every plan shares: the dataset opened fresh or resumed, `Started`, one commit (and manifest
//! checkpoint) per unit with its `Committed` event and the stop hook, then `Finished` or `Stopped`.

use std::collections::BTreeSet;
use std::sync::Arc;

use metaplate_core::clock::Clock;
use metaplate_store::{DatasetMeta, IrRecord};

use crate::engine::session::SessionState;
use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};
use crate::output::{self, Output};

/// A run in progress: the open dataset and the counts the events report.
pub(crate) struct Run {
    writer: metaplate_store::DatasetWriter,
    /// The (row, actuator) keys committed before this run (a resume), as the store found them.
    pub committed_keys: BTreeSet<(u32, u16)>,
    /// The session state committed with the last unit before this run (a resume), if any.
    restored: Option<SessionState>,
    total: usize,
    /// Units committed in the dataset, this run's and earlier ones'.
    done: usize,
    /// Units committed by this run.
    commits: usize,
    clock: Arc<dyn Clock>,
    t0_s: f64,
}

impl Run {
    /// Opens (or with `out.resume`, resumes) the dataset of `meta` in `out`; the clock starts now.
    ///
    /// # Errors
    /// As [`output::open`]; [`RecipeError::Config`] if the committed session state does not read.
    pub(crate) fn open(
        out: &Output,
        meta: DatasetMeta,
        clock: Arc<dyn Clock>,
        control: &RunControl,
    ) -> Result<Self, RecipeError> {
        let opened = output::open(out, meta, control)?;
        let restored =
            opened.report.as_ref().and_then(|r| r.state.as_ref()).map(SessionState::from_json).transpose()?;
        let t0_s = clock.now_s();
        Ok(Self {
            writer: opened.writer,
            committed_keys: opened.committed,
            restored,
            total: 0,
            done: 0,
            commits: 0,
            clock,
            t0_s,
        })
    }

    /// The session state to start from: the one committed with the last unit of an earlier run (a resume), else
    /// `configured`.
    pub(crate) fn session_state(&self, configured: SessionState) -> SessionState {
        match self.restored {
            Some(state) => {
                tracing::info!(
                    velocity_range_m_s = state.velocity_range_m_s,
                    configured_m_s = configured.velocity_range_m_s,
                    "resuming with the session state of the last committed unit"
                );
                state
            }
            None => configured,
        }
    }

    /// Reports the start: `total` units in the plan, `done` of them already committed.
    pub(crate) fn start(&mut self, total: usize, done: usize, observer: &mut dyn Observer) {
        self.total = total;
        self.done = done;
        observer.event(&Event::Started { total, done });
    }

    /// Seconds on the rig's clock since the run opened.
    pub(crate) fn elapsed_s(&self) -> f64 {
        self.clock.now_s() - self.t0_s
    }

    /// Units committed in the dataset (earlier runs' included).
    pub(crate) fn done(&self) -> usize {
        self.done
    }

    /// Commits `records` as one unit with `state`, the session state after its measurement (what the next unit
    /// starts from, restored by a resume), checkpoints the manifest (so a resume reads it without replaying the
    /// journal), reports it, and raises the stop level if the test hook asks. Returns the seconds the commit took.
    ///
    /// # Errors
    /// [`RecipeError::Store`] if the store refuses the batch or the checkpoint.
    #[allow(clippy::too_many_arguments)] // The unit (rows, state, index, SNR, status), the control and the observer.
    pub(crate) fn commit(
        &mut self,
        records: &[IrRecord],
        state: SessionState,
        unit: usize,
        snr_db: Option<f64>,
        status: &str,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<f64, RecipeError> {
        let started = std::time::Instant::now();
        self.writer.commit_batch_with_state(records, Some(state.to_json()))?;
        self.writer.checkpoint()?;
        let commit_s = started.elapsed().as_secs_f64();
        self.commits += 1;
        self.done += 1;
        observer.event(&Event::Committed {
            unit,
            done: self.done,
            total: self.total,
            snr_db,
            status: status.to_string(),
            clock_s: self.elapsed_s(),
        });
        control.committed(self.commits);
        Ok(commit_s)
    }

    /// Ends the run: `Finished` when every unit is committed, else `Stopped` and [`RecipeError::Interrupted`].
    ///
    /// # Errors
    /// [`RecipeError::Interrupted`] when units remain (a stop was requested).
    pub(crate) fn finish(self, observer: &mut dyn Observer) -> Result<usize, RecipeError> {
        if self.done < self.total {
            observer.event(&Event::Stopped { done: self.done });
            return Err(RecipeError::Interrupted { committed: self.done });
        }
        observer.event(&Event::Finished { done: self.done });
        Ok(self.done)
    }
}
