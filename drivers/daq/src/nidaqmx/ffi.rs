//! The foreign calls into NI-DAQmx: the library loaded at run time (libloading), its entry points with the
//! signatures `NIDAQmx.h` declares, and [`Task`], a task handle cleared when dropped. The crate's only unsafe code:
//! each block says why it is sound. Everything here returns [`NiFailure`] (NI's status and extended error text);
//! the callers turn it into their capability's error.
#![allow(unsafe_code)]

use std::ffi::{CString, OsStr, OsString, c_char, c_void};
use std::ptr;
use std::sync::Arc;

use libloading::Library;

use super::status::NiFailure;

type TaskHandle = *mut c_void;
// NI declares these `__stdcall` on Windows and plain C elsewhere: `extern "system"` is exactly that.
type CreateTask = unsafe extern "system" fn(*const c_char, *mut TaskHandle) -> i32;
type CreateAiVoltageChan =
    unsafe extern "system" fn(TaskHandle, *const c_char, *const c_char, i32, f64, f64, i32, *const c_char) -> i32;
type CreateAoVoltageChan =
    unsafe extern "system" fn(TaskHandle, *const c_char, *const c_char, f64, f64, i32, *const c_char) -> i32;
type CfgSampClkTiming = unsafe extern "system" fn(TaskHandle, *const c_char, f64, i32, i32, u64) -> i32;
type CfgDigEdgeStartTrig = unsafe extern "system" fn(TaskHandle, *const c_char, i32) -> i32;
type TaskCall = unsafe extern "system" fn(TaskHandle) -> i32;
type ReadAnalogF64 = unsafe extern "system" fn(TaskHandle, i32, f64, u32, *mut f64, u32, *mut i32, *mut u32) -> i32;
type WriteAnalogF64 = unsafe extern "system" fn(TaskHandle, i32, u32, f64, u32, *const f64, *mut i32, *mut u32) -> i32;
type GetAiTermCfg = unsafe extern "system" fn(TaskHandle, *const c_char, *mut i32) -> i32;
type GetDevString = unsafe extern "system" fn(*const c_char, *mut c_char, u32) -> i32;
type GetDevU32 = unsafe extern "system" fn(*const c_char, *mut u32) -> i32;
type GetString = unsafe extern "system" fn(*mut c_char, u32) -> i32;

// Constants from NIDAQmx.h.
const VAL_VOLTS: i32 = 10348;
const VAL_RISING: i32 = 10280;
const VAL_CONT_SAMPS: i32 = 10123;
const VAL_GROUP_BY_CHANNEL: u32 = 0;
const VAL_GROUP_BY_SCAN_NUMBER: u32 = 1;

/// The library's entry points, copied out of it (valid while `NiLibrary::_library` is loaded).
struct Api {
    create_task: CreateTask,
    create_ai_voltage_chan: CreateAiVoltageChan,
    create_ao_voltage_chan: CreateAoVoltageChan,
    cfg_samp_clk_timing: CfgSampClkTiming,
    cfg_dig_edge_start_trig: CfgDigEdgeStartTrig,
    start_task: TaskCall,
    stop_task: TaskCall,
    clear_task: TaskCall,
    read_analog_f64: ReadAnalogF64,
    write_analog_f64: WriteAnalogF64,
    get_ai_term_cfg: GetAiTermCfg,
    get_dev_product_type: GetDevString,
    get_dev_serial_num: GetDevU32,
    get_sys_dev_names: GetString,
    get_extended_error_info: GetString,
}

/// NI-DAQmx, loaded: shared (through `Arc`) by the tasks made from it, which it outlives.
pub(crate) struct NiLibrary {
    api: Api,
    path: OsString,
    // Last field: dropped after the tasks holding this `Arc` are gone.
    _library: Library,
}

impl std::fmt::Debug for NiLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NiLibrary").field("path", &self.path).finish_non_exhaustive()
    }
}

fn c_string(text: &str) -> Result<CString, NiFailure> {
    CString::new(text).map_err(|_| NiFailure::local(format!("{text:?} contains a NUL byte")))
}

/// What a library that cannot be loaded (or lacks a function) says: `Err(text)`.
pub(crate) type LoadError = String;

