//! Both sides of Zaber's ASCII protocol: arbitrary bytes, in arbitrary chunks, into `LineSplitter`, and each line
//! into `Command::parse` (the mock chain's side) and `Message::parse` (the stage driver's side).
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the splitter holds at most `MAX_LINE`
//! bytes; chunking does not change the lines; every command and message decoded re-encodes to a line that decodes
//! back to the same value (unless its content holds a colon: `:` and two hex digits at the end of a line are read
//! as a checksum, so such content is ambiguous without one, as in the protocol itself).

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_zaber_protocol::{Command, LineSplitter, MAX_LINE, Message};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut LineSplitter::new(),
        payload,
        &cuts,
        |s, bytes| s.push(bytes),
        |s| std::iter::from_fn(|| s.next_line()).collect::<Vec<_>>(),
        |s| s.buffered_len() <= MAX_LINE,
    );
    let mut whole = LineSplitter::new();
    whole.push(payload);
    let at_once: Vec<_> = std::iter::from_fn(|| whole.next_line()).collect();
    assert_eq!(chunked, at_once);

    for line in chunked.into_iter().flatten() {
        if let Ok(command) = Command::parse(&line)
            && !command.text.contains(':')
        {
            for checksum in [false, true] {
                let text = String::from_utf8(command.encode(checksum)).expect("commands are ASCII");
                assert_eq!(Command::parse(text.trim_end()), Ok(command.clone()));
            }
        }
        if let Ok(message) = Message::parse(&line)
            && !message.encode(false).contains(&b':')
        {
            let text = String::from_utf8(message.encode(false)).expect("messages are ASCII");
            let again = Message::parse(text.trim_end()).expect("an encoded message decodes");
            assert_eq!(again.encode(false), message.encode(false));
        }
    }
});
