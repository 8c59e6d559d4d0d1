//! Sans-IO codec of the USB HID boot keyboard input report, as a response keypad sends it (Device Class Definition
//! for HID 1.11, appendix B.1; key codes from the HID Usage Tables, keyboard/keypad page 0x07).
//!
//! A boot report is 8 bytes: a modifier bitmap (bit `i` is usage `0xE0 + i`: left Ctrl, Shift, Alt, GUI, then the
//! right ones), a reserved byte, and up to 6 usage codes of the other keys held down (0 = empty slot). It says which
//! keys are *held*, not what changed, so the decoder diffs each report against the previous one. When more keys are
//! held than the report can carry, the device sends `ErrorRollOver` (usage 0x01) in every slot; the spec asks the host
//! to keep the previous state then, and so does the decoder.
//!
//! Like every codec in `protocols/`, it does no I/O and trusts no input: a report of the wrong length or holding error
//! codes is a typed [`ReportError`], and the decoder's state is then unchanged. The crate's tests decode reports byte
//! for byte into key changes and round-trip [`encode`] and [`held_keys`] (proptest); the fuzz target `keypad_report` in
//! `fuzz/` feeds [`BootDecoder`] arbitrary sequences of arbitrary reports; run it with `cd fuzz && RUSTC_BOOTSTRAP=1
//! cargo fuzz run keypad_report -- -max_total_time=300` (`RUSTC_BOOTSTRAP` lets cargo-fuzz use its sanitizer flags on a
//! stable toolchain).

use std::collections::BTreeSet;

/// Length of a boot keyboard input report, bytes.
pub const BOOT_REPORT_LEN: usize = 8;
/// Key slots in a boot report.
pub const KEY_SLOTS: usize = 6;
/// Usage `ErrorRollOver`: too many keys held.
pub const ERROR_ROLL_OVER: u8 = 0x01;
/// Usage `POSTFail`: the keyboard failed its power-on self test.
pub const POST_FAIL: u8 = 0x02;
/// Usage `ErrorUndefined`.
pub const ERROR_UNDEFINED: u8 = 0x03;
/// Usage of the first modifier (left Control); modifiers are `0xE0..=0xE7`.
pub const FIRST_MODIFIER: u8 = 0xE0;

/// A key: its usage ID on the keyboard/keypad page (0x07), from 0x04 (`a`) up; modifiers are 0xE0..=0xE7.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key(u8);

impl Key {
    /// The key with this usage ID, or `None` for 0x00..=0x03, which are "no key" and error codes, not keys.
    pub fn new(usage: u8) -> Option<Key> {
        (usage > ERROR_UNDEFINED).then_some(Key(usage))
    }

    /// Its usage ID on page 0x07.
    pub fn usage(self) -> u8 {
        self.0
    }

    /// The character the key types unshifted, for the letters (`a` to `z`), the digits of the top row and of the
    /// numeric keypad (`0` to `9`), and space; `None` for any other key (Enter, arrows, modifiers...).
    pub fn character(self) -> Option<char> {
        match self.0 {
            0x04..=0x1D => Some(char::from(b'a' + (self.0 - 0x04))),
            0x1E..=0x26 => Some(char::from(b'1' + (self.0 - 0x1E))),
            0x59..=0x61 => Some(char::from(b'1' + (self.0 - 0x59))),
            0x27 | 0x62 => Some('0'),
            0x2C => Some(' '),
            _ => None,
        }
    }

    /// Whether it is a modifier (carried in the bitmap byte, not in a slot).
    pub fn is_modifier(self) -> bool {
        self.0 >= FIRST_MODIFIER && self.0 <= FIRST_MODIFIER + 7
    }
}

/// Whether a key went down or came up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KeyAction {
    /// Pressed.
    Down,
    /// Released.
    Up,
}

/// One change of one key between two reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct KeyChange {
    /// Which key.
    pub key: Key,
    /// Down or up.
    pub action: KeyAction,
}

