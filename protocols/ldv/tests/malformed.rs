//! Every class of malformed, truncated, oversized or out-of-range input gives its typed error (and, on the device
//! side, the documented ERR code), and decoding resumes with the next line.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use metaplate_ldv_protocol::{
    Command, CommandDecoder, ErrorCode, LdvProtocolError, MAX_LINE_CONTENT, MAX_NUMBER_LEN, Reply, ReplyDecoder,
    SignalLevel, encode_reply,
};

/// Decodes one command line (terminator added) followed by a good line, checks the good line still decodes, and
/// returns the first line's error.
fn command_error(line: &[u8]) -> LdvProtocolError {
    let mut decoder = CommandDecoder::new();
    decoder.push(line);
    decoder.push(b"\rSIG?\r");
    let results: Vec<_> = decoder.drain().collect();
    assert_eq!(results.len(), 2, "{:?} gave {results:?}", String::from_utf8_lossy(line));
    assert_eq!(results[1], Ok(Command::QuerySignal), "no resynchronisation after {line:?}");
    match &results[0] {
        Err(error) => error.clone(),
        Ok(command) => panic!("{:?} decoded to {command:?}", String::from_utf8_lossy(line)),
    }
}

/// As [`command_error`], for the host side.
fn reply_error(line: &[u8]) -> LdvProtocolError {
    let mut decoder = ReplyDecoder::new();
    decoder.push(line);
    decoder.push(b"\r\nOK\r\n");
    let results: Vec<_> = decoder.drain().collect();
    assert_eq!(results.len(), 2, "{:?} gave {results:?}", String::from_utf8_lossy(line));
    assert_eq!(results[1], Ok(Reply::Ok), "no resynchronisation after {line:?}");
    match &results[0] {
        Err(error) => error.clone(),
        Ok(reply) => panic!("{:?} decoded to {reply:?}", String::from_utf8_lossy(line)),
    }
}

fn assert_code(lines: &[&str], code: ErrorCode) {
    for line in lines {
        let error = command_error(line.as_bytes());
        assert_eq!(error.error_code(), code, "{line:?} gave {error:?}");
        // The device's reply to it carries the code and always encodes to a valid line.
        let reply = Reply::from_error(&error);
        assert!(matches!(reply, Reply::Error { code: c, .. } if c == code));
        let mut host = ReplyDecoder::new();
        host.push(&encode_reply(&reply));
        assert_eq!(host.poll(), Some(Ok(reply)));
    }
}

#[test]
fn unknown_keywords_are_code_1() {
    assert_code(&["FOCUS 3", "POSITION?", "IDN?", "OK", "*idn", "SIG", "CAL YES", "?"], ErrorCode::UnknownCommand);
    assert!(matches!(command_error(b"FOCUS 3"), LdvProtocolError::UnknownKeyword { keyword } if keyword == "FOCUS"));
}

#[test]
fn wrong_argument_counts_are_code_2() {
    assert_code(
        &["POS 1", "POS 1 2 3", "ANG", "*IDN? x", "SIG? 5", "VRANGE", "TRACK SLOW FAST", "SYNC"],
        ErrorCode::BadArgument,
    );
    assert_eq!(command_error(b"POS 1 2 3"), LdvProtocolError::ArgumentCount { keyword: "POS", expected: 2, found: 3 });
}

#[test]
fn non_finite_and_foreign_numbers_are_code_2() {
    let lines = [
        "POS nan 0",
        "POS 0 NaN",
        "POS inf 0",
        "POS -inf 0",
        "ANG 1e1 0",
        "ANG 0x10 0",
        "POS .5 0",
        "POS 5. 0",
        "POS 1,5 0",
        "VRANGE 5.0",
        "SYNC 1.5",
        "SYNC +-1",
        "POS 1.0001 0",
        "ANG 0 0.0005",
    ];
    assert_code(&lines, ErrorCode::BadArgument);
    for line in lines {
        assert!(matches!(command_error(line.as_bytes()), LdvProtocolError::MalformedNumber { .. }), "{line}");
    }
}

