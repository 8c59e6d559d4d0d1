//! Messages as Zaber's ASCII Protocol Manual writes them (section named on each), decoded and encoded.

use metaplate_zaber_protocol::{
    Command, LineSplitter, Message, Reply, ReplyFlag, Status, WarningFlag, ZaberProtocolError, format_warning_list,
    lrc, parse_warning_list,
};

#[test]
fn commands_encode_with_address_axis_and_id() {
    // Message Format, Commands: `/1 1 move abs 1000`; with a message id after the axis.
    assert_eq!(Command::new(1, 1, "move abs 1000").encode(false), b"/1 1 move abs 1000\n");
    let with_id = Command { device: 2, axis: 1, id: Some(7), text: "get pos".into() };
    assert_eq!(with_id.encode(false), b"/2 1 7 get pos\n");
    // The empty command asks for a status reply only.
    assert_eq!(Command::new(1, 0, "").encode(false), b"/1 0\n");
}

#[test]
fn commands_decode_with_optional_fields() {
    // Message Format, Commands: the address, axis and id may each be left out (0: all devices, the device).
    let parse = |line: &str| Command::parse(line).map(|c| (c.device, c.axis, c.id, c.text));
    assert_eq!(parse("/1 1 move abs 1000"), Ok((1, 1, None, "move abs 1000".into())));
    assert_eq!(parse("/get deviceid"), Ok((0, 0, None, "get deviceid".into())));
    assert_eq!(parse("/1 1 12 get pos"), Ok((1, 1, Some(12), "get pos".into())));
    assert_eq!(parse("/"), Ok((0, 0, None, String::new())));
    assert!(matches!(Command::parse("/100 1 home"), Err(ZaberProtocolError::Malformed { field: "device", .. })));
    assert!(matches!(Command::parse("1 1 home"), Err(ZaberProtocolError::WrongType { .. })));
}

#[test]
fn replies_decode_every_field() {
    // Zaber's article "Zaber's ASCII Protocol" (2022), its annotated reply: `@01 0 OK IDLE -- 0`.
    let Ok(Message::Reply(reply)) = Message::parse("@01 0 OK IDLE -- 0") else { panic!("not a reply") };
    assert_eq!(
        reply,
        Reply {
            device: 1,
            axis: 0,
            id: None,
            flag: ReplyFlag::Ok,
            status: Status::Idle,
            warning: WarningFlag::NONE,
            data: "0".into()
        }
    );
    // Reply Flags: a rejection names its reason in the data.
    let Ok(Message::Reply(rejected)) = Message::parse("@01 1 12 RJ IDLE -- BADCOMMAND") else { panic!("not a reply") };
    assert_eq!((rejected.id, rejected.flag, rejected.data.as_str()), (Some(12), ReplyFlag::Rejected, "BADCOMMAND"));
    // Warning Flags: a moving, unhomed axis.
    let Ok(Message::Reply(busy)) = Message::parse("@02 1 OK BUSY WR 0") else { panic!("not a reply") };
    assert_eq!((busy.status, busy.warning), (Status::Busy, WarningFlag::NO_REFERENCE));
}

#[test]
fn info_and_alert_messages_decode() {
    // Message Format, Info and Alerts.
    assert_eq!(
        Message::parse("#01 0 COMMAND USAGE:"),
        Ok(Message::Info { device: 1, axis: 0, data: "COMMAND USAGE:".into() })
    );
    assert_eq!(
        Message::parse("!01 1 IDLE --"),
        Ok(Message::Alert { device: 1, axis: 1, status: Status::Idle, warning: WarningFlag::NONE })
    );
}

#[test]
fn messages_round_trip_with_and_without_checksums() {
    let reply = Message::Reply(Reply {
        device: 3,
        axis: 2,
        id: Some(99),
        flag: ReplyFlag::Ok,
        status: Status::Busy,
        warning: WarningFlag::UNEXPECTED_LIMIT,
        data: "01 WL".into(),
    });
    for checksum in [false, true] {
        let bytes = reply.encode(checksum);
        assert!(bytes.ends_with(b"\r\n"), "devices end messages with CR LF");
        let text = String::from_utf8(bytes).unwrap_or_default();
        assert_eq!(Message::parse(text.trim_end()), Ok(reply.clone()));
    }
    let command = Command { device: 1, axis: 1, id: Some(5), text: "move rel -200".into() };
    let text = String::from_utf8(command.encode(true)).unwrap_or_default();
    assert_eq!(Command::parse(text.trim_end()), Ok(command));
}

#[test]
fn checksum_is_the_twos_complement_of_the_byte_sum() {
    // Message Format, Checksums: the content's bytes plus the checksum sum to 0 modulo 256.
    let content = b"01 1 OK IDLE -- 0";
    let sum = content.iter().fold(0u8, |s, b| s.wrapping_add(*b));
    assert_eq!(sum.wrapping_add(lrc(content)), 0);
    let good = format!("@01 1 OK IDLE -- 0:{:02X}", lrc(content));
    assert!(Message::parse(&good).is_ok());
    let bad = format!("@01 1 OK IDLE -- 0:{:02X}", lrc(content).wrapping_add(1));
    assert!(matches!(Message::parse(&bad), Err(ZaberProtocolError::Checksum { .. })));
}

#[test]
fn warnings_list_and_flag_names() {
    // Commands, warnings: a two-digit count, then the flags.
    assert_eq!(parse_warning_list("01 WR"), Some(vec![WarningFlag::NO_REFERENCE]));
    assert_eq!(parse_warning_list("00"), Some(vec![]));
    assert_eq!(parse_warning_list("02 WR"), None, "a count that does not match the flags");
    assert_eq!(format_warning_list(&[WarningFlag::NO_REFERENCE, WarningFlag::UNEXPECTED_LIMIT]), "02 WR WL");
    // Warning Flags: names, kinds and priority.
    let fs = WarningFlag::parse("FS").unwrap_or(WarningFlag::NONE);
    assert_eq!(fs.to_string(), "FS (stalled and stopped)");
    assert!(fs.is_fault() && fs.priority() > WarningFlag::NO_REFERENCE.priority());
    assert_eq!(WarningFlag::parse("WL").map(|f| f.name()), Some("unexpected limit trigger"));
    assert_eq!(WarningFlag::parse("XY").map(|f| f.name()), Some("unknown"));
    assert_eq!(WarningFlag::parse("w1"), None);
}

#[test]
fn lines_end_at_cr_or_lf_and_skip_empty_ones() {
    // Message Format: a message ends at CR, LF or both.
    let mut splitter = LineSplitter::new();
    splitter.push(b"@01 1 OK IDLE -- 0\r\n\r\n#01 0 a\r!01 1 ");
    assert_eq!(splitter.next_line(), Some(Ok("@01 1 OK IDLE -- 0".into())));
    assert_eq!(splitter.next_line(), Some(Ok("#01 0 a".into())));
    assert_eq!(splitter.next_line(), None);
    splitter.push(b"IDLE --\n");
    assert_eq!(splitter.next_line(), Some(Ok("!01 1 IDLE --".into())));
}
