//! The `Daq` capability: a data acquisition unit that records analog voltages, as recipes see it.
//!
//! A recipe configures channels (analog input index and +/- range, V) and a per-channel sample rate (Hz), starts an
//! acquisition, reads blocks of samples in volts with an integrity report, and stops. It never sees the transport.
//! Blocks are never stitched across a loss: each block is contiguous in the device's sample clock, and its
//! [`BlockIntegrity`] says what was lost just before it, so a recipe can repeat or repair a recording.

/// Who the device is, as it reports itself.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DaqIdentity {
    /// Manufacturer.
    pub vendor: String,
    /// Model.
    pub model: String,
    /// Serial number: what a reopen looks the device up by.
    pub serial: String,
    /// Firmware (or driver library) version.
    pub firmware: String,
}

/// One acquired channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DaqChannel {
    /// Analog input index on the device, from 0.
    pub input: u8,
    /// Input range: the channel measures `-range_v ..= +range_v`, V. Must be one the device offers (a finite
    /// value > 0); inputs beyond it clip.
    pub range_v: f64,
}

/// An acquisition configuration.
///
/// Valid range (checked by the device's driver, which answers [`DaqError::Config`] otherwise): at least one
/// channel, no input listed twice, every range offered by the device, a finite `sample_rate_hz > 0` the device
/// supports for that many channels, `1 <= block_len_samples` up to the driver's limit.
#[derive(Debug, Clone, PartialEq)]
pub struct DaqConfig {
    /// The channels, in the order their samples are returned.
    pub channels: Vec<DaqChannel>,
    /// Per-channel sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples per channel in a full block (the unit of transfer: latency against overhead).
    pub block_len_samples: u32,
}

/// What went wrong in the stream just before a block, and in it.
///
/// `samples_missing > 0` or `packets_lost > 0` or `overrun` means the block does not continue the previous one:
/// the recording has a gap at the block's start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BlockIntegrity {
    /// Transfers (packets) the device sent that never arrived, since the previous block.
    pub packets_lost: u64,
    /// Samples per channel missing between the previous block and this one (from the device's sample clock).
    pub samples_missing: u64,
    /// The device reported that its buffer overflowed before this block (samples were dropped at the source).
    pub overrun: bool,
    /// At least one sample of this block sits on a rail: the input exceeded the range.
    pub clipped: bool,
}

impl BlockIntegrity {
    /// Whether this block continues the previous one with nothing lost (clipping aside).
    pub fn is_contiguous(&self) -> bool {
        self.packets_lost == 0 && self.samples_missing == 0 && !self.overrun
    }
}

/// A block of samples of every configured channel.
#[derive(Debug, Clone, PartialEq)]
pub struct DaqBlock {
    /// The device's sample clock at the block's first sample: samples per channel since the acquisition started
    /// (0 for the first). Samples lost to an overrun are counted, so this is the block's timestamp.
    pub first_sample_index: u64,
    /// Samples per channel, V, one vector per configured channel in configuration order, all the same length
    /// (at least 1). Always finite.
    pub volts: Vec<Vec<f64>>,
    /// What was lost before this block, and whether it clipped.
    pub integrity: BlockIntegrity,
}

impl DaqBlock {
    /// Samples per channel in this block.
    pub fn len_samples(&self) -> usize {
        self.volts.first().map_or(0, Vec::len)
    }
}

/// Why a DAQ operation failed, sorted by what a recipe can do about it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DaqError {
    /// The device did not answer within the timeout, after the driver's bounded retries. Retry later or reopen.
    #[error("DAQ timed out: {what} (after {attempts} attempts)")]
    Timeout {
        /// What was waited for.
        what: String,
        /// How many attempts were made.
        attempts: u32,
    },
    /// The device is gone (unplugged, reset). Recoverable: [`Daq::reopen`] finds it again by serial number and
    /// re-applies the configuration; the acquisition in progress is lost and must be started again.
    #[error("DAQ disconnected: {detail}")]
    Disconnected {
        /// What the transport reported.
        detail: String,
    },
    /// The acquisition lost data at the device (its buffer overflowed) and ended; start again.
    #[error("DAQ overrun: {detail}")]
    Overrun {
        /// What the device reported.
        detail: String,
    },
    /// The device refused a command or reported a fault; `code` is the device's (or vendor library's) error code.
    #[error("DAQ device error {code}: {detail}")]
    Device {
        /// The device's error code.
        code: i64,
        /// Its explanation.
        detail: String,
    },
    /// The device sent something the driver cannot accept (corrupt or unexpected messages), or a command was
    /// used in the wrong state (read before start).
    #[error("DAQ protocol error: {detail}")]
    Protocol {
        /// What was wrong.
        detail: String,
    },
    /// The configuration is invalid or not supported by this device; nothing was changed on the device.
    #[error("invalid DAQ configuration: {detail}")]
    Config {
        /// What is wrong.
        detail: String,
    },
    /// The backend or device cannot be reached at all (no such device, a vendor library not installed).
    #[error("DAQ unavailable: {detail}")]
    Unavailable {
        /// What is missing.
        detail: String,
    },
}

/// A data acquisition unit: configure, start, read blocks in volts, stop.
///
/// State: idle (after opening, configuring or stopping) or running (after [`start`](Self::start)). A
/// configuration stays in force across acquisitions and across [`reopen`](Self::reopen).
pub trait Daq {
    /// The device's identity, as read when it was opened.
    fn identity(&self) -> &DaqIdentity;

    /// Applies `config` for the following acquisitions (only while idle).
    ///
    /// # Errors
    /// [`DaqError::Config`] for a configuration the device does not support (checked before anything is sent
    /// where possible); transport errors as for every exchange ([`DaqError::Timeout`],
    /// [`DaqError::Disconnected`]); [`DaqError::Device`] if the device refuses it anyway.
    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError>;

    /// Starts an acquisition with the configuration in force; sample index 0 is its first sample.
    ///
    /// # Errors
    /// [`DaqError::Protocol`] if never configured or already running; transport and device errors as above.
    fn start(&mut self) -> Result<(), DaqError>;

    /// The next block of the running acquisition: contiguous in itself, with what was lost before it reported in
    /// its integrity (never silently joined to the previous block).
    ///
    /// # Errors
    /// [`DaqError::Overrun`] if the device ended the acquisition because its buffer overflowed;
    /// [`DaqError::Device`] for a device fault that ended it; [`DaqError::Protocol`] if not running or the stream
    /// ended unexpectedly; [`DaqError::Timeout`] if no samples arrive within the retries;
    /// [`DaqError::Disconnected`].
    fn read_block(&mut self) -> Result<DaqBlock, DaqError>;

    /// Stops the acquisition (nothing happens if idle); samples not yet read are discarded.
    ///
    /// # Errors
    /// Transport and device errors as above.
    fn stop(&mut self) -> Result<(), DaqError>;

    /// Reconnects to the same device (by serial number) after [`DaqError::Disconnected`], and re-applies the
    /// configuration in force. The device is left idle: an acquisition that was running must be started again.
    ///
    /// # Errors
    /// [`DaqError::Disconnected`] or [`DaqError::Unavailable`] if it cannot be found again; errors of
    /// [`configure`](Self::configure) while re-applying.
    fn reopen(&mut self) -> Result<(), DaqError>;
}
