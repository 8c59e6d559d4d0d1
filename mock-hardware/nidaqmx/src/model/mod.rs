//! The simulated NI-DAQmx: tasks, their channels, timing, start triggers and state, answering with NI's status
//! codes and extended error texts. Safe Rust; `exports` turns the C calls into calls here.
//!
//! Time is real: a started input task acquires `rate_hz` samples per second from its start instant; a read waits
//! (up to its timeout) for the samples it asks for, and finds the buffer overwritten (-200279) when more than the
//! buffer holds were acquired and not read. Wiring of every device: `ao0` is looped back to `ai0` and `ao1` to
//! `ai1` (what a lab cables to check its outputs); `ai2` .. `ai15` carry a deterministic sine (0.5 V at
//! 1 kHz x (input - 1)), clipped to the channel's range. Beside a stand-in rig, its timed inputs and on-demand
//! outputs go to the rig instead ([`rig`]).

mod rig;

use std::collections::BTreeMap;
use std::time::Instant;

use crate::device::{self, Device, codes};
use crate::lab::LabLink;

/// An NI status with its extended error text.
#[derive(Debug, Clone, PartialEq)]
pub struct NiError {
    /// NI's status code (negative).
    pub code: i32,
    /// What `DAQmxGetExtendedErrorInfo` returns after it.
    pub message: String,
}

/// -200279: unread samples were overwritten (the input buffer overflowed).
fn overwritten(task_name: &str) -> NiError {
    err(
        codes::SAMPLES_NO_LONGER_AVAILABLE,
        "Attempted to read samples that are no longer available. The requested sample was \
        previously available, but has since been overwritten.\n\nIncreasing the buffer size, \
        reading the data more frequently, or specifying a fixed number of samples to read instead \
        of reading all available samples might correct the problem.",
        &format!(
            "Property: DAQmx_Read_RelativeTo\nCorresponding Value: DAQmx_Val_CurrReadPos\nProperty: \
            DAQmx_Read_Offset\nCorresponding Value: 0\n\nTask Name: {task_name}"
        ),
    )
}

fn err(code: i32, what: &str, detail: &str) -> NiError {
    let detail = if detail.is_empty() { String::new() } else { format!("\n\n{detail}") };
    NiError { code, message: format!("{what}{detail}\n\nStatus Code: {code}") }
}

#[derive(Debug, Clone)]
struct AiChan {
    name: String,
    device: String,
    index: u8,
    term_cfg: i32,
    range_v: f64,
}

#[derive(Debug, Clone)]
struct AoChan {
    device: String,
    index: u8,
    min_v: f64,
    max_v: f64,
}

#[derive(Debug, Clone, Copy)]
struct Timing {
    rate_hz: f64,
    continuous: bool,
    samps_per_chan: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    Idle,
    /// Started, waiting for its start trigger.
    Armed,
    Running {
        t0: Instant,
    },
}

#[derive(Debug, Clone)]
struct Task {
    name: String,
    ai: Vec<AiChan>,
    ao: Vec<AoChan>,
    timing: Option<Timing>,
    trigger: Option<String>,
    state: State,
    /// A timed output's samples, per channel (regenerated).
    waveform: Vec<Vec<f64>>,
    read_pos: u64,
}

/// Where a read's samples come from.
#[derive(Clone, Copy)]
enum Samples<'a> {
    /// The built-in wiring, for a task started at `t0` sampling at `rate_hz`.
    Wiring { t0: Instant, rate_hz: f64 },
    /// The stand-in rig's reply, by scan.
    Rig(&'a [f64]),
}

/// What a read found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReadOutcome {
    /// This many samples per channel were written to the caller's array.
    Done(usize),
    /// Not enough samples yet: they will be there at this instant (`None`: the task waits for its trigger).
    Wait(Option<Instant>),
}

