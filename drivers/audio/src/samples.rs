//! Sample formats of a sound card's streams and their conversion: full-scale `f32` to little-endian bytes for
//! playback, and back to full-scale values for capture. Pure functions, shared by both directions and fuzzed.

/// A sample format a stream can carry (playback or capture).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleFormat {
    /// 32-bit IEEE float, little-endian (`FLOAT_LE`): no conversion.
    F32,
    /// 32-bit signed integer, little-endian (`S32_LE`).
    S32,
    /// 24-bit signed integer in the low 3 bytes of a 32-bit little-endian word (`S24_LE`).
    S24,
    /// 24-bit signed integer packed in 3 bytes, little-endian (`S24_3LE`, common on USB interfaces).
    S24Packed,
    /// 16-bit signed integer, little-endian (`S16_LE`).
    S16,
}

impl SampleFormat {
    /// All formats, most preferred first.
    pub const PREFERENCE: [SampleFormat; 5] =
        [SampleFormat::F32, SampleFormat::S32, SampleFormat::S24, SampleFormat::S24Packed, SampleFormat::S16];

    /// Bytes per sample of one channel.
    pub fn bytes_per_sample(self) -> usize {
        match self {
            SampleFormat::F32 | SampleFormat::S32 | SampleFormat::S24 => 4,
            SampleFormat::S24Packed => 3,
            SampleFormat::S16 => 2,
        }
    }
}

/// Converts full-scale `f32` samples (|x| <= 1) to the little-endian bytes of `format`.
///
/// Valid range: any `f32`; values beyond +/-1 are clipped to full scale, NaN becomes 0 (the driver has already
/// refused non-finite buffers, so this only keeps the conversion total). Integer formats scale by the largest
/// positive code (so +1 maps to `2^(bits-1) - 1` and -1 to one above the most negative code) and round to nearest.
pub fn encode(samples: &[f32], format: SampleFormat) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(samples.len() * format.bytes_per_sample());
    for &sample in samples {
        let x = if sample.is_nan() { 0.0 } else { f64::from(sample).clamp(-1.0, 1.0) };
        match format {
            SampleFormat::F32 => bytes.extend_from_slice(&(x as f32).to_le_bytes()),
            SampleFormat::S32 => bytes.extend_from_slice(&to_int(x, 31).to_le_bytes()),
            SampleFormat::S24 => bytes.extend_from_slice(&to_int(x, 23).to_le_bytes()),
            SampleFormat::S24Packed => bytes.extend_from_slice(&to_int(x, 23).to_le_bytes()[..3]),
            SampleFormat::S16 => bytes.extend_from_slice(&to_int(x, 15).to_le_bytes()[..2]),
        }
    }
    bytes
}

/// Reads little-endian samples of `format` as full-scale values, the inverse of [`encode`]: integer codes over the
/// largest positive code (so that the most negative code reads a little below -1), floats as they are.
///
/// Valid range: any bytes; a trailing partial sample is ignored. A float sample that is not finite (no converter
/// writes one, but a device's bytes are not trusted) reads as 0.
pub fn decode(bytes: &[u8], format: SampleFormat) -> Vec<f64> {
    let width = format.bytes_per_sample();
    bytes
        .chunks_exact(width)
        .map(|b| match format {
            SampleFormat::F32 => {
                let x = f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                if x.is_finite() { x } else { 0.0 }
            }
            SampleFormat::S32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])) / f64::from(i32::MAX),
            // The low three bytes of the word, sign-extended from bit 23 (the top byte is padding).
            SampleFormat::S24 | SampleFormat::S24Packed => {
                f64::from(i32::from_le_bytes([0, b[0], b[1], b[2]]) >> 8) / f64::from((1 << 23) - 1)
            }
            SampleFormat::S16 => f64::from(i16::from_le_bytes([b[0], b[1]])) / f64::from(i16::MAX),
        })
        .collect()
}

