//! Byte-exact tests of the documented example exchange (crate documentation, section 7) and of the resynchronisation
//! procedure (section 6).

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use metaplate_ldv_protocol::{
    CalibrationState, Command, CommandDecoder, ErrorCode, ErrorText, Identity, IdentityField, LaserState, MirrorAngles,
    PlatePoint, Reply, ReplyDecoder, SignalLevel, SyncToken, TrackingFilter, VelocityRange, encode_command,
    encode_reply,
};

fn identity() -> Identity {
    let field = |s| IdentityField::new(s).unwrap();
    Identity { vendor: field("Ometron"), model: field("8330"), serial: field("SN04512"), firmware: field("2.14") }
}

/// The documented exchange, in order: (command, its bytes, reply, its bytes).
fn documented() -> Vec<(Command, &'static [u8], Reply, &'static [u8])> {
    vec![
        (Command::Identify, b"*IDN?\r", Reply::Identity(identity()), b"IDN Ometron,8330,SN04512,2.14\r\n"),
        (Command::QueryCalibration, b"CAL?\r", Reply::Calibration(CalibrationState::Calibrated), b"CAL YES\r\n"),
        (Command::SetLaser(LaserState::On), b"LASER ON\r", Reply::Ok, b"OK\r\n"),
        (Command::SetVelocityRange(VelocityRange::MmPerS5), b"VRANGE 5\r", Reply::Ok, b"OK\r\n"),
        (Command::MoveTo(PlatePoint::from_m(0.012, -0.0355).unwrap()), b"POS 12.000 -35.500\r", Reply::Ok, b"OK\r\n"),
        (Command::QuerySignal, b"SIG?\r", Reply::Signal(SignalLevel::from_percent(87).unwrap()), b"SIG 87\r\n"),
        (Command::Sync(SyncToken(17)), b"SYNC 17\r", Reply::Sync(SyncToken(17)), b"SYNC 17\r\n"),
    ]
}

#[test]
fn documented_exchange_is_byte_exact_both_ways() {
    for (command, command_bytes, reply, reply_bytes) in documented() {
        assert_eq!(encode_command(&command), command_bytes, "{command:?}");
        assert_eq!(encode_reply(&reply), reply_bytes, "{reply:?}");
        assert!(command.is_answered_by(&reply), "{command:?} / {reply:?}");

        let mut device = CommandDecoder::new();
        device.push(command_bytes);
        assert_eq!(device.drain().collect::<Vec<_>>(), [Ok(command)]);
        let mut host = ReplyDecoder::new();
        host.push(reply_bytes);
        assert_eq!(host.drain().collect::<Vec<_>>(), [Ok(reply)]);
    }
}

#[test]
fn documented_exchange_decodes_as_one_burst_and_byte_by_byte() {
    let (commands, replies): (Vec<_>, Vec<_>) = documented().into_iter().map(|(c, _, r, _)| (c, r)).unzip();
    let host_bytes: Vec<u8> = documented().iter().flat_map(|(_, b, _, _)| b.to_vec()).collect();
    let device_bytes: Vec<u8> = documented().iter().flat_map(|(_, _, _, b)| b.to_vec()).collect();

    let mut device = CommandDecoder::new();
    device.push(&host_bytes);
    let decoded: Vec<Command> = device.drain().map(Result::unwrap).collect();
    assert_eq!(decoded, commands);

    let mut host = ReplyDecoder::new();
    let mut decoded = Vec::new();
    for byte in device_bytes {
        host.push(&[byte]);
        decoded.extend(host.drain().map(Result::unwrap));
    }
    assert_eq!(decoded, replies);
    assert_eq!(host.buffered_len(), 0);
}

#[test]
fn documented_hand_typed_error_is_byte_exact() {
    let mut device = CommandDecoder::new();
    device.push(b"ANG 30 0\r");
    let error = device.poll().unwrap().unwrap_err();
    let reply = Reply::from_error(&error);
    let bytes = encode_reply(&reply);
    assert_eq!(bytes, b"ERR 3 mirror angle (deg) = 30.000 is outside -25.000..=25.000 deg\r\n");
    let mut host = ReplyDecoder::new();
    host.push(&bytes);
    assert_eq!(host.poll(), Some(Ok(reply)));
    assert_eq!(host.poll(), None);
}

