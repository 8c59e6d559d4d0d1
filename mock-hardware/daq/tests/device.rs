//! The mock U6 answers as the User's Guide (section 5.2) and LabJackPython describe the device: identity,
//! calibration memory, stream errorcodes, StreamData packets, auto-recovery after an overflow.

use metaplate_mock_daq::{MockU6, u6_info};
use metaplate_u6_protocol::{
    BAD_CHECKSUM_RESPONSE, Calibration, Command, Errorcode, Gain, Response, ResponseBody, StreamChannel, StreamClock,
    StreamConfig, StreamDecoder, StreamPacket,
};

fn device() -> MockU6 {
    // AIN0 carries 1 V, AIN1 carries -2 V.
    let source = |input: u8, _first: u64, _rate: f64, out: &mut [f64]| out.fill(if input == 0 { 1.0 } else { -2.0 });
    MockU6::new(u6_info(360_012_345), Calibration::nominal(), Box::new(source))
}

fn exchange(u6: &mut MockU6, command: &Command) -> Response {
    u6.receive(&command.encode().unwrap());
    Response::decode_for(command, &u6.next_response().unwrap()).unwrap()
}

fn config() -> StreamConfig {
    let ch = |positive| StreamChannel { positive, gain: Gain::X1, differential: false };
    StreamConfig {
        resolution_index: 0,
        samples_per_packet: 4,
        settling_factor: 0,
        clock: StreamClock::Mhz48,
        divide_by_256: false,
        scan_interval: 2000,
        channels: vec![ch(0), ch(1)],
    }
}

fn packets(u6: &mut MockU6, count: usize) -> Vec<StreamPacket> {
    let mut decoder = StreamDecoder::new(4);
    decoder.push(&u6.next_stream_transfer(count).unwrap());
    std::iter::from_fn(|| decoder.poll()).map(Result::unwrap).collect()
}

#[test]
fn identity_and_calibration_as_configu6_and_readcal_return_them() {
    let mut u6 = device();
    let r = exchange(&mut u6, &Command::ConfigU6);
    assert_eq!(r, Response { errorcode: Errorcode::OK, body: ResponseBody::ConfigU6(u6_info(360_012_345)) });
    let mut blocks = [[0u8; 32]; 4];
    for block in 0..4u8 {
        let r = exchange(&mut u6, &Command::ReadMem { calibration: true, block });
        let ResponseBody::ReadMem { data, .. } = r.body else { panic!("{r:?}") };
        blocks[usize::from(block)] = data;
    }
    assert_eq!(blocks, Calibration::nominal().to_blocks());
    let r = exchange(&mut u6, &Command::ReadMem { calibration: true, block: 4 });
    assert_eq!(r.errorcode, Errorcode::INVALID_BLOCK);
}

#[test]
fn stream_errorcodes_follow_the_device_state() {
    let mut u6 = device();
    assert_eq!(exchange(&mut u6, &Command::StreamStop).errorcode, Errorcode::STREAM_NOT_RUNNING);
    assert_eq!(exchange(&mut u6, &Command::StreamStart).errorcode, Errorcode::STREAM_CONFIG_INVALID);
    let mut bad = config();
    bad.samples_per_packet = 26;
    assert_eq!(exchange(&mut u6, &Command::StreamConfig(bad)).errorcode, Errorcode::STREAM_SAMPLE_NUM_INVALID);
    assert_eq!(exchange(&mut u6, &Command::StreamConfig(config())).errorcode, Errorcode::OK);
    assert_eq!(exchange(&mut u6, &Command::StreamStart).errorcode, Errorcode::OK);
    assert_eq!(exchange(&mut u6, &Command::StreamStart).errorcode, Errorcode::STREAM_IS_ACTIVE);
    assert_eq!(exchange(&mut u6, &Command::StreamConfig(config())).errorcode, Errorcode::STREAM_IS_ACTIVE);
    assert_eq!(exchange(&mut u6, &Command::StreamStop).errorcode, Errorcode::OK);
    assert!(u6.next_stream_transfer(1).is_none());
}

#[test]
fn a_command_with_a_bad_checksum_is_answered_b8_b8() {
    let mut u6 = device();
    let mut bytes = Command::ConfigU6.encode().unwrap();
    bytes[0] ^= 1;
    u6.receive(&bytes);
    assert_eq!(u6.next_response().unwrap(), BAD_CHECKSUM_RESPONSE);
}

#[test]
fn packets_carry_calibrated_codes_in_scan_order() {
    let mut u6 = device();
    exchange(&mut u6, &Command::StreamConfig(config()));
    exchange(&mut u6, &Command::StreamStart);
    let got = packets(&mut u6, 3);
    assert_eq!(got.iter().map(|p| p.packet_number).collect::<Vec<_>>(), [0, 1, 2]);
    let cal = Calibration::from_blocks(&Calibration::nominal().to_blocks()).unwrap();
    let (one, minus_two) = (cal.code(Gain::X1, 1.0).unwrap().0, cal.code(Gain::X1, -2.0).unwrap().0);
    assert_eq!(got[0].samples, [one, minus_two, one, minus_two]);
    assert!(got.iter().all(|p| p.errorcode == Errorcode::OK));
    assert_eq!(u6.scan_index(), Some(6));
}

#[test]
fn an_overflow_is_reported_by_errorcodes_59_then_60() {
    let mut u6 = device();
    exchange(&mut u6, &Command::StreamConfig(config()));
    exchange(&mut u6, &Command::StreamStart);
    packets(&mut u6, 1);
    u6.overflow(10);
    let got = packets(&mut u6, 3);
    assert_eq!(got[0].errorcode, Errorcode::STREAM_AUTORECOVER_ACTIVE);
    assert_eq!(got[1].errorcode, Errorcode::STREAM_AUTORECOVER_REPORT);
    // The dummy scan first; TimeStamp counts the scans the buffer still held (the transfer digitised 3 packets'
    // worth: 6 scans, 2 sent in the flagged packet) and the 10 discarded.
    assert_eq!(got[1].samples[..2], [0xffff, 0xffff]);
    assert_eq!(got[1].timestamp, 4 + 10);
    assert_eq!(got[2].errorcode, Errorcode::OK);
}
