//! `--notify-command` for a run the monitor watches: the user's command runs when the run's status changes to
//! finished, stopped, failed or stalled while the monitor watches (a run that had already ended when the monitor
//! started is not news), once per event (a new stall after progress is a new event).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use metaplate_recipes::notify::Notifier;

use crate::follow::Follower;
use crate::state::{RunState, RunStatus, snapshot};

/// How often the watch looks at the run.
const WATCH_INTERVAL: Duration = Duration::from_secs(1);

/// Watches the run in `dir` with a follower of its own (read-only, as the page's), every second, and tells
/// `notifier` of each event (see the module's documentation). Runs on a thread of its own until the process ends.
///
/// # Errors
/// The thread could not be started.
pub fn watch(dir: PathBuf, notifier: Arc<Notifier>) -> std::io::Result<()> {
    std::thread::Builder::new().name("monitor-notify".into()).spawn(move || {
        let mut follower = Follower::new(dir.clone());
        let mut previous = None;
        loop {
            follower.poll();
            let state = snapshot(follower.files(), &dir, chrono::Utc::now());
            if let Some(key) = news(previous, &state) {
                notifier.notify(&key, state.status.as_str(), &state.notice());
            }
            previous = Some(state.status);
            std::thread::sleep(WATCH_INTERVAL);
        }
    })?;
    Ok(())
}

/// The event key of `state` when it is news after a poll that saw `previous` (`None`: the first poll): a change of
/// status to finished, stopped, failed or stalled. The key names the status and the units done, so that a stall
/// after progress is a new event and the same one is not.
fn news(previous: Option<RunStatus>, state: &RunState) -> Option<String> {
    let status = state.status;
    let newsworthy = status.has_ended() || status == RunStatus::Stalled;
    (newsworthy && previous.is_some_and(|p| p != status))
        .then(|| format!("{} at {}", status.as_str(), state.points_done))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use std::path::Path;

    use super::*;
    use crate::follow::RunFiles;

    #[test]
    fn only_a_change_to_an_end_or_a_stall_seen_while_watching_is_news() {
        let mut state = snapshot(&RunFiles::default(), Path::new("run"), chrono::Utc::now());
        assert_eq!(state.status, RunStatus::Waiting);
        assert_eq!(news(None, &state), None);
        state.points_done = 6;
        for (status, key) in [
            (RunStatus::Finished, Some("finished at 6")),
            (RunStatus::Stopped, Some("stopped at 6")),
            (RunStatus::Failed, Some("failed at 6")),
            (RunStatus::Stalled, Some("stalled at 6")),
            (RunStatus::Running, None),
        ] {
            state.status = status;
            assert_eq!(news(Some(RunStatus::Running), &state).as_deref(), key.filter(|_| status != RunStatus::Running));
            assert_eq!(news(None, &state), None, "{status:?} when the monitor started is not news");
            assert_eq!(news(Some(status), &state), None, "{status:?} unchanged is not news");
        }
        let notice = state.notice();
        assert_eq!((notice.done, notice.source, notice.dataset.as_str()), (6, "monitor", "run"));
    }
}
