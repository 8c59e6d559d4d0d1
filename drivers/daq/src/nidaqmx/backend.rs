//! [`NiDaqmx`]: the [`Daq`] on an NI device, and the listing of NI devices.

use std::sync::Arc;

use metaplate_core::daq::{BlockIntegrity, Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};

use super::ffi::{NiLibrary, Task};
use super::settings::{NiSettings, StartTrigger, TerminalConfig, library_path};
use super::status;

/// Loads the library at `settings.library` (or [`library_path`]'s choice) and reads the device's identity.
pub(crate) fn open_device(
    library: Option<&std::path::Path>,
    device: &str,
) -> Result<(Arc<NiLibrary>, DaqIdentity), DaqError> {
    let path = library_path(library);
    let lib = NiLibrary::load(&path).map_err(|e| DaqError::Unavailable {
        detail: format!("cannot load the NI-DAQmx library {} (is NI-DAQmx installed?): {e}", path.to_string_lossy()),
    })?;
    let product = lib.product_type(device).map_err(|f| f.daq_error(device))?;
    let serial = lib.serial_number(device).map_err(|f| f.daq_error(device))?;
    let identity = DaqIdentity {
        vendor: "National Instruments".into(),
        model: format!("NI {product}"),
        serial: format!("{serial:08X}"),
        firmware: format!("NI-DAQmx device {device}"),
    };
    Ok((lib, identity))
}

/// An NI-DAQmx device as `DAQmxGetSysDevNames` and its properties describe it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NiDevice {
    /// Its NI name (`Dev1`), as `daq.device` takes it.
    pub name: String,
    /// `DAQmx_Dev_ProductType` (`USB-6211`).
    pub product_type: String,
    /// `DAQmx_Dev_SerialNum`.
    pub serial: u32,
}

/// The NI-DAQmx devices of this computer with their product type and serial number; `Ok(None)` when the library
/// ([`library_path`]'s choice) is not installed (no NI device can be driven: not an error).
///
/// # Errors
/// A [`DaqError`] naming NI's status when the library loads but a call fails.
pub fn devices() -> Result<Option<Vec<NiDevice>>, DaqError> {
    let Ok(lib) = NiLibrary::load(&library_path(None)) else { return Ok(None) };
    let names = lib.device_names().map_err(|f| f.daq_error("(all)"))?;
    let mut found = Vec::new();
    for name in names.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let product_type = lib.product_type(name).map_err(|f| f.daq_error(name))?;
        let serial = lib.serial_number(name).map_err(|f| f.daq_error(name))?;
        found.push(NiDevice { name: name.to_owned(), product_type, serial });
    }
    Ok(Some(found))
}

/// The NI names of [`devices`] (`Dev1`).
///
/// # Errors
/// As [`devices`].
pub fn device_names() -> Result<Option<Vec<String>>, DaqError> {
    Ok(devices()?.map(|found| found.into_iter().map(|d| d.name).collect()))
}

/// An output waveform the device generates while it acquires: `samples[k]` for output `outputs[k]` (`ao0` is 0),
/// regenerated for as long as the acquisition runs, at the acquisition's sample rate.
#[derive(Debug, Clone, PartialEq)]
pub struct NiOutputWaveform {
    /// The analog outputs, by index.
    pub outputs: Vec<u8>,
    /// Their range, +/- V; every sample must lie within it.
    pub range_v: f64,
    /// One waveform per output, all of one length (> 0), V.
    pub samples: Vec<Vec<f64>>,
}

/// An NI-DAQmx device as a [`Daq`], by its NI device name (`"Dev1"`).
pub struct NiDaqmx {
    lib: Arc<NiLibrary>,
    settings: NiSettings,
    identity: DaqIdentity,
    config: Option<DaqConfig>,
    output: Option<NiOutputWaveform>,
    /// The input task, then the output task (dropped, so cleared, in that order).
    input: Option<Task>,
    output_task: Option<Task>,
    /// Each configured input's range, V, and the terminal configuration the device took.
    inputs: Vec<(u8, f64, Option<TerminalConfig>)>,
    running: bool,
    next_index: u64,
}

impl std::fmt::Debug for NiDaqmx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NiDaqmx")
            .field("device", &self.settings.device)
            .field("identity", &self.identity)
            .field("running", &self.running)
            .finish_non_exhaustive()
    }
}

