//! Teaching the galvo fit with the keyboard: jog the beam onto marks whose plate coordinates are known, record the
//! voltages at each, fit.
//!
//! Keys ([`KeyDecoder`] turns a terminal's bytes into [`Key`]s): the arrow keys move the X (left, right) and Y
//! (down, up) mirror by the current step; `+` and `-` make the step coarser or finer ([`STEPS_V`]: 1 mV to 1 V);
//! Enter records the current voltages for the current mark and goes to the next; `q` finishes. Once enough marks
//! are recorded for a projective fit, the beam goes to the next mark by itself (through the fit so far), so only
//! the last few millivolts are left to jog.

use metaplate_core::aim::MirrorOutputs;

use super::{FitModel, GalvoError, GalvoFit, TaughtPoint};

/// The jog steps, V: 1 mV, 10 mV, 100 mV and 1 V. With mirrors of about 20 mm per volt on the plate, 1 mV is
/// 0.02 mm, well inside any beam spot.
pub const STEPS_V: [f64; 4] = [0.001, 0.01, 0.1, 1.0];

/// The step teaching starts with: 100 mV.
const START_STEP: usize = 2;

/// A key of the teaching.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Key {
    /// X mirror down a step.
    Left,
    /// X mirror up a step.
    Right,
    /// Y mirror up a step.
    Up,
    /// Y mirror down a step.
    Down,
    /// A larger step (`+`, or `=` on the same key).
    Coarser,
    /// A smaller step (`-`).
    Finer,
    /// Record the current voltages for the current mark (Enter).
    Record,
    /// Finish (`q`).
    Quit,
}

/// Turns a terminal's bytes into keys: `ESC [ A..D` and `ESC O A..D` (arrows, in normal and application cursor
/// mode), `+`, `=`, `-`, Enter (`\r` or `\n`; `\r\n` counts once), `q`. Other bytes are ignored.
#[derive(Debug, Clone, Default)]
pub struct KeyDecoder {
    escape: Vec<u8>,
    after_cr: bool,
}

impl KeyDecoder {
    /// A decoder with nothing pending.
    pub fn new() -> KeyDecoder {
        KeyDecoder::default()
    }

    /// Feeds one byte; returns the key it completes, if any.
    pub fn push(&mut self, byte: u8) -> Option<Key> {
        let after_cr = std::mem::replace(&mut self.after_cr, byte == b'\r');
        if !self.escape.is_empty() {
            self.escape.push(byte);
            return match self.escape.as_slice() {
                [0x1b, b'[' | b'O'] => None,
                [0x1b, b'[' | b'O', last] => {
                    let key = match last {
                        b'A' => Some(Key::Up),
                        b'B' => Some(Key::Down),
                        b'C' => Some(Key::Right),
                        b'D' => Some(Key::Left),
                        _ => None,
                    };
                    self.escape.clear();
                    key
                }
                _ => {
                    // Not a cursor key: drop the sequence.
                    self.escape.clear();
                    None
                }
            };
        }
        match byte {
            0x1b => {
                self.escape.push(byte);
                None
            }
            b'+' | b'=' => Some(Key::Coarser),
            b'-' => Some(Key::Finer),
            b'\r' => Some(Key::Record),
            b'\n' if !after_cr => Some(Key::Record),
            b'q' | b'Q' => Some(Key::Quit),
            _ => None,
        }
    }
}

/// What a key did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TeachEvent {
    /// The mirrors moved to these voltages, V (`clamped`: the step would have passed the outputs' range, so it
    /// stopped at the limit).
    Moved {
        /// X mirror, V.
        x_v: f64,
        /// Y mirror, V.
        y_v: f64,
        /// Whether the limit stopped it.
        clamped: bool,
    },
    /// The step changed, V.
    Step {
        /// The new step, V.
        step_v: f64,
    },
    /// The current mark was recorded; the next (if any) is current, and `moved_to` says where the beam went by
    /// itself (through the fit so far), V.
    Recorded {
        /// The mark recorded (0-based).
        mark: usize,
        /// What was recorded.
        point: TaughtPoint,
        /// The voltages the beam went to for the next mark, if it was moved.
        moved_to: Option<(f64, f64)>,
    },
    /// Every mark is recorded, or `q` was pressed.
    Finished,
    /// The key does nothing now (after the end).
    Ignored,
}

