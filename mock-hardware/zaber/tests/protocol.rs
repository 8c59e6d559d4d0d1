//! The mock chain's side of the protocol, byte for byte: each exchange with the section of Zaber's ASCII Protocol
//! Manual it follows.

use std::sync::{Arc, Mutex};

use metaplate_core::clock::VirtualClock;
use metaplate_mock_zaber::{ArmedFault, ChainSpec, MockChain};
use metaplate_zaber_protocol::{WarningFlag, lrc};
use proptest::prelude::*;

fn exchange(chain: &mut MockChain, command: &str) -> String {
    chain.receive(command.as_bytes());
    String::from_utf8_lossy(&chain.take_output()).into_owned()
}

fn fresh() -> (Arc<VirtualClock>, MockChain) {
    let clock = Arc::new(VirtualClock::new());
    (clock.clone(), MockChain::new(ChainSpec::xy_lsm100(10.0), clock))
}

#[test]
fn replies_address_the_device_and_axis_and_echo_the_id() {
    let (_, mut chain) = fresh();
    // Message Format, Replies; Warning Flags: `WR` until the axis is homed.
    assert_eq!(exchange(&mut chain, "/1 1 get pos\n"), "@01 1 OK IDLE WR 1049869\r\n");
    // Message Format, message ids: echoed after the axis.
    assert_eq!(exchange(&mut chain, "/2 1 42 get resolution\r\n"), "@02 1 42 OK IDLE WR 64\r\n");
    // Message Format, Commands: device 0 (or none) addresses every device, each replying.
    assert_eq!(exchange(&mut chain, "/get deviceid\n"), "@01 0 OK IDLE WR 50081\r\n@02 0 OK IDLE WR 50081\r\n");
    // A device not on the chain is silent.
    assert_eq!(exchange(&mut chain, "/9 1 get pos\n"), "");
    // Commands, warnings: the count, then the flags.
    assert_eq!(exchange(&mut chain, "/1 1 warnings\n"), "@01 1 OK IDLE WR 01 WR\r\n");
}

#[test]
fn rejections_name_their_reason() {
    let (_, mut chain) = fresh();
    // Reply Flags: an unknown command, data out of range, a missing axis.
    assert_eq!(exchange(&mut chain, "/1 1 fly\n"), "@01 1 RJ IDLE WR BADCOMMAND\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 move abs 2099739\n"), "@01 1 RJ IDLE WR BADDATA\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 move abs ten\n"), "@01 1 RJ IDLE WR BADDATA\r\n");
    assert_eq!(exchange(&mut chain, "/1 2 get pos\n"), "@01 2 RJ IDLE WR BADAXIS\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 get nothing\n"), "@01 1 RJ IDLE WR BADCOMMAND\r\n");
}

#[test]
fn homing_and_moves_take_their_time() {
    let (clock, mut chain) = fresh();
    // Commands, home: BUSY while it runs; the reference (and `WR`'s end) comes when it arrives.
    assert_eq!(exchange(&mut chain, "/1 1 home\n"), "@01 1 OK BUSY WR 0\r\n");
    clock.advance(4.9); // 50 mm at 10 mm/s takes 5 s.
    assert_eq!(exchange(&mut chain, "/1 1\n"), "@01 1 OK BUSY WR 0\r\n");
    clock.advance(0.2);
    assert_eq!(exchange(&mut chain, "/1 1\n"), "@01 1 OK IDLE -- 0\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 get pos\n"), "@01 1 OK IDLE -- 0\r\n");
    // Commands, move abs: 10 mm = 209974 microsteps, 1 s at 10 mm/s; half-way after 0.5 s.
    assert_eq!(exchange(&mut chain, "/1 1 move abs 209974\n"), "@01 1 OK BUSY -- 0\r\n");
    clock.advance(0.5);
    assert_eq!(exchange(&mut chain, "/1 1 get pos\n"), "@01 1 OK BUSY -- 104987\r\n");
    clock.advance(0.6);
    assert_eq!(exchange(&mut chain, "/1 1 get pos\n"), "@01 1 OK IDLE -- 209974\r\n");
    // move rel, and a relative move past the travel.
    assert_eq!(exchange(&mut chain, "/1 1 move rel -9974\n"), "@01 1 OK BUSY -- 0\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 move rel -9999999\n"), "@01 1 RJ BUSY -- BADDATA\r\n");
}

#[test]
fn faults_latch_until_cleared() {
    let (clock, mut chain) = fresh();
    exchange(&mut chain, "/1 1 home\n");
    clock.advance(10.0);
    let limit = ArmedFault { flag: WarningFlag::UNEXPECTED_LIMIT, fraction: 0.5 };
    assert!(chain.arm_fault(1, 1, limit));
    exchange(&mut chain, "/1 1 move abs 209974\n");
    clock.advance(2.0);
    // Warning Flags: `WL`, the move stopped short; `warnings clear` reports, then drops it (its reply's flag
    // field shows the state after the command, as a move's `BUSY` does: this mock's reading).
    assert_eq!(exchange(&mut chain, "/1 1 get pos\n"), "@01 1 OK IDLE WL 104987\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 warnings clear\n"), "@01 1 OK IDLE -- 01 WL\r\n");
    assert_eq!(exchange(&mut chain, "/1 1 warnings\n"), "@01 1 OK IDLE -- 00\r\n");
    // A fault outranks a warning in the reply's field.
    chain.arm_fault(1, 1, ArmedFault { flag: WarningFlag::parse("FS").unwrap_or(WarningFlag::NONE), fraction: 0.0 });
    chain.power_cycle();
    assert_eq!(exchange(&mut chain, "/1 1 warnings\n"), "@01 1 OK IDLE WR 01 WR\r\n", "a power cycle forgets");
}

#[test]
fn checksums_are_verified_and_sent_when_configured() {
    let clock = Arc::new(VirtualClock::new());
    let mut spec = ChainSpec::xy_lsm100(10.0);
    spec.reply_checksums = true;
    let mut chain = MockChain::new(spec, clock);
    // Message Format, Checksums: `:HH` after the content, both ways.
    let content = "1 1 get resolution";
    let good = format!("/{content}:{:02X}\n", lrc(content.as_bytes()));
    let reply = exchange(&mut chain, &good);
    let expected_content = "01 1 OK IDLE WR 64";
    assert_eq!(reply, format!("@{expected_content}:{:02X}\r\n", lrc(expected_content.as_bytes())));
    let bad = format!("/{content}:{:02X}\n", lrc(content.as_bytes()).wrapping_add(1));
    assert_eq!(exchange(&mut chain, &bad), "", "a command with a wrong checksum gets no reply");
}

proptest! {
    #[test]
    fn hostile_host_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..1024)) {
        let clock = Arc::new(VirtualClock::new());
        let chain = Mutex::new(MockChain::new(ChainSpec::xy_lsm100(10.0), clock));
        let Ok(mut chain) = chain.lock() else { return Ok(()) };
        chain.receive(&bytes);
        let output = chain.take_output();
        // Whatever it answers is well-formed replies.
        for line in String::from_utf8_lossy(&output).lines() {
            prop_assert!(metaplate_zaber_protocol::Message::parse(line).is_ok(), "{line:?}");
        }
    }
}
