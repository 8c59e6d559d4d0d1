//! Time as recipes and drivers see it: the wall clock in the lab, a virtual clock in the mock lab.
//!
//! Everything that waits (a beam settling, a sweep playing, a timeout) asks a [`Clock`], never the operating system
//! directly, so the mock lab can run a 30-hour scan in minutes: its virtual clock jumps forward instead of sleeping.

/// A source of time and a way to wait.
pub trait Clock: Send + Sync {
    /// Seconds since this clock's epoch (monotonic, never decreasing).
    fn now_s(&self) -> f64;

    /// Waits `duration_s` seconds (a real clock sleeps; a virtual clock advances). A negative or NaN duration waits
    /// nothing.
    fn sleep_s(&self, duration_s: f64);
}

/// The wall clock: seconds since it was created (monotonic), and real sleeps.
#[derive(Debug, Clone, Copy)]
pub struct RealClock {
    epoch: std::time::Instant,
}

impl RealClock {
    /// A clock whose epoch is now.
    pub fn new() -> Self {
        Self { epoch: std::time::Instant::now() }
    }
}

impl Default for RealClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for RealClock {
    fn now_s(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    /// Sleeps `duration_s` seconds; negative, NaN or infinite durations (and anything beyond
    /// `Duration::MAX`) sleep nothing rather than forever.
    fn sleep_s(&self, duration_s: f64) {
        if let Ok(duration) = std::time::Duration::try_from_secs_f64(duration_s) {
            std::thread::sleep(duration);
        }
    }
}

/// Simulated time for the mock lab: starts at 0 s and moves only when told, never sleeping, so a 3 s sweep costs
/// only its computation. Thread-safe: share it behind an `Arc` between the mock devices and the recipe.
#[derive(Debug, Default)]
pub struct VirtualClock {
    // f64 seconds as bits: one atomic word, so that readers never block and advances never tear.
    now_bits: std::sync::atomic::AtomicU64,
}

impl VirtualClock {
    /// A clock at 0 s.
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves time forward by `duration_s` seconds and returns the new time, s. Valid range: finite
    /// `duration_s >= 0`; anything else (negative, NaN, infinite) leaves the time unchanged, so that time never runs
    /// backwards and never becomes non-finite.
    pub fn advance(&self, duration_s: f64) -> f64 {
        use std::sync::atomic::Ordering;
        let step = |bits: u64| {
            let next = f64::from_bits(bits) + duration_s;
            (duration_s.is_finite() && duration_s > 0.0 && next.is_finite()).then(|| next.to_bits())
        };
        match self.now_bits.fetch_update(Ordering::AcqRel, Ordering::Acquire, step) {
            Ok(previous) => f64::from_bits(previous) + duration_s,
            Err(unchanged) => f64::from_bits(unchanged),
        }
    }
}

impl Clock for VirtualClock {
    fn now_s(&self) -> f64 {
        f64::from_bits(self.now_bits.load(std::sync::atomic::Ordering::Acquire))
    }

    /// Advances the clock by `duration_s` (see [`VirtualClock::advance`]) without sleeping.
    fn sleep_s(&self, duration_s: f64) {
        self.advance(duration_s);
    }
}
