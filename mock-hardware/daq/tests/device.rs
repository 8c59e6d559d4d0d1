//! The mock device replays the protocol's documented example byte for byte (protocols/daq/src/lib.rs), except the
//! sample packet, whose contents come from the signal source.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use metaplate_daq_protocol::{DeviceMessage, HostDecoder};
use metaplate_mock_daq::{Fault, FaultSchedule, MockDaq, usb6211_info};

fn hex(text: &str) -> Vec<u8> {
    text.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

fn exchange(device: &mut MockDaq, command: &str) -> Vec<u8> {
    device.receive(&hex(command));
    // Replies are queued, so one transfer carries them all (no packet is produced while any is queued).
    device.next_transfer(1 << 20).unwrap_or_default()
}

#[test]
fn documented_example_replies_are_byte_exact() {
    let mut device = MockDaq::new(
        usb6211_info("SN0001"),
        Box::new(|_: u8, _: u64, _: f64, out: &mut [f64]| {
            out.fill(0.5);
        }),
    )
    .unwrap();
    let info = "4d 44 01 81 00 00 00 00 00 00 33 00 00 00 00 00 10 90 d0 03 00 04 10 27 88 13 e8 03 c8 00 09 6d 65 \
        74 61 70 6c 61 74 65 09 6d 6f 63 6b 2d 36 32 31 31 06 53 4e 30 30 30 31 05 31 2e 30 2e 30 06 3f 59 01";
    assert_eq!(exchange(&mut device, "4d 44 01 01 00 00 00 00 00 00 00 00 61 65 31 4b"), hex(info));
    let configure = "4d 44 01 02 00 00 01 00 00 00 0d 00 c0 5d 00 00 f0 00 02 00 10 27 01 10 27 3b 99 9f fc";
    assert_eq!(exchange(&mut device, configure), hex("4d 44 01 82 00 00 01 00 00 00 04 00 01 00 00 00 8f de de 1a"));
    let start = "4d 44 01 03 00 00 02 00 00 00 00 00 ec ec 0f 28";
    assert_eq!(exchange(&mut device, start), hex("4d 44 01 82 00 00 02 00 00 00 04 00 02 00 00 00 62 ca 5c e3"));
    // One packet (device seq 3): packet 0 from sample 0, 240 samples of 0.5 V on +/-10 V = code 1638.4 -> 1638.
    let mut decoder = HostDecoder::new();
    decoder.push(&device.next_transfer(1 << 20).unwrap());
    let frame = decoder.poll().unwrap().unwrap();
    assert_eq!(frame.seq, 3);
    let DeviceMessage::Samples(packet) = frame.message else { panic!("expected samples") };
    assert_eq!((packet.packet_seq, packet.first_sample_index, packet.n_samples()), (0, 0, 240));
    assert!(packet.samples.iter().all(|&c| c == 1638));
    assert!(!packet.flags.overrun && !packet.flags.clipped);
    let stop = "4d 44 01 04 00 00 03 00 00 00 00 00 80 52 32 87";
    let stopped_ack = "4d 44 01 85 00 00 04 00 00 00 05 00 01 01 00 00 00 b1 c5 4e a5 \
        4d 44 01 82 00 00 05 00 00 00 04 00 03 00 00 00 7e b6 3c b9";
    assert_eq!(exchange(&mut device, stop), hex(stopped_ack));
    let reset = "4d 44 01 05 00 00 04 00 00 00 00 00 7b 76 4c 8d";
    assert_eq!(exchange(&mut device, reset), hex("4d 44 01 82 00 00 06 00 00 00 04 00 04 00 00 00 c4 35 dc cf"));
    let start_again = "4d 44 01 03 00 00 05 00 00 00 00 00 54 dc 0a 35";
    let not_configured = "4d 44 01 83 00 00 07 00 00 00 16 00 03 01 05 00 00 00 0f 63 6f 6e 66 69 67 75 72 65 \
        20 66 69 72 73 74 19 08 f8 dc";
    assert_eq!(exchange(&mut device, start_again), hex(not_configured));
    assert!(device.next_transfer(1 << 20).is_none(), "idle and nothing queued");
}

#[test]
fn schedule_orders_faults_and_keeps_insertion_order_at_one_index() {
    let s = FaultSchedule::none()
        .at(5, Fault::Disconnect)
        .at(2, Fault::Stall { reads: 1 })
        .at(5, Fault::Overrun { packets: 2 });
    assert_eq!(
        s.events(),
        &[(2, Fault::Stall { reads: 1 }), (5, Fault::Disconnect), (5, Fault::Overrun { packets: 2 })]
    );
}
