//! `metaplate deconvolve`: impulse responses from a recorded WAV file and the excitation that produced it.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::{DeconvConfig, deconvolve, deconvolve_with_reference};

use crate::wav;

/// Arguments of `metaplate deconvolve`.
#[derive(Args)]
pub struct DeconvolveArgs {
    /// Recording (WAV, any channel count): the responses, and optionally the loopback reference.
    #[arg(long)]
    recording: PathBuf,
    /// Excitation as played (mono WAV, e.g. from `metaplate sweep`). Not needed with --reference-channel.
    #[arg(long)]
    excitation: Option<PathBuf>,
    /// Divide by this channel of the recording (1-based: the loopback) instead of by the excitation, so latency and
    /// clock offset between player and recorder cancel.
    #[arg(long)]
    reference_channel: Option<usize>,
    /// Impulse-response length, s.
    #[arg(long, default_value_t = 0.5)]
    ir_len_s: f64,
    /// Lower band edge, Hz (a raised-cosine skirt of 20 Hz lies below it).
    #[arg(long, default_value_t = 62.0)]
    band_lo_hz: f64,
    /// Upper band edge, Hz (a raised-cosine skirt of 50 Hz lies above it).
    #[arg(long, default_value_t = 625.0)]
    band_hi_hz: f64,
    /// Regularisation relative to the excitation's strongest in-band power.
    #[arg(long, default_value_t = 1e-3)]
    regularisation: f64,
    /// Output WAV (32-bit float): one impulse response per response channel.
    #[arg(long)]
    out: PathBuf,
}

/// Deconvolves every response channel and writes the impulse responses.
pub fn run(args: &DeconvolveArgs) -> anyhow::Result<()> {
    let (fs_hz, channels) = wav::read(&args.recording)?;
    if !(args.ir_len_s.is_finite() && args.ir_len_s > 0.0) {
        bail!("--ir-len-s must be positive, got {}", args.ir_len_s);
    }
    let cfg = DeconvConfig {
        sample_rate_hz: fs_hz,
        ir_len: (args.ir_len_s * fs_hz).round() as usize,
        band: Some(BandLimit::new(args.band_lo_hz, args.band_hi_hz, 20.0, 50.0)?),
        regularisation: args.regularisation,
        ..DeconvConfig::paper()
    };
    let irs = match (args.reference_channel, &args.excitation) {
        (Some(reference), _) => {
            let index = reference.checked_sub(1).filter(|&i| i < channels.len()).with_context(|| {
                format!("--reference-channel {reference}: the recording has channels 1 to {}", channels.len())
            })?;
            let reference = &channels[index];
            channels
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != index)
                .map(|(_, c)| deconvolve_with_reference(c, reference, &cfg))
                .collect::<Result<Vec<_>, _>>()?
        }
        (None, Some(path)) => {
            let (excitation_fs_hz, excitation) = wav::read(path)?;
            if excitation_fs_hz != fs_hz || excitation.len() != 1 {
                bail!("the excitation must be mono at the recording's rate ({fs_hz} Hz)");
            }
            channels.iter().map(|c| deconvolve(c, &excitation[0], &cfg)).collect::<Result<Vec<_>, _>>()?
        }
        (None, None) => bail!("give --excitation FILE or --reference-channel N"),
    };
    if irs.is_empty() {
        bail!("the recording has no response channel besides the reference");
    }
    wav::write_f32(&args.out, fs_hz, &irs)?;
    println!("wrote {} ({} impulse responses of {} samples)", args.out.display(), irs.len(), cfg.ir_len);
    Ok(())
}
