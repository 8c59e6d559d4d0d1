//! A stand-in for NI's NI-DAQmx C library: built as `libnidaqmx_standin.so` (not NI's file name, so that it is
//! loaded only where named), it
//! exports the `DAQmx...` functions metaplate's NI-DAQmx backend loads, with the signatures of NI's C reference
//! (`NIDAQmx.h`), its task handles, status codes and extended error texts, so the backend's real code path (run-time
//! loading, foreign calls, error handling) runs in CI without NI's software or a device.
//!
//! What it imitates (NI's "NI-DAQmx C Reference" and the behaviour public drivers such as nidaqmx-python rely on):
//! - devices `Dev1` .. `Dev8`, each an NI USB-6211 ([`device`]): product type, serial number, `DAQmxGetSysDevNames`;
//!   an unknown device name is -200220;
//! - tasks: analog voltage input and output channels, terminal configuration (RSE, NRSE, differential; a USB-6211
//!   has no pseudo-differential: -200077) and range, the onboard sample clock, digital-edge start triggers
//!   (`/Dev1/ao/StartTrigger` starts an input at the instant its output starts; a PFI line never fires here);
//! - resources: an analog output or a device's input engine held by a started task is reserved (-50103);
//! - reads in real time: -200284 when the samples asked for do not arrive within the timeout (or the trigger never
//!   comes), -200279 when the input buffer (NI's default size for the rate) was overwritten before it was read;
//! - the wiring of every device: `ao0` looped back to `ai0`, `ao1` to `ai1`, so what is written reads back;
//!   `ai2` .. `ai15` a deterministic sine ([`model`]).
//!
//! Beside a running stand-in rig (`metaplate lab serve` copies the library into its folder, next to its socket), the
//! timed analog inputs read the mock lab's signals instead ([`lab`]).
//!
//! Point the backend at it with `METAPLATE_NIDAQMX_LIBRARY=/path/to/target/debug/libnidaqmx_standin.so` (or a hardware
//! file's `[daq] library`). Its state is per process, like NI-DAQmx's.
//!
//! Unsafe code: the workspace forbids it; this crate allows it in [`exports`] only (C strings and C buffers).

pub mod device;
pub mod exports;
pub mod lab;
pub mod model;

use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

pub use model::{NiError, ReadOutcome, StandIn};

/// The stand-in's file name as cargo builds it (`libnidaqmx_standin.so` on Linux): what a hardware file's
/// `library` names, and what a stand-in rig copies into its folder.
pub fn library_file_name() -> String {
    format!("{}nidaqmx_standin{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX)
}

/// The process's NI-DAQmx state.
static STATE: Mutex<StandIn> = Mutex::new(StandIn::new());

thread_local! {
    /// The extended error text of this thread's last failed call (NI keeps it per thread).
    static LAST_ERROR: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// The process's state, locked (a panic elsewhere does not make it unusable: the state stays consistent between
/// calls).
pub fn state() -> MutexGuard<'static, StandIn> {
    STATE.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Turns a result into NI's status (0 or the negative code), remembering the error's text for
/// `DAQmxGetExtendedErrorInfo`.
pub fn status<T>(result: Result<T, NiError>) -> (i32, Option<T>) {
    match result {
        Ok(value) => (0, Some(value)),
        Err(e) => {
            LAST_ERROR.with(|last| *last.borrow_mut() = e.message.clone());
            (e.code, None)
        }
    }
}

/// The extended error text of this thread's last failed call.
pub fn last_error() -> String {
    LAST_ERROR.with(|last| last.borrow().clone())
}

/// `DAQmxReadAnalogF64` with its waiting: tries, and while the samples are not there sleeps (without holding the
/// state) until they will be, or until `timeout_s` (negative: forever, `DAQmx_Val_WaitInfinitely`) has passed.
///
/// # Errors
/// -200284 when the timeout passes first; as [`StandIn::try_read`].
pub fn read_analog_f64(
    handle: u64,
    num: i32,
    timeout_s: f64,
    fill_mode: u32,
    out: &mut [f64],
) -> Result<usize, NiError> {
    let started = Instant::now();
    let deadline = (timeout_s >= 0.0).then(|| started + Duration::from_secs_f64(timeout_s.min(1e6)));
    loop {
        let now = Instant::now();
        let wait = match state().try_read(handle, num, fill_mode, out, now)? {
            ReadOutcome::Done(n) => return Ok(n),
            ReadOutcome::Wait(ready) => ready,
        };
        if deadline.is_some_and(|d| now >= d) {
            let code = device::codes::SAMPLES_NOT_YET_AVAILABLE;
            return Err(NiError {
                code,
                message: format!(
                    "Some or all of the samples requested have not yet been acquired.\n\nTo wait for the \
                    samples to become available use a longer read timeout or read later in your program. \
                    To make the samples available sooner, increase the sample rate. If your task uses a \
                    start trigger, make sure that your start trigger is configured correctly.\n\nProperty: \
                    DAQmx_Read_RelativeTo\nCorresponding Value: DAQmx_Val_CurrReadPos\n\nStatus Code: \
                    {code}"
                ),
            });
        }
        // Wake when the samples are due, at the deadline, or (armed: waiting for a trigger another thread may
        // fire) after a millisecond.
        let until = [wait, deadline].into_iter().flatten().min().unwrap_or(now + Duration::from_millis(1));
        let nap = until
            .saturating_duration_since(now)
            .clamp(Duration::from_micros(50), Duration::from_millis(if wait.is_none() { 1 } else { 50 }));
        std::thread::sleep(nap);
    }
}
