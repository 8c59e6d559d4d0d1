//! A stimulus rendered once through the calibration and checked, ready to play: what a session plays on every trial
//! of its condition, and what `experiment stimuli` judges.
//!
//! Timing: a stimulus starts one impulse-response length into its drive (the lead the inverse filter needs to build
//! it) and the drive lasts one more after it (the plate's ring-down): the drive is `2 x IR + stimulus` long.

use std::path::PathBuf;

use metaplate_control::focus::{PixelSpec, RenderOptions, TargetSpec};
use metaplate_control::target::Waveform;
use metaplate_core::hash::fnv1a_64;
use metaplate_core::rig::Wiring;
use metaplate_recipes::play::{PreparedPattern, prepare};
use metaplate_store::Dataset;

use crate::error::ExperimentError;
use crate::file::{Experiment, HASH_PREFIX, Stimulus};
use crate::participant::FieldAtPixels;

/// How stimuli are driven: through the calibration in `calibration`, at `level` (full scale 1).
#[derive(Debug, Clone, PartialEq)]
pub struct DriveOptions {
    /// The calibration dataset the scan was measured through.
    pub calibration: PathBuf,
    /// Playback level relative to full scale.
    pub level: f64,
}

/// A stimulus rendered and checked, ready to play.
#[derive(Debug, Clone)]
pub struct PreparedStimulus {
    /// The drives, checked, and each pixel's predicted peak.
    pub pattern: PreparedPattern,
    /// `fnv1a64:` over the drive samples' bits and the level.
    pub drive_hash: String,
    /// What the simulated participant feels (m/s), `None` for a human participant.
    pub field: Option<FieldAtPixels>,
}

/// Renders `stimulus` of `experiment` (noise drawn from `seed`) from `dataset` through the calibration and prepares
/// it for a rig wired as `wiring` says; `for_sim`: also the field the simulated participant feels (the target
/// pixels alone against silence elsewhere).
///
/// # Errors
/// [`ExperimentError::Playback`]: a pixel off the plate or in a gap, a drive that would clip, a dataset that is not
/// a scan through this calibration; two pixels that snap to one measured point (the scan is too coarse); the
/// stimulus's waveforms.
pub fn prepare_stimulus(
    dataset: &Dataset,
    drive: &DriveOptions,
    experiment: &Experiment,
    stimulus: &Stimulus,
    seed: u64,
    wiring: &Wiring,
    for_sim: bool,
) -> Result<PreparedStimulus, ExperimentError> {
    let lead_s = dataset.ir_len() as f64 / dataset.sample_rate_hz();
    let options = RenderOptions { pad_s: Some(lead_s + stimulus.duration_s()), ..RenderOptions::default() };
    let pixels = stimulus.waveforms(experiment, seed)?;
    let mut specs = Vec::with_capacity(pixels.len());
    for pw in &pixels {
        let pixel = &experiment.pixels[pw.pixel];
        // One waveform per pixel: the experiment file refuses a stimulus that would need several (a sine played
        // more than once).
        let waveform = &pw.waveform;
        specs.push(PixelSpec {
            x_m: pixel.x_m,
            y_m: pixel.y_m,
            target: TargetSpec::Waveform(waveform.delayed(lead_s)),
            label: format!("{}: {}", pixel.name, waveform_kind(waveform)),
        });
    }
    let mut pattern = prepare(dataset, &specs, &drive.calibration, &options, wiring, drive.level)?;
    if let Some(m) = &experiment.masking {
        // Each stimulus its own masker, the same on every run of the plan's seed.
        let noise_seed = seed ^ fnv1a_64(stimulus.id.bytes());
        let ears = m.render(pattern.playback.frames(), wiring.audio_sample_rate_hz, noise_seed)?;
        for (channel, noise) in m.channels.iter().zip(&ears) {
            pattern.playback.add_output(u32::from(*channel), noise)?;
        }
    }
    // Two pixels on one measured point would be asked to do two things at once: the scan is too coarse for the
    // experiment's pixels.
    let name = |k: usize| experiment.pixels[pixels[k].pixel].name.as_str();
    for (i, a) in pattern.pixels.iter().enumerate() {
        if let Some(j) = pattern.pixels[..i].iter().position(|b| b.point_index == a.point_index) {
            return Err(ExperimentError::Playback(format!(
                "the pixels `{}` and `{}` snap to the same measured point ({}): the scan is too coarse for this \
                 experiment's pixels",
                name(j),
                name(i),
                a.point_index
            )));
        }
    }
    let bytes = pattern.rendered.signals.iter().flatten().flat_map(|v| v.to_bits().to_le_bytes());
    let drive_hash = format!("{HASH_PREFIX}{:016x}", fnv1a_64(bytes.chain(drive.level.to_bits().to_le_bytes())));
    let field = if for_sim {
        // The answer is about the target pixels: predict them alone against silence elsewhere (for a stimulus
        // whose other pixels are null already, that is the stimulus itself).
        let alone = specs
            .iter()
            .zip(&pixels)
            .map(|(s, pw)| {
                let target = if pw.target { s.target.clone() } else { TargetSpec::Waveform(Waveform::Null) };
                PixelSpec { target, ..s.clone() }
            })
            .collect::<Vec<_>>();
        let peaks_m_s: Vec<f64> = if alone.iter().zip(&specs).all(|(a, s)| a.target == s.target) {
            pattern.pixels.iter().map(|p| p.predicted_peak_mm_s * 1e-3).collect()
        } else {
            let probe = prepare(dataset, &alone, &drive.calibration, &options, wiring, drive.level)?;
            probe.pixels.iter().map(|p| p.predicted_peak_mm_s * 1e-3).collect()
        };
        let pick = |target: bool| -> Vec<f64> {
            pixels.iter().zip(&peaks_m_s).filter(|(pw, _)| pw.target == target).map(|(_, v)| *v).collect()
        };
        Some(FieldAtPixels { target_peak_m_s: pick(true), other_peak_m_s: pick(false) })
    } else {
        None
    };
    Ok(PreparedStimulus { pattern, drive_hash, field })
}

/// The kind of a waveform, for reports.
fn waveform_kind(w: &Waveform) -> &'static str {
    match w {
        Waveform::Impulse { .. } | Waveform::Impulses { .. } => "impulses",
        Waveform::Noise { .. } | Waveform::NoiseBursts { .. } => "noise-bursts",
        Waveform::Sine { .. } => "sine",
        Waveform::WaveletTrain { .. } => "wavelets",
        Waveform::Null => "null",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_waveform_kind_has_its_report_name() {
        assert_eq!(waveform_kind(&Waveform::Null), "null");
        assert_eq!(waveform_kind(&Waveform::Impulse { time_s: 0.1 }), "impulses");
    }
}