#[test]
fn overlong_numbers_are_code_2_even_when_their_value_is_small() {
    let zeros = format!("POS {} 0", "0".repeat(MAX_NUMBER_LEN + 1));
    assert!(matches!(command_error(zeros.as_bytes()), LdvProtocolError::MalformedNumber { .. }));
    // Exactly MAX_NUMBER_LEN characters is still a number.
    let mut decoder = CommandDecoder::new();
    decoder.push(format!("POS {}1.5 0\r", "0".repeat(MAX_NUMBER_LEN - 3)).as_bytes());
    assert!(matches!(decoder.poll(), Some(Ok(Command::MoveTo(_)))));
}

#[test]
fn unknown_choice_words_are_code_2() {
    assert_code(&["TRACK BRISK", "TRACK 1", "LASER 1", "LASER YES"], ErrorCode::BadArgument);
    assert!(matches!(command_error(b"TRACK BRISK"), LdvProtocolError::InvalidChoice { .. }));
}

#[test]
fn values_outside_their_ranges_are_code_3() {
    let lines = [
        "POS 500.001 0",
        "POS 0 -500.001",
        "POS 99999 0",
        "ANG 25.001 0",
        "ANG 0 -25.001",
        "VRANGE 0",
        "VRANGE 10",
        "VRANGE -5",
        "SYNC 4294967296",
        "SYNC -1",
    ];
    assert_code(&lines, ErrorCode::OutOfRange);
    for line in lines {
        assert!(matches!(command_error(line.as_bytes()), LdvProtocolError::OutOfRange { .. }), "{line}");
    }
}

#[test]
fn range_limits_themselves_are_accepted() {
    let mut decoder = CommandDecoder::new();
    decoder.push(b"POS -500 500.000\rANG 25 -25.000\rVRANGE 1\rVRANGE 1000\rSYNC 4294967295\rSYNC 0\r");
    let decoded: Vec<_> = decoder.drain().collect();
    assert_eq!(decoded.len(), 6);
    assert!(decoded.iter().all(Result::is_ok), "{decoded:?}");
}

#[test]
fn bad_characters_are_code_2_with_their_column() {
    assert_code(&["SIG?\u{7}", "POS 1 2\u{b5}", "\tSIG?", "SIG?\u{7f}"], ErrorCode::BadArgument);
    assert_eq!(command_error(b"SIG?\x07"), LdvProtocolError::BadCharacter { byte: 0x07, column: 4 });
    assert_eq!(reply_error(b"OK\x00"), LdvProtocolError::BadCharacter { byte: 0x00, column: 2 });
}

#[test]
fn overlong_lines_are_code_4_and_resynchronise() {
    let longest = format!("SYNC{}1", " ".repeat(MAX_LINE_CONTENT - 5));
    assert_eq!(longest.len(), MAX_LINE_CONTENT);
    let mut decoder = CommandDecoder::new();
    decoder.push(format!("{longest}\r").as_bytes());
    assert!(matches!(decoder.poll(), Some(Ok(Command::Sync(_)))), "the longest line must pass");

    let one_more = format!("SYNC{}1", " ".repeat(MAX_LINE_CONTENT - 4));
    assert_eq!(command_error(one_more.as_bytes()), LdvProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT });
    assert_code(&[&"x".repeat(10_000)], ErrorCode::LineTooLong);
    assert_eq!(
        reply_error("OK".repeat(1000).as_bytes()),
        LdvProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT }
    );
}

#[test]
fn truncated_lines_wait_for_their_terminator() {
    let mut decoder = CommandDecoder::new();
    decoder.push(b"POS 1.0 2.");
    assert_eq!(decoder.poll(), None);
    assert_eq!(decoder.buffered_len(), 10);
    decoder.push(b"5");
    assert_eq!(decoder.poll(), None);
    decoder.push(b"\n");
    assert!(matches!(decoder.poll(), Some(Ok(Command::MoveTo(p))) if p.y.um() == 2_500));
    // A partial line dropped by clear() never reappears.
    decoder.push(b"SIG");
    decoder.clear();
    decoder.push(b"?\r");
    assert!(matches!(decoder.poll(), Some(Err(LdvProtocolError::UnknownKeyword { .. }))));
}