/// The stand-in's whole state: what one process's NI-DAQmx holds.
#[derive(Debug, Default)]
pub struct StandIn {
    tasks: BTreeMap<u64, Task>,
    next_handle: u64,
    /// The voltage each analog output holds when no timed task drives it, by (device, output).
    held_v: BTreeMap<(String, u8), f64>,
    /// The stand-in rig's socket, when set ([`StandIn::set_lab_socket`]); else the one beside the library, if any
    /// ([`crate::lab::socket_beside_library`]).
    lab_socket: Option<std::path::PathBuf>,
    /// The lab links of the running timed input tasks that read the stand-in rig, by task handle.
    labs: BTreeMap<u64, LabLink>,
    /// The lab link the on-demand output writes are told over, once one was made.
    outputs_link: Option<LabLink>,
}

fn device_or_error(name: &str) -> Result<Device, NiError> {
    device::find(name).ok_or_else(|| {
        let names: Vec<String> = device::devices().into_iter().map(|d| d.name).collect();
        err(
            codes::INVALID_DEVICE_ID,
            "Device identifier is invalid.",
            &format!("Device Specified: {name}\nSuggested Device(s): {}", names.join(", ")),
        )
    })
}

/// Parses `Dev1/ai0`, `Dev1/ai0:3` or a comma-separated list of these, for channels of `kind` (`ai`, `ao`) of
/// which the device has `count`.
fn physical_channels(text: &str, kind: &str, count: u8) -> Result<Vec<(Device, u8, String)>, NiError> {
    let mut out = Vec::new();
    for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let bad = || {
            err(
                codes::PHYSICAL_CHAN_DOES_NOT_EXIST,
                "Physical channel specified does not exist on this device.",
                &format!("Physical Channel Name: {item}"),
            )
        };
        let (dev_name, chan) = item.trim_start_matches('/').split_once('/').ok_or_else(bad)?;
        let dev = device_or_error(dev_name)?;
        let digits = chan.strip_prefix(kind).ok_or_else(bad)?;
        let (first, last) = match digits.split_once(':') {
            Some((a, b)) => (a.parse::<u8>().map_err(|_| bad())?, b.parse::<u8>().map_err(|_| bad())?),
            None => {
                let n = digits.parse::<u8>().map_err(|_| bad())?;
                (n, n)
            }
        };
        if first > last || last >= count {
            return Err(bad());
        }
        for i in first..=last {
            out.push((dev.clone(), i, format!("{}/{kind}{i}", dev.name)));
        }
    }
    if out.is_empty() {
        return Err(err(codes::PHYSICAL_CHAN_DOES_NOT_EXIST, "Physical channel name is empty.", ""));
    }
    Ok(out)
}

impl StandIn {
    /// An empty NI-DAQmx: no tasks, every output at 0 V.
    pub const fn new() -> Self {
        Self {
            tasks: BTreeMap::new(),
            next_handle: 0,
            held_v: BTreeMap::new(),
            lab_socket: None,
            labs: BTreeMap::new(),
            outputs_link: None,
        }
    }

    /// Reads timed analog inputs from the stand-in rig listening at `socket` ([`crate::lab`]) rather than from the
    /// built-in wiring (`None`: the socket beside the library, if there is one).
    pub fn set_lab_socket(&mut self, socket: Option<std::path::PathBuf>) {
        self.lab_socket = socket;
    }

    fn task(&mut self, handle: u64) -> Result<&mut Task, NiError> {
        self.tasks
            .get_mut(&handle)
            .ok_or_else(|| err(codes::INVALID_TASK, "Task specified is invalid or does not exist.", ""))
    }

