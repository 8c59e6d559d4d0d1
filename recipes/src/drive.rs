//! Drive signals: the excitation a protocol repeats, its compensated version for one actuator, and the playback
//! buffers (one per audio channel) that carry it, its loopback reference and silence.
//!
//! Everything is built at the DAQ's rate (where the deconvolution and the Kirkeby filters live) and converted to
//! the audio interface's rate by one band-limited interpolator, the same for the drive and the loopback, so that
//! whatever the conversion does to one it does to the other and the reference division cancels it.

use metaplate_core::rig::Wiring;
use metaplate_dsp::excitation::{ExcitationProtocol, Shot};
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::resample::Interpolator;
use metaplate_dsp::sweep::SweepSpec;

use crate::error::RecipeError;

/// Peak of a drive buffer, full scale: 1 dB below clipping, so that the interpolation to the audio rate (which can
/// overshoot between samples by a fraction of a percent) never reaches the rail.
pub const DRIVE_PEAK_FS: f64 = 0.89;

/// One actuator's playback, at the DAQ's rate before conversion: the drive (the repeated excitation through the
/// actuator's inverse filter, if any) and the loopback reference (the repeated excitation, delayed by the filter's
/// modelling delay so that the reference division removes that delay), both scaled alike.
#[derive(Debug, Clone, PartialEq)]
pub struct DrivePlayback {
    /// Signal for the actuator's channel, full scale, at the DAQ rate.
    pub drive: Vec<f64>,
    /// Signal for the loopback channel, full scale, at the DAQ rate.
    pub loopback: Vec<f64>,
    /// Scale applied to both so that the drive peaks at [`DRIVE_PEAK_FS`] (at most 1: a quiet drive is not
    /// amplified beyond the excitation's own amplitude).
    pub scale: f64,
}

impl DrivePlayback {
    /// Builds the playback of `repetitions` copies of `excitation` back to back, then `tail_samples` of silence,
    /// through `filter` (or raw when `None`), at the DAQ rate.
    ///
    /// # Errors
    /// [`RecipeError::Config`] for an empty excitation or zero repetitions; [`RecipeError::Dsp`] if filtering fails.
    pub fn new(
        excitation: &[f64],
        repetitions: usize,
        tail_samples: usize,
        filter: Option<&KirkebyFilter>,
    ) -> Result<Self, RecipeError> {
        if excitation.is_empty() || repetitions == 0 {
            return Err(RecipeError::Config(
                "a playback needs a non-empty excitation and at least 1 repetition".into(),
            ));
        }
        let total = repetitions * excitation.len() + tail_samples;
        let mut repeated: Vec<f64> = excitation.iter().copied().cycle().take(repetitions * excitation.len()).collect();
        repeated.resize(total, 0.0);
        let (mut drive, delay) = match filter {
            Some(f) => {
                let mut filtered = f.apply(&repeated)?;
                filtered.truncate(total);
                (filtered, f.modelling_delay_samples)
            }
            None => (repeated.clone(), 0),
        };
        let mut loopback = vec![0.0; delay.min(total)];
        loopback.extend_from_slice(&repeated[..total - loopback.len()]);
        let scale = peak_scale(&drive);
        drive.iter_mut().for_each(|v| *v *= scale);
        loopback.iter_mut().for_each(|v| *v *= scale);
        Ok(Self { drive, loopback, scale })
    }

    /// Duration of the playback, s, at `daq_rate_hz`.
    pub fn duration_s(&self, daq_rate_hz: f64) -> f64 {
        self.drive.len() as f64 / daq_rate_hz
    }

    /// The audio buffers (one per opened channel): the drive on `actuator`'s channel, the loopback on the loopback
    /// channel, silence elsewhere, converted from `daq_rate_hz` to the wiring's audio rate.
    ///
    /// Valid range: as [`DrivePlayback::at_audio_rate`].
    ///
    /// # Errors
    /// As [`DrivePlayback::at_audio_rate`].
    pub fn audio_buffers(
        &self,
        wiring: &Wiring,
        actuator: usize,
        daq_rate_hz: f64,
    ) -> Result<Vec<Vec<f64>>, RecipeError> {
        Ok(self.at_audio_rate(wiring, actuator, daq_rate_hz)?.buffers())
    }

