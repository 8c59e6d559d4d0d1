//! The U6's calibration constants and the conversion of its 16-bit stream codes to volts.
//!
//! The constants are read from calibration memory with ReadCal, blocks 0-3 (LabJackPython `getCalibrationData`
//! in `u6.py`; User's Guide section 5.4, "Calibration Constants"), each constant 8 bytes of signed fixed point
//! 32.32 (bytes 0-3: the fraction, u32 LE, in units of 2^-32; bytes 4-7: the integer part, i32 LE; LabJackPython
//! `toDouble`):
//!
//! | block | bytes 0-7 | 8-15 | 16-23 | 24-31 |
//! |---|---|---|---|---|
//! | 0 | AIN10vSlope | AIN10vOffset | AIN1vSlope | AIN1vOffset |
//! | 1 | AIN100mvSlope | AIN100mvOffset | AIN10mvSlope | AIN10mvOffset |
//! | 2 | AIN10vNegSlope | AIN10vCenter | AIN1vNegSlope | AIN1vCenter |
//! | 3 | AIN100mvNegSlope | AIN100mvCenter | AIN10mvNegSlope | AIN10mvCenter |
//!
//! A stream code `c` (16 bits) on a channel of gain `g` is `(c - Center) * Slope` V at or above the center and
//! `(Center - c) * NegSlope` V below it (LabJackPython `binaryToCalibratedAnalogVoltage` with `is16Bits`; NegSlope
//! is negative). Codes 0 and 65535 are the converter's rails: the input may have been beyond them.

use crate::config::Gain;
use crate::error::U6Error;

/// Calibration memory blocks holding the analog-input constants.
pub const CALIBRATION_BLOCKS: u8 = 4;
/// Bytes of one memory block.
pub const BLOCK_LEN: usize = 32;

/// The constants of one gain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeCalibration {
    /// Slope above the center, V per code (> 0).
    pub slope_v: f64,
    /// Offset, V (held in memory; the 16-bit stream conversion does not use it).
    pub offset_v: f64,
    /// Slope below the center, V per code (< 0).
    pub neg_slope_v: f64,
    /// The code of 0 V.
    pub center: f64,
}

/// The analog-input calibration of a U6, by gain index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Constants for gains x1, x10, x100, x1000.
    pub ranges: [RangeCalibration; 4],
}

/// A fixed-point 32.32 constant as f64.
pub fn from_fixed(bytes: [u8; 8]) -> f64 {
    let fraction = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
    let integer = i32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    f64::from(integer) + f64::from(fraction) / 4_294_967_296.0
}

/// `value` as fixed point 32.32, rounded to the nearest 2^-32 (saturating beyond the i32 range).
pub fn to_fixed(value: f64) -> [u8; 8] {
    // `as` saturates and maps NaN to 0, which is what a flash image of a non-finite value can hold at best.
    ((value * 4_294_967_296.0).round() as i64).to_le_bytes()
}

fn word(block: &[u8; BLOCK_LEN], i: usize) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&block[8 * i..8 * i + 8]);
    from_fixed(b)
}

impl Calibration {
    /// The nominal constants (LabJackPython's `CalibrationInfo` defaults, what a U6 holds before its own are read:
    /// 316 uV per code on +/-10 V, center 33523).
    pub fn nominal() -> Self {
        let range = |scale: f64| RangeCalibration {
            slope_v: 3.158_057_8e-4 * scale,
            offset_v: -10.586_956_522 * scale,
            neg_slope_v: -3.158_058e-4 * scale,
            center: 33_523.0,
        };
        Self { ranges: [range(1.0), range(0.1), range(0.01), range(0.001)] }
    }

    /// The constants of a converter with exactly `2 * range / 65536` V per code and 0 V at code 32768 on every
    /// gain (as close as fixed point holds them): what the mock lab's U6 carries so that it digitises as a scene's
    /// 16-bit `daq` says.
    pub fn ideal() -> Self {
        let range = |g: Gain| {
            let step = g.range_v() / 32_768.0;
            let q = |v: f64| from_fixed(to_fixed(v));
            RangeCalibration { slope_v: q(step), offset_v: q(-g.range_v()), neg_slope_v: q(-step), center: 32_768.0 }
        };
        Self { ranges: Gain::ALL.map(range) }
    }

