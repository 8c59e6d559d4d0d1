//! Host side of the DAQ protocol: arbitrary device bytes (bulk IN), in arbitrary chunks, into `HostDecoder`.
//! Input layout and assertions: `common/chunks.rs` and `common/daq.rs`.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;
#[path = "common/daq.rs"]
mod daq;

use libfuzzer_sys::fuzz_target;
use metaplate_daq_protocol::DeviceMessage;

fuzz_target!(|data: &[u8]| daq::check::<DeviceMessage>(data));
