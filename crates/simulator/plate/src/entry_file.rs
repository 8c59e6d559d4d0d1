//! The file of a cache entry ([`crate::entry`]), laid out so that a request reads only the blocks of its points.
//!
//! Format (little-endian, every field a 64-bit word): magic `MPGREEN2`; key; sample rate (f64); FFT length;
//! response length `ir_len`; representation (0 impulse responses, 1 band spectra); slot count; actuator count; bin
//! count; per bin its index, frequency (f64) and band gain (f64); per slot whether it is present (0 or 1) and its
//! block's checksum; the header's checksum (of every word before it, magic included). Then the blocks of the
//! present slots in slot order, each `actuators * words per pair` f64 (see [`crate::entry::EntryLayout`]).
//!
//! A reader checks the header against what it expects (key, rate, slot and actuator counts), the header's checksum
//! and the file's length, then seeks to each requested slot's block and checks its checksum and that its values
//! are finite: any mismatch makes the file a miss (it is recomputed and replaced), never a wrong answer. A file is
//! written to a temporary name of its writer's own, fsynced and renamed over the entry, so a reader never sees half
//! a file and concurrent writers of one entry (processes or threads) do not mix; a reader keeps the file it opened
//! even when a writer replaces it meanwhile.

use std::fs;
use std::io::{ErrorKind, Read, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use metaplate_dsp::fft;

use crate::entry::{EntryLayout, GreensEntry, Representation, Target};
use crate::error::PlateError;
use crate::greens::{GreensFunctions, GreensRequest, MAX_IR_SAMPLES, SpectralPlan};

const MAGIC: &[u8; 8] = b"MPGREEN2";

/// Words of the header before the bins: magic, key, rate, FFT length, `ir_len`, representation, slots, actuators,
/// bins.
const FIXED_WORDS: usize = 9;

/// What a reader expects of an entry's header: anything else is another entry (or a damaged file).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Expected {
    /// The entry's key ([`crate::cache_key`]).
    pub key: u64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Slots: the scene's grid points plus its actuators' driving points.
    pub slot_count: usize,
    /// The scene's actuators.
    pub actuator_count: usize,
}

/// What looking a request up in an entry file found.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Lookup {
    /// No usable file: absent, another entry's, truncated or damaged.
    Miss,
    /// A sound entry that does not hold one of the request's points or actuators (or the request's lists are
    /// empty): the request is not one the model can answer.
    NotServed,
    /// The request, cut from the entry.
    Hit(GreensFunctions),
}

/// A checksum of 64-bit words (FNV-1a over words): any change of one word changes it, since each step is a
/// bijection of the running value.
fn checksum(words: impl IntoIterator<Item = u64>) -> u64 {
    words.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, w| (h ^ w).wrapping_mul(0x0000_0100_0000_01b3))
}

/// The header's words, without its final checksum.
fn header_words(key: u64, entry: &GreensEntry, block_sums: &[u64]) -> Vec<u64> {
    let l = &entry.layout;
    let mut words = vec![
        u64::from_le_bytes(*MAGIC),
        key,
        l.sample_rate_hz.to_bits(),
        l.plan.fft_len as u64,
        l.plan.ir_len as u64,
        l.representation.code(),
        l.present.len() as u64,
        l.actuator_count as u64,
        l.plan.bins.len() as u64,
    ];
    words.extend(l.plan.bins.iter().flat_map(|&(k, f, g)| [k as u64, f.to_bits(), g.to_bits()]));
    let mut sums = block_sums.iter();
    for &present in &l.present {
        let sum = if present { sums.next().copied().unwrap_or(0) } else { 0 };
        words.extend([u64::from(present), sum]);
    }
    words
}

/// Distinguishes the temporary files of one process's concurrent writers (threads filling the same entry).
static TEMP_SERIAL: AtomicU64 = AtomicU64::new(0);

/// Writes `entry` under `key` to `path` atomically: a temporary name of its own (process id and a per-process
/// serial, so that two processes or threads filling the same entry at once never write one file), fsync, then
/// rename over the entry (a reader sees the old file, none, or the whole new one; the last writer wins with
/// identical content).
///
/// # Errors
/// [`PlateError::Cache`] when the file cannot be written.
pub(crate) fn write(path: &Path, key: u64, entry: &GreensEntry) -> Result<(), PlateError> {
    let block_words = entry.layout.block_words();
    let present_count = entry.layout.present.iter().filter(|&&p| p).count();
    let block_sums: Vec<u64> = (0..present_count)
        .map(|i| {
            let block = entry.data.get(i * block_words..(i + 1) * block_words).unwrap_or_default();
            checksum(block.iter().map(|v| v.to_bits()))
        })
        .collect();
    let mut header = header_words(key, entry, &block_sums);
    header.push(checksum(header.iter().copied()));
    let serial = TEMP_SERIAL.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp{}-{serial}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut out = std::io::BufWriter::with_capacity(1 << 20, fs::File::create(&tmp)?);
        for w in header.iter().copied().chain(entry.data.iter().map(|v| v.to_bits())) {
            out.write_all(&w.to_le_bytes())?;
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = fs::remove_file(&tmp);
        PlateError::cache(path, e)
    })
}

/// Reads `n` little-endian words; `Ok(None)` at the end of the file.
fn read_words(file: &mut fs::File, n: usize) -> std::io::Result<Option<Vec<u64>>> {
    let mut bytes = vec![0u8; n * 8];
    match file.read_exact(&mut bytes) {
        Ok(()) => Ok(Some(bytes.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect())),
        Err(e) if e.kind() == ErrorKind::UnexpectedEof => Ok(None),
        Err(e) => Err(e),
    }
}

