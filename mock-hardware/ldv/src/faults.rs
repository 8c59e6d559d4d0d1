//! The fault schedule: which received line suffers which fault, scripted or drawn from a seed.

use std::collections::BTreeMap;

use crate::speckle::{mix, unit};

/// A fault applied to one received line (lines count from 0 at power-on, every non-empty line). A `Set` gets no
/// reply, so the reply faults leave it alone, except [`Fault::NoReply`]: the line is lost and not carried out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fault {
    /// The line is lost: not carried out, no reply (the driver times out, or reads a `Set` back unchanged).
    NoReply,
    /// The reply is held back and sent just before the reply to the next line, where it is stale.
    LateReply,
    /// One byte of the reply (chosen by the seed) gets its top bit set: never valid ASCII, so it cannot decode.
    GarbledReply,
    /// Only a prefix of the reply is sent (at least 1 byte, no terminator; length chosen by the seed).
    PartialReply,
    /// The line is lost and the link goes down: every read and write fails until the host reopens. With
    /// `power_cycle`, the controller comes back with power-on defaults (remote off, echo as at power-up, each
    /// decoder at its default range and filters), as after a power failure.
    Disconnect {
        /// Whether the controller loses its settings.
        power_cycle: bool,
    },
    /// The line is answered normally, and the next `queries` signal-level queries report a dropout.
    Dropout {
        /// How many signal queries read low.
        queries: u32,
    },
}

/// Faults keyed by simulated time rather than by line index (the mock lab's scene schedule): consulted for every
/// line the device answers, with the device's virtual clock reading.
pub trait TimedFaults: Send + std::fmt::Debug {
    /// The fault for a line answered at `now_s` (simulated time, s), if any. [`Fault::Dropout`] here makes the
    /// line's own signal-level query (and the next `queries - 1`) read low.
    fn fault_at_time(&mut self, now_s: f64) -> Option<Fault>;

    /// Whether a dropped link may come back at `now_s` (false while the device is still absent); a true answer
    /// means the link is back, so the implementation may forget the disconnect.
    fn may_reconnect(&mut self, now_s: f64) -> bool;
}

/// Faults by received-line index, and the seed that places garbled bytes and partial cuts.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultSchedule {
    seed: u64,
    events: BTreeMap<u64, Fault>,
}

impl FaultSchedule {
    /// No faults.
    pub fn none() -> Self {
        Self::default()
    }

    /// A scripted schedule: `events` as (line index, fault); a later entry for the same line replaces an earlier
    /// one. `seed` places garbled bytes and partial cuts.
    pub fn scripted(seed: u64, events: impl IntoIterator<Item = (u64, Fault)>) -> Self {
        Self { seed, events: events.into_iter().collect() }
    }

    /// A random schedule over lines `0..lines`: each line independently suffers a fault with probability
    /// `rate` (valid range 0 to 1; NaN counts as 0, values beyond are clamped), its kind drawn uniformly from
    /// `kinds` (no faults when `kinds` is empty). Deterministic: the same arguments give the same schedule.
    pub fn random(seed: u64, rate: f64, lines: u64, kinds: &[Fault]) -> Self {
        let rate = if rate.is_nan() { 0.0 } else { rate.clamp(0.0, 1.0) };
        let events = (0..lines)
            .filter_map(|line| {
                let draw = mix(seed ^ mix(line));
                let count = u64::try_from(kinds.len()).ok().filter(|&n| n > 0)?;
                let kind = usize::try_from(mix(draw) % count).ok().and_then(|i| kinds.get(i))?;
                (unit(draw) < rate).then_some((line, *kind))
            })
            .collect();
        Self { seed, events }
    }

    /// The fault scheduled for line `line`, if any.
    pub fn fault_at(&self, line: u64) -> Option<Fault> {
        self.events.get(&line).copied()
    }

    /// Every scheduled fault, by line.
    pub fn events(&self) -> impl Iterator<Item = (u64, Fault)> + '_ {
        self.events.iter().map(|(&line, &fault)| (line, fault))
    }

    /// A number from the seed for line `line`, to place a garbled byte or a cut deterministically.
    pub(crate) fn draw(&self, line: u64) -> u64 {
        mix(self.seed.wrapping_add(0x5EED) ^ mix(line))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_schedule_is_deterministic_and_near_its_rate() {
        let kinds = [Fault::NoReply, Fault::GarbledReply, Fault::PartialReply];
        let a = FaultSchedule::random(42, 0.1, 10_000, &kinds);
        assert_eq!(a, FaultSchedule::random(42, 0.1, 10_000, &kinds));
        assert_ne!(a, FaultSchedule::random(43, 0.1, 10_000, &kinds));
        let n = a.events().count() as f64;
        // Binomial(10000, 0.1): sd 30; 5 sd either side.
        assert!((n - 1000.0).abs() < 150.0, "{n} faults");
        for kind in kinds {
            let k = a.events().filter(|&(_, f)| f == kind).count() as f64;
            // About a third each; 5 sd of a binomial(1000, 1/3) is 75.
            assert!((k - n / 3.0).abs() < 75.0, "{kind:?}: {k}");
        }
    }

    #[test]
    fn random_schedule_extremes() {
        let kinds = [Fault::NoReply];
        assert_eq!(FaultSchedule::random(1, 0.0, 1000, &kinds).events().count(), 0);
        assert_eq!(FaultSchedule::random(1, f64::NAN, 1000, &kinds).events().count(), 0);
        assert_eq!(FaultSchedule::random(1, 1.0, 1000, &kinds).events().count(), 1000);
        assert_eq!(FaultSchedule::random(1, 5.0, 1000, &kinds).events().count(), 1000);
        assert_eq!(FaultSchedule::random(1, 1.0, 1000, &[]).events().count(), 0);
        assert_eq!(FaultSchedule::random(1, 1.0, 0, &kinds).events().count(), 0);
    }
}