/// The keyboard teaching's state: the marks, what is recorded, the voltages and the step.
#[derive(Debug, Clone)]
pub struct Teach {
    marks_m: Vec<(f64, f64)>,
    recorded: Vec<TaughtPoint>,
    volts: (f64, f64),
    step: usize,
    limit_v: f64,
    finished: bool,
}

impl Teach {
    /// Teaching of `marks_m` (plate coordinates, m, in the order they are taught) on outputs of range
    /// `+/- limit_v`; the beam starts at 0 V, 0 V (call [`Teach::start`]).
    ///
    /// # Errors
    /// [`GalvoError::Teach`] for no marks, a non-finite mark or a limit that is not positive.
    pub fn new(marks_m: Vec<(f64, f64)>, limit_v: f64) -> Result<Teach, GalvoError> {
        if marks_m.is_empty() {
            return Err(GalvoError::Teach { detail: "no marks to teach".into() });
        }
        if let Some(i) = marks_m.iter().position(|m| !m.0.is_finite() || !m.1.is_finite()) {
            return Err(GalvoError::Teach { detail: format!("mark {i} is not finite: {:?}", marks_m[i]) });
        }
        if !(limit_v.is_finite() && limit_v > 0.0) {
            return Err(GalvoError::Teach { detail: format!("the outputs' limit {limit_v} V is not positive") });
        }
        Ok(Teach { marks_m, recorded: Vec::new(), volts: (0.0, 0.0), step: START_STEP, limit_v, finished: false })
    }

    /// Puts the beam at the start (0 V, 0 V).
    ///
    /// # Errors
    /// The outputs' error.
    pub fn start(&mut self, outputs: &mut dyn MirrorOutputs) -> Result<(), GalvoError> {
        outputs.set_volts(self.volts.0, self.volts.1)?;
        Ok(())
    }

    /// The mark to put the beam on now (index and plate coordinates, m); `None` when finished.
    pub fn current_mark(&self) -> Option<(usize, (f64, f64))> {
        if self.finished {
            return None;
        }
        let i = self.recorded.len();
        self.marks_m.get(i).map(|&m| (i, m))
    }

    /// The mirrors' voltages now, V.
    pub fn volts(&self) -> (f64, f64) {
        self.volts
    }

    /// The jog step now, V.
    pub fn step_v(&self) -> f64 {
        STEPS_V[self.step]
    }

    /// The points recorded so far.
    pub fn recorded(&self) -> &[TaughtPoint] {
        &self.recorded
    }

    /// Whether teaching is over (every mark recorded, or `q`).
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Applies `key`, moving the mirrors through `outputs` where it moves them.
    ///
    /// # Errors
    /// The outputs' error (the state keeps the voltages of the last successful write).
    pub fn press(&mut self, key: Key, outputs: &mut dyn MirrorOutputs) -> Result<TeachEvent, GalvoError> {
        if self.finished {
            return Ok(TeachEvent::Ignored);
        }
        let step_v = self.step_v();
        let jog = |dx: f64, dy: f64| (self.volts.0 + dx * step_v, self.volts.1 + dy * step_v);
        let target = match key {
            Key::Left => jog(-1.0, 0.0),
            Key::Right => jog(1.0, 0.0),
            Key::Up => jog(0.0, 1.0),
            Key::Down => jog(0.0, -1.0),
            Key::Coarser | Key::Finer => {
                self.step = if key == Key::Coarser {
                    (self.step + 1).min(STEPS_V.len() - 1)
                } else {
                    self.step.saturating_sub(1)
                };
                return Ok(TeachEvent::Step { step_v: self.step_v() });
            }
            Key::Record => return self.record(outputs),
            Key::Quit => {
                self.finished = true;
                return Ok(TeachEvent::Finished);
            }
        };
        let (x_v, y_v, clamped) = self.clamp(target);
        outputs.set_volts(x_v, y_v)?;
        self.volts = (x_v, y_v);
        Ok(TeachEvent::Moved { x_v, y_v, clamped })
    }

    /// Fits `model` to the recorded points.
    ///
    /// # Errors
    /// As [`GalvoFit::fit`] (too few points when teaching stopped early, collinear marks...).
    pub fn fit(&self, model: FitModel) -> Result<GalvoFit, GalvoError> {
        GalvoFit::fit(model, &self.recorded)
    }