    /// The drive and loopback converted to the wiring's audio rate, with the channels they go to.
    ///
    /// Valid range: `daq_rate_hz / audio_rate` within `[0.5, 2]` (the interpolator's range), and content below 0.4
    /// of the lower rate (true of every sweep here, which stops at a few hundred hertz).
    ///
    /// # Errors
    /// [`RecipeError::Config`] for an actuator the wiring does not have or rates out of range;
    /// [`RecipeError::Dsp`] from the interpolator.
    pub fn at_audio_rate(
        &self,
        wiring: &Wiring,
        actuator: usize,
        daq_rate_hz: f64,
    ) -> Result<AudioPlayback, RecipeError> {
        let channel = *wiring
            .actuator_channels
            .get(actuator)
            .ok_or_else(|| RecipeError::Config(format!("actuator {actuator} is not wired to an audio channel")))?;
        let mut converted = to_audio_rate(&[&self.drive, &self.loopback], wiring, daq_rate_hz)?.into_iter();
        let (Some(drive), Some(loopback)) = (converted.next(), converted.next()) else {
            return Err(RecipeError::Config("audio conversion lost a signal".into()));
        };
        Ok(AudioPlayback {
            channels: wiring.audio_channels as usize,
            drive_channel: channel as usize,
            loopback_channel: wiring.loopback_channel as usize,
            drive,
            loopback,
        })
    }
}

/// `signals` (all of one length, at `daq_rate_hz`) converted to the wiring's audio rate by one band-limited
/// interpolator.
///
/// Valid range: `daq_rate_hz / audio_rate` within `[0.5, 2]`, content below 0.4 of the lower rate.
///
/// # Errors
/// [`RecipeError::Config`] for rates out of range; [`RecipeError::Dsp`] from the interpolator.
pub(crate) fn to_audio_rate(
    signals: &[&[f64]],
    wiring: &Wiring,
    daq_rate_hz: f64,
) -> Result<Vec<Vec<f64>>, RecipeError> {
    let step = daq_rate_hz / wiring.audio_sample_rate_hz;
    if !(0.5..=2.0).contains(&step) {
        return Err(RecipeError::Config(format!(
            "the audio rate {} Hz must lie within 0.5 to 2 times the DAQ rate {daq_rate_hz} Hz",
            wiring.audio_sample_rate_hz
        )));
    }
    let interpolator = Interpolator::for_band(0.4 * daq_rate_hz.min(wiring.audio_sample_rate_hz), daq_rate_hz);
    signals
        .iter()
        .map(|signal| {
            let frames = (signal.len() as f64 / step).round() as usize;
            Ok(interpolator.resample(signal, 0.0, step, frames)?)
        })
        .collect()
}

/// The playback of a simultaneous protocol (every actuator in every shot, with a sign): each actuator's drive at
/// sign +1 (its delay, then the repeated excitation through its own inverse filter), and the loopback reference,
/// at the audio rate; shot `s` plays actuator `k`'s drive times the shot's gain.
///
/// Scaling: each drive is scaled on its own so that it peaks at [`DRIVE_PEAK_FS`] (at most 1), the loopback so
/// that it does; a response decoded against the loopback is then `loopback scale / drive scale` times the
/// actuator's (compensated) response, and [`SimultaneousPlayback::response_gain`] undoes it.
///
/// Filters with different modelling delays: every drive is delayed further by the difference to the largest
/// delay and the loopback by the largest, so that each response is referred to its own filter's target.
#[derive(Debug, Clone, PartialEq)]
pub struct SimultaneousPlayback {
    /// Output channels opened.
    pub channels: usize,
    /// Per actuator: (its audio channel, its drive at sign +1 at the audio rate, full scale).
    pub drives: Vec<(usize, Vec<f64>)>,
    /// Loopback channel and signal at the audio rate, full scale.
    pub loopback: (usize, Vec<f64>),
    /// Per shot, per actuator: the sign (+1 or -1) of its drive.
    pub signs: Vec<Vec<f64>>,
    /// Per actuator: multiply the response decoded against the loopback by this to get the response per full
    /// scale of the compensated drive (as the sequential [`DrivePlayback`] gives).
    pub response_gain: Vec<f64>,
    /// Samples per channel at the DAQ rate (drive, tail and all).
    pub daq_len: usize,
}