    /// `DAQmxCreateTask`: a new task (`name` empty: NI names it `_unnamedTask<N>`); its handle, never 0.
    ///
    /// # Errors
    /// -200089 for a name already taken.
    pub fn create_task(&mut self, name: &str) -> Result<u64, NiError> {
        if !name.is_empty() && self.tasks.values().any(|t| t.name == name) {
            return Err(err(
                codes::DUPLICATE_TASK,
                "Task name specified conflicts with an existing task name.",
                &format!("Task Name: {name}"),
            ));
        }
        let handle = self.next_handle + 1;
        self.next_handle = handle;
        let name = if name.is_empty() { format!("_unnamedTask<{}>", handle - 1) } else { name.to_owned() };
        let task = Task {
            name,
            ai: Vec::new(),
            ao: Vec::new(),
            timing: None,
            trigger: None,
            state: State::Idle,
            waveform: Vec::new(),
            read_pos: 0,
        };
        self.tasks.insert(handle, task);
        Ok(handle)
    }

    /// `DAQmxCreateAIVoltageChan`.
    ///
    /// # Errors
    /// -200088, -200220 (no such device), -200170 (no such input), -200077 (a terminal configuration, range or
    /// unit the USB-6211 does not have).
    pub fn create_ai_voltage_chan(
        &mut self,
        handle: u64,
        physical: &str,
        term_cfg: i32,
        min_v: f64,
        max_v: f64,
        units: i32,
    ) -> Result<(), NiError> {
        let channels = physical_channels(physical, "ai", device::AI_COUNT)?;
        let task = self.task(handle)?;
        if units != device::VAL_VOLTS {
            return Err(err(
                codes::INVALID_ATTRIBUTE_VALUE,
                "Requested value is not a supported value for this property.",
                &format!("Property: DAQmx_AI_Voltage_Units\nRequested Value: {units}"),
            ));
        }
        let needed = min_v.abs().max(max_v.abs());
        let range_v = device::AI_RANGES_V.iter().copied().find(|r| needed <= *r && min_v < max_v);
        let Some(range_v) = range_v else {
            return Err(err(
                codes::INVALID_ATTRIBUTE_VALUE,
                "Requested value is not a supported value for this property.",
                &format!(
                    "Property: DAQmx_AI_Min / DAQmx_AI_Max\nRequested Value: {min_v} to {max_v}\nYou Can \
                    Select: -10 to 10"
                ),
            ));
        };
        for (dev, index, name) in channels {
            let term = match term_cfg {
                // The stand-in resolves Default to RSE (NI chooses per device at run time).
                device::VAL_CFG_DEFAULT => device::VAL_RSE,
                device::VAL_RSE | device::VAL_NRSE => term_cfg,
                // In differential mode ai0-7 pair with ai8-15, which cannot be measured on their own.
                device::VAL_DIFF if index < device::AI_COUNT / 2 => term_cfg,
                other => {
                    return Err(err(
                        codes::INVALID_ATTRIBUTE_VALUE,
                        "Requested value is not a supported value for this property.",
                        &format!(
                            "Property: DAQmx_AI_TermCfg\nRequested Value: {} ({other})\nYou Can Select: \
                            RSE, NRSE{}\nPhysical Channel: {name}",
                            device::terminal_name(other),
                            if index < device::AI_COUNT / 2 { ", Differential" } else { "" }
                        ),
                    ));
                }
            };
            if task.ai.iter().any(|c| c.name == name) {
                return Err(err(
                    codes::INVALID_ATTRIBUTE_VALUE,
                    "Physical channel is repeated in the task.",
                    &format!("Physical Channel: {name}"),
                ));
            }
            task.ai.push(AiChan { name, device: dev.name, index, term_cfg: term, range_v });
        }
        Ok(())
    }

