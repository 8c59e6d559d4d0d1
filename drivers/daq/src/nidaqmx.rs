//! A [`Daq`] backend for National Instruments DAQs (the paper's USB-6211), through NI's NI-DAQmx C library
//! loaded at run time: nothing of NI's is needed to build or test; opening fails with
//! [`DaqError::Unavailable`] when the library is not installed.
//!
//! Only the functions a continuous analog-input acquisition needs are used, declared from NI's documented C API
//! (`NIDAQmx.h`): `DAQmxCreateTask`, `DAQmxCreateAIVoltageChan`, `DAQmxCfgSampClkTiming`, `DAQmxStartTask`,
//! `DAQmxReadAnalogF64`, `DAQmxStopTask`, `DAQmxClearTask`, `DAQmxGetExtendedErrorInfo`, and `DAQmxGetSysDevNames` to
//! list the devices.
//!
//! This is the crate's only module with `unsafe` code (foreign calls); each block says why it is sound.
//! Limits: NI-DAQmx reports neither lost packets nor a sample clock per block, so a block's integrity carries only
//! clipping (a sample at or beyond the range) and an overrun ends the acquisition ([`DaqError::Overrun`]); a
//! removed device shows up as [`DaqError::Device`] with NI's code, not as [`DaqError::Disconnected`].
#![allow(unsafe_code)]

use std::ffi::{CString, OsStr, c_char, c_void};
use std::ptr;

use libloading::Library;
use metaplate_core::daq::{BlockIntegrity, Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};

/// The library's file name on this platform.
#[cfg(windows)]
pub const LIBRARY_NAME: &str = "nicaiu.dll";
/// The library's file name on this platform.
#[cfg(not(windows))]
pub const LIBRARY_NAME: &str = "libnidaqmx.so";

type TaskHandle = *mut c_void;
// NI declares these `__stdcall` on Windows and plain C elsewhere: `extern "system"` is exactly that.
type CreateTask = unsafe extern "system" fn(*const c_char, *mut TaskHandle) -> i32;
type CreateAiVoltageChan =
    unsafe extern "system" fn(TaskHandle, *const c_char, *const c_char, i32, f64, f64, i32, *const c_char) -> i32;
type CfgSampClkTiming = unsafe extern "system" fn(TaskHandle, *const c_char, f64, i32, i32, u64) -> i32;
type TaskCall = unsafe extern "system" fn(TaskHandle) -> i32;
type ReadAnalogF64 = unsafe extern "system" fn(TaskHandle, i32, f64, u32, *mut f64, u32, *mut i32, *mut u32) -> i32;
type GetExtendedErrorInfo = unsafe extern "system" fn(*mut c_char, u32) -> i32;

// Constants from NIDAQmx.h.
const VAL_CFG_DEFAULT: i32 = -1;
const VAL_VOLTS: i32 = 10348;
const VAL_RISING: i32 = 10280;
const VAL_CONT_SAMPS: i32 = 10123;
const VAL_GROUP_BY_SCAN_NUMBER: u32 = 1;
const ERROR_SAMPLES_NO_LONGER_AVAILABLE: i32 = -200279;
const ERROR_SAMPLES_NOT_YET_AVAILABLE: i32 = -200284;

/// The library's entry points, copied out of it (valid while `NiDaqmx::_library` is loaded).
#[derive(Clone, Copy)]
struct Api {
    create_task: CreateTask,
    create_ai_voltage_chan: CreateAiVoltageChan,
    cfg_samp_clk_timing: CfgSampClkTiming,
    start_task: TaskCall,
    read_analog_f64: ReadAnalogF64,
    stop_task: TaskCall,
    clear_task: TaskCall,
    get_extended_error_info: GetExtendedErrorInfo,
}

/// An NI-DAQmx device, by its NI device name (`"Dev1"`).
pub struct NiDaqmx {
    api: Api,
    device: String,
    identity: DaqIdentity,
    config: Option<DaqConfig>,
    task: Option<TaskHandle>,
    running: bool,
    next_index: u64,
    /// How long one read waits for a block, s.
    read_timeout_s: f64,
    // Last field: dropped after `Drop::drop` has cleared the task with `api`.
    _library: Library,
}

