//! Property tests: every message type survives encoding and decoding at arbitrary split points, in any lenient
//! spelling the specification allows; anything decoded from arbitrary bytes re-encodes to itself.

#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the failure report

use metaplate_ldv_protocol::{
    CalibrationState, Command, CommandDecoder, ErrorCode, ErrorText, Identity, IdentityField, LaserState,
    LdvProtocolError, LineDecoder, LineMessage, MAX_LINE_CONTENT, MAX_LINE_LEN, MirrorAngle, MirrorAngles, PlateCoord,
    PlatePoint, Reply, ReplyDecoder, SignalLevel, SyncToken, TrackingFilter, VelocityRange, encode_command,
    encode_reply,
};
use proptest::prelude::*;
use proptest::sample::{Index, select};

/// Values at and near the ends of `-limit..=limit` and around zero (where "-0.001" must keep its sign) come up often;
/// the rest is covered uniformly.
fn steps(limit: i32) -> impl Strategy<Value = i32> {
    prop_oneof![
        1 => Just(limit),
        1 => Just(-limit),
        1 => -1000..=1000,
        1 => limit - 3..=limit,
        1 => -limit..=-limit + 3,
        5 => -limit..=limit,
    ]
}

fn plate_point() -> impl Strategy<Value = PlatePoint> {
    (steps(PlateCoord::MAX_UM), steps(PlateCoord::MAX_UM))
        .prop_map(|(x, y)| PlatePoint { x: PlateCoord::from_um(x).unwrap(), y: PlateCoord::from_um(y).unwrap() })
}

fn mirror_angles() -> impl Strategy<Value = MirrorAngles> {
    (steps(MirrorAngle::MAX_MDEG), steps(MirrorAngle::MAX_MDEG)).prop_map(|(x, y)| MirrorAngles {
        x: MirrorAngle::from_mdeg(x).unwrap(),
        y: MirrorAngle::from_mdeg(y).unwrap(),
    })
}

fn laser() -> impl Strategy<Value = LaserState> {
    select(&[LaserState::On, LaserState::Off][..])
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        Just(Command::Identify),
        Just(Command::Reset),
        Just(Command::ClearErrors),
        plate_point().prop_map(Command::MoveTo),
        mirror_angles().prop_map(Command::MoveToAngles),
        Just(Command::QueryPosition),
        Just(Command::QueryAngles),
        Just(Command::QuerySignal),
        select(&VelocityRange::ALL[..]).prop_map(Command::SetVelocityRange),
        Just(Command::QueryVelocityRange),
        select(&TrackingFilter::ALL[..]).prop_map(Command::SetTrackingFilter),
        Just(Command::QueryTrackingFilter),
        laser().prop_map(Command::SetLaser),
        Just(Command::QueryLaser),
        Just(Command::QueryCalibration),
        any::<u32>().prop_map(|t| Command::Sync(SyncToken(t))),
    ]
}

fn identity_field() -> impl Strategy<Value = IdentityField> {
    "[ -~]{1,24}".prop_filter_map("not a valid identity field", |s| IdentityField::new(&s).ok())
}

fn reply() -> impl Strategy<Value = Reply> {
    prop_oneof![
        Just(Reply::Ok),
        (select(&ErrorCode::ALL[..]), "[ -~]{0,100}").prop_filter_map("not a valid error text", |(code, text)| {
            ErrorText::new(&text).ok().map(|text| Reply::Error { code, text })
        }),
        (identity_field(), identity_field(), identity_field(), identity_field()).prop_map(
            |(vendor, model, serial, firmware)| Reply::Identity(Identity { vendor, model, serial, firmware })
        ),
        plate_point().prop_map(Reply::Position),
        mirror_angles().prop_map(Reply::Angles),
        (0_u8..=100).prop_map(|p| Reply::Signal(SignalLevel::from_percent(p).unwrap())),
        select(&VelocityRange::ALL[..]).prop_map(Reply::VelocityRange),
        select(&TrackingFilter::ALL[..]).prop_map(Reply::TrackingFilter),
        laser().prop_map(Reply::Laser),
        select(&[CalibrationState::Calibrated, CalibrationState::NotCalibrated][..]).prop_map(Reply::Calibration),
        any::<u32>().prop_map(|t| Reply::Sync(SyncToken(t))),
    ]
}