impl NiLibrary {
    /// Loads the library at `path` (a file name searched on the system's library path, or a path).
    ///
    /// # Errors
    /// The loader's message when it is not there or lacks one of the functions.
    pub(crate) fn load(path: &OsStr) -> Result<Arc<Self>, LoadError> {
        // SAFETY: loading runs the library's initialisers; NI-DAQmx (or its stand-in) is a library meant to be
        // loaded by applications, and nothing else in this process depends on what its initialisers do.
        let lib = unsafe { Library::new(path) }.map_err(|e| e.to_string())?;
        // SAFETY: each symbol is given the signature NIDAQmx.h declares for it; the copied function pointers are
        // used only while `lib` stays loaded (it is stored in the same struct, dropped last, and every task holds
        // an `Arc` of that struct).
        let api = unsafe {
            Api {
                create_task: *lib.get(b"DAQmxCreateTask\0").map_err(|e| e.to_string())?,
                create_ai_voltage_chan: *lib.get(b"DAQmxCreateAIVoltageChan\0").map_err(|e| e.to_string())?,
                create_ao_voltage_chan: *lib.get(b"DAQmxCreateAOVoltageChan\0").map_err(|e| e.to_string())?,
                cfg_samp_clk_timing: *lib.get(b"DAQmxCfgSampClkTiming\0").map_err(|e| e.to_string())?,
                cfg_dig_edge_start_trig: *lib.get(b"DAQmxCfgDigEdgeStartTrig\0").map_err(|e| e.to_string())?,
                start_task: *lib.get(b"DAQmxStartTask\0").map_err(|e| e.to_string())?,
                stop_task: *lib.get(b"DAQmxStopTask\0").map_err(|e| e.to_string())?,
                clear_task: *lib.get(b"DAQmxClearTask\0").map_err(|e| e.to_string())?,
                read_analog_f64: *lib.get(b"DAQmxReadAnalogF64\0").map_err(|e| e.to_string())?,
                write_analog_f64: *lib.get(b"DAQmxWriteAnalogF64\0").map_err(|e| e.to_string())?,
                get_ai_term_cfg: *lib.get(b"DAQmxGetAITermCfg\0").map_err(|e| e.to_string())?,
                get_dev_product_type: *lib.get(b"DAQmxGetDevProductType\0").map_err(|e| e.to_string())?,
                get_dev_serial_num: *lib.get(b"DAQmxGetDevSerialNum\0").map_err(|e| e.to_string())?,
                get_sys_dev_names: *lib.get(b"DAQmxGetSysDevNames\0").map_err(|e| e.to_string())?,
                get_extended_error_info: *lib.get(b"DAQmxGetExtendedErrorInfo\0").map_err(|e| e.to_string())?,
            }
        };
        Ok(Arc::new(Self { api, path: path.to_owned(), _library: lib }))
    }

    /// Turns NI's status into a result: negative is an error, with NI's extended explanation of this thread's
    /// last error; 0 or positive (a warning) is success.
    fn check(&self, status: i32, call: &'static str) -> Result<(), NiFailure> {
        if status >= 0 {
            return Ok(());
        }
        // Asked with no buffer, NI returns the size the text needs.
        // SAFETY: a null buffer of size 0 is the documented way to ask for the size.
        let needed = unsafe { (self.api.get_extended_error_info)(ptr::null_mut(), 0) };
        let text = self.read_string(usize::try_from(needed).unwrap_or(0).clamp(1, 1 << 16), |buf, len| {
            // SAFETY: `buf` is writable for `len` chars; NI writes at most that many, NUL-terminated.
            unsafe { (self.api.get_extended_error_info)(buf, len) }
        });
        Err(NiFailure { code: status, call, text })
    }

    /// Fills a buffer of `len` chars through `call` and returns its text up to the first NUL.
    fn read_string(&self, len: usize, call: impl FnOnce(*mut c_char, u32) -> i32) -> String {
        let mut buffer = vec![0 as c_char; len];
        let capacity = u32::try_from(buffer.len()).unwrap_or(u32::MAX);
        if call(buffer.as_mut_ptr(), capacity) < 0 {
            return String::new();
        }
        let bytes: Vec<u8> = buffer.iter().take_while(|c| **c != 0).map(|c| *c as u8).collect();
        String::from_utf8_lossy(&bytes).into_owned()
    }

    /// A string property of NI: asks its size, then reads it.
    fn string_property(&self, call: &'static str, get: impl Fn(*mut c_char, u32) -> i32) -> Result<String, NiFailure> {
        let size = get(ptr::null_mut(), 0);
        self.check(size.min(0), call)?;
        let len = usize::try_from(size).unwrap_or(0).max(1);
        let mut status = 0;
        let text = self.read_string(len, |buf, cap| {
            status = get(buf, cap);
            status
        });
        self.check(status, call)?;
        Ok(text)
    }