    /// `DAQmxCreateAOVoltageChan`.
    ///
    /// # Errors
    /// As [`create_ai_voltage_chan`](Self::create_ai_voltage_chan), the range beyond +/-10 V.
    pub fn create_ao_voltage_chan(
        &mut self,
        handle: u64,
        physical: &str,
        min_v: f64,
        max_v: f64,
        units: i32,
    ) -> Result<(), NiError> {
        let channels = physical_channels(physical, "ao", device::AO_COUNT)?;
        let task = self.task(handle)?;
        let within = (-device::AO_RANGE_V..=device::AO_RANGE_V).contains(&min_v)
            && (-device::AO_RANGE_V..=device::AO_RANGE_V).contains(&max_v)
            && min_v < max_v;
        if units != device::VAL_VOLTS || !within {
            return Err(err(
                codes::INVALID_ATTRIBUTE_VALUE,
                "Requested value is not a supported value for this property.",
                &format!(
                    "Property: DAQmx_AO_Min / DAQmx_AO_Max\nRequested Value: {min_v} to {max_v}\nYou Can \
                    Select: -10 to 10"
                ),
            ));
        }
        for (dev, index, _) in channels {
            task.ao.push(AoChan { device: dev.name, index, min_v, max_v });
        }
        Ok(())
    }

    /// `DAQmxCfgSampClkTiming` with the onboard clock (`source` empty or `OnboardClock`).
    ///
    /// # Errors
    /// -200077 for another source, edge or mode; -200332 beyond the device's rate.
    pub fn cfg_samp_clk_timing(
        &mut self,
        handle: u64,
        source: &str,
        rate_hz: f64,
        edge: i32,
        mode: i32,
        samps_per_chan: u64,
    ) -> Result<(), NiError> {
        let task = self.task(handle)?;
        let invalid = |what: &str| {
            err(codes::INVALID_ATTRIBUTE_VALUE, "Requested value is not a supported value for this property.", what)
        };
        if !(source.is_empty() || source.eq_ignore_ascii_case("OnboardClock")) {
            return Err(invalid(&format!("Property: DAQmx_SampClk_Src\nRequested Value: {source}")));
        }
        if edge != device::VAL_RISING && edge != device::VAL_FALLING {
            return Err(invalid(&format!("Property: DAQmx_SampClk_ActiveEdge\nRequested Value: {edge}")));
        }
        let continuous = match mode {
            device::VAL_CONT_SAMPS => true,
            device::VAL_FINITE_SAMPS => false,
            other => return Err(invalid(&format!("Property: DAQmx_SampQuant_SampMode\nRequested Value: {other}"))),
        };
        let max_hz = if task.ao.is_empty() {
            device::AI_MAX_AGGREGATE_HZ / task.ai.len().max(1) as f64
        } else {
            device::AO_MAX_RATE_HZ
        };
        if !(rate_hz.is_finite() && rate_hz > 0.0) || rate_hz > max_hz {
            return Err(err(
                codes::SAMP_RATE_TOO_HIGH,
                "Requested sample clock rate is invalid for this device.",
                &format!("Requested Rate: {rate_hz}\nMaximum Rate: {max_hz}"),
            ));
        }
        task.timing = Some(Timing { rate_hz, continuous, samps_per_chan });
        Ok(())
    }

    /// `DAQmxCfgDigEdgeStartTrig`: the task waits, once started, for an edge on `source` (`/Dev1/ao/StartTrigger`,
    /// `/Dev1/ai/StartTrigger`, `/Dev1/PFI0`).
    ///
    /// # Errors
    /// -200220 for an unknown device, -200254 for an unknown terminal, -200077 for an edge that is neither.
    pub fn cfg_dig_edge_start_trig(&mut self, handle: u64, source: &str, edge: i32) -> Result<(), NiError> {
        let bad_term = || {
            err(
                codes::INVALID_TERM,
                "Source terminal to be routed could not be found on the device.",
                &format!("Source Terminal: {source}"),
            )
        };
        let (dev_name, terminal) = source.strip_prefix('/').and_then(|s| s.split_once('/')).ok_or_else(bad_term)?;
        let dev = device_or_error(dev_name)?;
        let known = terminal.eq_ignore_ascii_case("ao/StartTrigger")
            || terminal.eq_ignore_ascii_case("ai/StartTrigger")
            || terminal.strip_prefix("PFI").and_then(|n| n.parse::<u8>().ok()).is_some_and(|n| n < 8);
        if !known {
            return Err(bad_term());
        }
        let task = self.task(handle)?;
        if edge != device::VAL_RISING && edge != device::VAL_FALLING {
            return Err(err(
                codes::INVALID_ATTRIBUTE_VALUE,
                "Requested value is not a supported value for this property.",
                &format!("Property: DAQmx_DigEdge_StartTrig_Edge\nRequested Value: {edge}"),
            ));
        }
        task.trigger = Some(format!("/{}/{}", dev.name, terminal.to_ascii_lowercase()));
        Ok(())
    }