    /// The constants from calibration blocks 0-3, as ReadCal returns them.
    ///
    /// # Errors
    /// [`U6Error::BadCalibration`] for a slope that is not finite and of its sign, or a center outside 0-65535
    /// (an erased memory reads all `FF`: slopes of -2^-32).
    pub fn from_blocks(blocks: &[[u8; BLOCK_LEN]; 4]) -> Result<Self, U6Error> {
        let mut ranges = [RangeCalibration { slope_v: 0.0, offset_v: 0.0, neg_slope_v: 0.0, center: 0.0 }; 4];
        for (g, r) in ranges.iter_mut().enumerate() {
            let (pos, neg) = (&blocks[g / 2], &blocks[2 + g / 2]);
            let k = 2 * (g % 2);
            *r = RangeCalibration {
                slope_v: word(pos, k),
                offset_v: word(pos, k + 1),
                neg_slope_v: word(neg, k),
                center: word(neg, k + 1),
            };
            let bad = |name: &str, value: f64, reason| U6Error::BadCalibration {
                name: format!("{name} (gain index {g})"),
                value: value.to_string(),
                reason,
            };
            if r.slope_v.is_nan() || r.slope_v <= 0.0 {
                return Err(bad("Slope", r.slope_v, "must be positive"));
            }
            if r.neg_slope_v.is_nan() || r.neg_slope_v >= 0.0 {
                return Err(bad("NegSlope", r.neg_slope_v, "must be negative"));
            }
            if !(0.0..=65_535.0).contains(&r.center) {
                return Err(bad("Center", r.center, "must lie on the 16-bit scale"));
            }
        }
        Ok(Self { ranges })
    }

    /// The constants as calibration blocks 0-3 (device side: what the mock U6's memory holds).
    pub fn to_blocks(&self) -> [[u8; BLOCK_LEN]; 4] {
        let mut blocks = [[0u8; BLOCK_LEN]; 4];
        for (g, r) in self.ranges.iter().enumerate() {
            let k = 16 * (g % 2);
            blocks[g / 2][k..k + 8].copy_from_slice(&to_fixed(r.slope_v));
            blocks[g / 2][k + 8..k + 16].copy_from_slice(&to_fixed(r.offset_v));
            blocks[2 + g / 2][k..k + 8].copy_from_slice(&to_fixed(r.neg_slope_v));
            blocks[2 + g / 2][k + 8..k + 16].copy_from_slice(&to_fixed(r.center));
        }
        blocks
    }

    /// The voltage of stream code `code` on a channel of gain `gain`, V.
    pub fn volts(&self, gain: Gain, code: u16) -> f64 {
        let r = &self.ranges[usize::from(gain.index())];
        let c = f64::from(code);
        if c < r.center { (r.center - c) * r.neg_slope_v } else { (c - r.center) * r.slope_v }
    }

    /// The code the converter gives for `volts` on gain `gain` (the nearest, inverting [`volts`](Self::volts)), and
    /// whether the input lay beyond the codes' span (then the code is held at 0 or 65535). What a device (the mock
    /// U6) does when it digitises.
    ///
    /// # Errors
    /// [`U6Error::NonFiniteVolts`] for NaN or infinite `volts`.
    pub fn code(&self, gain: Gain, volts: f64) -> Result<(u16, bool), U6Error> {
        if !volts.is_finite() {
            return Err(U6Error::NonFiniteVolts { volts: volts.to_string() });
        }
        let r = &self.ranges[usize::from(gain.index())];
        let steps = if volts >= 0.0 { volts / r.slope_v } else { volts / -r.neg_slope_v };
        // Rounded about the center's whole part so that an integral center adds exactly (a 16-bit code and the
        // voltage's steps are then rounded as one number, as the converter's rule says).
        let base = r.center.floor();
        let code = base + (steps + (r.center - base)).round();
        let clipped = !(0.0..=65_535.0).contains(&code);
        // In range after the clamp, so the cast is exact.
        Ok((code.clamp(0.0, 65_535.0) as u16, clipped))
    }
}

/// Whether `code` is a rail (0 or 65535): the input may have been beyond the range.
pub fn is_rail(code: u16) -> bool {
    code == 0 || code == u16::MAX
}
