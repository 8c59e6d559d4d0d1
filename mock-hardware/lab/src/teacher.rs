//! A user at the plate teaching the galvo mirrors (`metaplate aim teach` on the mock lab, in tests): watches where
//! the beam lands and presses keys, sent as a terminal sends them.
//!
//! The user presses an arrow; if the spot went further from the mark, presses the opposite arrow and tries another;
//! when no arrow brings it closer, takes a finer step; at the finest step (1 mV, about 0.02 mm), when no arrow
//! helps, presses Enter. After a provisional fit (from the fourth mark on) has moved the beam near the next mark,
//! a fine step is enough from there.

use metaplate_aim::galvo::GalvoError;
use metaplate_aim::galvo::teach::{Key, KeyDecoder, STEPS_V, Teach, TeachEvent, parse_marks_mm};

use crate::mirrors::{MIRRORS_LIMIT_V, MirrorGeometry, MockMirrors};

/// Nine marks, 3 x 3, spanning the built-in scenes' 7 x 5 scan inside their plates' outline, as a user writes them
/// in a marks file (`metaplate aim teach --marks-file`), mm.
pub const NINE_MARKS_MM: &str = "# x, y in mm\n-100,-50\n0,-50\n100,-50\n-100,0\n0,0\n100,0\n-100,50\n0,50\n100,50\n";

/// The user of [`teach_like_a_user`] teaching [`NINE_MARKS_MM`] on mirrors of `geometry` from their start (as
/// `metaplate aim teach --scene` builds them): the finished teaching, to fit, and the bytes pressed.
///
/// # Errors
/// As [`teach_like_a_user`].
pub fn teach_nine_marks(geometry: MirrorGeometry) -> Result<(Teach, Vec<u8>), GalvoError> {
    let mut mirrors = MockMirrors::new(geometry);
    let mut teach = Teach::new(parse_marks_mm(NINE_MARKS_MM, "marks")?, MIRRORS_LIMIT_V)?;
    teach.start(&mut mirrors)?;
    let keys = teach_like_a_user(&mut teach, &mut mirrors)?;
    Ok((teach, keys))
}

/// The most keys the user presses before giving up (a user going round in circles is a bug).
const MAX_PRESSES: usize = 20_000;

/// The bytes a terminal sends for `key` (arrows in normal cursor mode, Enter as a raw terminal sends it).
pub fn key_bytes(key: Key) -> &'static [u8] {
    match key {
        Key::Up => b"\x1b[A",
        Key::Down => b"\x1b[B",
        Key::Right => b"\x1b[C",
        Key::Left => b"\x1b[D",
        Key::Coarser => b"+",
        Key::Finer => b"-",
        Key::Record => b"\r",
        Key::Quit => b"q",
    }
}

/// Teaches every mark of `teach` (started on `mirrors`) as the user above, through a [`KeyDecoder`]; returns the
/// bytes pressed, in order (piped to `metaplate aim teach --scene`, they teach the same marks the same way).
///
/// # Errors
/// The teaching's error as it comes; [`GalvoError::Teach`] for a user who has not finished after 20,000 presses.
pub fn teach_like_a_user(teach: &mut Teach, mirrors: &mut MockMirrors) -> Result<Vec<u8>, GalvoError> {
    let eyes = mirrors.clone();
    let distance = |mark: (f64, f64)| eyes.beam_m().map_or(f64::INFINITY, |(x, y)| (x - mark.0).hypot(y - mark.1));
    let mut decoder = KeyDecoder::new();
    let mut pressed: Vec<u8> = Vec::new();
    let mut send = |teach: &mut Teach, key: Key| -> Result<Option<TeachEvent>, GalvoError> {
        if pressed.len() > MAX_PRESSES * 3 {
            return Err(GalvoError::Teach {
                detail: format!("the simulated user gave up after {MAX_PRESSES} presses"),
            });
        }
        let mut event = None;
        for &b in key_bytes(key) {
            pressed.push(b);
            if let Some(k) = decoder.push(b) {
                event = Some(teach.press(k, mirrors)?);
            }
        }
        Ok(event)
    };
    let opposite = |k| match k {
        Key::Left => Key::Right,
        Key::Right => Key::Left,
        Key::Up => Key::Down,
        _ => Key::Up,
    };
    let (finest, coarsest) = (STEPS_V[0], STEPS_V[STEPS_V.len() - 1]);
    while teach.step_v() < coarsest {
        send(teach, Key::Coarser)?;
    }
    while let Some((_, mark)) = teach.current_mark() {
        loop {
            let mut improved = false;
            for key in [Key::Right, Key::Left, Key::Up, Key::Down] {
                let before = distance(mark);
                send(teach, key)?;
                if distance(mark) < before {
                    improved = true;
                    break;
                }
                send(teach, opposite(key))?;
            }
            if improved {
                continue;
            }
            if teach.step_v() > finest {
                send(teach, Key::Finer)?;
            } else {
                break;
            }
        }
        let recorded = send(teach, Key::Record)?;
        if teach.is_finished() {
            break;
        }
        if let Some(TeachEvent::Recorded { moved_to: Some(_), .. }) = recorded {
            while teach.step_v() > STEPS_V[1] {
                send(teach, Key::Finer)?;
            }
        } else {
            while teach.step_v() < coarsest {
                send(teach, Key::Coarser)?;
            }
        }
    }
    Ok(pressed)
}