    /// Whether `other` holds a resource `task` needs: an analog output channel, or the device's input timing engine.
    fn conflict(task: &Task, other: &Task) -> bool {
        if other.state == State::Idle {
            return false;
        }
        let ao = task.ao.iter().any(|a| other.ao.iter().any(|b| a.device == b.device && a.index == b.index));
        let ai = task.ai.iter().any(|a| other.ai.iter().any(|b| a.device == b.device));
        ao || ai
    }

    /// `DAQmxStartTask`: reserves the task's resources, then runs it (or arms it when it has a start trigger); a
    /// running output task fires the start trigger of the tasks armed on its `ao/StartTrigger`, which start at
    /// the same instant.
    ///
    /// # Errors
    /// -50103 when another started task holds an output or the input engine; -200462 for a timed output with no
    /// samples written.
    pub fn start(&mut self, handle: u64, now: Instant) -> Result<(), NiError> {
        let task = self.task(handle)?.clone();
        if task.state != State::Idle {
            return Ok(());
        }
        if let Some((_, other)) = self.tasks.iter().find(|(h, other)| **h != handle && Self::conflict(&task, other)) {
            return Err(err(
                codes::RESOURCE_RESERVED,
                "The specified resource is reserved. The operation could not be completed as specified.",
                &format!("Task Name: {}\nReserved by Task: {}", task.name, other.name),
            ));
        }
        if task.timing.is_some() && !task.ao.is_empty() && task.waveform.iter().all(Vec::is_empty) {
            return Err(err(
                codes::OUTPUT_BUFFER_EMPTY,
                "Generation cannot be started because the output buffer is empty.",
                &format!("Task Name: {}", task.name),
            ));
        }
        let state = if task.trigger.is_some() { State::Armed } else { State::Running { t0: now } };
        let t = self.task(handle)?;
        t.state = state;
        t.read_pos = 0;
        if let State::Running { t0 } = state {
            if let Err(e) = self.open_lab(handle) {
                // Not started: a later start tries again, rather than reading the built-in wiring.
                self.task(handle)?.state = State::Idle;
                return Err(e);
            }
            self.fire_triggers(&task, t0)?;
        }
        Ok(())
    }

    fn fire_triggers(&mut self, started: &Task, t0: Instant) -> Result<(), NiError> {
        let mut sources: Vec<String> = started.ao.iter().map(|c| format!("/{}/ao/starttrigger", c.device)).collect();
        sources.extend(started.ai.iter().map(|c| format!("/{}/ai/starttrigger", c.device)));
        let mut fired = Vec::new();
        for (handle, other) in &mut self.tasks {
            if other.state == State::Armed && other.trigger.as_ref().is_some_and(|t| sources.contains(t)) {
                other.state = State::Running { t0 };
                fired.push(*handle);
            }
        }
        for handle in fired {
            if let Err(e) = self.open_lab(handle) {
                self.task(handle)?.state = State::Armed;
                return Err(e);
            }
        }
        Ok(())
    }