// SAFETY: the only field that is not `Send` is the task handle, an opaque pointer owned by NI-DAQmx; NI documents
// NI-DAQmx as multithread-safe (a task may be used from any thread), and `NiDaqmx` is used by one thread at a time
// (`&mut self`). `Send` is what lets the rig hand the DAQ to a recipe's thread.
unsafe impl Send for NiDaqmx {}

impl std::fmt::Debug for NiDaqmx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NiDaqmx").field("device", &self.device).field("running", &self.running).finish_non_exhaustive()
    }
}

fn unavailable(library: &OsStr, e: impl std::fmt::Display) -> DaqError {
    DaqError::Unavailable {
        detail: format!("cannot load the NI-DAQmx library {} (is NI-DAQmx installed?): {e}", library.to_string_lossy()),
    }
}

fn c_string(text: &str) -> Result<CString, DaqError> {
    CString::new(text).map_err(|_| DaqError::Config { detail: format!("{text:?} contains a NUL byte") })
}

/// The NI-DAQmx devices of this computer (their NI names, `Dev1`, as `daq.device` takes them), by
/// `DAQmxGetSysDevNames`; `Ok(None)` when the library is not installed (no NI device can be driven: not an error).
///
/// # Errors
/// [`DaqError::Device`] with NI's status when the library loads but the call fails; [`DaqError::Unavailable`]
/// when it lacks the function.
pub fn device_names() -> Result<Option<Vec<String>>, DaqError> {
    type GetSysDevNames = unsafe extern "system" fn(*mut c_char, u32) -> i32;
    let library = OsStr::new(LIBRARY_NAME);
    // SAFETY: as in `open_library`: a vendor library meant to be loaded by applications.
    let Ok(lib) = (unsafe { Library::new(library) }) else { return Ok(None) };
    // SAFETY: the signature NIDAQmx.h declares (`int32 DAQmxGetSysDevNames(char *data, uInt32 bufferSize)`); the
    // pointer is used only while `lib` is loaded, within this function.
    let get: GetSysDevNames = unsafe { *lib.get(b"DAQmxGetSysDevNames\0").map_err(|e| unavailable(library, e))? };
    // Called with no buffer, it returns the size the names need (a positive number), or an error (negative).
    // SAFETY: a null buffer of size 0 is the documented way to ask for the size.
    let size = unsafe { get(ptr::null_mut(), 0) };
    if size < 0 {
        return Err(DaqError::Device { code: i64::from(size), detail: "DAQmxGetSysDevNames (asking the size)".into() });
    }
    let mut buffer = vec![0 as c_char; usize::try_from(size).unwrap_or(0).max(1)];
    let capacity = u32::try_from(buffer.len()).unwrap_or(u32::MAX);
    // SAFETY: `buffer` holds `capacity` writable chars; NI writes at most that many, NUL-terminated.
    let status = unsafe { get(buffer.as_mut_ptr(), capacity) };
    if status < 0 {
        return Err(DaqError::Device { code: i64::from(status), detail: "DAQmxGetSysDevNames".into() });
    }
    let bytes: Vec<u8> = buffer.iter().take_while(|c| **c != 0).map(|c| *c as u8).collect();
    let names = String::from_utf8_lossy(&bytes);
    Ok(Some(names.split(',').map(str::trim).filter(|n| !n.is_empty()).map(str::to_owned).collect()))
}

impl NiDaqmx {
    /// Loads NI-DAQmx ([`LIBRARY_NAME`] from the system's library path) for device `device` (its NI name, e.g.
    /// `"Dev1"`; also the identity's serial, which reopens find it by). `read_timeout_s` bounds each block read.
    ///
    /// # Errors
    /// [`DaqError::Unavailable`] if the library is not installed or lacks a function.
    pub fn open(device: &str, read_timeout_s: f64) -> Result<Self, DaqError> {
        Self::open_library(OsStr::new(LIBRARY_NAME), device, read_timeout_s)
    }