/// Pushes `bytes` cut at the given points, polling after every push, and returns everything decoded.
fn decode_split<M: LineMessage>(bytes: &[u8], cuts: &[Index]) -> Vec<Result<M, LdvProtocolError>> {
    let mut points: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
    points.push(0);
    points.push(bytes.len());
    points.sort_unstable();
    let mut decoder = LineDecoder::<M>::new();
    let mut out = Vec::new();
    for pair in points.windows(2) {
        decoder.push(&bytes[pair[0]..pair[1]]);
        out.extend(decoder.drain());
        assert!(decoder.buffered_len() <= MAX_LINE_CONTENT, "decoder holds more than one line");
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn commands_round_trip_at_any_split(
        commands in prop::collection::vec(command(), 1..10),
        cuts in prop::collection::vec(any::<Index>(), 0..12),
    ) {
        let bytes: Vec<u8> = commands.iter().flat_map(encode_command).collect();
        let decoded = decode_split::<Command>(&bytes, &cuts);
        let want: Vec<Result<Command, LdvProtocolError>> = commands.into_iter().map(Ok).collect();
        prop_assert_eq!(decoded, want);
    }

    #[test]
    fn replies_round_trip_at_any_split(
        replies in prop::collection::vec(reply(), 1..10),
        cuts in prop::collection::vec(any::<Index>(), 0..12),
    ) {
        let bytes: Vec<u8> = replies.iter().flat_map(encode_reply).collect();
        let decoded = decode_split::<Reply>(&bytes, &cuts);
        let want: Vec<Result<Reply, LdvProtocolError>> = replies.into_iter().map(Ok).collect();
        prop_assert_eq!(decoded, want);
    }

    #[test]
    fn every_encoded_line_fits_the_maximum(command in command(), reply in reply()) {
        prop_assert!(encode_command(&command).len() <= MAX_LINE_LEN);
        prop_assert!(encode_reply(&reply).len() <= MAX_LINE_LEN);
    }

    /// What a person at a terminal may type: any case, runs of spaces, any terminator.
    #[test]
    fn commands_decode_in_any_lenient_spelling(
        command in command(),
        lower in any::<bool>(),
        gaps in prop::collection::vec(1_usize..4, 4),
        terminator in select(&["\r", "\n", "\r\n"][..]),
    ) {
        let canonical = command.to_string();
        let text = if lower { canonical.to_lowercase() } else { canonical };
        let spaced = text.split(' ').enumerate().fold(" ".repeat(gaps[0] - 1), |mut line, (i, word)| {
            if i > 0 {
                line.push_str(&" ".repeat(gaps[i.min(3)]));
            }
            line.push_str(word);
            line
        });
        let line = format!("{spaced}{}{terminator}", " ".repeat(gaps[3] - 1));
        prop_assume!(line.len() <= MAX_LINE_LEN);
        let mut decoder = CommandDecoder::new();
        decoder.push(line.as_bytes());
        prop_assert_eq!(decoder.drain().collect::<Vec<_>>(), vec![Ok(command)]);
    }

    #[test]
    fn replies_decode_with_any_terminator(reply in reply(), terminator in select(&["\r", "\n", "\r\n"][..])) {
        let mut decoder = ReplyDecoder::new();
        decoder.push(format!("{reply}{terminator}").as_bytes());
        prop_assert_eq!(decoder.drain().collect::<Vec<_>>(), vec![Ok(reply)]);
    }

    /// Bytes from the protocol's own alphabet, glued at random: whatever decodes must re-encode to itself, and no
    /// input may panic or leave more than one line buffered.
    #[test]
    fn anything_decoded_re_encodes_to_itself(
        words in prop::collection::vec(
            select(&[
                "POS", "ANG", "POS?", "SIG", "SIG?", "ERR", "IDN", "OK", "SYNC", "VRANGE", "TRACK", "LASER", "CAL",
                "*IDN?", "*RST", "ON", "off", "slow", "YES", "0", "-1", "25", "500.000", "1.5", "a,b,c,d", " ", "  ",
                "\r", "\n", "\r\n", "\u{0}", "nan", "1e3", "4294967295",
            ][..]),
            0..40,
        ),
        cuts in prop::collection::vec(any::<Index>(), 0..8),
    ) {
        let bytes: Vec<u8> = words.concat().into_bytes();
        for command in decode_split::<Command>(&bytes, &cuts).into_iter().flatten() {
            prop_assert_eq!(decode_split::<Command>(&encode_command(&command), &[]), vec![Ok(command)]);
        }
        for reply in decode_split::<Reply>(&bytes, &cuts).into_iter().flatten() {
            let encoded = encode_reply(&reply);
            prop_assert_eq!(decode_split::<Reply>(&encoded, &[]), vec![Ok(reply)]);
        }
    }

    /// The metre constructors keep a coordinate within half a step of its input: 0.5 um, plus 1e-12 m for the
    /// rounding of `x_m * 1e6` and of `m()` (both far below 1e-15 m at these magnitudes).
    #[test]
    fn plate_coordinates_quantize_to_the_nearest_micrometre(x_m in -0.5_f64..=0.5) {
        let x = PlateCoord::from_m(x_m).unwrap();
        prop_assert!((x.m() - x_m).abs() <= 0.5e-6 + 1e-12);
    }

    #[test]
    fn mirror_angles_quantize_to_the_nearest_millidegree(angle_deg in -25.0_f64..=25.0) {
        let angle = MirrorAngle::from_deg(angle_deg).unwrap();
        prop_assert!((angle.deg() - angle_deg).abs() <= 0.5e-3 + 1e-12);
    }
}
