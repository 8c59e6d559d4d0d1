//! Device side of the LabJack U6 codec: arbitrary bytes as one OUT transfer into `Command::decode` (what the mock
//! U6 runs on every command). Checks: no panic; a decoded command re-encodes to bytes that decode to it again.

#![no_main]

use libfuzzer_sys::fuzz_target;
use metaplate_u6_protocol::Command;

fuzz_target!(|data: &[u8]| {
    if let Ok(command) = Command::decode(data) {
        let bytes = command.encode().expect("a decoded command re-encodes");
        assert_eq!(Command::decode(&bytes), Ok(command));
    }
});
