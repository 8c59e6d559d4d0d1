//! What a hardware file says about a Polytec controller: which velocity decoder, which filters, whether to focus.

/// Which velocity decoder the driver uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DecoderChoice {
    /// The first installed velocity decoder, by index (`VeloDec,0` first).
    First,
    /// The decoder at this index (`VeloDec,<i>`); it must be installed.
    Index(u8),
    /// The installed decoder whose name this is (`VD-09`, as `GetDevInfo,VeloDec,<i>,Name` gives it).
    Name(String),
}

/// The autofocus span (`Set,SensorHead,0,AutoFocusSpan,<span>`, as PLACE's `_autofocus_vibrometer` sends it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FocusSpan {
    /// `Full`.
    Full,
    /// `Medium`.
    Medium,
    /// `Small`.
    Small,
}

impl FocusSpan {
    /// The wire spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            FocusSpan::Full => "Full",
            FocusSpan::Medium => "Medium",
            FocusSpan::Small => "Small",
        }
    }
}

/// The settings of a Polytec controller a hardware file can make.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PolytecConfig {
    /// The velocity decoder.
    pub decoder: DecoderChoice,
    /// The decoder's low-pass filter, as the unit spells it (`20kHz`), if it has one and the file names one.
    pub low_pass: Option<String>,
    /// Autofocus at open and after a reconnect, with this span; `None`: leave the focus alone. A head without
    /// autofocus is reported when one is asked for.
    pub autofocus: Option<FocusSpan>,
}

impl Default for PolytecConfig {
    /// The first velocity decoder, filters and focus as the unit has them.
    fn default() -> Self {
        Self { decoder: DecoderChoice::First, low_pass: None, autofocus: None }
    }
}

/// Velocity decoders looked for (`VeloDec,0` to `VeloDec,7`): a controller carries one or two, eight is margin.
pub const MAX_DECODERS: u8 = 8;

/// The decoder's analog output at a range's full scale, V: the OFV-5000's velocity output swings +/- 10 V, so
/// full scale (m/s) = range (m/s per V) x 10 V.
pub const OUTPUT_FULL_SCALE_V: f64 = 10.0;
