//! The codec against transcripts from the public sources, and against hostile bytes.
#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod hostile;
mod transcripts;
