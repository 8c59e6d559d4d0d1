//! Calibration constants: fixed point 32.32 as LabJackPython's `toDouble` reads it, blocks 0-3 as
//! `getCalibrationData` lays them out, and the conversion of `binaryToCalibratedAnalogVoltage`.

use metaplate_u6_protocol::calibration::{from_fixed, is_rail, to_fixed};
use metaplate_u6_protocol::{Calibration, Gain, U6Error};

use crate::hex;

#[test]
fn fixed_point_reads_as_labjackpython_does() {
    // Bytes made with Python's struct: round(-3.158058e-4 * 2**32) as '<q'; toDouble gives -0.00031580589711666107.
    let bytes: [u8; 8] = hex("a8 4d eb ff ff ff ff ff").try_into().unwrap();
    assert_eq!(from_fixed(bytes), -0.000_315_805_897_116_661_07);
    assert_eq!(to_fixed(-3.158058e-4), bytes);
    // Center 33523.0: integer part in bytes 4-7.
    assert_eq!(to_fixed(33_523.0), hex("00 00 00 00 f3 82 00 00").as_slice());
    // 10 / 32768 V per code is exact in 32.32 (1310720 / 2^32).
    assert_eq!(from_fixed(to_fixed(10.0 / 32_768.0)), 10.0 / 32_768.0);
}

#[test]
fn blocks_round_trip_and_are_laid_out_by_gain() {
    let cal = Calibration::nominal();
    let blocks = cal.to_blocks();
    // Block 0 bytes 16-23: AIN1vSlope (gain x10); block 2 bytes 8-15: AIN10vCenter.
    assert_eq!(from_fixed(blocks[0][16..24].try_into().unwrap()), from_fixed(to_fixed(3.1580578e-5)));
    assert_eq!(from_fixed(blocks[2][8..16].try_into().unwrap()), 33_523.0);
    let back = Calibration::from_blocks(&blocks).unwrap();
    for (a, b) in back.ranges.iter().zip(cal.ranges.iter()) {
        // Fixed point holds 2^-32 V: far below a 16-bit step of any range.
        assert!((a.slope_v - b.slope_v).abs() <= 2f64.powi(-32));
        assert_eq!(a.center, b.center);
    }
}

#[test]
fn an_erased_calibration_memory_is_refused() {
    let erased = [[0xffu8; 32]; 4];
    assert!(matches!(Calibration::from_blocks(&erased), Err(U6Error::BadCalibration { .. })));
}

#[test]
fn codes_convert_about_the_center_with_two_slopes() {
    let cal = Calibration::nominal();
    // binaryToCalibratedAnalogVoltage: (code - center) * slope above, (center - code) * negSlope below.
    assert_eq!(cal.volts(Gain::X1, 33_523), 0.0);
    assert_eq!(cal.volts(Gain::X1, 33_533), 10.0 * 3.158_057_8e-4);
    assert_eq!(cal.volts(Gain::X1, 33_513), 10.0 * -3.158_058e-4);
    // The nominal +/-10 V range is asymmetric: code 0 is -10.587 V, code 65535 is +10.109 V.
    assert!((cal.volts(Gain::X1, 0) + 10.5868).abs() < 1e-3);
    assert!((cal.volts(Gain::X1, 65_535) - 10.1094).abs() < 1e-3);
}

#[test]
fn digitising_inverts_the_conversion_to_half_a_step() {
    for cal in [Calibration::nominal(), Calibration::ideal()] {
        for gain in Gain::ALL {
            let step = cal.ranges[usize::from(gain.index())].slope_v;
            for k in -20..=20 {
                let v = f64::from(k) * 0.049 * gain.range_v();
                let (code, clipped) = cal.code(gain, v).unwrap();
                assert!(!clipped);
                assert!((cal.volts(gain, code) - v).abs() <= 0.5 * step * (1.0 + 1e-6), "{gain:?} {v}");
            }
            let (top, clipped) = cal.code(gain, 2.0 * gain.range_v()).unwrap();
            assert!(clipped && top == u16::MAX && is_rail(top));
            let (bottom, clipped) = cal.code(gain, -2.0 * gain.range_v()).unwrap();
            assert!(clipped && bottom == 0);
        }
    }
    assert!(matches!(Calibration::ideal().code(Gain::X1, f64::NAN), Err(U6Error::NonFiniteVolts { .. })));
}

#[test]
fn the_ideal_calibration_is_the_16_bit_rule_of_a_symmetric_range() {
    // What the mock lab's U6 carries: code = 32768 + round(v * 32768 / R), v = (code - 32768) * R / 32768, exactly.
    let cal = Calibration::ideal();
    for v in [0.0, 1.234_567, -9.999, 3.0517578125e-4 * 0.5, -0.7] {
        let (code, _) = cal.code(Gain::X1, v).unwrap();
        let old = (v * 32_768.0 / 10.0).round();
        assert_eq!(f64::from(code) - 32_768.0, old);
        assert_eq!(cal.volts(Gain::X1, code), old * 10.0 / 32_768.0);
    }
    assert_eq!(cal.code(Gain::X1, -10.0).unwrap(), (0, false));
    assert_eq!(cal.code(Gain::X1, 10.0).unwrap(), (u16::MAX, true));
}
