//! What a lab chooses for an NI DAQ: the device, where the library is, each input's terminal configuration and
//! range, and what starts the acquisition.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::PathBuf;

/// The library's file name on this platform.
#[cfg(windows)]
pub const LIBRARY_NAME: &str = "nicaiu.dll";
/// The library's file name on this platform.
#[cfg(not(windows))]
pub const LIBRARY_NAME: &str = "libnidaqmx.so";

/// The environment variable naming the library to load instead of NI's (a path: the stand-in,
/// `target/debug/libnidaqmx_standin.so`, or NI's in an unusual place).
pub const LIBRARY_ENV: &str = "METAPLATE_NIDAQMX_LIBRARY";

/// The library to load: `explicit` (a hardware file's `library`), else [`LIBRARY_ENV`], else [`LIBRARY_NAME`] from
/// the system's library path.
pub fn library_path(explicit: Option<&std::path::Path>) -> OsString {
    match explicit {
        Some(path) => path.as_os_str().to_owned(),
        None => std::env::var_os(LIBRARY_ENV).filter(|v| !v.is_empty()).unwrap_or_else(|| LIBRARY_NAME.into()),
    }
}

/// How an analog input is wired (NI's terminal configuration).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TerminalConfig {
    /// The device chooses (`DAQmx_Val_Cfg_Default`).
    #[default]
    Default,
    /// Referenced single-ended, against AI GND (`DAQmx_Val_RSE`).
    Rse,
    /// Non-referenced single-ended, against AI SENSE (`DAQmx_Val_NRSE`).
    Nrse,
    /// Differential, `aiN` against `ai(N+8)` on M-series devices (`DAQmx_Val_Diff`).
    Differential,
    /// Pseudo-differential (`DAQmx_Val_PseudoDiff`; DSA and some X-series devices).
    PseudoDifferential,
}

impl TerminalConfig {
    /// All of them with the names a hardware file uses.
    pub const NAMES: [(&'static str, TerminalConfig); 5] = [
        ("default", Self::Default),
        ("rse", Self::Rse),
        ("nrse", Self::Nrse),
        ("differential", Self::Differential),
        ("pseudo-differential", Self::PseudoDifferential),
    ];

    /// NI's value (`NIDAQmx.h`).
    pub fn value(self) -> i32 {
        match self {
            Self::Default => -1,
            Self::Rse => 10083,
            Self::Nrse => 10078,
            Self::Differential => 10106,
            Self::PseudoDifferential => 12529,
        }
    }

    /// The configuration of NI's value `value`, if it is one.
    pub fn from_value(value: i32) -> Option<Self> {
        Self::NAMES.iter().map(|(_, t)| *t).find(|t| t.value() == value)
    }

    /// The configuration a hardware file names (`rse`, `nrse`, `differential` or `diff`, `pseudo-differential`,
    /// `default`; any case).
    ///
    /// # Errors
    /// A sentence listing the names.
    pub fn parse(text: &str) -> Result<Self, String> {
        let lower = text.trim().to_ascii_lowercase();
        let lower = if lower == "diff" { "differential".to_owned() } else { lower };
        Self::NAMES.iter().find(|(name, _)| *name == lower).map(|(_, t)| *t).ok_or_else(|| {
            let names: Vec<&str> = Self::NAMES.iter().map(|(n, _)| *n).collect();
            format!("{text:?} is not a terminal configuration: one of {}", names.join(", "))
        })
    }

    /// The name a hardware file uses.
    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, t)| *t == self).map_or("default", |(n, _)| n)
    }
}

/// One analog input's settings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NiInput {
    /// Its terminal configuration.
    pub terminal: TerminalConfig,
    /// Its range, +/- V; `None`: the range the acquisition asks for (the wiring's `daq_range_v`).
    pub range_v: Option<f64>,
}

/// What starts the acquisition.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum StartTrigger {
    /// `DAQmxStartTask` starts it (the inputs start when the call returns).
    #[default]
    Software,
    /// The device's output task: the inputs wait on `/Dev1/ao/StartTrigger`, so they start on the output's first
    /// sample clock (needs an output waveform, [`super::NiDaqmx::set_output_waveform`]).
    OutputStart,
    /// A digital edge on a terminal (`/Dev1/PFI0`): inputs and outputs both wait on it.
    Terminal(String),
}

impl StartTrigger {
    /// The trigger a hardware file names: `software`, `ao` (the output's start), or a terminal (`/Dev1/PFI0`,
    /// `PFI0` for the device's own).
    ///
    /// # Errors
    /// A sentence saying what is accepted.
    pub fn parse(text: &str, device: &str) -> Result<Self, String> {
        let text = text.trim();
        match text.to_ascii_lowercase().as_str() {
            "software" | "" => Ok(Self::Software),
            "ao" | "ao/starttrigger" => Ok(Self::OutputStart),
            _ if text.starts_with('/') && text.matches('/').count() >= 2 => Ok(Self::Terminal(text.to_owned())),
            _ if text.to_ascii_uppercase().starts_with("PFI") && text[3..].parse::<u8>().is_ok() => {
                Ok(Self::Terminal(format!("/{device}/{}", text.to_ascii_uppercase())))
            }
            _ => Err(format!(
                "{text:?} is not a start trigger: \"software\", \"ao\" (the output task's start) or a \
                terminal (\"/{device}/PFI0\")"
            )),
        }
    }

    /// The terminal NI takes for it, on `device` (`None` for a software start).
    pub fn source(&self, device: &str) -> Option<String> {
        match self {
            Self::Software => None,
            Self::OutputStart => Some(format!("/{device}/ao/StartTrigger")),
            Self::Terminal(terminal) => Some(terminal.clone()),
        }
    }
}

/// How to open an NI DAQ.
#[derive(Debug, Clone, PartialEq)]
pub struct NiSettings {
    /// The NI device name (`Dev1`, as NI MAX shows it).
    pub device: String,
    /// The library to load; `None`: [`library_path`]'s choice.
    pub library: Option<PathBuf>,
    /// How long one block read waits, s (finite, > 0).
    pub read_timeout_s: f64,
    /// The terminal configuration of inputs not in `inputs`.
    pub terminal: TerminalConfig,
    /// Per input (by index: 0 for `ai0`): its settings.
    pub inputs: BTreeMap<u8, NiInput>,
    /// What starts the acquisition.
    pub trigger: StartTrigger,
}

impl NiSettings {
    /// `device` with the defaults: the system's library, 10 s reads, the device's terminal configuration,
    /// software start.
    pub fn new(device: &str) -> Self {
        Self {
            device: device.to_owned(),
            library: None,
            read_timeout_s: 10.0,
            terminal: TerminalConfig::Default,
            inputs: BTreeMap::new(),
            trigger: StartTrigger::Software,
        }
    }

    /// The settings of input `input`.
    pub fn input(&self, input: u8) -> NiInput {
        self.inputs.get(&input).copied().unwrap_or(NiInput { terminal: self.terminal, range_v: None })
    }
}
