//! The crate documentation's example exchange, byte for byte. The expected bytes were computed independently in
//! Python with LabJackPython's `setChecksum8` and `setChecksum16` (`LabJackPython.py`) over the byte lists that
//! `u6.py` builds (`configU6`, `streamConfig(NumChannels=2, SamplesPerPacket=24, ChannelNumbers=[0, 1],
//! ChannelOptions=[0, 0], ScanFrequency=24000)`, `readCal(0)`, `streamStart`, `streamStop`).

use metaplate_u6_protocol::{Command, DeviceInfo, Errorcode, Response, ResponseBody, StreamDecoder, StreamPacket};

use crate::{hex, two_channels};

fn info() -> DeviceInfo {
    DeviceInfo {
        firmware: (1, 43),
        bootloader: (6, 15),
        hardware: (2, 0),
        serial: 360_012_345,
        product_id: 6,
        local_id: 1,
        version_info: 4,
    }
}

/// Encodes `command`, checks its bytes, and decodes them back on the device side.
fn command(command: Command, bytes: &str) {
    let encoded = command.encode().unwrap();
    assert_eq!(encoded, hex(bytes), "{}", command.name());
    assert_eq!(Command::decode(&encoded).unwrap(), command);
}

/// Encodes `response`, checks its bytes, and decodes them back as the answer to `to`.
fn response(to: &Command, response: Response, bytes: &str) {
    let encoded = response.encode();
    assert_eq!(encoded, hex(bytes), "{}", to.name());
    assert_eq!(Response::decode_for(to, &encoded).unwrap(), response);
}

fn ok(body: ResponseBody) -> Response {
    Response { errorcode: Errorcode::OK, body }
}

#[test]
fn the_documented_exchange_byte_for_byte() {
    command(Command::ConfigU6, "0b f8 0a 08 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00");
    response(
        &Command::ConfigU6,
        ok(ResponseBody::ConfigU6(info())),
        "7d f8 10 08 6b 01 00 00 00 2b 01 0f 06 00 02 39 5a 75 15 06 00 01 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 04",
    );
    assert_eq!(info().firmware_version(), "1.43");
    assert_eq!(info().model(), "U6");
    command(Command::ReadMem { calibration: true, block: 0 }, "27 f8 01 2d 00 00 00 00");
    let config = Command::StreamConfig(two_channels());
    command(config.clone(), "0b f8 06 11 fa 00 02 00 18 00 00 08 d0 07 00 00 01 00");
    response(&config, ok(ResponseBody::StreamConfig), "0b f8 01 11 00 00 00 00");
    command(Command::StreamStart, "a8 a8");
    response(&Command::StreamStart, ok(ResponseBody::StreamStart), "a9 a9 00 00");
    let packet = StreamPacket {
        timestamp: 0,
        packet_number: 0,
        errorcode: Errorcode::OK,
        samples: vec![0x8000, 0x8010, 0x0000, 0xffff],
        backlog: 3,
    };
    let bytes = hex("d6 f9 08 c0 11 03 00 00 00 00 00 00 00 80 10 80 00 00 ff ff 03 00");
    assert_eq!(packet.encode().unwrap(), bytes);
    let mut decoder = StreamDecoder::new(4);
    decoder.push(&bytes);
    assert_eq!(decoder.poll(), Some(Ok(packet)));
    assert_eq!(decoder.poll(), None);
    command(Command::StreamStop, "b0 b0");
    response(&Command::StreamStop, ok(ResponseBody::StreamStop), "b1 b1 00 00");
    // StreamStop while stopped: errorcode 52 STREAM_NOT_RUNNING (same checksum rule).
    let not_running = Response { errorcode: Errorcode::STREAM_NOT_RUNNING, body: ResponseBody::StreamStop };
    response(&Command::StreamStop, not_running, "e5 b1 34 00");
}

#[test]
fn the_48_mhz_clock_gives_the_papers_rate() {
    assert_eq!(two_channels().scan_rate_hz(), 24_000.0);
    assert_eq!(two_channels().check(), Ok(()));
}