impl NiDaqmx {
    /// Loads NI-DAQmx and opens `settings.device`, reading its product type and serial number.
    ///
    /// # Errors
    /// [`DaqError::Unavailable`] if the library is not there (or lacks a function) or there is no such device
    /// (-200220); [`DaqError::Config`] for a read timeout that is not a positive time.
    pub fn open(settings: &NiSettings) -> Result<Self, DaqError> {
        if !(settings.read_timeout_s.is_finite() && settings.read_timeout_s > 0.0) {
            return Err(DaqError::Config {
                detail: format!("read timeout {} s is not a positive time", settings.read_timeout_s),
            });
        }
        let (lib, identity) = open_device(settings.library.as_deref(), &settings.device)?;
        Ok(Self {
            lib,
            settings: settings.clone(),
            identity,
            config: None,
            output: None,
            input: None,
            output_task: None,
            inputs: Vec::new(),
            running: false,
            next_index: 0,
        })
    }

    /// The output waveform generated with the following acquisitions (`None`: inputs only); applied by the next
    /// [`configure`](Daq::configure).
    ///
    /// # Errors
    /// [`DaqError::Config`] for no outputs, waveforms of unequal or zero length, a sample beyond the range or not
    /// finite; [`DaqError::Protocol`] while an acquisition runs.
    pub fn set_output_waveform(&mut self, output: Option<NiOutputWaveform>) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: "cannot change the output while an acquisition runs".into() });
        }
        if let Some(out) = &output {
            let len = out.samples.first().map_or(0, Vec::len);
            let bad = |detail: String| Err(DaqError::Config { detail });
            if out.outputs.is_empty() || out.outputs.len() != out.samples.len() || len == 0 {
                return bad("an output waveform needs one non-empty waveform per output".into());
            }
            if out.samples.iter().any(|s| s.len() != len) {
                return bad("the outputs' waveforms differ in length".into());
            }
            if !(out.range_v.is_finite() && out.range_v > 0.0) {
                return bad(format!("output range {} V is invalid", out.range_v));
            }
            if let Some(v) = out.samples.iter().flatten().find(|v| !(v.is_finite() && v.abs() <= out.range_v)) {
                return bad(format!("output sample {v} V is beyond +/- {} V", out.range_v));
            }
        }
        self.output = output;
        Ok(())
    }

    /// The terminal configuration each configured input has on the device (read back from NI-DAQmx after
    /// configuring), by input index.
    pub fn input_terminals(&self) -> Vec<(u8, Option<TerminalConfig>)> {
        self.inputs.iter().map(|(input, _, terminal)| (*input, *terminal)).collect()
    }

    /// The settings it was opened with.
    pub fn settings(&self) -> &NiSettings {
        &self.settings
    }

    fn clear(&mut self) {
        // The input first: it may wait on the output's start trigger.
        self.input = None;
        self.output_task = None;
        self.running = false;
    }

    fn fail(&self) -> impl Fn(status::NiFailure) -> DaqError + '_ {
        |f| f.daq_error(&self.settings.device)
    }

    /// Creates the tasks for `config`: one voltage channel per input (terminal configuration and range from the
    /// settings), the onboard clock, continuous, the start trigger; the output task with its waveform.
    fn create_tasks(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if config.channels.is_empty() || config.block_len_samples == 0 {
            return Err(DaqError::Config {
                detail: "need at least one channel and a block of at least 1 sample".into(),
            });
        }
        if !(config.sample_rate_hz.is_finite() && config.sample_rate_hz > 0.0) {
            return Err(DaqError::Config { detail: format!("sample rate {} Hz is invalid", config.sample_rate_hz) });
        }
        if self.settings.trigger == StartTrigger::OutputStart && self.output.is_none() {
            return Err(DaqError::Config {
                detail: "trigger = \"ao\" starts the inputs with the output task, and no output waveform is set".into(),
            });
        }
        let device = self.settings.device.clone();
        let input = self.lib.create_task().map_err(self.fail())?;
        let mut inputs = Vec::new();
        for ch in &config.channels {
            let settings = self.settings.input(ch.input);
            let range_v = settings.range_v.unwrap_or(ch.range_v);
            if !(range_v.is_finite() && range_v > 0.0) {
                return Err(DaqError::Config { detail: format!("ai{}: range {range_v} V is invalid", ch.input) });
            }
            let physical = format!("{device}/ai{}", ch.input);
            input.add_ai_voltage(&physical, settings.terminal.value(), range_v).map_err(self.fail())?;
            let taken = input.ai_terminal(&physical).map_err(self.fail())?;
            inputs.push((ch.input, range_v, TerminalConfig::from_value(taken)));
        }
        // Buffer hint: ten blocks per channel (NI takes the larger of this and its default for the rate).
        let buffer = u64::from(config.block_len_samples) * 10;
        input.sample_clock(config.sample_rate_hz, buffer).map_err(self.fail())?;
        if let Some(source) = self.settings.trigger.source(&device) {
            input.start_trigger(&source).map_err(self.fail())?;
        }
        if let Some(out) = &self.output {
            let task = self.lib.create_task().map_err(self.fail())?;
            for ao in &out.outputs {
                task.add_ao_voltage(&format!("{device}/ao{ao}"), out.range_v).map_err(self.fail())?;
            }
            let len = out.samples.first().map_or(0, Vec::len);
            task.sample_clock(config.sample_rate_hz, len as u64).map_err(self.fail())?;
            if let StartTrigger::Terminal(terminal) = &self.settings.trigger {
                task.start_trigger(terminal).map_err(self.fail())?;
            }
            let flat: Vec<f64> = out.samples.iter().flatten().copied().collect();
            task.write(&flat, len, self.settings.read_timeout_s).map_err(self.fail())?;
            self.output_task = Some(task);
        }
        self.input = Some(input);
        self.inputs = inputs;
        Ok(())
    }
}

