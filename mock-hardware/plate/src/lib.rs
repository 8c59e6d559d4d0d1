//! Simulated plate (being written).
