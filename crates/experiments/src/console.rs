//! The experimenter's console as the binary runs it: entries from a line-based input (the terminal) and from the
//! response keypad (each key press one entry of its character), read on threads so that a stimulus can repeat while
//! the console waits ([`ChannelConsole`], a [`Console`] for the runner).

use std::io::BufRead;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use metaplate_keypad::{HidInput, KeyAction, Keypad};

use crate::runner::{Console, ConsoleEntry};

/// How long the keypad's thread waits for a report before looking again, s.
const KEYPAD_POLL_S: f64 = 0.2;

/// Entries handed over by reader threads.
pub struct ChannelConsole {
    entries: Receiver<String>,
}

impl ChannelConsole {
    /// Reads `lines` (the terminal) and, if given, `keypad`'s key presses on threads of their own; `log` reports the
    /// keypad's errors (a device that asks to be reopened is reopened a second later).
    pub fn spawn<H: HidInput + Send + 'static>(
        lines: impl BufRead + Send + 'static,
        keypad: Option<Keypad<H>>,
        log: fn(&str),
    ) -> Self {
        let (tx, entries) = std::sync::mpsc::channel();
        if let Some(keypad) = keypad {
            log("the keypad answers too: its keys are the console's");
            let tx = tx.clone();
            std::thread::spawn(move || forward_keypad_keys(keypad, |entry| tx.send(entry).is_ok(), log));
        }
        std::thread::spawn(move || {
            for line in lines.lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self { entries }
    }
}

impl Console for ChannelConsole {
    fn next_entry(&mut self, timeout: Option<Duration>) -> ConsoleEntry {
        match timeout {
            Some(t) => match self.entries.recv_timeout(t) {
                Ok(line) => ConsoleEntry::Line(line),
                Err(RecvTimeoutError::Timeout) => ConsoleEntry::TimedOut,
                Err(RecvTimeoutError::Disconnected) => ConsoleEntry::Closed,
            },
            None => self.entries.recv().map_or(ConsoleEntry::Closed, ConsoleEntry::Line),
        }
    }
}

/// Hands each key pressed on `keypad` (a key down with a character: letters and digits) to `send` as a console
/// entry of that one character; ignores releases and keys without a character, reopens a device that asks for it
/// (a second later), and returns when `send` says the console is gone (returns false).
pub fn forward_keypad_keys<H: HidInput>(mut keypad: Keypad<H>, send: impl Fn(String) -> bool, log: fn(&str)) {
    loop {
        match keypad.next_event(KEYPAD_POLL_S) {
            Ok(Some(event)) if event.action == KeyAction::Down => {
                if let Some(c) = event.key.character()
                    && !send(c.to_string())
                {
                    return;
                }
            }
            Ok(_) => {}
            Err(e) if e.suggests_reopen() => {
                log(&format!("keypad: {e}; reopening"));
                std::thread::sleep(Duration::from_secs(1));
                let _ = keypad.reopen();
            }
            Err(e) => log(&format!("keypad: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use std::sync::Arc;

    use metaplate_core::clock::VirtualClock;
    use metaplate_keypad::{ReportPrefix, ScriptStep, ScriptedHid, TransportError};

    use super::*;

    #[test]
    fn the_keypads_key_presses_are_console_entries() {
        // Boot keyboard reports (modifiers, reserved, six key slots): `2` (usage 0x1f) down and up, a shift alone,
        // `u` (0x18), an unplugged pad (reopened), `r` (0x15), then `z` (0x1d) an hour later, which finds the
        // console gone.
        let key = |usage: u8| [0, 0, usage, 0, 0, 0, 0, 0];
        let script = vec![
            ScriptStep::boot_report(0.5, key(0x1f)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::boot_report(0.2, [0x02, 0, 0, 0, 0, 0, 0, 0]),
            ScriptStep::boot_report(0.2, [0; 8]),
            ScriptStep::boot_report(0.3, key(0x18)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::Fail(TransportError::Disconnected("unplugged".into())),
            ScriptStep::boot_report(0.3, key(0x15)),
            ScriptStep::boot_report(0.1, key(0)),
            ScriptStep::boot_report(3600.0, key(0x1d)),
        ];
        let clock = Arc::new(VirtualClock::new());
        let keypad = Keypad::new(ScriptedHid::new(&clock, script), clock, ReportPrefix::None);
        // A channel without a buffer: the last key's hand-over waits for the console, which is gone by then.
        let (tx, rx) = std::sync::mpsc::sync_channel::<String>(0);
        let forwarder = std::thread::spawn(move || forward_keypad_keys(keypad, |entry| tx.send(entry).is_ok(), |_| {}));
        let entries: Vec<String> = (0..3).map(|_| rx.recv_timeout(Duration::from_secs(10)).unwrap()).collect();
        assert_eq!(entries, ["2", "u", "r"]);
        drop(rx);
        forwarder.join().unwrap();
    }

    #[test]
    fn lines_are_entries_and_their_end_closes_the_console() {
        let keypad: Option<Keypad<ScriptedHid>> = None;
        let mut console = ChannelConsole::spawn(std::io::Cursor::new(b"1\nr\n".to_vec()), keypad, |_| {});
        assert_eq!(console.next_entry(None), ConsoleEntry::Line("1".into()));
        assert_eq!(console.next_entry(Some(Duration::from_secs(10))), ConsoleEntry::Line("r".into()));
        assert_eq!(console.next_entry(None), ConsoleEntry::Closed);
    }
}