impl Daq for NiDaqmx {
    fn identity(&self) -> &DaqIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: "cannot configure while an acquisition runs".into() });
        }
        self.clear();
        let result = self.create_tasks(config);
        match &result {
            Ok(()) => self.config = Some(config.clone()),
            Err(_) => self.clear(),
        }
        result
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: "an acquisition is already running".into() });
        }
        let input = self.input.as_ref().ok_or_else(|| DaqError::Protocol { detail: "not configured".into() })?;
        // The input first: with a start trigger it arms, and the output's start (or the external edge) starts both.
        input.start().map_err(self.fail())?;
        if let Some(output) = &self.output_task
            && let Err(e) = output.start()
        {
            let _ = input.stop();
            return Err(e.daq_error(&self.settings.device));
        }
        self.running = true;
        self.next_index = 0;
        Ok(())
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        let (Some(config), Some(input), true) = (self.config.as_ref(), self.input.as_ref(), self.running) else {
            return Err(DaqError::Protocol { detail: "read_block while no acquisition runs".into() });
        };
        let n_ch = config.channels.len();
        let block = config.block_len_samples as usize;
        let (data, read) = input.read(block, n_ch, self.settings.read_timeout_s).map_err(self.fail())?;
        if read == 0 {
            return Err(DaqError::Timeout { what: "samples from NI-DAQmx".into(), attempts: 1 });
        }
        // Interleaved by scan: sample i of channel c is at i * n_ch + c.
        let volts: Vec<Vec<f64>> =
            (0..n_ch).map(|c| data[..read * n_ch].iter().skip(c).step_by(n_ch).copied().collect()).collect();
        if volts.iter().flatten().any(|v| !v.is_finite()) {
            return Err(DaqError::Device { code: 0, detail: "NI-DAQmx returned a non-finite sample".into() });
        }
        let clipped = self.inputs.iter().zip(&volts).any(|((_, range_v, _), v)| v.iter().any(|x| x.abs() >= *range_v));
        let first_sample_index = self.next_index;
        self.next_index += read as u64;
        Ok(DaqBlock { first_sample_index, volts, integrity: BlockIntegrity { clipped, ..BlockIntegrity::default() } })
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        if !self.running {
            return Ok(());
        }
        self.running = false;
        let output = self.output_task.as_ref().map(Task::stop).unwrap_or(Ok(()));
        let input = self.input.as_ref().map(Task::stop).unwrap_or(Ok(()));
        input.and(output).map_err(self.fail())
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.clear();
        let (lib, identity) = open_device(self.settings.library.as_deref(), &self.settings.device)?;
        self.lib = lib;
        self.identity = identity;
        match self.config.clone() {
            Some(config) => self.configure(&config),
            None => Ok(()),
        }
    }
}