/// Why a report was not decoded. The decoder's state is unchanged after any of them.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ReportError {
    /// Not an 8-byte boot report (a report protocol device with another layout, or a report ID not stripped).
    #[error("a boot keyboard report has {BOOT_REPORT_LEN} bytes, this one has {len}")]
    WrongLength {
        /// Bytes received.
        len: usize,
    },
    /// Too many keys held at once (`ErrorRollOver` in every slot): which keys are down is unknown until the next
    /// ordinary report, and the previous state stands.
    #[error("keyboard roll-over: too many keys held at once")]
    RollOver,
    /// The device reported an error code (`POSTFail`, `ErrorUndefined`, or `ErrorRollOver` in only some slots).
    #[error("keyboard error code 0x{code:02x} in a key slot")]
    DeviceError {
        /// The usage code received.
        code: u8,
    },
}

/// Decodes a stream of boot reports into key changes, remembering which keys are held.
#[derive(Debug, Clone, Default)]
pub struct BootDecoder {
    held: BTreeSet<Key>,
}

impl BootDecoder {
    /// A decoder with no key held.
    pub fn new() -> Self {
        Self::default()
    }

    /// The keys held after the last decoded report.
    pub fn held(&self) -> &BTreeSet<Key> {
        &self.held
    }

    /// Forgets every held key (after a reconnection, when the device's state is unknown), without events.
    pub fn reset(&mut self) {
        self.held.clear();
    }

    /// Decodes one report and returns what changed since the previous one: releases first, then presses, each in
    /// ascending usage order (a report does not say in which order keys changed within one polling interval).
    /// A report identical to the previous one returns no change.
    ///
    /// # Errors
    /// [`ReportError`], leaving the state unchanged.
    pub fn decode(&mut self, report: &[u8]) -> Result<Vec<KeyChange>, ReportError> {
        let now = held_keys(report)?;
        let mut changes: Vec<KeyChange> =
            self.held.difference(&now).map(|&key| KeyChange { key, action: KeyAction::Up }).collect();
        changes.extend(now.difference(&self.held).map(|&key| KeyChange { key, action: KeyAction::Down }));
        self.held = now;
        Ok(changes)
    }
}

/// The keys a report says are held.
///
/// # Errors
/// As for [`BootDecoder::decode`].
pub fn held_keys(report: &[u8]) -> Result<BTreeSet<Key>, ReportError> {
    let Ok(bytes) = <&[u8; BOOT_REPORT_LEN]>::try_from(report) else {
        return Err(ReportError::WrongLength { len: report.len() });
    };
    let slots = &bytes[2..];
    if slots.iter().all(|&code| code == ERROR_ROLL_OVER) {
        return Err(ReportError::RollOver);
    }
    if let Some(&code) = slots.iter().find(|&&code| code != 0 && code <= ERROR_UNDEFINED) {
        return Err(ReportError::DeviceError { code });
    }
    // Byte 1 is reserved (OEM use): ignored, as the spec asks.
    let modifiers = (0..8).filter(|bit| bytes[0] & (1 << bit) != 0).map(|bit| Key(FIRST_MODIFIER + bit));
    // A usage listed twice is one held key; `Key::new` drops the empty slots.
    Ok(modifiers.chain(slots.iter().filter_map(|&code| Key::new(code))).collect())
}

/// Encodes the boot report of a set of held keys (what a keyboard sends; for tests and simulated keypads).
///
/// Modifiers go to the bitmap, the other keys to the slots in ascending usage order. More than 6 non-modifier
/// keys give the roll-over report (modifiers still set, every slot `ErrorRollOver`), as a real keyboard does.
pub fn encode(held: &BTreeSet<Key>) -> [u8; BOOT_REPORT_LEN] {
    let mut report = [0_u8; BOOT_REPORT_LEN];
    for key in held.iter().filter(|key| key.is_modifier()) {
        report[0] |= 1 << (key.0 - FIRST_MODIFIER);
    }
    let keys: Vec<u8> = held.iter().filter(|key| !key.is_modifier()).map(|key| key.0).collect();
    if keys.len() > KEY_SLOTS {
        report[2..].fill(ERROR_ROLL_OVER);
    } else {
        report[2..2 + keys.len()].copy_from_slice(&keys);
    }
    report
}
