//! Tests of the Zaber ASCII codec: the manual's messages, and hostile bytes.

mod hostile;
mod transcripts;
