//! Opt-in test on a real LabJack U6, through nusb.
//!
//! `METAPLATE_DAQ_USB=SERIAL` names the U6 by its serial number (as ConfigU6 and the label report it; `any`
//! takes the first U6 on the bus). Connect a signal or nothing to AIN0. Run with
//! `METAPLATE_DAQ_USB=360012345 cargo test -p metaplate-daq --test tests real_device -- --ignored`.

use metaplate_core::daq::{Daq, DaqChannel, DaqConfig};
use metaplate_daq::{DriverSettings, U6Driver, UsbSelector, UsbTransport};

#[test]
#[ignore = "needs a LabJack U6 on USB, named by METAPLATE_DAQ_USB=SERIAL (or `any`)"]
fn real_device_streams_one_second() {
    let spec = std::env::var("METAPLATE_DAQ_USB").expect("set METAPLATE_DAQ_USB=SERIAL or any");
    let serial = (spec != "any").then(|| spec.clone());
    let transport = UsbTransport::open(UsbSelector::u6(serial.clone())).unwrap();
    let mut daq = U6Driver::open(transport, DriverSettings::default()).unwrap();
    if let Some(serial) = serial {
        assert_eq!(daq.identity().serial, serial);
    }
    assert_eq!(daq.identity().vendor, "LabJack");
    println!("{:?}, calibration {:?}", daq.identity(), daq.calibration());
    let config = DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 1, range_v: 10.0 }],
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
        assert!(block.volts.iter().flatten().all(|v| v.abs() <= 10.6));
        next += block.len_samples() as u64;
    }
    daq.stop().unwrap();
    println!("stream: {:?}", daq.stats().stream);
}
