//! Device side of the DAQ protocol: arbitrary host bytes (bulk OUT), in arbitrary chunks, into `DeviceDecoder`.
//! Input layout and assertions: `common/chunks.rs` and `common/daq.rs`.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;
#[path = "common/daq.rs"]
mod daq;

use libfuzzer_sys::fuzz_target;
use metaplate_daq_protocol::HostCommand;

fuzz_target!(|data: &[u8]| daq::check::<HostCommand>(data));