    /// `DAQmxStopTask`: the task is idle again and its resources free; a timed output keeps the voltage it was at.
    ///
    /// # Errors
    /// -200088 for a handle that is not a task.
    pub fn stop(&mut self, handle: u64, now: Instant) -> Result<(), NiError> {
        let task = self.task(handle)?.clone();
        if let (State::Running { t0 }, Some(timing)) = (task.state, task.timing) {
            let index = ((now - t0).as_secs_f64() * timing.rate_hz) as usize;
            for (chan, wave) in task.ao.iter().zip(&task.waveform) {
                if !wave.is_empty() {
                    self.held_v.insert((chan.device.clone(), chan.index), wave[index % wave.len()]);
                }
            }
        }
        self.task(handle)?.state = State::Idle;
        // Hanging up ends the rig's acquisition.
        self.labs.remove(&handle);
        Ok(())
    }

    /// `DAQmxClearTask`: stops and forgets the task.
    ///
    /// # Errors
    /// -200088 for a handle that is not a task.
    pub fn clear(&mut self, handle: u64, now: Instant) -> Result<(), NiError> {
        self.stop(handle, now)?;
        self.tasks.remove(&handle);
        Ok(())
    }

    /// The voltage analog output `index` of `device` drives at `t`.
    fn ao_value(&self, device: &str, index: u8, t: Instant, same_clock: Option<(Instant, f64, u64)>) -> f64 {
        for task in self.tasks.values() {
            let (State::Running { t0 }, Some(timing)) = (task.state, task.timing) else { continue };
            let Some(pos) = task.ao.iter().position(|c| c.device == device && c.index == index) else { continue };
            let wave = &task.waveform[pos];
            if wave.is_empty() {
                continue;
            }
            let sample = match same_clock {
                // Started by the same trigger at the same rate: sample n of the input is sample n of the output.
                Some((ai_t0, rate_hz, n)) if ai_t0 == t0 && rate_hz == timing.rate_hz => n,
                _ if t < t0 => break,
                _ => ((t - t0).as_secs_f64() * timing.rate_hz + 1e-9).floor() as u64,
            };
            return wave[(sample % wave.len() as u64) as usize];
        }
        self.held_v.get(&(device.to_owned(), index)).copied().unwrap_or(0.0)
    }

    fn ai_value(&self, chan: &AiChan, ai_t0: Instant, rate_hz: f64, n: u64) -> f64 {
        let v = if chan.index < device::AO_COUNT {
            let t = ai_t0 + std::time::Duration::from_secs_f64(n as f64 / rate_hz);
            self.ao_value(&chan.device, chan.index, t, Some((ai_t0, rate_hz, n)))
        } else {
            let f_hz = 1000.0 * f64::from(chan.index - 1);
            0.5 * (std::f64::consts::TAU * f_hz * n as f64 / rate_hz).sin()
        };
        v.clamp(-chan.range_v, chan.range_v)
    }

    /// One attempt of `DAQmxReadAnalogF64` at `now`: `num` samples per channel (-1: all available) into `out`,
    /// grouped by `fill_mode`.
    ///
    /// # Errors
    /// -200460 without inputs, -200229 for a short array, -200279 when unread samples were overwritten.
    pub fn try_read(
        &mut self,
        handle: u64,
        num: i32,
        fill_mode: u32,
        out: &mut [f64],
        now: Instant,
    ) -> Result<ReadOutcome, NiError> {
        if self.task(handle)?.state == State::Idle {
            // NI starts a task a read finds idle.
            self.start(handle, now)?;
        }
        let task = self.task(handle)?.clone();
        if task.ai.is_empty() {
            return Err(err(
                codes::READ_NO_INPUT_CHANS,
                "Read cannot be performed because this task has no input channels.",
                &format!("Task Name: {}", task.name),
            ));
        }
        let Some(timing) = task.timing else {
            // On-demand: one sample, now.
            return self.fill(&task, handle, Samples::Wiring { t0: now, rate_hz: 1.0 }, 1, fill_mode, out);
        };
        let State::Running { t0 } = task.state else { return Ok(ReadOutcome::Wait(None)) };
        let mut acquired = ((now - t0).as_secs_f64() * timing.rate_hz) as u64;
        if !timing.continuous {
            acquired = acquired.min(timing.samps_per_chan);
        }
        if self.labs.contains_key(&handle) {
            return self.read_from_lab(&task, handle, acquired, num, fill_mode, out, now);
        }
        let buffer = if timing.continuous {
            timing.samps_per_chan.max(device::default_buffer_samples(timing.rate_hz))
        } else {
            timing.samps_per_chan
        };
        let unread = acquired.saturating_sub(task.read_pos);
        if unread > buffer {
            return Err(overwritten(&task.name));
        }
        let want = if num < 0 { unread } else { u64::from(num.unsigned_abs()) };
        if unread < want {
            let ready = t0 + std::time::Duration::from_secs_f64((task.read_pos + want) as f64 / timing.rate_hz);
            return Ok(ReadOutcome::Wait(Some(ready)));
        }
        self.fill(&task, handle, Samples::Wiring { t0, rate_hz: timing.rate_hz }, want, fill_mode, out)
    }