    /// `DAQmxGetDevProductType`: the device's product (`USB-6211`).
    pub(crate) fn product_type(&self, device: &str) -> Result<String, NiFailure> {
        let device = c_string(device)?;
        self.string_property("DAQmxGetDevProductType", |buf, len| {
            // SAFETY: `device` is a C string; `buf` is null with `len` 0, or writable for `len` chars.
            unsafe { (self.api.get_dev_product_type)(device.as_ptr(), buf, len) }
        })
    }

    /// `DAQmxGetDevSerialNum`: the device's serial number.
    pub(crate) fn serial_number(&self, device: &str) -> Result<u32, NiFailure> {
        let device = c_string(device)?;
        let mut serial = 0u32;
        // SAFETY: `device` is a C string; `serial` is a valid place for the number.
        let status = unsafe { (self.api.get_dev_serial_num)(device.as_ptr(), &mut serial) };
        self.check(status, "DAQmxGetDevSerialNum")?;
        Ok(serial)
    }

    /// `DAQmxGetSysDevNames`: the devices' names, as NI lists them (comma-separated).
    pub(crate) fn device_names(&self) -> Result<String, NiFailure> {
        self.string_property("DAQmxGetSysDevNames", |buf, len| {
            // SAFETY: `buf` is null with `len` 0, or writable for `len` chars.
            unsafe { (self.api.get_sys_dev_names)(buf, len) }
        })
    }

    /// `DAQmxCreateTask`: a new unnamed task.
    pub(crate) fn create_task(self: &Arc<Self>) -> Result<Task, NiFailure> {
        let empty = c_string("")?;
        let mut handle: TaskHandle = ptr::null_mut();
        // SAFETY: `empty` is a valid C string (an unnamed task); `handle` is a valid place for the handle.
        let status = unsafe { (self.api.create_task)(empty.as_ptr(), &mut handle) };
        self.check(status, "DAQmxCreateTask")?;
        Ok(Task { lib: Arc::clone(self), handle })
    }
}

/// An NI-DAQmx task, cleared (`DAQmxClearTask`) when dropped.
pub(crate) struct Task {
    lib: Arc<NiLibrary>,
    handle: TaskHandle,
}

// SAFETY: the handle is an opaque token owned by NI-DAQmx, which NI documents as multithread-safe (a task may be
// used from any thread); a `Task` is used by one thread at a time (`&mut` or owned). `Send` lets the rig hand the
// DAQ to a recipe's thread.
unsafe impl Send for Task {}

impl Drop for Task {
    fn drop(&mut self) {
        // SAFETY: `handle` came from DAQmxCreateTask and is cleared exactly once, here.
        unsafe { (self.lib.api.clear_task)(self.handle) };
    }
}

impl Task {
    /// `DAQmxCreateAIVoltageChan`: input `physical` (`Dev1/ai0`), `terminal` (NI's value), `-range_v..range_v`.
    pub(crate) fn add_ai_voltage(&self, physical: &str, terminal: i32, range_v: f64) -> Result<(), NiFailure> {
        let physical = c_string(physical)?;
        let empty = c_string("")?;
        // SAFETY: the task is live; the strings are valid C strings that outlive the call; the custom scale may be
        // NULL (documented).
        let status = unsafe {
            (self.lib.api.create_ai_voltage_chan)(
                self.handle,
                physical.as_ptr(),
                empty.as_ptr(),
                terminal,
                -range_v,
                range_v,
                VAL_VOLTS,
                ptr::null(),
            )
        };
        self.lib.check(status, "DAQmxCreateAIVoltageChan")
    }

    /// `DAQmxCreateAOVoltageChan`: output `physical` (`Dev1/ao0`), `-range_v..range_v`.
    pub(crate) fn add_ao_voltage(&self, physical: &str, range_v: f64) -> Result<(), NiFailure> {
        let physical = c_string(physical)?;
        let empty = c_string("")?;
        // SAFETY: as in `add_ai_voltage`.
        let status = unsafe {
            (self.lib.api.create_ao_voltage_chan)(
                self.handle,
                physical.as_ptr(),
                empty.as_ptr(),
                -range_v,
                range_v,
                VAL_VOLTS,
                ptr::null(),
            )
        };
        self.lib.check(status, "DAQmxCreateAOVoltageChan")
    }

    /// `DAQmxGetAITermCfg`: the terminal configuration of input channel `physical`, as the device took it.
    pub(crate) fn ai_terminal(&self, physical: &str) -> Result<i32, NiFailure> {
        let physical = c_string(physical)?;
        let mut value = 0i32;
        // SAFETY: the task is live; `physical` a C string; `value` a valid place.
        let status = unsafe { (self.lib.api.get_ai_term_cfg)(self.handle, physical.as_ptr(), &mut value) };
        self.lib.check(status, "DAQmxGetAITermCfg")?;
        Ok(value)
    }

