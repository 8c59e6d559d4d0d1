//! The engine: everything a plan needs of the lab and the dataset, and nothing of what a plan decides.
//!
//! - [`session`]: the instruments configured for recipes, and recovery from device faults;
//! - [`acquire`]: one acquisition with the one retry policy (gaps, underruns, clipping);
//! - [`aim`]: the beam on a point, with deterministic nudges;
//! - [`reference`]: the re-measure of a committed reference point after a recovery;
//! - [`plan`]: what the engine asks of a plan (the [`plan::Plan`] trait, steps, verdicts);
//! - [`run`]: the engine's loop, [`run::run`], that runs any plan (open or resume the dataset, started, steps
//!   acquired while the last is processed, commit and checkpoint per unit, stopped or finished).
//!
//! Dependencies point one way: the plans (`crate::plans`) use the engine; the engine never names a plan.

pub mod acquire;
pub mod aim;
pub mod plan;
pub mod reference;
pub(crate) mod rig_record;
pub mod run;
pub mod session;

/// Microseconds since the Unix epoch now (0 if the system clock is before 1970): a row's `measured_at`.
pub(crate) fn now_unix_us() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_micros()).unwrap_or(i64::MAX))
}
