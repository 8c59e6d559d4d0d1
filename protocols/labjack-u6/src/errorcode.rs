//! The U6's low-level errorcodes (User's Guide section 5.3, "Errorcodes"; the same table as LabJackPython's
//! `ERROR_TO_STRING_DICT` in `LabJackPython.py`). Only the codes this codec's functions can return are named.

/// An errorcode byte of a response or a stream packet; 0 is success.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Errorcode(pub u8);

impl Errorcode {
    /// Success.
    pub const OK: Errorcode = Errorcode(0);
    /// `FUNCTION_INVALID`: a command the device does not know.
    pub const FUNCTION_INVALID: Errorcode = Errorcode(5);
    /// `INVALID_BLOCK`: a ReadMem/ReadCal block number out of range.
    pub const INVALID_BLOCK: Errorcode = Errorcode(26);
    /// `STREAM_IS_ACTIVE`: StreamConfig or StreamStart while a stream runs.
    pub const STREAM_IS_ACTIVE: Errorcode = Errorcode(48);
    /// `STREAM_CONFIG_INVALID`: a StreamConfig the device refuses (channel count, channel, resolution).
    pub const STREAM_CONFIG_INVALID: Errorcode = Errorcode(50);
    /// `STREAM_NOT_RUNNING`: StreamStop while no stream runs.
    pub const STREAM_NOT_RUNNING: Errorcode = Errorcode(52);
    /// `STREAM_SCAN_OVERLAP`: a scan was due before the previous one finished (rate too high for the channels,
    /// resolution and settling). Ends the stream's usefulness: scans are lost.
    pub const STREAM_SCAN_OVERLAP: Errorcode = Errorcode(55);
    /// `STREAM_SAMPLE_NUM_INVALID`: SamplesPerPacket out of 1-25.
    pub const STREAM_SAMPLE_NUM_INVALID: Errorcode = Errorcode(56);
    /// `STREAM_BIPOLAR_GAIN_INVALID`: a gain the channel cannot take.
    pub const STREAM_BIPOLAR_GAIN_INVALID: Errorcode = Errorcode(57);
    /// `STREAM_SCAN_RATE_INVALID`: a scan rate the device refuses.
    pub const STREAM_SCAN_RATE_INVALID: Errorcode = Errorcode(58);
    /// `STREAM_AUTORECOVER_ACTIVE`: the stream buffer overflowed; new scans are being discarded while the buffer
    /// drains. The packet's samples are valid (taken before the overflow).
    pub const STREAM_AUTORECOVER_ACTIVE: Errorcode = Errorcode(59);
    /// `STREAM_AUTORECOVER_REPORT`: the first packet after auto-recovery: it starts with one dummy scan (every
    /// sample `0xFFFF`) and its TimeStamp holds the number of scans discarded, the dummy included.
    pub const STREAM_AUTORECOVER_REPORT: Errorcode = Errorcode(60);
    /// `STREAM_AUTORECOVER_OVERFLOW`: more scans were discarded than auto-recovery can count: the gap is unknown.
    pub const STREAM_AUTORECOVER_OVERFLOW: Errorcode = Errorcode(63);

    /// Whether this is success.
    pub fn is_ok(self) -> bool {
        self.0 == 0
    }

    /// The guide's name of this code, `"UNKNOWN"` for one this codec does not name.
    pub fn name(self) -> &'static str {
        match self.0 {
            0 => "NOERROR",
            1 => "SCRATCH_WRT_FAIL",
            2 => "SCRATCH_ERASE_FAIL",
            3 => "DATA_BUFFER_OVERFLOW",
            4 => "ADC0_BUFFER_OVERFLOW",
            5 => "FUNCTION_INVALID",
            6 => "SWDT_TIME_INVALID",
            7 => "XBR_CONFIG_ERROR",
            16 => "FLASH_WRITE_FAIL",
            17 => "FLASH_ERASE_FAIL",
            24 => "MEM_ILLEGAL_ADDRESS",
            26 => "INVALID_BLOCK",
            48 => "STREAM_IS_ACTIVE",
            49 => "STREAM_TABLE_INVALID",
            50 => "STREAM_CONFIG_INVALID",
            52 => "STREAM_NOT_RUNNING",
            53 => "STREAM_INVALID_TRIGGER",
            54 => "STREAM_ADC0_BUFFER_OVERFLOW",
            55 => "STREAM_SCAN_OVERLAP",
            56 => "STREAM_SAMPLE_NUM_INVALID",
            57 => "STREAM_BIPOLAR_GAIN_INVALID",
            58 => "STREAM_SCAN_RATE_INVALID",
            59 => "STREAM_AUTORECOVER_ACTIVE",
            60 => "STREAM_AUTORECOVER_REPORT",
            63 => "STREAM_AUTORECOVER_OVERFLOW",
            _ => "UNKNOWN",
        }
    }
}

impl std::fmt::Display for Errorcode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.name(), self.0)
    }
}