    /// `DAQmxCfgSampClkTiming`: the onboard clock at `rate_hz`, continuous, a buffer of `buffer_samples` per
    /// channel.
    pub(crate) fn sample_clock(&self, rate_hz: f64, buffer_samples: u64) -> Result<(), NiFailure> {
        let onboard = c_string("")?;
        // SAFETY: the task is live; an empty source string selects the onboard clock.
        let status = unsafe {
            (self.lib.api.cfg_samp_clk_timing)(
                self.handle,
                onboard.as_ptr(),
                rate_hz,
                VAL_RISING,
                VAL_CONT_SAMPS,
                buffer_samples,
            )
        };
        self.lib.check(status, "DAQmxCfgSampClkTiming")
    }

    /// `DAQmxCfgDigEdgeStartTrig`: the task starts on a rising edge of `source` (`/Dev1/ao/StartTrigger`).
    pub(crate) fn start_trigger(&self, source: &str) -> Result<(), NiFailure> {
        let source = c_string(source)?;
        // SAFETY: the task is live; `source` a C string that outlives the call.
        let status = unsafe { (self.lib.api.cfg_dig_edge_start_trig)(self.handle, source.as_ptr(), VAL_RISING) };
        self.lib.check(status, "DAQmxCfgDigEdgeStartTrig")
    }

    /// `DAQmxStartTask`.
    pub(crate) fn start(&self) -> Result<(), NiFailure> {
        // SAFETY: the task is live.
        let status = unsafe { (self.lib.api.start_task)(self.handle) };
        self.lib.check(status, "DAQmxStartTask")
    }

    /// `DAQmxStopTask`.
    pub(crate) fn stop(&self) -> Result<(), NiFailure> {
        // SAFETY: the task is live.
        let status = unsafe { (self.lib.api.stop_task)(self.handle) };
        self.lib.check(status, "DAQmxStopTask")
    }

    /// `DAQmxReadAnalogF64`: `per_channel` samples of each of `channels` inputs, interleaved by scan (sample `i` of
    /// channel `c` at `i * channels + c`), waiting at most `timeout_s`. Returns the samples and how many per
    /// channel were read.
    pub(crate) fn read(
        &self,
        per_channel: usize,
        channels: usize,
        timeout_s: f64,
    ) -> Result<(Vec<f64>, usize), NiFailure> {
        let mut data = vec![0.0f64; per_channel * channels];
        let too_large = || NiFailure::local("block too large for one NI-DAQmx read".into());
        let capacity = u32::try_from(data.len()).map_err(|_| too_large())?;
        let num = i32::try_from(per_channel).map_err(|_| too_large())?;
        let mut read: i32 = 0;
        // SAFETY: the task is live; `data` holds `capacity` f64 values and outlives the call; `read` is a valid
        // place; the reserved argument is documented as NULL.
        let status = unsafe {
            (self.lib.api.read_analog_f64)(
                self.handle,
                num,
                timeout_s,
                VAL_GROUP_BY_SCAN_NUMBER,
                data.as_mut_ptr(),
                capacity,
                &mut read,
                ptr::null_mut(),
            )
        };
        self.lib.check(status, "DAQmxReadAnalogF64")?;
        Ok((data, usize::try_from(read).unwrap_or(0).min(per_channel)))
    }

    /// `DAQmxWriteAnalogF64`: `per_channel` samples of each output, grouped by channel (`samples[c * per_channel
    /// + i]`), without starting the task.
    pub(crate) fn write(&self, samples: &[f64], per_channel: usize, timeout_s: f64) -> Result<(), NiFailure> {
        let num = i32::try_from(per_channel).map_err(|_| NiFailure::local("waveform too long".into()))?;
        if per_channel == 0 || !samples.len().is_multiple_of(per_channel) {
            return Err(NiFailure::local(format!("{} samples are not whole channels of {per_channel}", samples.len())));
        }
        let mut written: i32 = 0;
        // SAFETY: the task is live; `samples` holds `per_channel` values for each of the task's channels (the
        // callers build it from the channels they created) and outlives the call; `written` is a valid place; the
        // reserved argument is documented as NULL.
        let status = unsafe {
            (self.lib.api.write_analog_f64)(
                self.handle,
                num,
                0,
                timeout_s,
                VAL_GROUP_BY_CHANNEL,
                samples.as_ptr(),
                &mut written,
                ptr::null_mut(),
            )
        };
        self.lib.check(status, "DAQmxWriteAnalogF64")
    }
}
