//! The C functions, with the signatures `NIDAQmx.h` declares (`int32 __CFUNC DAQmx...`; `__CFUNC` is `__stdcall`
//! on Windows and plain C elsewhere: `extern "system"`). Each converts its arguments, calls [`crate::model`] and
//! returns NI's status. The crate's only unsafe code: each block says what the caller's contract guarantees.
#![allow(unsafe_code)]

use std::ffi::{CStr, c_char, c_void};
use std::time::Instant;

use crate::device::codes;
use crate::model::{self, NiError};
use crate::{state, status};

/// NI's opaque task handle.
pub type TaskHandle = *mut c_void;

fn handle_of(task: TaskHandle) -> u64 {
    task as usize as u64
}

fn null_error(what: &str) -> NiError {
    let code = codes::NULL_PTR;
    NiError { code, message: format!("NULL pointer passed for {what}.\n\nStatus Code: {code}") }
}

/// Reads a C string argument; NULL reads as empty (NI treats a NULL name as "").
///
/// # Safety
/// `text` is NULL or a NUL-terminated string valid for the call.
unsafe fn text<'a>(text: *const c_char) -> std::borrow::Cow<'a, str> {
    if text.is_null() {
        return "".into();
    }
    // SAFETY: the caller passes a NUL-terminated string that outlives the call (NI's contract for `const char[]`).
    unsafe { CStr::from_ptr(text) }.to_string_lossy()
}

/// Copies `value` into a caller's `data` of `size` bytes, NI's way for string properties: `size` 0 asks for the
/// size needed (returned, positive); a buffer too small is -200228.
///
/// # Safety
/// `data` is NULL or writable for `size` bytes.
unsafe fn copy_out(value: &str, data: *mut c_char, size: u32, truncate: bool) -> i32 {
    let bytes = value.as_bytes();
    let needed = i32::try_from(bytes.len() + 1).unwrap_or(i32::MAX);
    if data.is_null() || size == 0 {
        return needed;
    }
    let size = size as usize;
    if size < bytes.len() + 1 && !truncate {
        let code = codes::BUFFER_TOO_SMALL_FOR_STRING;
        let message =
            format!("Buffer is too small to fit the string.\n\nRequired Size: {needed}\n\nStatus Code: {code}");
        return status::<()>(Err(NiError { code, message })).0;
    }
    let n = bytes.len().min(size - 1);
    // SAFETY: `data` is writable for `size` bytes (caller's contract) and `n + 1 <= size`.
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr().cast::<c_char>(), data, n);
        *data.add(n) = 0;
    }
    0
}

/// `int32 DAQmxCreateTask(const char taskName[], TaskHandle *taskHandle)`.
///
/// # Safety
/// NI's contract: `name` NULL or a C string; `task` writable.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxCreateTask(name: *const c_char, task: *mut TaskHandle) -> i32 {
    if task.is_null() {
        return status::<()>(Err(null_error("taskHandle"))).0;
    }
    // SAFETY: `name` is NULL or a C string (contract).
    let name = unsafe { text(name) };
    let (code, handle) = status(state().create_task(&name));
    if let Some(handle) = handle {
        // SAFETY: `task` is non-null and writable (contract); the handle is a number, never dereferenced.
        unsafe { *task = std::ptr::without_provenance_mut(handle as usize) };
    }
    code
}

/// `int32 DAQmxCreateAIVoltageChan(TaskHandle, const char physicalChannel[], const char nameToAssignToChannel[],
/// int32 terminalConfig, float64 minVal, float64 maxVal, int32 units, const char customScaleName[])`.
///
/// # Safety
/// NI's contract: the strings NULL or C strings.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "system" fn DAQmxCreateAIVoltageChan(
    task: TaskHandle,
    physical: *const c_char,
    _name: *const c_char,
    terminal_config: i32,
    min_v: f64,
    max_v: f64,
    units: i32,
    _custom_scale: *const c_char,
) -> i32 {
    // SAFETY: a C string (contract).
    let physical = unsafe { text(physical) };
    status(state().create_ai_voltage_chan(handle_of(task), &physical, terminal_config, min_v, max_v, units)).0
}

/// `int32 DAQmxCreateAOVoltageChan(TaskHandle, const char physicalChannel[], const char nameToAssignToChannel[],
/// float64 minVal, float64 maxVal, int32 units, const char customScaleName[])`.
///
/// # Safety
/// NI's contract: the strings NULL or C strings.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxCreateAOVoltageChan(
    task: TaskHandle,
    physical: *const c_char,
    _name: *const c_char,
    min_v: f64,
    max_v: f64,
    units: i32,
    _custom_scale: *const c_char,
) -> i32 {
    // SAFETY: a C string (contract).
    let physical = unsafe { text(physical) };
    status(state().create_ao_voltage_chan(handle_of(task), &physical, min_v, max_v, units)).0
}

