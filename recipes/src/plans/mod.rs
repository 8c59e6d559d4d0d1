//! The plans: what each recipe measures and what its results mean. They use the engine's narrow types (a session,
//! `acquire`, the run skeleton); the engine never names a plan.

pub mod calibrate;
pub mod scan;
