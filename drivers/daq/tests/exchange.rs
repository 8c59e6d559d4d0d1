//! Byte-exact exchanges of the driver with a scripted U6: the packets are the protocol crate's documented example
//! (protocols/labjack-u6/src/lib.rs, "Example exchange", made with LabJackPython's checksum functions over
//! `u6.py`'s byte lists), so the driver's OUT bytes are checked against the User's Guide's layouts.

use crate::common;

use common::{Scripted, hex};
use metaplate_core::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use metaplate_daq::{DriverSettings, U6Driver};
use metaplate_u6_protocol::{Calibration, Command, Errorcode, Response, ResponseBody, StreamPacket, checksum};

const CONFIG_U6: &str = "0b f8 0a 08 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00";
const CONFIG_U6_RESPONSE: &str = "7d f8 10 08 6b 01 00 00 00 2b 01 0f 06 00 02 39 5a 75 15 06 00 01 00 00 00 00 00 \
    00 00 00 00 00 00 00 00 00 00 04";
const READ_CAL_0: &str = "27 f8 01 2d 00 00 00 00";
const STREAM_CONFIG: &str = "0b f8 06 11 fa 00 02 00 18 00 00 08 d0 07 00 00 01 00";
const STREAM_CONFIG_RESPONSE: &str = "0b f8 01 11 00 00 00 00";
const STREAM_START: &str = "a8 a8";
const STREAM_START_RESPONSE: &str = "a9 a9 00 00";
const STREAM_STOP: &str = "b0 b0";
const STREAM_STOP_RESPONSE: &str = "b1 b1 00 00";
/// StreamStop while no stream runs: errorcode 52 (`STREAM_NOT_RUNNING`).
const STREAM_STOP_NOT_RUNNING: &str = "e5 b1 34 00";

/// The example's configuration: AIN0 and AIN1 at +/-10 V, 24 kHz, 12-scan blocks.
fn example_config() -> DaqConfig {
    DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 1, range_v: 10.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 12,
    }
}

/// The ReadCal response for block `block` of the ideal calibration.
fn read_cal(block: u8) -> Vec<u8> {
    let data = Calibration::ideal().to_blocks()[usize::from(block)];
    Response { errorcode: Errorcode::OK, body: ResponseBody::ReadMem { calibration: true, data } }.encode()
}

/// The responses of opening: StreamStop (none running), ConfigU6, ReadCal 0-3.
fn open_replies() -> Vec<Vec<Vec<u8>>> {
    let mut all = vec![vec![hex(STREAM_STOP_NOT_RUNNING)], vec![hex(CONFIG_U6_RESPONSE)]];
    all.extend((0..4).map(|b| vec![read_cal(b)]));
    all
}

#[test]
fn documented_exchange_is_byte_exact() {
    let mut replies = open_replies();
    replies.extend([
        vec![hex(STREAM_CONFIG_RESPONSE)],
        vec![hex(STREAM_START_RESPONSE)],
        vec![hex(STREAM_STOP_RESPONSE)],
    ]);
    let samples: Vec<u16> = (0..24).map(|k| 32_768 + k).collect();
    let packet = StreamPacket { timestamp: 0, packet_number: 0, errorcode: Errorcode::OK, samples, backlog: 2 };
    let mut daq =
        U6Driver::open(Scripted::new(replies, vec![packet.encode().unwrap()]), DriverSettings::default()).unwrap();
    let id = daq.identity().clone();
    assert_eq!(
        (id.vendor.as_str(), id.model.as_str(), id.serial.as_str(), id.firmware.as_str()),
        ("LabJack", "U6", "360012345", "1.43")
    );
    assert_eq!(daq.calibration(), &Calibration::from_blocks(&Calibration::ideal().to_blocks()).unwrap());
    daq.configure(&example_config()).unwrap();
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    daq.stop().unwrap();
    let written: Vec<Vec<u8>> = daq.transport().written.clone();
    let mut expected = vec![hex(STREAM_STOP), hex(CONFIG_U6), hex(READ_CAL_0)];
    expected.extend((1..4).map(|block| Command::ReadMem { calibration: true, block }.encode().unwrap()));
    expected.extend([hex(STREAM_CONFIG), hex(STREAM_START), hex(STREAM_STOP)]);
    assert_eq!(written, expected);
    // The samples interleave AIN0, AIN1: codes 32768 + 2k on AIN0, 32769 + 2k on AIN1, 10/32768 V per code.
    assert_eq!(block.first_sample_index, 0);
    let step = 10.0 / 32_768.0;
    assert_eq!(block.volts[0], (0..12).map(|k| f64::from(2 * k) * step).collect::<Vec<_>>());
    assert_eq!(block.volts[1], (0..12).map(|k| f64::from(2 * k + 1) * step).collect::<Vec<_>>());
    assert!(block.integrity.is_contiguous() && !block.integrity.clipped);
}

#[test]
fn a_stale_response_is_dropped_and_a_bad_checksum_resends() {
    let mut replies = open_replies();
    // StreamConfig is answered first by a stale StreamStop response, then `B8 B8`; the resend gets its answer.
    replies.push(vec![hex(STREAM_STOP_RESPONSE), vec![0xb8, 0xb8]]);
    replies.push(vec![hex(STREAM_CONFIG_RESPONSE)]);
    let mut daq = U6Driver::open(Scripted::new(replies, vec![]), DriverSettings::default()).unwrap();
    daq.configure(&example_config()).unwrap();
    assert_eq!(daq.stats().stale_responses, 1);
    assert_eq!(daq.stats().retries, 1);
    let written = &daq.transport().written;
    assert_eq!(written[written.len() - 2..], [hex(STREAM_CONFIG), hex(STREAM_CONFIG)]);
}

#[test]
fn a_device_errorcode_is_typed_with_its_name() {
    let mut replies = open_replies();
    let mut refused = hex(STREAM_CONFIG_RESPONSE);
    refused[6] = 58;
    checksum::seal(&mut refused);
    replies.push(vec![refused]);
    let mut daq = U6Driver::open(Scripted::new(replies, vec![]), DriverSettings::default()).unwrap();
    let err = daq.configure(&example_config()).unwrap_err();
    assert_eq!(
        err,
        DaqError::Device { code: 58, detail: "StreamConfig returned STREAM_SCAN_RATE_INVALID (58)".into() }
    );
}

#[test]
fn a_device_that_is_not_a_u6_is_refused() {
    let mut info = hex(CONFIG_U6_RESPONSE);
    info[19] = 3; // ProductID 3: a U3.
    checksum::seal(&mut info);
    let replies = vec![vec![hex(STREAM_STOP_NOT_RUNNING)], vec![info]];
    let err = U6Driver::open(Scripted::new(replies, vec![]), DriverSettings::default()).unwrap_err();
    assert!(matches!(err, DaqError::Unavailable { .. }), "{err:?}");
}

#[test]
fn an_erased_calibration_memory_is_refused() {
    let mut replies = vec![vec![hex(STREAM_STOP_NOT_RUNNING)], vec![hex(CONFIG_U6_RESPONSE)]];
    let erased =
        Response { errorcode: Errorcode::OK, body: ResponseBody::ReadMem { calibration: true, data: [0xff; 32] } };
    replies.extend((0..4).map(|_| vec![erased.encode()]));
    let err = U6Driver::open(Scripted::new(replies, vec![]), DriverSettings::default()).unwrap_err();
    assert!(matches!(&err, DaqError::Unavailable { detail } if detail.contains("calibration")), "{err:?}");
}