    /// What to show for the current mark: its index and plate coordinates, mm; `None` when finished.
    pub fn prompt(&self) -> Option<String> {
        self.current_mark().map(|(i, (x, y))| format!("mark {i} at ({:.1}, {:.1}) mm", x * 1e3, y * 1e3))
    }

    /// What to show after `event` (the voltages, the step, the mark recorded and the next one), if anything.
    pub fn message(&self, event: &TeachEvent) -> Option<String> {
        match *event {
            TeachEvent::Moved { x_v, y_v, clamped } => {
                let limit = if clamped { " (at the outputs' limit)" } else { "" };
                Some(format!("X {x_v:+.3} V, Y {y_v:+.3} V{limit}"))
            }
            TeachEvent::Step { step_v } => Some(format!("step {} mV", step_v * 1e3)),
            TeachEvent::Recorded { mark, point, .. } => {
                let next = self.prompt().map_or(String::new(), |p| format!("; next: {p}"));
                Some(format!("mark {mark} recorded at X {:+.3} V, Y {:+.3} V{next}", point.x_v, point.y_v))
            }
            TeachEvent::Finished | TeachEvent::Ignored => None,
        }
    }

    fn clamp(&self, (x_v, y_v): (f64, f64)) -> (f64, f64, bool) {
        let l = self.limit_v;
        let (cx, cy) = (x_v.clamp(-l, l), y_v.clamp(-l, l));
        (cx, cy, cx != x_v || cy != y_v)
    }

    fn record(&mut self, outputs: &mut dyn MirrorOutputs) -> Result<TeachEvent, GalvoError> {
        let Some((mark, (x_m, y_m))) = self.current_mark() else {
            return Ok(TeachEvent::Ignored);
        };
        let point = TaughtPoint { x_m, y_m, x_v: self.volts.0, y_v: self.volts.1 };
        self.recorded.push(point);
        let Some((_, (nx_m, ny_m))) = self.current_mark() else {
            self.finished = true;
            return Ok(TeachEvent::Recorded { mark, point, moved_to: None });
        };
        // With enough points, a provisional fit takes the beam near the next mark; a set that does not fit yet
        // (marks on one line so far) just leaves the beam where it is.
        let guess = GalvoFit::fit(FitModel::Projective, &self.recorded).ok().and_then(|f| f.volts_at(nx_m, ny_m));
        let moved_to = match guess {
            Some(v) => {
                let (x_v, y_v, _) = self.clamp(v);
                outputs.set_volts(x_v, y_v)?;
                self.volts = (x_v, y_v);
                Some((x_v, y_v))
            }
            None => None,
        };
        Ok(TeachEvent::Recorded { mark, point, moved_to })
    }
}

/// Parses marks given in millimetres, one `X, Y` (or `X Y`) per line, `#` starting a comment; `origin` names the
/// text in errors. Returns plate coordinates, m.
///
/// # Errors
/// [`GalvoError::Teach`] naming the origin and line of anything that is not two finite numbers.
pub fn parse_marks_mm(text: &str, origin: &str) -> Result<Vec<(f64, f64)>, GalvoError> {
    let mut marks = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        marks.push(
            parse_mark_mm(line)
                .map_err(|detail| GalvoError::Teach { detail: format!("{origin}:{}: {detail}", n + 1) })?,
        );
    }
    Ok(marks)
}

/// One mark `X,Y` (or `X Y`) in mm, as plate coordinates, m.
///
/// # Errors
/// What is wrong, for the caller to locate.
pub fn parse_mark_mm(text: &str) -> Result<(f64, f64), String> {
    let fields: Vec<&str> = text.split([',', ' ', '\t']).filter(|f| !f.is_empty()).collect();
    let number = |f: &str| f.parse::<f64>().ok().filter(|v| v.is_finite());
    match fields.as_slice() {
        [x, y] => match (number(x), number(y)) {
            (Some(x_mm), Some(y_mm)) => Ok((x_mm * 1e-3, y_mm * 1e-3)),
            _ => Err(format!("\"{text}\": the coordinates are not finite numbers (mm)")),
        },
        _ => Err(format!("\"{text}\": expected two numbers X, Y in mm")),
    }
}