#[test]
fn every_reply_shape_has_its_documented_bytes() {
    let angles = MirrorAngles::from_deg(-3.25, 0.001).unwrap();
    let cases: Vec<(Reply, &[u8])> = vec![
        (Reply::Error { code: ErrorCode::NotCalibrated, text: ErrorText::default() }, b"ERR 5\r\n"),
        (
            Reply::Error { code: ErrorCode::HardwareFault, text: ErrorText::new("mirror drive").unwrap() },
            b"ERR 8 mirror drive\r\n",
        ),
        (Reply::Position(PlatePoint::from_m(-0.5, 0.5).unwrap()), b"POS -500.000 500.000\r\n"),
        (Reply::Angles(angles), b"ANG -3.250 0.001\r\n"),
        (Reply::VelocityRange(VelocityRange::MmPerS1000), b"VRANGE 1000\r\n"),
        (Reply::TrackingFilter(TrackingFilter::Medium), b"TRACK MEDIUM\r\n"),
        (Reply::Laser(LaserState::Off), b"LASER OFF\r\n"),
        (Reply::Calibration(CalibrationState::NotCalibrated), b"CAL NO\r\n"),
        (Reply::Sync(SyncToken(u32::MAX)), b"SYNC 4294967295\r\n"),
    ];
    for (reply, bytes) in cases {
        assert_eq!(encode_reply(&reply), bytes);
        assert_eq!(Reply::parse_line(std::str::from_utf8(&bytes[..bytes.len() - 2]).unwrap()), Ok(reply));
    }
}

#[test]
fn every_command_shape_has_its_documented_bytes() {
    let cases: Vec<(Command, &[u8])> = vec![
        (Command::Reset, b"*RST\r"),
        (Command::ClearErrors, b"*CLS\r"),
        (Command::MoveToAngles(MirrorAngles::from_deg(25.0, -25.0).unwrap()), b"ANG 25.000 -25.000\r"),
        (Command::QueryPosition, b"POS?\r"),
        (Command::QueryAngles, b"ANG?\r"),
        (Command::QueryVelocityRange, b"VRANGE?\r"),
        (Command::SetTrackingFilter(TrackingFilter::Off), b"TRACK OFF\r"),
        (Command::QueryTrackingFilter, b"TRACK?\r"),
        (Command::SetLaser(LaserState::Off), b"LASER OFF\r"),
        (Command::QueryLaser, b"LASER?\r"),
        (Command::Sync(SyncToken(0)), b"SYNC 0\r"),
    ];
    for (command, bytes) in cases {
        assert_eq!(encode_command(&command), bytes);
    }
}

/// Section 6: after a timeout the host sends a fresh SYNC and discards everything, errors included, until its echo.
#[test]
fn sync_drains_stale_replies_and_garbage() {
    let sync = Command::Sync(SyncToken(18));
    let mut host = ReplyDecoder::new();
    host.push(b"SIG 87\r\nOK\r\n\x00\xff garbage\r\n");
    host.push(format!("{}\r\n", "z".repeat(300)).as_bytes());
    host.push(b"SYNC 17\r\nSYNC 18\r\nSIG 40\r\n");
    let mut discarded = 0;
    let mut found = None;
    while let Some(result) = host.poll() {
        match result {
            Ok(reply) if sync.is_answered_by(&reply) => {
                found = Some(reply);
                break;
            }
            _ => discarded += 1,
        }
    }
    assert_eq!(found, Some(Reply::Sync(SyncToken(18))));
    // SIG 87, OK, the bad-character line, the overlong line, and the stale SYNC 17.
    assert_eq!(discarded, 5);
    // The next reply, not yet consumed, is still there for the next command.
    assert_eq!(host.poll(), Some(Ok(Reply::Signal(SignalLevel::from_percent(40).unwrap()))));
}

#[test]
fn answers_match_their_commands_only() {
    let error = Reply::Error { code: ErrorCode::Busy, text: ErrorText::default() };
    let point = PlatePoint::default();
    assert!(Command::MoveTo(point).is_answered_by(&Reply::Ok));
    assert!(Command::MoveTo(point).is_answered_by(&error));
    assert!(!Command::MoveTo(point).is_answered_by(&Reply::Position(point)));
    assert!(Command::QueryPosition.is_answered_by(&Reply::Position(point)));
    assert!(!Command::QueryPosition.is_answered_by(&Reply::Ok));
    assert!(!Command::QuerySignal.is_answered_by(&Reply::Laser(LaserState::On)));
    assert!(Command::QueryLaser.is_answered_by(&Reply::Laser(LaserState::On)));
    assert!(Command::Identify.is_answered_by(&Reply::Identity(identity())));
    assert!(!Command::Sync(SyncToken(1)).is_answered_by(&Reply::Sync(SyncToken(2))));
    assert!(!Command::Sync(SyncToken(1)).is_answered_by(&error), "SYNC is always echoed, never refused");
}

#[test]
fn slow_commands_get_the_long_timeout() {
    // The specified worst cases: 2 s for *RST and LASER ON, 30 ms (SIG?) for the rest; each timeout must exceed its
    // worst case plus a maximal line time of 11.1 ms at 115200 baud.
    assert_eq!(Command::Reset.timeout_s(), 3.0);
    assert_eq!(Command::SetLaser(LaserState::On).timeout_s(), 3.0);
    assert_eq!(Command::SetLaser(LaserState::Off).timeout_s(), 0.25);
    assert_eq!(Command::QuerySignal.timeout_s(), 0.25);
    assert_eq!(Command::MoveTo(PlatePoint::default()).timeout_s(), 0.25);
    assert!(Command::Reset.timeout_s() > 2.0 + 0.0111);
    assert!(Command::QuerySignal.timeout_s() > 0.030 + 0.0111);
}
