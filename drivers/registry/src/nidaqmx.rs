//! `[daq]` with `backend = "nidaqmx"`: an NI DAQ through NI-DAQmx.
//!
//! ```toml
//! [daq]
//! backend = "nidaqmx"
//! device = "Dev1"                  # the NI name, as NI MAX (or `metaplate devices`) shows it
//! read_timeout_s = 10.0            # optional: how long one block read waits
//! terminal = "rse"                 # optional: every input's terminal configuration (default: the device's)
//! trigger = "software"             # optional: "software", "ao" (the output task's start), or "/Dev1/PFI0"
//! library = "/opt/.../libnidaqmx.so" # optional: instead of NI's (default: $METAPLATE_NIDAQMX_LIBRARY, else NI's)
//!
//! [daq.inputs.ai0]                 # optional, per input: its terminal configuration and range
//! terminal = "differential"        # rse, nrse, differential (diff), pseudo-differential, default
//! range_v = 5.0                    # +/- V; default: the wiring's daq_range_v
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metaplate_daq::{NiInput, NiSettings, StartTrigger, TerminalConfig};
use serde::Deserialize;

/// `[daq]` with `backend = "nidaqmx"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NidaqmxDaq {
    /// NI device name as NI MAX shows it (`Dev1`).
    pub device: String,
    /// How long one block read waits, s (default 10; valid range: finite, > 0).
    #[serde(default = "default_read_timeout_s")]
    pub read_timeout_s: f64,
    /// Every input's terminal configuration unless `inputs` says otherwise (`rse`, `nrse`, `differential`,
    /// `pseudo-differential`; default: the device's).
    pub terminal: Option<String>,
    /// What starts the acquisition: `software` (default), `ao` (the output task's start trigger), or a terminal
    /// (`/Dev1/PFI0`) both inputs and outputs wait on.
    pub trigger: Option<String>,
    /// The library to load instead of NI's (the stand-in `libnidaqmx_standin.so`), relative to the hardware file's
    /// folder; default: `$METAPLATE_NIDAQMX_LIBRARY`, else NI's.
    pub library: Option<PathBuf>,
    /// Per input (`ai0`): its terminal configuration and range.
    #[serde(default)]
    pub inputs: BTreeMap<String, NidaqmxInput>,
}

/// `[daq.inputs.aiN]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NidaqmxInput {
    /// Its terminal configuration (as `daq.terminal`).
    pub terminal: Option<String>,
    /// Its range, +/- V (finite, > 0); default: the wiring's `daq_range_v`.
    pub range_v: Option<f64>,
}

fn default_read_timeout_s() -> f64 {
    10.0
}

impl NidaqmxDaq {
    /// The backend's settings, for the hardware file at `file` (a relative `library` is taken from its folder).
    ///
    /// # Errors
    /// The key in error (`daq.inputs.ai0.terminal`) and what is wrong with it.
    pub fn settings(&self, file: &Path) -> Result<NiSettings, (String, String)> {
        let key = |k: &str| format!("daq.{k}");
        if self.device.trim().is_empty() || self.device.contains(['\0', '/', ',']) {
            return Err((key("device"), format!("{:?} is not an NI device name (`Dev1`)", self.device)));
        }
        if !(self.read_timeout_s.is_finite() && self.read_timeout_s > 0.0) {
            return Err((key("read_timeout_s"), format!("{} is not a positive time", self.read_timeout_s)));
        }
        let terminal = match &self.terminal {
            Some(t) => TerminalConfig::parse(t).map_err(|reason| (key("terminal"), reason))?,
            None => TerminalConfig::Default,
        };
        let trigger = match &self.trigger {
            Some(t) => StartTrigger::parse(t, &self.device).map_err(|reason| (key("trigger"), reason))?,
            None => StartTrigger::Software,
        };
        let mut inputs = BTreeMap::new();
        for (name, input) in &self.inputs {
            let index = name
                .strip_prefix("ai")
                .and_then(|n| n.parse::<u8>().ok())
                .ok_or_else(|| (key(&format!("inputs.{name}")), format!("{name:?} is not an analog input (`ai0`)")))?;
            let terminal = match &input.terminal {
                Some(t) => {
                    TerminalConfig::parse(t).map_err(|reason| (key(&format!("inputs.{name}.terminal")), reason))?
                }
                None => terminal,
            };
            if let Some(range_v) = input.range_v
                && !(range_v.is_finite() && range_v > 0.0)
            {
                return Err((key(&format!("inputs.{name}.range_v")), format!("{range_v} is not a positive voltage")));
            }
            inputs.insert(index, NiInput { terminal, range_v: input.range_v });
        }
        let library = self.library.as_ref().map(|l| match file.parent() {
            Some(dir) if l.is_relative() => dir.join(l),
            _ => l.clone(),
        });
        Ok(NiSettings {
            device: self.device.trim().to_owned(),
            library,
            read_timeout_s: self.read_timeout_s,
            terminal,
            inputs,
            trigger,
        })
    }
}
