//! Every class of malformed input gives a typed error, never a panic; the stream decoder resynchronises.

use metaplate_u6_protocol::{
    BAD_CHECKSUM_RESPONSE, Command, Errorcode, Response, StreamDecoder, StreamPacket, U6Error, checksum,
};

use crate::hex;

fn packet(number: u8) -> Vec<u8> {
    StreamPacket { timestamp: 0, packet_number: number, errorcode: Errorcode::OK, samples: vec![1, 2], backlog: 0 }
        .encode()
        .unwrap()
}

#[test]
fn commands_with_bad_checksums_or_shapes_are_refused() {
    let mut c = Command::ConfigU6.encode().unwrap();
    c[10] = 1;
    assert!(matches!(Command::decode(&c), Err(U6Error::Checksum { .. })));
    assert!(matches!(Command::decode(&[]), Err(U6Error::BadLength { .. })));
    assert!(matches!(Command::decode(&[0xf8]), Err(U6Error::BadLength { .. })));
    // A normal command the codec does not know (U6 Feedback is extended; 0x99 is the reset command).
    let mut unknown = vec![0, 0x99, 0x03];
    checksum::seal(&mut unknown);
    assert!(matches!(Command::decode(&unknown), Err(U6Error::UnexpectedCommandBytes { .. })));
    // An extended command whose data-word count disagrees with its length.
    let mut short = hex("00 f8 06 11 00 00 02 00");
    checksum::seal(&mut short);
    assert!(matches!(Command::decode(&short), Err(U6Error::BadLength { .. })));
    // StreamConfig with a reserved ScanConfig bit.
    let mut config = hex("0b f8 06 11 fa 00 02 00 18 00 00 08 d0 07 00 00 01 00");
    config[11] = 0x09;
    checksum::seal(&mut config);
    assert!(matches!(Command::decode(&config), Err(U6Error::InvalidField { field: "ScanConfig", .. })));
}

#[test]
fn responses_are_matched_to_their_command() {
    assert_eq!(Response::decode_for(&Command::StreamStart, &BAD_CHECKSUM_RESPONSE), Err(U6Error::DeviceSawBadChecksum));
    // StreamStop's response read as StreamStart's: a stale reply.
    let stop = hex("b1 b1 00 00");
    assert!(matches!(Response::decode_for(&Command::StreamStart, &stop), Err(U6Error::UnexpectedCommandBytes { .. })));
    let mut corrupt = hex("0b f8 01 11 00 00 00 00");
    corrupt[6] = 50;
    assert!(matches!(
        Response::decode_for(&Command::ConfigU6, &corrupt),
        Err(U6Error::Checksum { .. } | U6Error::UnexpectedCommandBytes { .. })
    ));
    let mut long = hex("a9 a9 00 00");
    long.push(0);
    checksum::seal(&mut long);
    assert!(matches!(Response::decode_for(&Command::StreamStart, &long), Err(U6Error::BadLength { .. })));
}

#[test]
fn the_stream_decoder_resynchronises_after_garbage_and_corruption() {
    let mut bytes = vec![0x55, 0xf9, 0x00];
    bytes.extend(packet(0));
    let mut corrupt = packet(1);
    corrupt[12] ^= 0x40;
    bytes.extend(&corrupt);
    bytes.extend(packet(2));
    let mut d = StreamDecoder::new(2);
    d.push(&bytes);
    let got: Vec<_> = std::iter::from_fn(|| d.poll()).collect();
    assert_eq!(got[0], Err(U6Error::Garbage { skipped_bytes: 3 }));
    assert_eq!(got[1].as_ref().map(|p| p.packet_number), Ok(0));
    assert!(matches!(got[2], Err(U6Error::Checksum { what: "StreamData", .. })));
    // The rest of the corrupt packet is skipped as garbage, then packet 2.
    assert_eq!(got[3], Err(U6Error::Garbage { skipped_bytes: corrupt.len() - 1 }));
    assert_eq!(got[4].as_ref().map(|p| p.packet_number), Ok(2));
    assert_eq!(got.len(), 5);
    assert_eq!(d.buffered_len(), 0);
}

#[test]
fn a_packet_with_a_nonzero_last_byte_is_refused() {
    let mut p = packet(0);
    let n = p.len();
    p[n - 1] = 7;
    checksum::seal(&mut p);
    let mut d = StreamDecoder::new(2);
    d.push(&p);
    assert!(matches!(d.poll(), Some(Err(U6Error::InvalidField { field: "last byte", .. }))));
}

#[test]
fn packets_of_no_or_too_many_samples_do_not_encode() {
    let p =
        |n| StreamPacket { timestamp: 0, packet_number: 0, errorcode: Errorcode::OK, samples: vec![0; n], backlog: 0 };
    assert!(p(0).encode().is_err());
    assert!(p(26).encode().is_err());
    assert!(p(25).encode().is_ok());
}
