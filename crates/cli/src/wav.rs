//! WAV files for the command line: the store's reader and writer ([`metaplate_store::read_wav`],
//! [`metaplate_store::write_wav_f32`]), plus what a command needs on top: an `--out` may name a folder that does not
//! exist yet.

use std::path::Path;

use anyhow::Context;

/// Writes `channels` (equal lengths) as an interleaved 32-bit float WAV at `sample_rate_hz`, creating the file's
/// folder when missing.
pub fn write_f32(path: &Path, sample_rate_hz: f64, channels: &[Vec<f64>]) -> anyhow::Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    Ok(metaplate_store::write_wav_f32(path, channels, sample_rate_hz)?)
}

/// Reads a WAV file into its sample rate in Hz and one f64 vector per channel, scaled to +/-1 full scale.
pub fn read(path: &Path) -> anyhow::Result<(f64, Vec<Vec<f64>>)> {
    Ok(metaplate_store::read_wav(path)?)
}
