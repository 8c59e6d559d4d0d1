//! Two analog outputs of an NI DAQ holding static volts: what drives a pair of galvanometer mirrors
//! ([`MirrorOutputs`]). One on-demand task holds both outputs (reserving them: a second program or task asking
//! for them gets -50103) and writes one sample per channel per move.

use std::path::PathBuf;
use std::sync::Arc;

use metaplate_core::aim::{AimError, MirrorOutputs};

use super::backend::open_device;
use super::ffi::{NiLibrary, Task};

/// How long one write may take, s (an on-demand write returns at once on NI's devices).
const WRITE_TIMEOUT_S: f64 = 1.0;

/// Two analog outputs of an NI DAQ holding static volts (for example `Dev1/ao0` and `Dev1/ao1` driving the X and
/// Y mirrors of a Thorlabs GVS, +/-10 V).
pub struct NiMirrorOutputs {
    device: String,
    x_output: String,
    y_output: String,
    limit_v: f64,
    library: Option<PathBuf>,
    /// "NI USB-6211 s/n 01A2B3C4".
    instrument: String,
    /// `None` after a failure that calls for a reconnect.
    task: Option<Task>,
}

impl std::fmt::Debug for NiMirrorOutputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NiMirrorOutputs").field("describe", &self.describe()).finish_non_exhaustive()
    }
}

/// `ao0` or `Dev1/ao0` as the physical channel `Dev1/ao0` of `device`.
fn physical(device: &str, output: &str) -> Result<String, AimError> {
    let output = output.trim();
    let name = output.rsplit('/').next().unwrap_or(output);
    let index = name.strip_prefix("ao").and_then(|n| n.parse::<u8>().ok());
    match index {
        Some(i)
            if output == name || output.trim_start_matches('/').eq_ignore_ascii_case(&format!("{device}/ao{i}")) =>
        {
            Ok(format!("{device}/ao{i}"))
        }
        _ => {
            Err(AimError::InvalidArgument { detail: format!("{output:?} is not an analog output of {device} (`ao0`)") })
        }
    }
}

impl NiMirrorOutputs {
    /// Opens analog outputs `x_output` and `y_output` (`ao0`, or `Dev1/ao0`) of NI device `device`, each limited to
    /// `-limit_v..=limit_v` (also the range the outputs are configured with), loading `library` (`None`:
    /// [`super::library_path`]'s choice). The outputs are reserved until this is dropped; they are not moved until the
    /// first [`set_volts`](MirrorOutputs::set_volts).
    ///
    /// # Errors
    /// `InvalidArgument` for a limit that is not a positive voltage, an output name that is not `aoN`, or the same
    /// output twice; `Unavailable` when the library or the device is missing; `Device` when NI refuses (the
    /// outputs reserved by another task or program: -50103; a range the device lacks).
    pub fn open(
        device: &str,
        x_output: &str,
        y_output: &str,
        limit_v: f64,
        library: Option<PathBuf>,
    ) -> Result<Self, AimError> {
        if !(limit_v.is_finite() && limit_v > 0.0) {
            return Err(AimError::InvalidArgument { detail: format!("limit_v = {limit_v}: not a positive voltage") });
        }
        let x_output = physical(device, x_output)?;
        let y_output = physical(device, y_output)?;
        if x_output == y_output {
            return Err(AimError::InvalidArgument { detail: format!("X and Y are both {x_output}") });
        }
        let (lib, identity) = open_device(library.as_deref(), device).map_err(|e| match e {
            metaplate_core::daq::DaqError::Disconnected { detail } => AimError::Disconnected { reason: detail },
            other => AimError::Unavailable { detail: other.to_string() },
        })?;
        let instrument = format!("{} s/n {}", identity.model, identity.serial);
        let mut outputs =
            Self { device: device.to_owned(), x_output, y_output, limit_v, library, instrument, task: None };
        outputs.task = Some(outputs.create_task(&lib)?);
        Ok(outputs)
    }

    /// The on-demand task holding both outputs, started (so reserved).
    fn create_task(&self, lib: &Arc<NiLibrary>) -> Result<Task, AimError> {
        let fail = |f: super::status::NiFailure| f.aim_error(&self.device);
        let task = lib.create_task().map_err(fail)?;
        task.add_ao_voltage(&self.x_output, self.limit_v).map_err(fail)?;
        task.add_ao_voltage(&self.y_output, self.limit_v).map_err(fail)?;
        task.start().map_err(fail)?;
        Ok(task)
    }
}

impl MirrorOutputs for NiMirrorOutputs {
    fn set_volts(&mut self, x_v: f64, y_v: f64) -> Result<(), AimError> {
        for (name, v) in [("x_v", x_v), ("y_v", y_v)] {
            if !(v.is_finite() && v.abs() <= self.limit_v) {
                return Err(AimError::InvalidArgument {
                    detail: format!("{name} = {v}: beyond +/- {} V", self.limit_v),
                });
            }
        }
        let task = self.task.as_ref().ok_or_else(|| AimError::Disconnected {
            reason: format!("{} outputs closed after an error: reconnect", self.instrument),
        })?;
        if let Err(f) = task.write(&[x_v, y_v], 1, WRITE_TIMEOUT_S) {
            let e = f.aim_error(&self.device);
            if e.suggests_reconnect() {
                self.task = None;
            }
            return Err(e);
        }
        Ok(())
    }

    fn limit_v(&self) -> f64 {
        self.limit_v
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        self.task = None;
        let (lib, _) = open_device(self.library.as_deref(), &self.device)
            .map_err(|e| AimError::Disconnected { reason: e.to_string() })?;
        self.task = Some(self.create_task(&lib)?);
        Ok(())
    }

    fn describe(&self) -> String {
        format!("{} {}, {}", self.instrument, self.x_output, self.y_output)
    }
}