/// `int32 DAQmxCfgSampClkTiming(TaskHandle, const char source[], float64 rate, int32 activeEdge,
/// int32 sampleMode, uInt64 sampsPerChan)`.
///
/// # Safety
/// NI's contract: `source` NULL or a C string.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxCfgSampClkTiming(
    task: TaskHandle,
    source: *const c_char,
    rate_hz: f64,
    active_edge: i32,
    sample_mode: i32,
    samps_per_chan: u64,
) -> i32 {
    // SAFETY: a C string (contract).
    let source = unsafe { text(source) };
    status(state().cfg_samp_clk_timing(handle_of(task), &source, rate_hz, active_edge, sample_mode, samps_per_chan)).0
}

/// `int32 DAQmxCfgDigEdgeStartTrig(TaskHandle, const char triggerSource[], int32 triggerEdge)`.
///
/// # Safety
/// NI's contract: `source` a C string.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxCfgDigEdgeStartTrig(task: TaskHandle, source: *const c_char, edge: i32) -> i32 {
    // SAFETY: a C string (contract).
    let source = unsafe { text(source) };
    status(state().cfg_dig_edge_start_trig(handle_of(task), &source, edge)).0
}

/// `int32 DAQmxStartTask(TaskHandle)`.
#[unsafe(no_mangle)]
pub extern "system" fn DAQmxStartTask(task: TaskHandle) -> i32 {
    status(state().start(handle_of(task), Instant::now())).0
}

/// `int32 DAQmxStopTask(TaskHandle)`.
#[unsafe(no_mangle)]
pub extern "system" fn DAQmxStopTask(task: TaskHandle) -> i32 {
    status(state().stop(handle_of(task), Instant::now())).0
}

/// `int32 DAQmxClearTask(TaskHandle)`.
#[unsafe(no_mangle)]
pub extern "system" fn DAQmxClearTask(task: TaskHandle) -> i32 {
    status(state().clear(handle_of(task), Instant::now())).0
}

/// `int32 DAQmxReadAnalogF64(TaskHandle, int32 numSampsPerChan, float64 timeout, bool32 fillMode,
/// float64 readArray[], uInt32 arraySizeInSamps, int32 *sampsPerChanRead, bool32 *reserved)`.
///
/// # Safety
/// NI's contract: `array` writable for `array_size` values; `read` NULL or writable.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "system" fn DAQmxReadAnalogF64(
    task: TaskHandle,
    num_samps_per_chan: i32,
    timeout_s: f64,
    fill_mode: u32,
    array: *mut f64,
    array_size: u32,
    read: *mut i32,
    _reserved: *mut u32,
) -> i32 {
    if array.is_null() {
        return status::<()>(Err(null_error("readArray"))).0;
    }
    // SAFETY: `array` is non-null and writable for `array_size` values (contract); the slice lives for this call.
    let out = unsafe { std::slice::from_raw_parts_mut(array, array_size as usize) };
    let (code, n) = status(crate::read_analog_f64(handle_of(task), num_samps_per_chan, timeout_s, fill_mode, out));
    if !read.is_null() {
        // SAFETY: `read` is non-null and writable (contract).
        unsafe { *read = n.map_or(0, |n| i32::try_from(n).unwrap_or(i32::MAX)) };
    }
    code
}

/// `int32 DAQmxWriteAnalogF64(TaskHandle, int32 numSampsPerChan, bool32 autoStart, float64 timeout,
/// bool32 dataLayout, const float64 writeArray[], int32 *sampsPerChanWritten, bool32 *reserved)`; the array holds
/// `numSampsPerChan` values per channel of the task.
///
/// # Safety
/// NI's contract: `array` readable for `numSampsPerChan` x (channels in the task) values; `written` NULL or
/// writable.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "system" fn DAQmxWriteAnalogF64(
    task: TaskHandle,
    num_samps_per_chan: i32,
    auto_start: u32,
    _timeout_s: f64,
    layout: u32,
    array: *const f64,
    written: *mut i32,
    _reserved: *mut u32,
) -> i32 {
    // SAFETY: `array` holds `num_samps_per_chan` values per channel of the task (contract).
    let result = unsafe { write_f64(handle_of(task), num_samps_per_chan, auto_start != 0, layout, array) };
    let (code, n) = status(result);
    if !written.is_null() {
        // SAFETY: `written` is non-null and writable (contract).
        unsafe { *written = n.map_or(0, |n| i32::try_from(n).unwrap_or(i32::MAX)) };
    }
    code
}