    /// As [`open`](Self::open), loading the library from `library` (a file name or path).
    ///
    /// # Errors
    /// As [`open`](Self::open).
    pub fn open_library(library: &OsStr, device: &str, read_timeout_s: f64) -> Result<Self, DaqError> {
        // SAFETY: loading runs the library's initialisers; NI-DAQmx is a vendor library meant to be loaded by
        // applications, and nothing else in this process depends on what its initialisers do.
        let lib = unsafe { Library::new(library) }.map_err(|e| unavailable(library, e))?;
        // SAFETY: each symbol is given the signature NIDAQmx.h declares for it; the copied function pointers are
        // used only while `lib` stays loaded (it is stored in the same struct, dropped last).
        let api = unsafe {
            Api {
                create_task: *lib.get(b"DAQmxCreateTask\0").map_err(|e| unavailable(library, e))?,
                create_ai_voltage_chan: *lib.get(b"DAQmxCreateAIVoltageChan\0").map_err(|e| unavailable(library, e))?,
                cfg_samp_clk_timing: *lib.get(b"DAQmxCfgSampClkTiming\0").map_err(|e| unavailable(library, e))?,
                start_task: *lib.get(b"DAQmxStartTask\0").map_err(|e| unavailable(library, e))?,
                read_analog_f64: *lib.get(b"DAQmxReadAnalogF64\0").map_err(|e| unavailable(library, e))?,
                stop_task: *lib.get(b"DAQmxStopTask\0").map_err(|e| unavailable(library, e))?,
                clear_task: *lib.get(b"DAQmxClearTask\0").map_err(|e| unavailable(library, e))?,
                get_extended_error_info: *lib
                    .get(b"DAQmxGetExtendedErrorInfo\0")
                    .map_err(|e| unavailable(library, e))?,
            }
        };
        let identity = DaqIdentity {
            vendor: "National Instruments".into(),
            model: "NI-DAQmx device".into(),
            serial: device.into(),
            firmware: String::new(),
        };
        Ok(Self {
            api,
            device: device.into(),
            identity,
            config: None,
            task: None,
            running: false,
            next_index: 0,
            read_timeout_s,
            _library: lib,
        })
    }

    /// Turns an NI status into a result: negative is an error (with NI's extended explanation), 0 or positive
    /// (a warning) is success.
    fn check(&self, status: i32, call: &str) -> Result<(), DaqError> {
        if status >= 0 {
            return Ok(());
        }
        let mut text = vec![0 as c_char; 2048];
        // SAFETY: the buffer is writable for the length passed; NI writes a NUL-terminated string into it.
        unsafe { (self.api.get_extended_error_info)(text.as_mut_ptr(), text.len() as u32) };
        let bytes: Vec<u8> = text.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
        let detail = format!("{call}: {}", String::from_utf8_lossy(&bytes));
        Err(match status {
            ERROR_SAMPLES_NO_LONGER_AVAILABLE => DaqError::Overrun { detail },
            ERROR_SAMPLES_NOT_YET_AVAILABLE => DaqError::Timeout { what: detail, attempts: 1 },
            code => DaqError::Device { code: i64::from(code), detail },
        })
    }

    fn clear(&mut self) {
        if let Some(task) = self.task.take() {
            // SAFETY: `task` came from DAQmxCreateTask and is cleared exactly once (taken out of `self.task`).
            unsafe { (self.api.clear_task)(task) };
        }
        self.running = false;
    }

    /// Creates the task for `config`: one voltage channel per input, the onboard sample clock, continuous.
    fn create_task(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if config.channels.is_empty() || config.block_len_samples == 0 {
            return Err(DaqError::Config {
                detail: "need at least one channel and a block of at least 1 sample".into(),
            });
        }
        if !(config.sample_rate_hz.is_finite() && config.sample_rate_hz > 0.0) {
            return Err(DaqError::Config { detail: format!("sample rate {} Hz is invalid", config.sample_rate_hz) });
        }
        let empty = c_string("")?;
        let mut task: TaskHandle = ptr::null_mut();
        // SAFETY: `empty` is a valid C string (an unnamed task); `task` is a valid place for the handle.
        let status = unsafe { (self.api.create_task)(empty.as_ptr(), &mut task) };
        self.check(status, "DAQmxCreateTask")?;
        self.task = Some(task);
        for ch in &config.channels {
            if !(ch.range_v.is_finite() && ch.range_v > 0.0) {
                return Err(DaqError::Config { detail: format!("range {} V is invalid", ch.range_v) });
            }
            let physical = c_string(&format!("{}/ai{}", self.device, ch.input))?;
            // SAFETY: `task` is live; the strings are valid C strings that outlive the call.
            let status = unsafe {
                (self.api.create_ai_voltage_chan)(
                    task,
                    physical.as_ptr(),
                    empty.as_ptr(),
                    VAL_CFG_DEFAULT,
                    -ch.range_v,
                    ch.range_v,
                    VAL_VOLTS,
                    ptr::null(),
                )
            };
            self.check(status, "DAQmxCreateAIVoltageChan")?;
        }
        // Buffer hint: ten blocks per channel.
        let buffer = u64::from(config.block_len_samples) * 10;
        // SAFETY: `task` is live; an empty source string selects the onboard clock.
        let status = unsafe {
            (self.api.cfg_samp_clk_timing)(
                task,
                empty.as_ptr(),
                config.sample_rate_hz,
                VAL_RISING,
                VAL_CONT_SAMPS,
                buffer,
            )
        };
        self.check(status, "DAQmxCfgSampClkTiming")
    }

