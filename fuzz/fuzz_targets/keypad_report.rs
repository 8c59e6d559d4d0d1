//! The keypad's boot keyboard report decoder, over arbitrary sequences of arbitrary reports.
//!
//! Input: a sequence of records, each a length byte (taken modulo 12, so that wrong lengths around 8 are common)
//! and that many bytes (fewer at the end of the input). Asserts that the decoder
//! - never panics;
//! - on success holds exactly the keys `held_keys` reads from the report, and its changes replayed on the previous
//!   state give that state (no press of a held key, no release of a free one);
//! - on any error leaves its state unchanged;
//! - holds a state that `encode` turns into a report decoding back to the same keys.

#![no_main]

use std::collections::BTreeSet;

use libfuzzer_sys::fuzz_target;
use metaplate_keypad_protocol::{BootDecoder, KeyAction, encode, held_keys};

fuzz_target!(|data: &[u8]| {
    let mut decoder = BootDecoder::new();
    let mut rest = data;
    while let Some((&len, tail)) = rest.split_first() {
        let (report, next) = tail.split_at(usize::from(len % 12).min(tail.len()));
        rest = next;
        let before: BTreeSet<_> = decoder.held().clone();
        match decoder.decode(report) {
            Ok(changes) => {
                assert_eq!(Ok(decoder.held()), held_keys(report).as_ref());
                let mut replayed = before;
                for change in changes {
                    let fresh = match change.action {
                        KeyAction::Down => replayed.insert(change.key),
                        KeyAction::Up => replayed.remove(&change.key),
                    };
                    assert!(fresh, "{change:?}");
                }
                assert_eq!(&replayed, decoder.held());
            }
            Err(_) => assert_eq!(&before, decoder.held()),
        }
        assert_eq!(held_keys(&encode(decoder.held())).as_ref(), Ok(decoder.held()));
    }
});
