//! Boot keyboard reports, byte for byte, into key changes; and encode/decode round trips.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use std::collections::BTreeSet;

use metaplate_keypad_protocol::{BootDecoder, Key, KeyAction, KeyChange, ReportError, encode, held_keys};
use proptest::prelude::*;

fn key(usage: u8) -> Key {
    Key::new(usage).unwrap()
}

fn down(usage: u8) -> KeyChange {
    KeyChange { key: key(usage), action: KeyAction::Down }
}

fn up(usage: u8) -> KeyChange {
    KeyChange { key: key(usage), action: KeyAction::Up }
}

#[test]
fn a_press_and_release_sequence() {
    // Usages: 0x1E = "1", 0x1F = "2", 0x20 = "3" (HID Usage Tables, keyboard page); bit 1 = left Shift (0xE1).
    let mut decoder = BootDecoder::new();
    let sequence: [(&[u8], Vec<KeyChange>); 7] = [
        (&[0, 0, 0, 0, 0, 0, 0, 0], vec![]),
        (&[0, 0, 0x1E, 0, 0, 0, 0, 0], vec![down(0x1E)]),
        // Same report again (a device re-sends on its idle rate): nothing changed.
        (&[0, 0, 0x1E, 0, 0, 0, 0, 0], vec![]),
        // "2" joins in the second slot, Shift goes down.
        (&[0x02, 0, 0x1E, 0x1F, 0, 0, 0, 0], vec![down(0x1F), down(0xE1)]),
        // "1" released: "2" moves to the first slot, which is not a change.
        (&[0x02, 0, 0x1F, 0, 0, 0, 0, 0], vec![up(0x1E)]),
        // Releases come before presses, each ascending.
        (&[0x00, 0, 0x20, 0, 0, 0, 0, 0], vec![up(0x1F), up(0xE1), down(0x20)]),
        (&[0, 0, 0, 0, 0, 0, 0, 0], vec![up(0x20)]),
    ];
    for (step, (report, expected)) in sequence.iter().enumerate() {
        assert_eq!(&decoder.decode(report).unwrap(), expected, "step {step}");
    }
    assert!(decoder.held().is_empty());
}