impl SimultaneousPlayback {
    /// Builds the playback of `protocol` for the wiring's actuators at `daq_rate_hz`, with `tail_samples` of silence
    /// after the last period, through `filters` (one per actuator, or raw when `None`).
    ///
    /// Valid range: a protocol whose shots all play every actuator with a gain of +1 or -1 and share their delays
    /// (Hadamard, interleaved); one filter per wired actuator; rates as [`DrivePlayback::at_audio_rate`].
    ///
    /// # Errors
    /// [`RecipeError::Config`] for a protocol outside that range, the wrong number of filters, or rates out of
    /// range; [`RecipeError::Dsp`] from the protocol, the filters or the interpolator.
    pub fn new(
        protocol: &ExcitationProtocol,
        wiring: &Wiring,
        daq_rate_hz: f64,
        tail_samples: usize,
        filters: Option<&[KirkebyFilter]>,
    ) -> Result<Self, RecipeError> {
        let actuators = wiring.actuator_channels.len();
        let shots = protocol.shots(actuators)?;
        let first = shots.first().ok_or_else(|| RecipeError::Config("the protocol has no shot".into()))?;
        let simultaneous = shots.iter().all(|s| s.delays_s == first.delays_s && s.gains.iter().all(|g| g.abs() == 1.0));
        if !simultaneous {
            return Err(RecipeError::Config(
                "a simultaneous playback needs every actuator in every shot, signed +/-1, with the same delays".into(),
            ));
        }
        if let Some(f) = filters
            && f.len() != actuators
        {
            return Err(RecipeError::Config(format!("{} filters for {actuators} actuators", f.len())));
        }
        let delays: Vec<usize> = (0..actuators).map(|k| filters.map_or(0, |f| f[k].modelling_delay_samples)).collect();
        let max_delay = delays.iter().copied().max().unwrap_or(0);
        let total = protocol.shot_len_samples(actuators, daq_rate_hz) + max_delay + tail_samples;
        let unit = unit_shot(first);
        let mut drives_daq = Vec::with_capacity(actuators);
        let mut drive_scales = Vec::with_capacity(actuators);
        for k in 0..actuators {
            let mut drive = vec![0.0; max_delay - delays[k]];
            drive.extend(protocol.drive(&unit, k, daq_rate_hz)?.unwrap_or_default());
            drive.resize(total, 0.0);
            let mut drive = match filters {
                Some(f) => {
                    let mut filtered = f[k].apply(&drive)?;
                    filtered.truncate(total);
                    filtered
                }
                None => drive,
            };
            let scale = peak_scale(&drive);
            drive.iter_mut().for_each(|v| *v *= scale);
            drives_daq.push(drive);
            drive_scales.push(scale);
        }
        let mut loopback = vec![0.0; max_delay];
        loopback.extend(protocol.reference(daq_rate_hz)?);
        loopback.resize(total, 0.0);
        let loopback_scale = peak_scale(&loopback);
        loopback.iter_mut().for_each(|v| *v *= loopback_scale);
        let mut all: Vec<&[f64]> = drives_daq.iter().map(Vec::as_slice).collect();
        all.push(&loopback);
        let mut converted = to_audio_rate(&all, wiring, daq_rate_hz)?;
        let loopback_audio = converted.pop().unwrap_or_default();
        let drives = wiring.actuator_channels.iter().map(|&c| c as usize).zip(converted).collect();
        Ok(Self {
            channels: wiring.audio_channels as usize,
            drives,
            loopback: (wiring.loopback_channel as usize, loopback_audio),
            signs: shots.iter().map(|s| s.gains.clone()).collect(),
            response_gain: drive_scales.iter().map(|s| loopback_scale / s).collect(),
            daq_len: total,
        })
    }

    /// The audio buffers of shot `shot` (one per opened channel); `None` for a shot the protocol does not have.
    pub fn buffers(&self, shot: usize) -> Option<Vec<Vec<f64>>> {
        let signs = self.signs.get(shot)?;
        let frames = self.loopback.1.len();
        let mut out = vec![vec![0.0; frames]; self.channels];
        for ((channel, drive), sign) in self.drives.iter().zip(signs) {
            out.get_mut(*channel)?.iter_mut().zip(drive).for_each(|(o, d)| *o += sign * d);
        }
        out.get_mut(self.loopback.0)?.copy_from_slice(&self.loopback.1);
        Some(out)
    }
}

/// `shot` with every gain +1: each actuator's drive at sign +1, with the shot's delays.
fn unit_shot(shot: &Shot) -> Shot {
    Shot { gains: vec![1.0; shot.gains.len()], delays_s: shot.delays_s.clone() }
}

/// The scale that makes `signal` peak at [`DRIVE_PEAK_FS`], at most 1 (1 for silence).
fn peak_scale(signal: &[f64]) -> f64 {
    let peak = signal.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if peak > 0.0 { (DRIVE_PEAK_FS / peak).min(1.0) } else { 1.0 }
}

