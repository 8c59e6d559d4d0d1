//! StreamConfig's parameters (User's Guide section 5.2.12; LabJackPython `U6.streamConfig` in `u6.py`), the scan
//! clock, and the check the device applies before it answers.

use crate::error::U6Error;
use crate::errorcode::Errorcode;

/// Most channels StreamConfig takes (the guide: NumChannels 1-25; more need StreamAddChannels, not used here).
pub const MAX_STREAM_CHANNELS: usize = 25;
/// Most samples per StreamData packet (SamplesPerPacket 1-25).
pub const MAX_SAMPLES_PER_PACKET: u8 = 25;
/// Analog inputs of a U6 (AIN0-AIN13, screw terminals and DB37); higher numbers need a Mux80 extension.
pub const ANALOG_INPUTS: u8 = 14;
/// Highest resolution index stream mode takes (9-12 use the U6-Pro's converter, not available in stream).
pub const MAX_STREAM_RESOLUTION_INDEX: u8 = 8;
/// The fastest aggregate stream rate, samples/s (User's Guide section 3.2, "Stream Mode": 50 kS/s at resolution
/// index 1, gain x1); slower at higher resolution indices or gains, which the device reports by errorcode 55
/// (`STREAM_SCAN_OVERLAP`) while streaming.
pub const MAX_STREAM_SAMPLES_PER_S: f64 = 50_000.0;

/// An analog input's gain (ChannelOptions bits 4-5), which sets its range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Gain {
    /// x1: +/-10 V.
    X1,
    /// x10: +/-1 V.
    X10,
    /// x100: +/-0.1 V.
    X100,
    /// x1000: +/-0.01 V.
    X1000,
}

impl Gain {
    /// Every gain, by gain index.
    pub const ALL: [Gain; 4] = [Gain::X1, Gain::X10, Gain::X100, Gain::X1000];

    /// The gain index (0-3), as the guide and the calibration tables number them.
    pub fn index(self) -> u8 {
        match self {
            Gain::X1 => 0,
            Gain::X10 => 1,
            Gain::X100 => 2,
            Gain::X1000 => 3,
        }
    }

    /// The gain of index `index`, `None` beyond 3.
    pub fn from_index(index: u8) -> Option<Gain> {
        Gain::ALL.get(usize::from(index)).copied()
    }

    /// The nominal range: the input spans `-range_v ..= +range_v`, V.
    pub fn range_v(self) -> f64 {
        match self {
            Gain::X1 => 10.0,
            Gain::X10 => 1.0,
            Gain::X100 => 0.1,
            Gain::X1000 => 0.01,
        }
    }

    /// The gain whose nominal range is `range_v` (to 1 part in 10^9), `None` for a range the U6 does not offer.
    pub fn for_range_v(range_v: f64) -> Option<Gain> {
        Gain::ALL.into_iter().find(|g| (g.range_v() - range_v).abs() <= 1e-9 * g.range_v())
    }
}

/// The stream's base clock (ScanConfig bit 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StreamClock {
    /// 4 MHz.
    Mhz4,
    /// 48 MHz.
    Mhz48,
}

impl StreamClock {
    /// The clock frequency, Hz.
    pub fn hz(self) -> f64 {
        match self {
            StreamClock::Mhz4 => 4.0e6,
            StreamClock::Mhz48 => 48.0e6,
        }
    }
}

/// One entry of the scan list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StreamChannel {
    /// ChannelNumber (positive channel): 0-13 for AIN0-AIN13.
    pub positive: u8,
    /// Gain (range).
    pub gain: Gain,
    /// Differential: the negative input is `positive + 1` (`positive` must be even); otherwise single-ended.
    pub differential: bool,
}

impl StreamChannel {
    /// ChannelOptions: bit 7 differential, bits 4-5 gain index.
    pub fn options_byte(self) -> u8 {
        (u8::from(self.differential) << 7) | (self.gain.index() << 4)
    }

    /// The entry for ChannelNumber `positive` and ChannelOptions `options`.
    ///
    /// # Errors
    /// [`U6Error::InvalidField`] when `options` sets a bit other than 7, 4 and 5.
    pub fn from_bytes(positive: u8, options: u8) -> Result<Self, U6Error> {
        if options & !0xb0 != 0 {
            return Err(U6Error::InvalidField {
                what: "StreamConfig",
                field: "ChannelOptions",
                value: u64::from(options),
                reason: "only bit 7 (differential) and bits 4-5 (gain index) are defined",
            });
        }
        // Two bits: always a gain index 0-3.
        let gain = Gain::from_index((options >> 4) & 0x3).unwrap_or(Gain::X1);
        Ok(Self { positive, gain, differential: options & 0x80 != 0 })
    }
}