#[test]
fn every_modifier_bit_is_its_own_key() {
    let mut decoder = BootDecoder::new();
    let changes = decoder.decode(&[0xFF, 0, 0, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(changes, (0xE0..=0xE7).map(down).collect::<Vec<_>>());
}

#[test]
fn the_reserved_byte_is_ignored_and_duplicates_count_once() {
    let mut decoder = BootDecoder::new();
    assert_eq!(decoder.decode(&[0, 0xAB, 0x04, 0x04, 0, 0, 0, 0x05]).unwrap(), vec![down(0x04), down(0x05)]);
    assert_eq!(decoder.decode(&[0, 0x00, 0x05, 0, 0, 0, 0, 0x04]).unwrap(), vec![]);
}

#[test]
fn roll_over_keeps_the_previous_state() {
    let mut decoder = BootDecoder::new();
    decoder.decode(&[0, 0, 0x1E, 0x1F, 0, 0, 0, 0]).unwrap();
    // Modifiers are still reported beside a roll-over; the slots are all ErrorRollOver.
    assert_eq!(decoder.decode(&[0x01, 0, 1, 1, 1, 1, 1, 1]), Err(ReportError::RollOver));
    assert_eq!(decoder.held(), &BTreeSet::from([key(0x1E), key(0x1F)]));
    // When the participant lets go, the next ordinary report gives the changes against the state before.
    assert_eq!(decoder.decode(&[0, 0, 0x1F, 0, 0, 0, 0, 0]).unwrap(), vec![up(0x1E)]);
}

#[test]
fn error_codes_and_wrong_lengths_are_typed_errors() {
    let mut decoder = BootDecoder::new();
    decoder.decode(&[0, 0, 0x04, 0, 0, 0, 0, 0]).unwrap();
    assert_eq!(decoder.decode(&[0, 0, 0x02, 0, 0, 0, 0, 0]), Err(ReportError::DeviceError { code: 0x02 }));
    assert_eq!(decoder.decode(&[0, 0, 0x04, 0x03, 0, 0, 0, 0]), Err(ReportError::DeviceError { code: 0x03 }));
    // ErrorRollOver in only some slots is not a roll-over report.
    assert_eq!(decoder.decode(&[0, 0, 1, 1, 1, 1, 1, 0]), Err(ReportError::DeviceError { code: 0x01 }));
    for len in [0, 1, 7, 9, 64] {
        let err = decoder.decode(&vec![0; len]).unwrap_err();
        assert_eq!(err, ReportError::WrongLength { len });
        assert!(err.to_string().contains(&format!("this one has {len}")), "{err}");
    }
    // None of them changed the state.
    assert_eq!(decoder.held(), &BTreeSet::from([key(0x04)]));
}

#[test]
fn encoding_is_byte_exact() {
    let held = BTreeSet::from([key(0x1F), key(0xE1), key(0x1E), key(0xE4)]);
    assert_eq!(encode(&held), [0x12, 0, 0x1E, 0x1F, 0, 0, 0, 0]);
    let seven: BTreeSet<Key> = (0x04..0x0B).map(key).chain([key(0xE0)]).collect();
    assert_eq!(encode(&seven), [0x01, 0, 1, 1, 1, 1, 1, 1]);
    assert_eq!(encode(&BTreeSet::new()), [0; 8]);
}

/// Any set of held keys: modifiers and keys from the whole usage range a keyboard can send in a slot.
fn held_set(max_keys: usize) -> impl Strategy<Value = BTreeSet<Key>> {
    (any::<u8>(), prop::collection::btree_set(0x04_u8..0xE0, 0..=max_keys)).prop_map(|(bits, keys)| {
        (0..8).filter(|b| bits & (1 << b) != 0).map(|b| key(0xE0 + b)).chain(keys.into_iter().map(key)).collect()
    })
}

proptest! {
    #[test]
    fn round_trip_of_held_sets(held in held_set(6)) {
        prop_assert_eq!(held_keys(&encode(&held)).unwrap(), held);
    }

    /// Replaying the decoded changes on the previous state gives the encoded state, step after step; and too many
    /// keys (a roll-over report) leave the state where it was.
    #[test]
    fn decoded_changes_replay_to_the_encoded_state(states in prop::collection::vec(held_set(8), 1..20)) {
        let mut decoder = BootDecoder::new();
        let mut replayed = BTreeSet::new();
        for held in states {
            let report = encode(&held);
            let slots = held.iter().filter(|k| !k.is_modifier()).count();
            match decoder.decode(&report) {
                Ok(changes) => {
                    prop_assert!(slots <= 6);
                    for change in changes {
                        let fresh = match change.action {
                            KeyAction::Down => replayed.insert(change.key),
                            KeyAction::Up => replayed.remove(&change.key),
                        };
                        // A press of a held key or a release of a free one would be a decoder bug.
                        prop_assert!(fresh, "{:?}", change);
                    }
                    prop_assert_eq!(&replayed, &held);
                }
                Err(ReportError::RollOver) => prop_assert!(slots > 6),
                Err(other) => prop_assert!(false, "{other}"),
            }
            prop_assert_eq!(decoder.held(), &replayed);
        }
    }

    /// Arbitrary bytes never panic, and a decoded report re-encodes to one that decodes to the same keys.
    #[test]
    fn arbitrary_reports_decode_or_fail_cleanly(bytes in prop::collection::vec(any::<u8>(), 0..12)) {
        let mut decoder = BootDecoder::new();
        if let Ok(held) = held_keys(&bytes) {
            prop_assert_eq!(bytes.len(), 8);
            decoder.decode(&bytes).unwrap();
            // A report holds at most 6 slot keys, so re-encoding them never rolls over.
            prop_assert_eq!(held_keys(&encode(&held)).unwrap(), held);
        } else {
            prop_assert!(decoder.decode(&bytes).is_err());
            prop_assert!(decoder.held().is_empty());
        }
    }
}