    fn fill(
        &mut self,
        task: &Task,
        handle: u64,
        samples: Samples<'_>,
        want: u64,
        fill_mode: u32,
        out: &mut [f64],
    ) -> Result<ReadOutcome, NiError> {
        let n_ch = task.ai.len();
        let want_usize = usize::try_from(want).unwrap_or(usize::MAX);
        if out.len() < want_usize.saturating_mul(n_ch) {
            return Err(err(
                codes::READ_BUFFER_TOO_SMALL,
                "Buffer is too small to fit read data.",
                &format!(
                    "Required Buffer Size in Samples: {}\nBuffer Size in Samples: {}\n\nTask Name: {}",
                    want_usize * n_ch,
                    out.len(),
                    task.name
                ),
            ));
        }
        for s in 0..want_usize {
            for (c, chan) in task.ai.iter().enumerate() {
                let v = match samples {
                    Samples::Wiring { t0, rate_hz } => self.ai_value(chan, t0, rate_hz, task.read_pos + s as u64),
                    Samples::Rig(values) => values[s * n_ch + c].clamp(-chan.range_v, chan.range_v),
                };
                let at = if fill_mode == device::VAL_GROUP_BY_SCAN_NUMBER { s * n_ch + c } else { c * want_usize + s };
                out[at] = v;
            }
        }
        self.task(handle)?.read_pos += want;
        Ok(ReadOutcome::Done(want_usize))
    }