#[test]
fn malformed_replies_are_typed_errors() {
    type Check = fn(&LdvProtocolError) -> bool;
    let cases: Vec<(&[u8], Check)> = vec![
        (b"HELLO", |e| matches!(e, LdvProtocolError::UnknownKeyword { .. })),
        (b"POS?", |e| matches!(e, LdvProtocolError::UnknownKeyword { .. })),
        (b"OK 1", |e| matches!(e, LdvProtocolError::ArgumentCount { expected: 0, found: 1, .. })),
        (b"ERR", |e| matches!(e, LdvProtocolError::ArgumentCount { keyword: "ERR", .. })),
        (b"ERR x oops", |e| matches!(e, LdvProtocolError::MalformedNumber { .. })),
        (b"ERR 9 new", |e| matches!(e, LdvProtocolError::UnknownErrorCode { code: 9 })),
        (b"ERR 0", |e| matches!(e, LdvProtocolError::UnknownErrorCode { code: 0 })),
        (b"ERR -3", |e| matches!(e, LdvProtocolError::UnknownErrorCode { code: -3 })),
        (b"IDN a,b,c", |e| matches!(e, LdvProtocolError::ArgumentCount { expected: 4, found: 3, .. })),
        (b"IDN a,b,c,d,e", |e| matches!(e, LdvProtocolError::ArgumentCount { expected: 4, found: 5, .. })),
        (b"IDN", |e| matches!(e, LdvProtocolError::ArgumentCount { expected: 4, found: 1, .. })),
        (b"IDN a,,c,d", |e| matches!(e, LdvProtocolError::InvalidText { .. })),
        (b"IDN aaaaaaaaaaaaaaaaaaaaaaaaa,b,c,d", |e| matches!(e, LdvProtocolError::InvalidText { .. })),
        (b"SIG 101", |e| matches!(e, LdvProtocolError::OutOfRange { .. })),
        (b"SIG -1", |e| matches!(e, LdvProtocolError::OutOfRange { .. })),
        (b"SIG nan", |e| matches!(e, LdvProtocolError::MalformedNumber { .. })),
        (b"POS 1", |e| matches!(e, LdvProtocolError::ArgumentCount { .. })),
        (b"POS inf 0", |e| matches!(e, LdvProtocolError::MalformedNumber { .. })),
        (b"ANG 0 26", |e| matches!(e, LdvProtocolError::OutOfRange { .. })),
        (b"VRANGE 7", |e| matches!(e, LdvProtocolError::OutOfRange { .. })),
        (b"TRACK FASTER", |e| matches!(e, LdvProtocolError::InvalidChoice { .. })),
        (b"CAL MAYBE", |e| matches!(e, LdvProtocolError::InvalidChoice { .. })),
        (b"LASER", |e| matches!(e, LdvProtocolError::ArgumentCount { .. })),
        (b"SYNC 1.5", |e| matches!(e, LdvProtocolError::MalformedNumber { .. })),
    ];
    for (line, is_expected) in cases {
        let error = reply_error(line);
        assert!(is_expected(&error), "{:?} gave {error:?}", String::from_utf8_lossy(line));
    }
    let long_text = format!("ERR 3 {}", "e".repeat(101));
    assert!(matches!(reply_error(long_text.as_bytes()), LdvProtocolError::InvalidText { .. }));
}

#[test]
fn lenient_reply_forms_decode() {
    let mut decoder = ReplyDecoder::new();
    decoder.push(b"  sig   87 \nerr 003\r\nIDN Ometron , 8330,SN1 ,2.14\r");
    let replies: Vec<_> = decoder.drain().collect();
    assert_eq!(replies[0], Ok(Reply::Signal(SignalLevel::from_percent(87).unwrap())));
    assert!(matches!(&replies[1], Ok(Reply::Error { code: ErrorCode::OutOfRange, text }) if text.as_str().is_empty()));
    assert!(
        matches!(&replies[2], Ok(Reply::Identity(id)) if id.vendor.as_str() == "Ometron" && id.serial.as_str() == "SN1")
    );
}
