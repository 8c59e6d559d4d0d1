//! The universal-file bridge as a library: datasets written through the store, exported, changed as other tools'
//! files differ, and imported back.

mod common;
mod corpus;
mod foreign;
mod pyuff_reads;
mod refusals;
mod round_trip;
mod scattered;