/// The parameters of StreamConfig.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamConfig {
    /// ResolutionIndex, 0-8 (0 means 1, the usual stream setting; 16-bit samples either way).
    pub resolution_index: u8,
    /// SamplesPerPacket, 1-25: samples (not scans) per StreamData packet.
    pub samples_per_packet: u8,
    /// SettlingFactor: extra settling per channel in 10 us steps; 0 lets the U6 choose from gain and resolution.
    pub settling_factor: u8,
    /// Base clock.
    pub clock: StreamClock,
    /// Divide the base clock by 256 (ScanConfig bit 1).
    pub divide_by_256: bool,
    /// ScanInterval, 1-65535: clock ticks between scans.
    pub scan_interval: u16,
    /// The scan list, in sample order within each scan (1-25 entries).
    pub channels: Vec<StreamChannel>,
}

/// The clock settings giving exactly `scan_rate_hz` scans per second: (clock, divide by 256, ScanInterval), the
/// fastest clock that reaches it (the finest timing), as LabJackPython's `streamConfig(ScanFrequency=...)` picks;
/// `None` when no setting gives the rate exactly.
pub fn scan_timing(scan_rate_hz: f64) -> Option<(StreamClock, bool, u16)> {
    if !(scan_rate_hz.is_finite() && scan_rate_hz > 0.0) {
        return None;
    }
    for (clock, divide) in
        [(StreamClock::Mhz48, false), (StreamClock::Mhz4, false), (StreamClock::Mhz48, true), (StreamClock::Mhz4, true)]
    {
        let base_hz = clock.hz() / if divide { 256.0 } else { 1.0 };
        let interval = base_hz / scan_rate_hz;
        if interval.fract() == 0.0 && (1.0..=65535.0).contains(&interval) {
            // A whole number in 1..=65535.
            return Some((clock, divide, interval as u16));
        }
    }
    None
}

impl StreamConfig {
    /// Scans per second: the clock (divided by 256 if asked) over ScanInterval, Hz.
    pub fn scan_rate_hz(&self) -> f64 {
        let base = self.clock.hz() / if self.divide_by_256 { 256.0 } else { 1.0 };
        base / f64::from(self.scan_interval.max(1))
    }

    /// Checks the configuration as the device does before answering StreamConfig (and as a host may before
    /// sending it).
    ///
    /// # Errors
    /// [`U6Error::ConfigRejected`] with errorcode 50 `STREAM_CONFIG_INVALID` (0 or over 25 channels, an input
    /// beyond AIN13, a differential channel on an odd input or on AIN13, a resolution index over 8), 56
    /// `STREAM_SAMPLE_NUM_INVALID` (SamplesPerPacket outside 1-25), or 58 `STREAM_SCAN_RATE_INVALID`
    /// (ScanInterval 0, or an aggregate rate over 50 kS/s).
    pub fn check(&self) -> Result<(), U6Error> {
        let invalid = |reason: String| U6Error::ConfigRejected { errorcode: Errorcode::STREAM_CONFIG_INVALID, reason };
        let n = self.channels.len();
        if n == 0 || n > MAX_STREAM_CHANNELS {
            return Err(invalid(format!("{n} channels, the U6 streams 1 to {MAX_STREAM_CHANNELS}")));
        }
        for ch in &self.channels {
            if ch.positive >= ANALOG_INPUTS {
                return Err(invalid(format!("AIN{} does not exist (AIN0-AIN{})", ch.positive, ANALOG_INPUTS - 1)));
            }
            if ch.differential && (ch.positive % 2 != 0 || ch.positive + 1 >= ANALOG_INPUTS) {
                return Err(invalid(format!("AIN{} cannot be the positive input of a differential pair", ch.positive)));
            }
        }
        if self.resolution_index > MAX_STREAM_RESOLUTION_INDEX {
            return Err(invalid(format!(
                "resolution index {} (stream takes 0-{MAX_STREAM_RESOLUTION_INDEX})",
                self.resolution_index
            )));
        }
        if self.samples_per_packet == 0 || self.samples_per_packet > MAX_SAMPLES_PER_PACKET {
            return Err(U6Error::ConfigRejected {
                errorcode: Errorcode::STREAM_SAMPLE_NUM_INVALID,
                reason: format!("SamplesPerPacket {} outside 1-{MAX_SAMPLES_PER_PACKET}", self.samples_per_packet),
            });
        }
        let aggregate = self.scan_rate_hz() * n as f64;
        if self.scan_interval == 0 || aggregate > MAX_STREAM_SAMPLES_PER_S {
            return Err(U6Error::ConfigRejected {
                errorcode: Errorcode::STREAM_SCAN_RATE_INVALID,
                reason: format!(
                    "ScanInterval {}: {aggregate} samples/s over the U6's {MAX_STREAM_SAMPLES_PER_S}",
                    self.scan_interval
                ),
            });
        }
        Ok(())
    }
}
