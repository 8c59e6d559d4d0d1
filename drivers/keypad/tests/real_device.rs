//! Opt-in test on a real keypad (any USB HID keyboard), through hidapi.
//!
//! `METAPLATE_KEYPAD=VID:PID[:SERIAL]` (hex ids, as `lsusb` prints them) names the device; the user needs read
//! access to its `/dev/hidraw*` node. Run with
//! `METAPLATE_KEYPAD=046d:c31c cargo test -p metaplate-keypad --test real_device -- --ignored --nocapture`
//! and press and release one key within 10 s.
#![cfg(target_os = "linux")] // hidapi's hidraw backend, the `hidraw` feature's transport, is Linux only.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use std::sync::Arc;

use metaplate_core::clock::RealClock;
use metaplate_keypad::{HidInput, HidapiInput, HidapiSelector, KeyAction, Keypad, ReportPrefix};

#[test]
#[ignore = "needs a real keypad: METAPLATE_KEYPAD=vid:pid cargo test -p metaplate-keypad --test real_device -- --ignored --nocapture"]
fn a_real_keypad_reports_a_press_and_its_release() {
    let spec = std::env::var("METAPLATE_KEYPAD").expect("this test needs METAPLATE_KEYPAD=VID:PID[:SERIAL]");
    // VID:PID[:SERIAL], hex ids (a hardware file's `keypad.usb`, which `metaplate_drivers::UsbIds` parses).
    let mut parts = spec.splitn(3, ':');
    let mut id = || u16::from_str_radix(parts.next().expect("VID:PID[:SERIAL]"), 16).expect("hex USB ids");
    let (vendor_id, product_id) = (id(), id());
    let selector = HidapiSelector { vendor_id, product_id, serial: parts.next().map(str::to_string) };
    let input = HidapiInput::open(selector).unwrap();
    eprintln!("opened {:?}; press and release one key within 10 s", input.describe());
    let mut pad = Keypad::new(input, Arc::new(RealClock::new()), ReportPrefix::None);
    let press = pad.next_event(10.0).unwrap().expect("no key pressed within 10 s");
    assert_eq!(press.action, KeyAction::Down, "{press:?}");
    let release = loop {
        let event = pad.next_event(10.0).unwrap().expect("no key released within 10 s");
        if event.key == press.key {
            break event;
        }
    };
    assert_eq!(release.action, KeyAction::Up);
    // Held for a positive time, as timed by the driver's clock.
    assert!(release.time_s > press.time_s, "{press:?} then {release:?}");
    eprintln!("key 0x{:02x} held {:.3} s", press.key.usage(), release.time_s - press.time_s);
}

#[test]
fn an_absent_device_is_a_typed_error() {
    // 0xFFFF:0xFFFF is no vendor's id; with or without HID devices on this machine, it is not found.
    let selector = HidapiSelector { vendor_id: 0xFFFF, product_id: 0xFFFF, serial: Some("none".into()) };
    match HidapiInput::open(selector) {
        Err(error) => assert!(error.to_string().contains("ffff:ffff"), "{error}"),
        Ok(_) => panic!("opened a device that cannot exist"),
    }
}