/// `x` in [-1, 1] scaled to a signed integer of `magnitude_bits + 1` bits, rounded to nearest.
fn to_int(x: f64, magnitude_bits: i32) -> i32 {
    let full_scale = ((1_i64 << magnitude_bits) - 1) as f64;
    // |x| <= 1, so the product is within +/-full_scale and the cast cannot saturate.
    (x * full_scale).round() as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversion_hits_full_scale_codes_exactly() {
        // Exact: +/-1 and 0 are exactly representable and scale to integers.
        let samples = [1.0_f32, -1.0, 0.0, 2.0, -2.0, f32::NAN];
        let s16 = encode(&samples, SampleFormat::S16);
        let codes: Vec<i16> = s16.chunks_exact(2).map(|b| i16::from_le_bytes([b[0], b[1]])).collect();
        assert_eq!(codes, [32767, -32767, 0, 32767, -32767, 0]);
        let s32 = encode(&samples, SampleFormat::S32);
        let codes: Vec<i32> = s32.chunks_exact(4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        assert_eq!(codes, [i32::MAX, -i32::MAX, 0, i32::MAX, -i32::MAX, 0]);
        let s24 = encode(&samples[..2], SampleFormat::S24);
        assert_eq!(s24, [0xff, 0xff, 0x7f, 0x00, 0x01, 0x00, 0x80, 0xff]);
        let packed = encode(&samples[..2], SampleFormat::S24Packed);
        assert_eq!(packed, [0xff, 0xff, 0x7f, 0x01, 0x00, 0x80]);
        let float = encode(&[0.25, -3.0], SampleFormat::F32);
        assert_eq!(float, [0.25_f32.to_le_bytes(), (-1.0_f32).to_le_bytes()].concat());
    }

    #[test]
    fn conversion_rounds_to_nearest_code() {
        // 0.5 / 32767 of full scale is half a code: rounds away from zero; a third of a code rounds to 0.
        let half_code = (0.5 / 32767.0) as f32;
        let third_code = (1.0 / 3.0 / 32767.0) as f32;
        let s16 = encode(&[half_code * 1.001, third_code, -third_code], SampleFormat::S16);
        assert_eq!(s16, [1, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn decoding_inverts_encoding_to_a_code_and_reads_the_extremes() {
        let samples: Vec<f32> = vec![1.0, -1.0, 0.0, 0.5, -0.25, 0.123_456, -0.987_654];
        for (format, bits) in [
            (SampleFormat::F32, 24),
            (SampleFormat::S32, 31),
            (SampleFormat::S24, 23),
            (SampleFormat::S24Packed, 23),
            (SampleFormat::S16, 15),
        ] {
            let back = decode(&encode(&samples, format), format);
            assert_eq!(back.len(), samples.len());
            // Half a code of the format (f32's own 24-bit mantissa for floats) plus f32's rounding of the input.
            let code = 0.5 / f64::from((1_u32 << bits) - 1) + 1e-7;
            for (x, y) in samples.iter().zip(&back) {
                assert!((f64::from(*x) - y).abs() <= code, "{format:?}: {x} read back as {y}");
            }
            // Full scale reads exactly +/-1.
            assert_eq!((back[0], back[1]), (1.0, -1.0), "{format:?}");
        }
        // The most negative integer codes read a little below -1; a trailing partial sample is ignored; a float
        // that is not finite reads 0.
        assert!(decode(&i16::MIN.to_le_bytes(), SampleFormat::S16)[0] < -1.0);
        assert!(decode(&[0x00, 0x00, 0x80], SampleFormat::S24Packed)[0] < -1.0);
        assert_eq!(decode(&[1, 2, 3], SampleFormat::S16).len(), 1);
        let odd = [f32::NAN.to_le_bytes(), f32::INFINITY.to_le_bytes()].concat();
        assert_eq!(decode(&odd, SampleFormat::F32), [0.0, 0.0]);
    }
}
