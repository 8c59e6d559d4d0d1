//! Warning flags: the two-letter field of every reply and alert, and the list the `warnings` command returns.
//!
//! *Manual, Warning Flags*: a reply shows the highest-priority flag of its device or axis (`--` for none): faults
//! (`F*`) before warnings (`W*`) before notices (`N*`). The names below are the manual's; a code not listed keeps
//! its two letters and is named as unknown.

/// A two-letter warning flag, or `--` for none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct WarningFlag([u8; 2]);

/// The flags this crate names, with the manual's names.
const NAMES: [(&str, &str); 29] = [
    ("FF", "critical system error"),
    ("FN", "peripheral not supported"),
    ("FZ", "peripheral inactive"),
    ("FH", "hardware emergency stop driver disabled"),
    ("FV", "overdrive limit exceeded"),
    ("FO", "driver disabled"),
    ("FC", "current inrush error"),
    ("FM", "motor temperature error"),
    ("FD", "driver disabled"),
    ("FQ", "encoder error"),
    ("FS", "stalled and stopped"),
    ("FB", "stream bounds error"),
    ("FP", "interpolated path deviation"),
    ("FE", "limit error"),
    ("FT", "excessive twist"),
    ("WL", "unexpected limit trigger"),
    ("WV", "voltage out of range"),
    ("WT", "controller temperature high"),
    ("WS", "stalled with recovery"),
    ("WM", "displaced when stationary"),
    ("WP", "invalid calibration type"),
    ("WR", "no reference position"),
    ("WH", "device not homed"),
    ("NC", "manual control"),
    ("NI", "command interrupted"),
    ("ND", "stream discontinuity"),
    ("NR", "value rounded"),
    ("NT", "value truncated"),
    ("NU", "setting update pending"),
];

impl WarningFlag {
    /// No warning: `--`.
    pub const NONE: WarningFlag = WarningFlag(*b"--");
    /// `WR`, no reference position: the axis has not been homed since power-up (firmware 7).
    pub const NO_REFERENCE: WarningFlag = WarningFlag(*b"WR");
    /// `WH`, device not homed (the firmware 6 spelling of the same state).
    pub const NOT_HOMED: WarningFlag = WarningFlag(*b"WH");
    /// `WL`, unexpected limit trigger: a limit sensor tripped during a move, which stopped short.
    pub const UNEXPECTED_LIMIT: WarningFlag = WarningFlag(*b"WL");
    /// `NI`, command interrupted: a move was cut short by a newer command.
    pub const INTERRUPTED: WarningFlag = WarningFlag(*b"NI");

    /// The flag spelt by `code`, if it is two upper-case letters or `--`.
    pub fn parse(code: &str) -> Option<Self> {
        let bytes: [u8; 2] = code.as_bytes().try_into().ok()?;
        let valid = bytes == *b"--" || bytes.iter().all(u8::is_ascii_uppercase);
        valid.then_some(WarningFlag(bytes))
    }

    /// The two letters (or `--`).
    pub fn code(&self) -> &str {
        // Only ASCII is ever stored (see `parse` and the constants).
        std::str::from_utf8(&self.0).unwrap_or("??")
    }

    /// The manual's name of the flag, "no warning" for `--`, "unknown" for a code this crate does not name.
    pub fn name(&self) -> &'static str {
        if self.is_none() {
            return "no warning";
        }
        NAMES.iter().find(|(code, _)| code.as_bytes() == self.0).map_or("unknown", |(_, name)| name)
    }

    /// Whether this is `--`.
    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    /// A fault (`F*`): the axis stopped and needs attention; cleared by `warnings clear` once the cause is gone.
    pub fn is_fault(&self) -> bool {
        self.0[0] == b'F'
    }

    /// A warning (`W*`).
    pub fn is_warning(&self) -> bool {
        self.0[0] == b'W'
    }

    /// Whether the axis needs homing before its positions mean anything (`WR` or `WH`).
    pub fn needs_homing(&self) -> bool {
        *self == Self::NO_REFERENCE || *self == Self::NOT_HOMED
    }

    /// Priority for the reply field: faults 3, warnings 2, notices 1, none 0.
    pub fn priority(&self) -> u8 {
        match self.0[0] {
            b'F' => 3,
            b'W' => 2,
            b'N' => 1,
            _ => 0,
        }
    }
}

impl std::fmt::Display for WarningFlag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.code(), self.name())
    }
}

/// The flags in the data of a reply to `warnings`: a two-digit count, then the flags (*Manual, warnings command*:
/// `@01 1 OK IDLE WR 01 WR`).
///
/// # Errors
/// `None` when the count or a flag is malformed, or the count does not match.
pub fn parse_warning_list(data: &str) -> Option<Vec<WarningFlag>> {
    let mut words = data.split_whitespace();
    let count: usize = words.next()?.parse().ok()?;
    let flags = words.map(WarningFlag::parse).collect::<Option<Vec<_>>>()?;
    (flags.len() == count).then_some(flags)
}

/// The data of a reply to `warnings` listing `flags`.
pub fn format_warning_list(flags: &[WarningFlag]) -> String {
    let mut data = format!("{:02}", flags.len());
    for flag in flags {
        data.push(' ');
        data.push_str(flag.code());
    }
    data
}