    /// `DAQmxWriteAnalogF64`: a timed task takes `data` as its (regenerated) waveform; an on-demand task drives
    /// each output to its channel's last sample at once. `data` holds `num` samples per channel, grouped by
    /// `layout`. Returns the samples per channel written.
    ///
    /// # Errors
    /// -200459 without outputs, -200077 for a sample outside a channel's range, a short array or an on-demand
    /// write to a task neither started nor auto-started; as [`start`](Self::start) when auto-starting.
    pub fn write_analog_f64(
        &mut self,
        handle: u64,
        num: usize,
        auto_start: bool,
        layout: u32,
        data: &[f64],
        now: Instant,
    ) -> Result<usize, NiError> {
        let task = self.task(handle)?.clone();
        let n_ch = task.ao.len();
        if n_ch == 0 {
            return Err(err(
                codes::WRITE_NO_OUTPUT_CHANS,
                "Write cannot be performed because this task has no output channels.",
                &format!("Task Name: {}", task.name),
            ));
        }
        let invalid = |detail: String| {
            err(codes::INVALID_ATTRIBUTE_VALUE, "Requested value is not a supported value for this property.", &detail)
        };
        if num == 0 || data.len() < num * n_ch {
            return Err(invalid(format!(
                "Samples per channel: {num}; array length {} for {n_ch} channels",
                data.len()
            )));
        }
        let per_channel: Vec<Vec<f64>> = (0..n_ch)
            .map(|c| {
                (0..num)
                    .map(|s| {
                        if layout == device::VAL_GROUP_BY_SCAN_NUMBER { data[s * n_ch + c] } else { data[c * num + s] }
                    })
                    .collect()
            })
            .collect();
        for (chan, samples) in task.ao.iter().zip(&per_channel) {
            if let Some(v) = samples.iter().find(|v| !(v.is_finite() && **v >= chan.min_v && **v <= chan.max_v)) {
                return Err(invalid(format!(
                    "Attempted writing analog data that is too large or too small.\nValue: {v}\nChannel: \
                    {}/ao{}\nRange: {} to {}",
                    chan.device, chan.index, chan.min_v, chan.max_v
                )));
            }
        }
        if task.timing.is_some() {
            self.task(handle)?.waveform = per_channel;
            if auto_start {
                self.start(handle, now)?;
            }
            return Ok(num);
        }
        if task.state == State::Idle {
            if !auto_start {
                return Err(invalid(format!(
                    "On-demand write to a task not started (autoStart false)\n\nTask Name: {}",
                    task.name
                )));
            }
            if let Some((_, other)) = self.tasks.iter().find(|(h, other)| **h != handle && Self::conflict(&task, other))
            {
                return Err(err(
                    codes::RESOURCE_RESERVED,
                    "The specified resource is reserved. The operation could not be completed as specified.",
                    &format!("Task Name: {}\nReserved by Task: {}", task.name, other.name),
                ));
            }
        }
        for (chan, samples) in task.ao.iter().zip(&per_channel) {
            if let Some(last) = samples.last() {
                self.held_v.insert((chan.device.clone(), chan.index), *last);
            }
        }
        if let Some(device) = task.ao.first().map(|c| c.device.clone()) {
            self.forward_outputs(&device)?;
        }
        Ok(num)
    }

    /// `DAQmxGetAITermCfg`: the terminal configuration an input channel (by its physical name) was created with,
    /// as the device resolved it.
    ///
    /// # Errors
    /// -200088; -200170 when the task has no such channel.
    pub fn ai_term_cfg(&mut self, handle: u64, channel: &str) -> Result<i32, NiError> {
        let task = self.task(handle)?;
        task.ai.iter().find(|c| c.name.eq_ignore_ascii_case(channel.trim())).map(|c| c.term_cfg).ok_or_else(|| {
            err(
                codes::PHYSICAL_CHAN_DOES_NOT_EXIST,
                "Specified channel is not in the task.",
                &format!("Channel Name: {channel}"),
            )
        })
    }

    /// How many analog outputs the task has (how long a write's array is per sample).
    ///
    /// # Errors
    /// -200088 for a handle that is not a task.
    pub fn ao_channel_count(&mut self, handle: u64) -> Result<usize, NiError> {
        Ok(self.task(handle)?.ao.len())
    }

    /// The voltage an analog output holds now (what a meter on it would read; for tests).
    pub fn output_v(&self, device: &str, index: u8, now: Instant) -> f64 {
        self.ao_value(device, index, now, None)
    }
}

/// `DAQmxGetDevProductType`.
///
/// # Errors
/// -200220 for an unknown device.
pub fn product_type(device_name: &str) -> Result<String, NiError> {
    Ok(device_or_error(device_name)?.product_type.to_owned())
}

/// `DAQmxGetDevSerialNum`.
///
/// # Errors
/// -200220 for an unknown device.
pub fn serial_number(device_name: &str) -> Result<u32, NiError> {
    Ok(device_or_error(device_name)?.serial)
}

/// `DAQmxGetSysDevNames`: the devices' names, comma-separated as NI lists them.
pub fn sys_dev_names() -> String {
    device::devices().into_iter().map(|d| d.name).collect::<Vec<_>>().join(", ")
}
