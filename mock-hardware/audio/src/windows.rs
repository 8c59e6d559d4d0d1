//! Time-keyed faults of a scene, as the mock devices consult them: is a fault of this kind active now, and has a
//! disconnect taken a device off its bus.

use metaplate_core::scene::{FaultKind, FaultSpec};

/// The windows of one scene's fault schedule, `[at_s, at_s + duration_s]` (closed: a zero-length window is an
/// instant that still catches an operation at exactly `at_s`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FaultWindows {
    faults: Vec<FaultSpec>,
}

impl FaultWindows {
    /// The scene's `faults`, in any order (non-finite or negative times never match).
    pub fn new(faults: &[FaultSpec]) -> Self {
        let mut faults = faults.to_vec();
        faults.sort_by(|a, b| a.at_s.total_cmp(&b.at_s));
        Self { faults }
    }

    /// Every fault of `kind`, by start time.
    pub fn of_kind(&self, kind: FaultKind) -> impl Iterator<Item = &FaultSpec> + '_ {
        self.faults.iter().filter(move |f| f.kind == kind)
    }

    /// The first fault of `kind` whose window contains `now_s`, if any.
    pub fn active(&self, kind: FaultKind, now_s: f64) -> Option<&FaultSpec> {
        self.of_kind(kind).find(|f| f.at_s <= now_s && now_s <= f.at_s + f.duration_s)
    }
}

/// One device's view of the scene's `disconnect` faults: a disconnect whose start has passed takes the device off
/// its bus the next time it is used (its handle is stale even if the window has ended by then); it can be reopened
/// only once the window has ended.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DisconnectTracker {
    /// (start, end) of each disconnect, by start.
    windows: Vec<(f64, f64)>,
    /// Disconnects already suffered (the first `seen` windows).
    seen: usize,
    /// The end of the window that took the device away, while it is away.
    away_until_s: Option<f64>,
}

impl DisconnectTracker {
    /// The tracker of `windows`' `disconnect` faults.
    pub fn new(windows: &FaultWindows) -> Self {
        let windows = windows.of_kind(FaultKind::Disconnect).map(|f| (f.at_s, f.at_s + f.duration_s)).collect();
        Self { windows, seen: 0, away_until_s: None }
    }

    /// Called on every use of the device at `now_s`: true when the device is (or has just gone) off its bus.
    pub fn is_away(&mut self, now_s: f64) -> bool {
        while let Some(&(start, end)) = self.windows.get(self.seen) {
            if start > now_s {
                break;
            }
            self.seen += 1;
            self.away_until_s = Some(self.away_until_s.map_or(end, |e: f64| e.max(end)));
        }
        self.away_until_s.is_some()
    }

    /// A reopen at `now_s`: succeeds (true) unless the device is within a disconnect window.
    pub fn reopen(&mut self, now_s: f64) -> bool {
        self.is_away(now_s);
        match self.away_until_s {
            Some(end) if now_s < end => false,
            _ => {
                self.away_until_s = None;
                true
            }
        }
    }

    /// Whether a reopen at `now_s` would succeed, without changing anything.
    pub fn may_reopen(&self, now_s: f64) -> bool {
        let pending_end =
            self.windows.iter().skip(self.seen).filter(|&&(s, _)| s <= now_s).map(|&(_, e)| e).fold(None, max_opt);
        !matches!(max_opt(self.away_until_s, pending_end), Some(end) if now_s < end)
    }
}

fn max_opt(a: Option<f64>, b: impl Into<Option<f64>>) -> Option<f64> {
    match (a, b.into()) {
        (Some(x), Some(y)) => Some(x.max(y)),
        (x, y) => x.or(y),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fault(kind: FaultKind, at_s: f64, duration_s: f64) -> FaultSpec {
        FaultSpec { kind, at_s, duration_s }
    }

    #[test]
    fn windows_are_closed_intervals() {
        let w = FaultWindows::new(&[fault(FaultKind::UsbStall, 2.0, 1.0), fault(FaultKind::LdvDropout, 5.0, 0.0)]);
        assert!(w.active(FaultKind::UsbStall, 1.999).is_none());
        assert!(w.active(FaultKind::UsbStall, 2.0).is_some());
        assert!(w.active(FaultKind::UsbStall, 3.0).is_some());
        assert!(w.active(FaultKind::UsbStall, 3.001).is_none());
        assert!(w.active(FaultKind::LdvDropout, 5.0).is_some(), "an instant still matches");
        assert!(w.active(FaultKind::DaqOverrun, 2.5).is_none());
    }

    #[test]
    fn a_disconnect_lasts_until_reopened_after_its_window() {
        let w = FaultWindows::new(&[fault(FaultKind::Disconnect, 10.0, 5.0)]);
        let mut t = DisconnectTracker::new(&w);
        assert!(!t.is_away(9.0));
        assert!(t.may_reopen(9.0));
        assert!(!t.may_reopen(12.0));
        // First use after the start: gone, and stays gone (a stale handle) even after the window.
        assert!(t.is_away(12.0));
        assert!(!t.reopen(14.9));
        assert!(t.is_away(20.0));
        assert!(t.reopen(15.0));
        assert!(!t.is_away(20.0));
    }
}
