//! The stand-in's devices: simulated NI USB-6211s, as NI's specifications describe the product (16 single-ended or
//! 8 differential analog inputs at 250 kS/s aggregate, ranges +/-0.2, 1, 5, 10 V, RSE/NRSE/differential; two
//! analog outputs, +/-10 V, 250 kS/s), and the constants of `NIDAQmx.h` the stand-in understands.

/// `DAQmx_Val_Cfg_Default`: the device chooses the terminal configuration.
pub const VAL_CFG_DEFAULT: i32 = -1;
/// `DAQmx_Val_RSE`: referenced single-ended.
pub const VAL_RSE: i32 = 10083;
/// `DAQmx_Val_NRSE`: non-referenced single-ended.
pub const VAL_NRSE: i32 = 10078;
/// `DAQmx_Val_Diff`: differential.
pub const VAL_DIFF: i32 = 10106;
/// `DAQmx_Val_PseudoDiff`: pseudo-differential (not on a USB-6211).
pub const VAL_PSEUDO_DIFF: i32 = 12529;
/// `DAQmx_Val_Volts`.
pub const VAL_VOLTS: i32 = 10348;
/// `DAQmx_Val_Rising`.
pub const VAL_RISING: i32 = 10280;
/// `DAQmx_Val_Falling`.
pub const VAL_FALLING: i32 = 10171;
/// `DAQmx_Val_ContSamps`.
pub const VAL_CONT_SAMPS: i32 = 10123;
/// `DAQmx_Val_FiniteSamps`.
pub const VAL_FINITE_SAMPS: i32 = 10178;
/// `DAQmx_Val_GroupByChannel`.
pub const VAL_GROUP_BY_CHANNEL: u32 = 0;
/// `DAQmx_Val_GroupByScanNumber`.
pub const VAL_GROUP_BY_SCAN_NUMBER: u32 = 1;

/// NI's status codes the stand-in returns (`NIDAQmx.h`'s `DAQmxError...` values).
pub mod codes {
    /// `DAQmxErrorPALResourceReserved`: another task holds the channel or timing engine.
    pub const RESOURCE_RESERVED: i32 = -50103;
    /// `DAQmxErrorInvalidAttributeValue`: a value the device does not support.
    pub const INVALID_ATTRIBUTE_VALUE: i32 = -200077;
    /// `DAQmxErrorDuplicateTask`.
    pub const DUPLICATE_TASK: i32 = -200089;
    /// `DAQmxErrorInvalidTask`: not a live task handle.
    pub const INVALID_TASK: i32 = -200088;
    /// `DAQmxErrorPhysicalChanDoesNotExist`.
    pub const PHYSICAL_CHAN_DOES_NOT_EXIST: i32 = -200170;
    /// `DAQmxErrorInvalidDeviceID`: no device of that name.
    pub const INVALID_DEVICE_ID: i32 = -200220;
    /// `DAQmxErrorBufferTooSmallForString`.
    pub const BUFFER_TOO_SMALL_FOR_STRING: i32 = -200228;
    /// `DAQmxErrorReadBufferTooSmall`.
    pub const READ_BUFFER_TOO_SMALL: i32 = -200229;
    /// `DAQmxErrorNULLPtrForC_Api`.
    pub const NULL_PTR: i32 = -200230;
    /// `DAQmxErrorInvalidTerm`: no such terminal (trigger source).
    pub const INVALID_TERM: i32 = -200254;
    /// `DAQmxErrorSamplesNoLongerAvailable`: the input buffer was overwritten before it was read (overrun).
    pub const SAMPLES_NO_LONGER_AVAILABLE: i32 = -200279;
    /// `DAQmxErrorSamplesNotYetAvailable`: the read timed out.
    pub const SAMPLES_NOT_YET_AVAILABLE: i32 = -200284;
    /// `DAQmxErrorSampRateTooHigh`.
    pub const SAMP_RATE_TOO_HIGH: i32 = -200332;
    /// `DAQmxErrorWriteNoOutputChansInTask`.
    pub const WRITE_NO_OUTPUT_CHANS: i32 = -200459;
    /// `DAQmxErrorReadNoInputChansInTask`.
    pub const READ_NO_INPUT_CHANS: i32 = -200460;
    /// `DAQmxErrorOutputBufferEmpty`: a timed output started before any sample was written.
    pub const OUTPUT_BUFFER_EMPTY: i32 = -200462;
    /// `DAQmxErrorDeviceCannotBeAccessed` (-201003): the device went away (here: the stand-in rig it reads).
    pub const DEVICE_CANNOT_BE_ACCESSED: i32 = -201003;
}

/// What a simulated device is.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    /// Its NI name (`Dev1`), as NI MAX shows it.
    pub name: String,
    /// `DAQmx_Dev_ProductType`.
    pub product_type: &'static str,
    /// `DAQmx_Dev_SerialNum`.
    pub serial: u32,
}

/// Analog inputs of a USB-6211 (single-ended; ai0-7 pair with ai8-15 when differential).
pub const AI_COUNT: u8 = 16;
/// Analog outputs of a USB-6211.
pub const AO_COUNT: u8 = 2;
/// The USB-6211's input ranges, +/- V, smallest first.
pub const AI_RANGES_V: [f64; 4] = [0.2, 1.0, 5.0, 10.0];
/// The USB-6211's output range, +/- V.
pub const AO_RANGE_V: f64 = 10.0;
/// The USB-6211's aggregate input rate, S/s (all channels together).
pub const AI_MAX_AGGREGATE_HZ: f64 = 250_000.0;
/// The USB-6211's output rate, S/s per channel.
pub const AO_MAX_RATE_HZ: f64 = 250_000.0;
/// How many devices the stand-in has: `Dev1` .. `Dev8`, so parallel tests each take their own.
pub const DEVICE_COUNT: u32 = 8;

/// The stand-in's devices, `Dev1` .. `Dev8`: USB-6211s with serials 0x01A2B3C1 ..
pub fn devices() -> Vec<Device> {
    (1..=DEVICE_COUNT)
        .map(|i| Device { name: format!("Dev{i}"), product_type: "USB-6211", serial: 0x01A2_B3C0 + i })
        .collect()
}

/// The device named `name` (NI device names are case-insensitive).
pub fn find(name: &str) -> Option<Device> {
    devices().into_iter().find(|d| d.name.eq_ignore_ascii_case(name.trim()))
}

/// The input buffer NI-DAQmx allocates for a continuous acquisition at `rate_hz` when asked for fewer samples
/// (NI's documented defaults: 1 kS up to 100 S/s, 10 kS up to 10 kS/s, 100 kS up to 1 MS/s, 1 MS beyond).
pub fn default_buffer_samples(rate_hz: f64) -> u64 {
    if rate_hz <= 100.0 {
        1_000
    } else if rate_hz <= 10_000.0 {
        10_000
    } else if rate_hz <= 1_000_000.0 {
        100_000
    } else {
        1_000_000
    }
}

/// The text of a terminal configuration value, for messages.
pub fn terminal_name(value: i32) -> &'static str {
    match value {
        VAL_RSE => "RSE",
        VAL_NRSE => "NRSE",
        VAL_DIFF => "Differential",
        VAL_PSEUDO_DIFF => "Pseudodifferential",
        VAL_CFG_DEFAULT => "Default",
        _ => "unknown",
    }
}
