//! Fuzzes the cassette decoder with arbitrary bytes, split at arbitrary points.
//!
//! Input: byte 0 gives the number of cuts `n` (bits 0..3, 0..=7) and a reseal flag (bit 3); the next `2n` bytes
//! give the cut positions (u16 LE, taken modulo the payload length + 1); the rest is the cassette. With the reseal
//! flag, the target first rewrites every CRC it can locate, so that the fuzzer also explores what lies behind the
//! checksums (payload parsing, timestamps, counts). Asserts that the decoder
//! - never panics;
//! - keeps its buffer under `MAX_RECORD_LEN` after each drained push, and its heap (buffer and frames, measured
//!   by a counting allocator) under a bound proportional to the input, whatever lengths the bytes claim;
//! - gives the same results however the input is split;
//! - yields only records that the encoder accepts, and that decode back unchanged and without error.
#![no_main]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use libfuzzer_sys::fuzz_target;
use metaplate_cassette::{Cassette, CassetteError, Decoder, END_SYNC, Frame, MAX_RECORD_LEN, RECORD_SYNC, TRAILER_LEN};

/// Counts live heap bytes and their peak, so the target can check what decoding allocates.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged; only counts sizes on the side.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let live = LIVE.fetch_add(new_size, Ordering::Relaxed) + new_size;
        PEAK.fetch_max(live, Ordering::Relaxed);
        let out = unsafe { System.realloc(ptr, layout, new_size) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        out
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Splits the fuzz input into cut positions, the reseal flag and the cassette bytes.
fn plan(data: &[u8]) -> (Vec<usize>, bool, &[u8]) {
    let Some((&first, rest)) = data.split_first() else { return (vec![0, 0], false, data) };
    let n = usize::from(first % 8).min(rest.len() / 2);
    let (cut_bytes, input) = rest.split_at(2 * n);
    let mut cuts: Vec<usize> =
        cut_bytes.chunks_exact(2).map(|c| usize::from(u16::from_le_bytes([c[0], c[1]])) % (input.len() + 1)).collect();
    cuts.push(0);
    cuts.push(input.len());
    cuts.sort_unstable();
    (cuts, first & 8 != 0, input)
}

/// Rewrites the CRC-32 stored in `bytes[end - 4..end]` to match `bytes[start..end - 4]`, if `end` is in range.
fn seal(bytes: &mut [u8], start: usize, end: usize) {
    if start + 4 <= end && end <= bytes.len() {
        let crc = crc32fast::hash(&bytes[start..end - 4]);
        bytes[end - 4..end].copy_from_slice(&crc.to_le_bytes());
    }
}

/// Walks the layout as far as the bytes follow it (header length, record lengths) and fixes every CRC met.
fn reseal(bytes: &mut [u8]) {
    let u32_at = |b: &[u8], at: usize| b.get(at..at + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]));
    let Some(h) = bytes.get(12..14).map(|s| usize::from(u16::from_le_bytes([s[0], s[1]]))) else { return };
    seal(bytes, 0, h);
    let mut at = h;
    while let Some(sync) = bytes.get(at..at + 4) {
        if sync == RECORD_SYNC {
            seal(bytes, at, at + 23);
            let Some(len) = u32_at(bytes, at + 15) else { return };
            let end = at + 27 + len as usize;
            seal(bytes, at, end);
            at = end;
        } else if sync == END_SYNC {
            seal(bytes, at, at + TRAILER_LEN);
            at += TRAILER_LEN;
        } else {
            return;
        }
    }
}

/// Decodes `input` pushed in the pieces between consecutive `cuts`, checking the buffer bound on the way.
fn decode(input: &[u8], cuts: &[usize], mut each: impl FnMut(Result<Frame, CassetteError>)) {
    let mut decoder = Decoder::new();
    for pair in cuts.windows(2) {
        decoder.push(&input[pair[0]..pair[1]]);
        decoder.frames().for_each(&mut each);
        assert!(decoder.buffered_len() < MAX_RECORD_LEN, "buffer {} over its bound", decoder.buffered_len());
    }
    decoder.finish();
    decoder.frames().for_each(&mut each);
    assert!(decoder.poll().is_none(), "results after the end");
}

fuzz_target!(|data: &[u8]| {
    let (cuts, resealed, input) = plan(data);
    let mut owned;
    let input = if resealed {
        owned = input.to_vec();
        reseal(&mut owned);
        &owned[..]
    } else {
        input
    };

    // Memory: the buffer (grown by doubling) plus one frame's copy of its payload, whatever the lengths claim.
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    decode(input, &cuts, drop);
    let peak = PEAK.load(Ordering::Relaxed) - base;
    assert!(peak <= 4 * input.len() + (64 << 10), "decoding {} bytes used {peak} bytes of heap", input.len());

    // Split independence: the same results as one push.
    let mut split = Vec::new();
    decode(input, &cuts, |r| split.push(r));
    let mut whole = Vec::new();
    decode(input, &[0, input.len()], |r| whole.push(r));
    assert_eq!(format!("{split:?}"), format!("{whole:?}"));

    // Whatever was decoded re-encodes, and the re-encoding decodes to the same, cleanly.
    let Some(Ok(Frame::Header(header))) = split.first() else { return };
    let records = split
        .iter()
        .filter_map(|r| match r {
            Ok(Frame::Record(record)) => Some(record.clone()),
            _ => None,
        })
        .collect();
    let cassette = Cassette { header: header.clone(), records };
    let bytes = match cassette.to_bytes() {
        Ok(bytes) => bytes,
        Err(error) => panic!("a decoded cassette does not re-encode: {error}"),
    };
    match Cassette::from_bytes(&bytes) {
        Ok(back) => assert_eq!(back, cassette),
        Err(error) => panic!("a re-encoded cassette does not decode: {error}"),
    }
});