/// A playback at the audio rate: the two signals that are not silence, and where they go.
#[derive(Debug, Clone, PartialEq)]
pub struct AudioPlayback {
    /// Output channels opened.
    pub channels: usize,
    /// Channel of the drive.
    pub drive_channel: usize,
    /// Channel of the loopback reference.
    pub loopback_channel: usize,
    /// The drive, full scale.
    pub drive: Vec<f64>,
    /// The loopback reference, full scale.
    pub loopback: Vec<f64>,
}

impl AudioPlayback {
    /// One buffer per channel: drive and loopback on theirs, silence elsewhere.
    pub fn buffers(&self) -> Vec<Vec<f64>> {
        (0..self.channels)
            .map(|c| {
                if c == self.drive_channel {
                    self.drive.clone()
                } else if c == self.loopback_channel {
                    self.loopback.clone()
                } else {
                    vec![0.0; self.drive.len()]
                }
            })
            .collect()
    }
}

/// The excitation of a protocol at the DAQ rate.
///
/// # Errors
/// [`RecipeError::Dsp`] for a sweep outside its valid range.
pub fn excitation(sweep: &SweepSpec, daq_rate_hz: f64) -> Result<Vec<f64>, RecipeError> {
    Ok(SweepSpec { sample_rate_hz: daq_rate_hz, ..*sweep }.generate()?)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Two actuators on channels 0 and 1, the loopback on 2, four channels opened; the paper's rates.
    pub(crate) fn wiring() -> Wiring {
        Wiring {
            actuator_channels: vec![0, 1],
            loopback_channel: 2,
            audio_channels: 4,
            audio_sample_rate_hz: 48_000.0,
            velocity_input: 0,
            loopback_input: 1,
            daq_range_v: 10.0,
            daq_sample_rate_hz: 24_000.0,
            loopback_volts_per_full_scale: 1.0,
        }
    }

    #[test]
    fn filter_delay_moves_the_loopback_and_scale_bounds_the_drive() {
        let x = vec![0.0, 1.0, -1.0, 0.5];
        let filter = KirkebyFilter {
            taps: vec![0.0, 0.0, 3.0],
            sample_rate_hz: 24_000.0,
            modelling_delay_samples: 2,
            max_boost_db: 0.0,
        };
        let p = DrivePlayback::new(&x, 2, 3, Some(&filter)).unwrap();
        assert_eq!(p.drive.len(), 11);
        // Drive peak 3 scaled to DRIVE_PEAK_FS; the loopback is the excitation delayed by 2, scaled alike.
        let scale = DRIVE_PEAK_FS / 3.0;
        assert!((p.scale - scale).abs() < 1e-15);
        for (i, (d, l)) in p.drive.iter().zip(&p.loopback).enumerate() {
            // Exact up to one rounding of the FFT convolution: 1e-12 is far above f64 rounding of 11 samples.
            assert!((d - 3.0 * l).abs() < 1e-12, "sample {i}: {d} vs {l}");
        }
        assert_eq!(p.loopback[2], 0.0);
        assert!((p.loopback[3] - scale).abs() < 1e-15);
        let raw = DrivePlayback::new(&x, 1, 0, None).unwrap();
        assert_eq!(raw.scale, DRIVE_PEAK_FS.min(1.0) / 1.0);
    }

    #[test]
    fn buffers_put_drive_and_loopback_on_their_channels_at_the_audio_rate() {
        let x = excitation(&SweepSpec { duration_s: 0.1, ..SweepSpec::default() }, 24_000.0).unwrap();
        let p = DrivePlayback::new(&x, 2, 100, None).unwrap();
        let buffers = p.audio_buffers(&wiring(), 1, 24_000.0).unwrap();
        assert_eq!(buffers.len(), 4);
        assert_eq!(buffers[1].len(), 2 * p.drive.len());
        assert!(buffers[0].iter().chain(&buffers[3]).all(|v| *v == 0.0));
        // Every other output sample lands on an input sample; the interpolator reproduces it to within its
        // accuracy for content below 0.03 of the rate (better than 1e-6, see dsp::resample).
        for k in (0..p.drive.len()).step_by(97) {
            assert!((buffers[1][2 * k] - p.drive[k]).abs() < 1e-6, "sample {k}");
            assert!((buffers[2][2 * k] - p.loopback[k]).abs() < 1e-6, "sample {k}");
        }
        assert!(p.audio_buffers(&wiring(), 2, 24_000.0).is_err());
    }
}