/// An entry file's header.
struct Header {
    layout: EntryLayout,
    /// Bytes before the first block.
    len: u64,
    /// Per slot, its block's checksum (0 for an absent slot).
    block_sums: Vec<u64>,
}

/// The header of the entry file open in `file`; `Ok(None)` when it is not the expected entry or is damaged.
fn read_header(file: &mut fs::File, expected: &Expected) -> std::io::Result<Option<Header>> {
    let Some(fixed) = read_words(file, FIXED_WORDS)? else { return Ok(None) };
    let &[magic, key, rate, fft_len, ir_len, representation, slots, actuators, bins] = fixed.as_slice() else {
        return Ok(None);
    };
    let fits = |w: u64, max: usize| usize::try_from(w).ok().filter(|&v| v <= max);
    let (Some(fft_len), Some(slots), Some(actuators)) = (
        fits(fft_len, fft::MAX_FFT_LEN).filter(|&n| n > 0),
        fits(slots, expected.slot_count).filter(|&n| n == expected.slot_count),
        fits(actuators, expected.actuator_count).filter(|&n| n == expected.actuator_count),
    ) else {
        return Ok(None);
    };
    let (Some(ir_len), Some(bins), Some(representation)) = (
        fits(ir_len, MAX_IR_SAMPLES.min(fft_len)).filter(|&n| n > 0),
        fits(bins, fft::bin_count(fft_len)),
        Representation::from_code(representation),
    ) else {
        return Ok(None);
    };
    if magic != u64::from_le_bytes(*MAGIC) || key != expected.key || rate != expected.sample_rate_hz.to_bits() {
        return Ok(None);
    }
    let Some(rest) = read_words(file, 3 * bins + 2 * slots + 1)? else { return Ok(None) };
    let (body, sum) = rest.split_at(rest.len() - 1);
    if checksum(fixed.iter().chain(body).copied()) != sum[0] {
        return Ok(None);
    }
    let (bin_words, slot_words) = body.split_at(3 * bins);
    let plan_bins: Vec<(usize, f64, f64)> =
        bin_words.chunks_exact(3).map(|w| (w[0] as usize, f64::from_bits(w[1]), f64::from_bits(w[2]))).collect();
    if plan_bins.iter().any(|&(k, _, _)| k >= fft::bin_count(fft_len)) {
        return Ok(None);
    }
    let present: Vec<bool> = slot_words.chunks_exact(2).map(|w| w[0] == 1).collect();
    let block_sums: Vec<u64> = slot_words.chunks_exact(2).map(|w| w[1]).collect();
    let layout = EntryLayout {
        sample_rate_hz: expected.sample_rate_hz,
        plan: SpectralPlan { fft_len, ir_len, bins: plan_bins },
        representation,
        actuator_count: actuators,
        present,
    };
    Ok(Some(Header { layout, len: ((FIXED_WORDS + rest.len()) * 8) as u64, block_sums }))
}

/// Looks `request` up in the entry file at `path`: reads the header, then only the blocks of the request's points
/// (one seek each), and cuts the request from them (spectra synthesised on `threads` threads), on `target`'s plan
/// when given ([`EntryLayout::cut`]: an entry that cannot give its bins does not serve the request).
///
/// # Errors
/// [`PlateError::Cache`] when the file exists but cannot be read (not for a damaged one: that is a
/// [`Lookup::Miss`]); as [`EntryLayout::cut`].
pub(crate) fn lookup(
    path: &Path,
    expected: &Expected,
    request: &GreensRequest,
    target: Option<&Target>,
    threads: usize,
) -> Result<Lookup, PlateError> {
    let mut file = match fs::File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == ErrorKind::NotFound => return Ok(Lookup::Miss),
        Err(e) => return Err(PlateError::cache(path, e)),
    };
    let io = |e: std::io::Error| PlateError::cache(path, e);
    let file_len = file.metadata().map_err(io)?.len();
    let Some(Header { layout, len: header_len, block_sums }) = read_header(&mut file, expected).map_err(io)? else {
        return Ok(Lookup::Miss);
    };
    let block_words = layout.block_words();
    let block_bytes = (block_words * 8) as u64;
    let present_count = layout.present.iter().filter(|&&p| p).count() as u64;
    if file_len != header_len + present_count * block_bytes {
        return Ok(Lookup::Miss);
    }
    if !layout.serves(request) {
        return Ok(Lookup::NotServed);
    }
    let mut slots: Vec<usize> = request.points.clone();
    slots.sort_unstable();
    slots.dedup();
    let mut blocks: Vec<Vec<f64>> = Vec::with_capacity(slots.len());
    let mut rank = 0usize;
    let mut next = 0usize;
    for &slot in &slots {
        rank += layout.present[next..slot].iter().filter(|&&p| p).count();
        next = slot;
        file.seek(SeekFrom::Start(header_len + rank as u64 * block_bytes)).map_err(io)?;
        let Some(words) = read_words(&mut file, block_words).map_err(io)? else { return Ok(Lookup::Miss) };
        if checksum(words.iter().copied()) != block_sums[slot] {
            return Ok(Lookup::Miss);
        }
        let block: Vec<f64> = words.into_iter().map(f64::from_bits).collect();
        if !block.iter().all(|v| v.is_finite()) {
            return Ok(Lookup::Miss);
        }
        blocks.push(block);
    }
    let refs: Vec<&[f64]> =
        request.points.iter().map(|p| slots.binary_search(p).map_or(&[][..], |i| blocks[i].as_slice())).collect();
    Ok(layout.cut(request, &refs, target, threads)?.map_or(Lookup::NotServed, Lookup::Hit))
}
