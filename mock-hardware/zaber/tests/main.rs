//! Tests of the mock Zaber chain and of the stage driver against it: transcripts of the protocol (each with the
//! manual's section), the driver in process on a virtual clock, and the driver over a pseudo-terminal through the
//! real serial port.

mod common;
mod driver;
mod protocol;
#[cfg(unix)]
mod pty;
mod real_stages;
