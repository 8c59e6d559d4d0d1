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