/// The samples of a write, read from the caller's array, written.
///
/// # Safety
/// `array` is NULL or readable for `num` values per channel of the task.
unsafe fn write_f64(handle: u64, num: i32, auto_start: bool, layout: u32, array: *const f64) -> Result<usize, NiError> {
    let num = usize::try_from(num).map_err(|_| null_error("numSampsPerChan (negative)"))?;
    let channels = state().ao_channel_count(handle)?;
    if array.is_null() {
        return Err(null_error("writeArray"));
    }
    // SAFETY: `array` holds `num` values per channel of the task (contract), `channels` of them.
    let data = unsafe { std::slice::from_raw_parts(array, num * channels) };
    state().write_analog_f64(handle, num, auto_start, layout, data, Instant::now())
}

/// `int32 DAQmxWriteAnalogScalarF64(TaskHandle, bool32 autoStart, float64 timeout, float64 value,
/// bool32 *reserved)`: one sample to a task of one channel.
#[unsafe(no_mangle)]
pub extern "system" fn DAQmxWriteAnalogScalarF64(
    task: TaskHandle,
    auto_start: u32,
    _timeout_s: f64,
    value: f64,
    _reserved: *mut u32,
) -> i32 {
    let data = [value];
    status(state().write_analog_f64(handle_of(task), 1, auto_start != 0, 0, &data, Instant::now())).0
}

/// `int32 DAQmxGetAITermCfg(TaskHandle, const char channel[], int32 *data)`.
///
/// # Safety
/// NI's contract: `channel` a C string; `data` writable.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxGetAITermCfg(task: TaskHandle, channel: *const c_char, data: *mut i32) -> i32 {
    if data.is_null() {
        return status::<()>(Err(null_error("data"))).0;
    }
    // SAFETY: a C string (contract).
    let channel = unsafe { text(channel) };
    let (code, value) = status(state().ai_term_cfg(handle_of(task), &channel));
    if let Some(value) = value {
        // SAFETY: `data` is non-null and writable (contract).
        unsafe { *data = value };
    }
    code
}

/// `int32 DAQmxGetDevProductType(const char device[], char *data, uInt32 bufferSize)`.
///
/// # Safety
/// NI's contract: `device` a C string; `data` NULL or writable for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxGetDevProductType(device: *const c_char, data: *mut c_char, size: u32) -> i32 {
    // SAFETY: a C string (contract).
    let device = unsafe { text(device) };
    match status(model::product_type(&device)) {
        // SAFETY: `data` is NULL or writable for `size` bytes (contract).
        (0, Some(product)) => unsafe { copy_out(&product, data, size, false) },
        (code, _) => code,
    }
}

/// `int32 DAQmxGetDevSerialNum(const char device[], uInt32 *data)`.
///
/// # Safety
/// NI's contract: `device` a C string; `data` writable.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxGetDevSerialNum(device: *const c_char, data: *mut u32) -> i32 {
    if data.is_null() {
        return status::<()>(Err(null_error("data"))).0;
    }
    // SAFETY: a C string (contract).
    let device = unsafe { text(device) };
    let (code, serial) = status(model::serial_number(&device));
    if let Some(serial) = serial {
        // SAFETY: `data` is non-null and writable (contract).
        unsafe { *data = serial };
    }
    code
}

/// `int32 DAQmxGetSysDevNames(char *data, uInt32 bufferSize)`.
///
/// # Safety
/// NI's contract: `data` NULL or writable for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxGetSysDevNames(data: *mut c_char, size: u32) -> i32 {
    // SAFETY: `data` is NULL or writable for `size` bytes (contract).
    unsafe { copy_out(&model::sys_dev_names(), data, size, false) }
}

/// `int32 DAQmxGetExtendedErrorInfo(char errorString[], uInt32 bufferSize)`: this thread's last error text;
/// `size` 0 returns the size needed; a shorter buffer gets the text truncated.
///
/// # Safety
/// NI's contract: `data` NULL or writable for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "system" fn DAQmxGetExtendedErrorInfo(data: *mut c_char, size: u32) -> i32 {
    // SAFETY: `data` is NULL or writable for `size` bytes (contract).
    unsafe { copy_out(&crate::last_error(), data, size, true) }
}
