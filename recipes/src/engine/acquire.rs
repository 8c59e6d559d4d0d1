//! One acquisition, with the one retry policy every plan uses: a recording with a gap, an underrun or a clipped
//! sample is repeated up to the policy's count; clipping first asks the vibrometer for a wider velocity range (kept
//! for the rest of the run, and committed with each unit so that a resume continues with it). Every repeat is counted and reported as an [`Event::Retry`].

use crate::drive::DrivePlayback;
use crate::engine::session::{Acquisition, Instruments};
use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};

/// How often an unusable acquisition is repeated.
///
/// Valid range: `max_attempts >= 1` (0 is taken as 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RetryPolicy {
    /// Acquisitions at most, the first included.
    pub max_attempts: u32,
}

/// What made an acquisition unusable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AcquisitionProblem {
    /// Samples were lost or the audio underran: the recording has a gap.
    Gap,
    /// Some sample sat on a rail.
    Clipped,
}

impl AcquisitionProblem {
    /// The problem of `acq`, if any: a gap before clipping (a gap spoils the recording whatever its range).
    pub fn of(acq: &Acquisition) -> Option<Self> {
        if !acq.is_whole() {
            Some(Self::Gap)
        } else if acq.recording.clipped {
            Some(Self::Clipped)
        } else {
            None
        }
    }

    /// A short description, for events and logs.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Gap => "gap or underrun",
            Self::Clipped => "clipped",
        }
    }
}

/// The acquisition kept, how many were made for it, and what is still wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Acquired {
    /// The last acquisition made.
    pub acquisition: Acquisition,
    /// Acquisitions made (1 when the first was usable): `attempts - 1` retries.
    pub attempts: u32,
    /// `None` when usable; otherwise why the policy gave up (its count reached, or clipped at the widest range).
    pub problem: Option<AcquisitionProblem>,
}

/// Plays `buffers` (one per audio channel, at the audio rate) while recording `record_samples` samples per DAQ
/// channel, repeating as `policy` says; device faults are recovered by the session. `unit` names the point or
/// actuator in the retry events. A clipped acquisition at a range that cannot grow is returned as it is (a repeat
/// at the same range clips again).
///
/// Returns `None` when a stop to abandon the unit in flight is requested (checked before every acquisition).
///
/// # Errors
/// Device faults recovery cannot fix, as [`RecipeError`] says.
#[allow(clippy::too_many_arguments)] // The session, what to play, how to retry, and the run's control and observer.
pub(crate) fn acquire(
    session: &mut Instruments<'_>,
    buffers: &[Vec<f64>],
    record_samples: usize,
    policy: RetryPolicy,
    unit: usize,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<Option<Acquired>, RecipeError> {
    let mut attempts = 0;
    loop {
        if control.abandon_requested() {
            return Ok(None);
        }
        let acquisition = session.with_recovery(control, observer, |s| s.acquire(buffers, record_samples))?;
        attempts += 1;
        let Some(problem) = AcquisitionProblem::of(&acquisition) else {
            return Ok(Some(Acquired { acquisition, attempts, problem: None }));
        };
        if attempts >= policy.max_attempts.max(1) {
            return Ok(Some(Acquired { acquisition, attempts, problem: Some(problem) }));
        }
        if problem == AcquisitionProblem::Clipped {
            let grew = session.with_recovery(control, observer, Instruments::widen_range)?;
            if !grew {
                return Ok(Some(Acquired { acquisition, attempts, problem: Some(problem) }));
            }
            tracing::info!(unit, "clipped: velocity range widened");
        }
        observer.event(&Event::Retry { unit, attempt: attempts, reason: problem.describe().into() });
    }
}

/// Samples to record for `playback`: all of it, plus 0.1 s for the audio interface's output latency.
pub fn record_samples(playback: &DrivePlayback, fs: f64) -> usize {
    record_samples_for(playback.drive.len(), fs)
}

/// Samples to record for a playback of `daq_len` samples at the DAQ rate `fs`: all of it, plus 0.1 s for the audio
/// interface's output latency.
pub fn record_samples_for(daq_len: usize, fs: f64) -> usize {
    const LATENCY_MARGIN_S: f64 = 0.1;
    daq_len + (LATENCY_MARGIN_S * fs).ceil() as usize
}
