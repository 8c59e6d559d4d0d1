//! The design crate's tests: the band structure against known answers (the analytic A0, a plane-wave expansion of
//! point spring-mass resonators, the paper's Fig. 2 figures) and the homogenised plate.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod homogeneous;
mod homogenised;
mod paper;
mod pwe;
mod search;
mod spring_mass;
