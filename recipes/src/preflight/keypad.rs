//! The keypad check of `metaplate check` (a hardware file's response keypad answers), beside the rig's checks.

use metaplate_keypad::{HidInput, Keypad};
use serde_json::json;

use super::CheckOutcome;

/// The check `keypad`: it answers, with `wait_s > 0` by a key pressed within that time (s), otherwise only by
/// having opened.
pub fn keypad_check(keypad: &mut Keypad<impl HidInput>, wait_s: f64) -> CheckOutcome {
    let (vendor, product, serial) = keypad.transport().describe();
    let who = format!("{vendor} {product} (serial {serial})");
    let details = json!({"vendor": vendor, "product": product, "serial": serial, "waited_s": wait_s});
    if wait_s == 0.0 {
        let message = format!("{who} opened; its keys were not tested (--keypad-wait-s 10 to test them)");
        return CheckOutcome { name: "keypad", passed: true, message, details };
    }
    let (passed, message) = match keypad.next_event(wait_s) {
        Ok(Some(event)) => (true, format!("{who} answers: key 0x{:02x} {:?}", event.key.usage(), event.action)),
        Ok(None) => (false, format!("{who} opened, but no key was pressed within {wait_s} s: is it the right device?")),
        Err(e) => (false, format!("{who}: {e}")),
    };
    CheckOutcome { name: "keypad", passed, message, details }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use metaplate_core::clock::VirtualClock;
    use metaplate_keypad::{ReportPrefix, ScriptStep, ScriptedHid};

    use super::*;

    /// A keypad that sends `reports` (each after `after_s` of virtual time), then nothing.
    fn pad(reports: Vec<(f64, [u8; 8])>) -> Keypad<ScriptedHid> {
        let clock = Arc::new(VirtualClock::new());
        let script = reports.into_iter().map(|(after_s, bytes)| ScriptStep::boot_report(after_s, bytes)).collect();
        Keypad::new(ScriptedHid::new(&clock, script), clock, ReportPrefix::None)
    }

    #[test]
    fn a_key_pressed_in_time_passes_and_silence_fails_by_name() {
        // Boot keyboard report: modifiers, reserved, six key slots; 0x1e is the key `1`.
        let press = [0, 0, 0x1e, 0, 0, 0, 0, 0];
        let outcome = keypad_check(&mut pad(vec![(2.0, press)]), 10.0);
        assert!(outcome.passed && outcome.message.contains("key 0x1e Down"), "{}", outcome.message);
        let late = keypad_check(&mut pad(vec![(12.0, press)]), 10.0);
        assert!(!late.passed && late.message.contains("no key was pressed within 10 s"), "{}", late.message);
        let unasked = keypad_check(&mut pad(Vec::new()), 0.0);
        assert!(unasked.passed && unasked.message.contains("not tested"), "{}", unasked.message);
    }
}
