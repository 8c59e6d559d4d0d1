//! The NI-DAQmx backend without NI-DAQmx installed: opening says so with a typed error.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use std::ffi::OsStr;

use metaplate_core::daq::DaqError;
use metaplate_daq::NiDaqmx;

#[test]
fn missing_library_is_reported_as_unavailable() {
    let err = NiDaqmx::open_library(OsStr::new("/nonexistent/libnidaqmx.so"), "Dev1", 1.0).unwrap_err();
    match err {
        DaqError::Unavailable { detail } => {
            assert!(detail.contains("NI-DAQmx") && detail.contains("/nonexistent/libnidaqmx.so"), "{detail}")
        }
        other => panic!("expected Unavailable, got {other:?}"),
    }
}
