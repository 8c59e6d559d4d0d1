//! Opt-in test on a real DAQ that speaks metaplate's bulk protocol, through nusb.
//!
//! `METAPLATE_DAQ_USB=VID:PID:SERIAL` (hex ids) names the device; interface 0, endpoints 0x01 (OUT) and 0x81
//! (IN). Run with `METAPLATE_DAQ_USB=1209:0001:SN0001 cargo test -p metaplate-daq --test real_device -- --ignored`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use metaplate_core::daq::{Daq, DaqChannel, DaqConfig};
use metaplate_daq::{DaqDriver, DriverSettings, UsbSelector, UsbTransport};

#[test]
#[ignore = "needs a real DAQ speaking metaplate's bulk protocol, named by METAPLATE_DAQ_USB=VID:PID:SERIAL"]
fn real_device_streams_one_second() {
    let spec = std::env::var("METAPLATE_DAQ_USB").expect("set METAPLATE_DAQ_USB=VID:PID:SERIAL");
    let parts: Vec<&str> = spec.split(':').collect();
    assert_eq!(parts.len(), 3, "METAPLATE_DAQ_USB must be VID:PID:SERIAL");
    let selector = UsbSelector {
        vendor_id: u16::from_str_radix(parts[0], 16).unwrap(),
        product_id: u16::from_str_radix(parts[1], 16).unwrap(),
        serial: Some(parts[2].to_string()),
        interface: 0,
        endpoint_out: 0x01,
        endpoint_in: 0x81,
    };
    let mut daq = DaqDriver::open(UsbTransport::open(selector).unwrap(), DriverSettings::default()).unwrap();
    assert_eq!(daq.identity().serial, parts[2]);
    let config = DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 240,
    };
    daq.configure(&config).unwrap();
    daq.start().unwrap();
    let mut next = 0;
    for _ in 0..100 {
        let block = daq.read_block().unwrap();
        assert_eq!(block.first_sample_index, next);
        assert!(block.integrity.is_contiguous(), "{:?}", block.integrity);
        next += block.len_samples() as u64;
    }
    daq.stop().unwrap();
}
