//! Hostile bytes: whatever arrives, in whatever chunks, the splitter and both decoders return values or errors,
//! never panic, and hold a bounded buffer.

use metaplate_zaber_protocol::{Command, LineSplitter, MAX_LINE, Message, ZaberProtocolError};
use proptest::prelude::*;

fn drain(splitter: &mut LineSplitter) -> Vec<Result<String, ZaberProtocolError>> {
    std::iter::from_fn(|| splitter.next_line()).collect()
}

proptest! {
    #[test]
    fn arbitrary_bytes_in_chunks_decode_without_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048), cut in 0usize..2048) {
        let cut = cut.min(bytes.len());
        let mut chunked = LineSplitter::new();
        chunked.push(&bytes[..cut]);
        let mut lines = drain(&mut chunked);
        chunked.push(&bytes[cut..]);
        lines.extend(drain(&mut chunked));
        prop_assert!(chunked.buffered_len() <= MAX_LINE);
        let mut whole = LineSplitter::new();
        whole.push(&bytes);
        prop_assert_eq!(&lines, &drain(&mut whole));
        for line in lines.into_iter().flatten() {
            let _ = Message::parse(&line);
            // A decoded command re-encodes to a line that decodes to the same command (unless it holds a colon: `:`
            // and two hex digits at the end read as a checksum).
            if let Ok(command) = Command::parse(&line)
                && !command.text.contains(':')
            {
                let encoded = String::from_utf8(command.encode(false)).unwrap_or_default();
                prop_assert_eq!(Command::parse(encoded.trim_end()), Ok(command));
            }
        }
    }

    #[test]
    fn near_valid_replies_decode_without_panic(line in "[@#!/]([0-9]{1,3} ){0,3}(OK|RJ|XX)? ?(BUSY|IDLE)? ?(--|W[A-Z]|F[A-Z]|[a-z]{2})? ?[ -~]{0,20}(:[0-9A-F]{0,3})?") {
        let _ = Message::parse(&line);
        let _ = Command::parse(&line);
    }
}