    fn live_task(&self) -> Result<TaskHandle, DaqError> {
        self.task.ok_or_else(|| DaqError::Protocol { detail: "not configured".into() })
    }
}

impl Drop for NiDaqmx {
    fn drop(&mut self) {
        self.clear();
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
        let result = self.create_task(config);
        if result.is_err() {
            self.clear();
        } else {
            self.config = Some(config.clone());
        }
        result
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: "an acquisition is already running".into() });
        }
        let task = self.live_task()?;
        // SAFETY: `task` is a live handle created by `create_task`.
        let status = unsafe { (self.api.start_task)(task) };
        self.check(status, "DAQmxStartTask")?;
        self.running = true;
        self.next_index = 0;
        Ok(())
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        let (Some(config), true) = (self.config.as_ref(), self.running) else {
            return Err(DaqError::Protocol { detail: "read_block while no acquisition runs".into() });
        };
        let task = self.live_task()?;
        let n_ch = config.channels.len();
        let block = config.block_len_samples as usize;
        let mut data = vec![0.0f64; block * n_ch];
        let capacity = u32::try_from(data.len())
            .map_err(|_| DaqError::Config { detail: "block too large for one NI-DAQmx read".into() })?;
        let per_channel = i32::try_from(block)
            .map_err(|_| DaqError::Config { detail: "block too large for one NI-DAQmx read".into() })?;
        let mut read: i32 = 0;
        // SAFETY: `data` holds `capacity` f64 values and outlives the call; `read` is a valid place; the reserved
        // argument is documented as NULL.
        let status = unsafe {
            (self.api.read_analog_f64)(
                task,
                per_channel,
                self.read_timeout_s,
                VAL_GROUP_BY_SCAN_NUMBER,
                data.as_mut_ptr(),
                capacity,
                &mut read,
                ptr::null_mut(),
            )
        };
        self.check(status, "DAQmxReadAnalogF64")?;
        let read = usize::try_from(read).unwrap_or(0).min(block);
        if read == 0 {
            return Err(DaqError::Timeout { what: "samples from NI-DAQmx".into(), attempts: 1 });
        }
        // Interleaved by scan: sample i of channel c is at i * n_ch + c.
        let volts: Vec<Vec<f64>> =
            (0..n_ch).map(|c| data[..read * n_ch].iter().skip(c).step_by(n_ch).copied().collect()).collect();
        if volts.iter().flatten().any(|v| !v.is_finite()) {
            return Err(DaqError::Device { code: 0, detail: "NI-DAQmx returned a non-finite sample".into() });
        }
        let clipped = config.channels.iter().zip(&volts).any(|(ch, v)| v.iter().any(|x| x.abs() >= ch.range_v));
        let first_sample_index = self.next_index;
        self.next_index += read as u64;
        Ok(DaqBlock { first_sample_index, volts, integrity: BlockIntegrity { clipped, ..BlockIntegrity::default() } })
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        if let (Some(task), true) = (self.task, self.running) {
            // SAFETY: `task` is a live handle created by `create_task`.
            let status = unsafe { (self.api.stop_task)(task) };
            self.running = false;
            self.check(status, "DAQmxStopTask")?;
        }
        Ok(())
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.clear();
        match self.config.clone() {
            Some(config) => self.configure(&config),
            None => Ok(()),
        }
    }
}
