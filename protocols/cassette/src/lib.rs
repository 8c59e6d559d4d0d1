//! Cassette files (being written).
