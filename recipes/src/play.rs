//! Playing a rendered pattern on the rig: every actuator's drive at a level relative to full scale, a timing
//! marker on the loopback, and the pattern's onset located in the recorded loopback. What `metaplate play` and an
//! experiment's trials run; no dataset is written.
//!
//! Timing: every channel starts with [`LEAD_S`] of silence; the marker (a short faded sweep) starts on the loopback
//! channel at the same audio frame as the drives, so its position in the DAQ's loopback input is the drives' onset
//! on the DAQ's clock, counted from the DAQ's start (which [`Rig::play_and_record`] issues just before the audio's).
//! The scheduled onset is [`LEAD_S`], the onset in the buffers handed to the audio interface; the measured one minus
//! it is the latency: the interface's output latency plus the time between the DAQ's and the audio's start. The
//! marker is located by cross-correlation with what was sent (dsp's `drift::locate_repetitions`, one copy).
//!
//! Clipping is checked on the buffers at the audio rate (the band-limited conversion can overshoot between the
//! source samples), before any device is touched: a pattern that would clip is refused and nothing is played.
//! There is no retry and no recovery: a failed playback is reported, and the caller decides.

use metaplate_core::audio::AudioConfig;
use metaplate_core::rig::{PlayRecordError, Rig, Wiring};
use metaplate_dsp::drift::locate_repetitions;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};

use crate::drive::{DRIVE_PEAK_FS, to_audio_rate};
use crate::engine::session::BLOCK_LEN_SAMPLES;
use crate::error::RecipeError;

mod prepare;
pub use prepare::{
    PixelPrediction, PixelReport, PlayReport, PreparedPattern, SCAN_IR_UNIT, calibration_filters, check_playable,
    prepare, render_through,
};

/// Silence before the onset on every channel, s: the marker's fade-in starts from silence, and the onset search
/// never looks before the recording's start.
pub const LEAD_S: f64 = 0.05;

/// The loopback marker's length, s: 1200 samples at 24 kHz, long enough for a sharp, unambiguous correlation peak.
const MARKER_S: f64 = 0.05;

/// The longest latency the recording covers, s (the marker must arrive within it): audio interfaces add a few to a
/// few hundred milliseconds.
pub const MAX_LATENCY_S: f64 = 0.5;

/// A pattern ready to play: the audio buffers at the requested level (checked not to clip) and the loopback marker
/// as the DAQ should record it.
#[derive(Debug, Clone, PartialEq)]
pub struct PatternPlayback {
    /// One buffer per opened audio channel, at the audio rate, full scale.
    buffers: Vec<Vec<f64>>,
    /// The marker at the DAQ rate (what the loopback input records, up to its scale and the latency).
    marker: Vec<f64>,
    /// The DAQ rate, Hz.
    daq_rate_hz: f64,
    /// The wiring the buffers were laid out for.
    wiring: Wiring,
    /// The level applied, relative to full scale.
    pub level: f64,
    /// Peak of the drive buffers at the audio rate, full scale (0 for a silent pattern).
    pub peak_fs: f64,
    /// The pattern's length, s (lead silence excluded).
    pub duration_s: f64,
}

/// What a playback did: the onset, scheduled and measured, and what went wrong in the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Played {
    /// Onset in the buffers handed to the audio interface, s ([`LEAD_S`]).
    pub scheduled_onset_s: f64,
    /// Onset located in the recorded loopback, s from the DAQ's start.
    pub measured_onset_s: f64,
    /// `measured_onset_s - scheduled_onset_s`, s.
    pub latency_s: f64,
    /// Audio underruns during the playback (silence inserted: the pattern did not play as rendered).
    pub underruns: u32,
    /// The recording has a gap (samples lost).
    pub gap: bool,
}

impl PatternPlayback {
    /// Prepares `drives` (one per entry of `actuators`, the dataset's actuator numbers, all at `sample_rate_hz`,
    /// full scale) at `level` for the rig wired as `rig_wiring` says, recording at `daq_rate_hz` (the wiring's).
    ///
    /// Valid range: `level` finite and > 0; rates within a factor 2 of the audio rate; drives of one length.
    ///
    /// # Errors
    /// [`RecipeError::Clipping`] when a drive would exceed full scale at `level`; [`RecipeError::Config`] for a
    /// level, an actuator or rates out of range, drives of different lengths, non-finite or in a different number
    /// than `actuators`; [`RecipeError::Dsp`] from the conversion or the marker.
    pub fn new(
        wiring: &Wiring,
        drives: &[Vec<f64>],
        actuators: &[u16],
        sample_rate_hz: f64,
        level: f64,
    ) -> Result<Self, RecipeError> {
        wiring.validate().map_err(RecipeError::Config)?;
        if !(level.is_finite() && level > 0.0) {
            return Err(RecipeError::Config(format!("the level must be finite and > 0, got {level}")));
        }
        if drives.len() != actuators.len() {
            return Err(RecipeError::Config(format!("{} drives for {} actuators", drives.len(), actuators.len())));
        }
        let len = drives.first().map_or(0, Vec::len);
        if drives.iter().any(|d| d.len() != len) || len == 0 {
            return Err(RecipeError::Config("the drives must be non-empty and of one length".into()));
        }
        if let Some(k) = drives.iter().position(|d| d.iter().any(|v| !v.is_finite())) {
            return Err(RecipeError::Config(format!("drive {k} holds a non-finite sample")));
        }
        let channels: Vec<usize> = actuators
            .iter()
            .map(|&a| {
                wiring.actuator_channels.get(usize::from(a)).map(|&c| c as usize).ok_or_else(|| {
                    RecipeError::Config(format!(
                        "actuator {a} is not wired to an audio channel (the rig has {})",
                        wiring.actuator_channels.len()
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let daq_rate_hz = wiring.daq_sample_rate_hz;
        let lead = |rate: f64| (LEAD_S * rate).round() as usize;
        let led: Vec<Vec<f64>> = drives
            .iter()
            .map(|d| {
                let mut v = vec![0.0; lead(sample_rate_hz)];
                v.extend(d.iter().map(|s| s * level));
                v
            })
            .collect();
        let refs: Vec<&[f64]> = led.iter().map(Vec::as_slice).collect();
        let audio_drives = to_audio_rate(&refs, wiring, sample_rate_hz)?;
        let peak_fs = audio_drives.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        if peak_fs > 1.0 {
            return Err(RecipeError::Clipping { level, peak_fs, max_level: level / peak_fs });
        }
        let marker = SweepSpec {
            kind: SweepKind::Linear,
            f1_hz: 200.0,
            f2_hz: 0.3 * daq_rate_hz.min(wiring.audio_sample_rate_hz),
            duration_s: MARKER_S,
            sample_rate_hz: daq_rate_hz,
            amplitude: DRIVE_PEAK_FS,
            fade_in_s: 0.002,
            fade_out_s: 0.002,
        }
        .generate()?;
        let mut loopback = vec![0.0; lead(daq_rate_hz)];
        loopback.extend_from_slice(&marker);
        let loopback_audio = to_audio_rate(&[&loopback], wiring, daq_rate_hz)?.pop().unwrap_or_default();
        let frames = audio_drives.iter().map(Vec::len).chain([loopback_audio.len()]).max().unwrap_or(0);
        let mut buffers = vec![vec![0.0; frames]; wiring.audio_channels as usize];
        for (channel, drive) in channels.iter().zip(audio_drives) {
            buffers[*channel][..drive.len()].copy_from_slice(&drive);
        }
        buffers[wiring.loopback_channel as usize][..loopback_audio.len()].copy_from_slice(&loopback_audio);
        Ok(Self {
            buffers,
            marker,
            daq_rate_hz,
            wiring: wiring.clone(),
            level,
            peak_fs,
            duration_s: len as f64 / sample_rate_hz,
        })
    }

    /// Frames of the playback at the audio rate (the lead, the pattern and the marker's end, whichever is last).
    pub fn frames(&self) -> usize {
        self.buffers.first().map_or(0, Vec::len)
    }

    /// Output channels the playback opens: the wiring's, or more when an added output lies beyond them.
    pub fn channels(&self) -> u32 {
        self.buffers.len() as u32
    }

    /// Adds `samples` (at the audio rate, full scale 1.0) on output `channel` beside the pattern, from the
    /// playback's first frame: an experiment's masking noise, for example. The playback then opens as many
    /// channels as its highest needs, beyond the wiring's `audio_channels` if need be (the interface must have
    /// them: its driver refuses otherwise). Samples past [`Self::frames`] are dropped; a shorter signal is followed
    /// by silence.
    ///
    /// # Errors
    /// [`RecipeError::Config`] for a channel the wiring drives (an actuator or the loopback) or one already added,
    /// a non-finite sample, or a sample beyond full scale (it would clip).
    pub fn add_output(&mut self, channel: u32, samples: &[f64]) -> Result<(), RecipeError> {
        let w = &self.wiring;
        if channel == w.loopback_channel || w.actuator_channels.contains(&channel) {
            return Err(RecipeError::Config(format!(
                "audio channel {channel} drives an actuator or the loopback: an added output needs a channel of its own"
            )));
        }
        if let Some(k) = samples.iter().position(|v| !v.is_finite()) {
            return Err(RecipeError::Config(format!(
                "the output for channel {channel} holds a non-finite sample at {k}"
            )));
        }
        if let Some(k) = samples.iter().position(|v| v.abs() > 1.0) {
            return Err(RecipeError::Config(format!(
                "the output for channel {channel} exceeds full scale at sample {k} ({}): it would clip",
                samples[k]
            )));
        }
        let frames = self.frames();
        let index = channel as usize;
        if index >= self.buffers.len() {
            self.buffers.resize(index + 1, vec![0.0; frames]);
        } else if self.buffers[index].iter().any(|&v| v != 0.0) {
            return Err(RecipeError::Config(format!("audio channel {channel} already has an output")));
        }
        let n = samples.len().min(frames);
        self.buffers[index][..n].copy_from_slice(&samples[..n]);
        Ok(())
    }

    /// Headroom left at the playback's peak, dB (`None` for a silent pattern).
    pub fn clip_margin_db(&self) -> Option<f64> {
        (self.peak_fs > 0.0).then(|| -20.0 * self.peak_fs.log10())
    }

    /// Plays the pattern on `rig` (configuring its DAQ and audio interface as the wiring says) and locates the
    /// onset in the recorded loopback.
    ///
    /// # Errors
    /// [`RecipeError::Config`] for a rig wired differently from the wiring this was prepared for; the devices'
    /// errors; [`RecipeError::Device`] when the marker is not found in the loopback (nothing looped back, or later
    /// than [`MAX_LATENCY_S`]).
    pub fn play(&self, rig: &mut Rig) -> Result<Played, RecipeError> {
        let wiring = &self.wiring;
        if rig.wiring != *wiring {
            return Err(RecipeError::Config("the rig is not wired as the pattern was prepared for".into()));
        }
        rig.daq.configure(&wiring.daq_config(BLOCK_LEN_SAMPLES))?;
        // As many channels as the buffers hold: the wiring's, and any added output beyond them.
        rig.audio.configure(&AudioConfig { channels: self.channels(), ..wiring.audio_config() })?;
        // The marker and the latency the recording must cover; the rest of the pattern plays on unrecorded.
        let record_samples = ((LEAD_S + MARKER_S + MAX_LATENCY_S) * self.daq_rate_hz).ceil() as usize;
        let recording = rig.play_and_record(&self.buffers, record_samples).map_err(|e| match e {
            PlayRecordError::Daq(e) => RecipeError::Daq(e),
            PlayRecordError::Audio(e) => RecipeError::Audio(e),
            other => RecipeError::Device(other.to_string()),
        })?;
        let position = locate_repetitions(&recording.loopback_v, &self.marker, 1, None, self.daq_rate_hz)
            .map_err(|e| RecipeError::Device(format!("the loopback marker was not found: {e}")))?;
        let measured_onset_s = position.first().copied().unwrap_or(f64::NAN) / self.daq_rate_hz;
        if !measured_onset_s.is_finite() {
            return Err(RecipeError::Internal("the located onset is not finite".into()));
        }
        // The marker starts `LEAD_S` into the loopback buffer (a whole number of DAQ samples at the usual rates).
        let scheduled_onset_s = (LEAD_S * self.daq_rate_hz).round() / self.daq_rate_hz;
        Ok(Played {
            scheduled_onset_s,
            measured_onset_s,
            latency_s: measured_onset_s - scheduled_onset_s,
            underruns: recording.underruns,
            gap: recording.gap,
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;
    use crate::drive::tests::wiring;

    /// Two drives peaking at 1 (a 200 Hz tone burst and its half).
    fn drives() -> Vec<Vec<f64>> {
        let tone: Vec<f64> = (0..2400).map(|i| (2.0 * std::f64::consts::PI * 200.0 * i as f64 / 24e3).sin()).collect();
        let peak = tone.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tone: Vec<f64> = tone.iter().map(|v| v / peak).collect();
        vec![tone.clone(), tone.iter().map(|v| 0.5 * v).collect()]
    }

    #[test]
    fn a_pattern_is_laid_on_its_channels_after_the_lead_with_the_marker_on_the_loopback() {
        let p = PatternPlayback::new(&wiring(), &drives(), &[1, 0], 24e3, 0.5).unwrap();
        assert_eq!(p.buffers.len(), 4);
        let lead = (LEAD_S * 48e3) as usize;
        let peak =
            |c: usize, range: std::ops::Range<usize>| p.buffers[c][range].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // The band-limited conversion rings a little before the tone's abrupt start.
        assert!(peak(1, 0..lead) < 0.01);
        assert!((peak(1, lead..p.buffers[1].len()) - 0.5).abs() < 0.01);
        assert!((peak(0, lead..p.buffers[0].len()) - 0.25).abs() < 0.01);
        assert_eq!(peak(3, 0..p.buffers[3].len()), 0.0);
        // The marker on the loopback channel (2).
        assert!(peak(2, lead..lead + 2400) > 0.5 && peak(2, 0..lead) < 1e-3);
        assert!((p.duration_s - 0.1).abs() < 1e-12);
        let margin = p.clip_margin_db().unwrap();
        assert!((margin - 20.0 * (1.0 / p.peak_fs).log10()).abs() < 1e-12 && margin > 5.0);
    }

    #[test]
    fn an_added_output_widens_the_playback_and_bad_ones_are_refused() {
        let mut p = PatternPlayback::new(&wiring(), &drives(), &[1, 0], 24e3, 0.5).unwrap();
        let frames = p.frames();
        let before = p.buffers.clone();
        // A masker on channels 6 and 7, beyond the wiring's 4: the playback opens 8; one longer than the
        // playback is cut, one shorter followed by silence.
        p.add_output(6, &vec![0.25; frames + 10]).unwrap();
        p.add_output(7, &[-0.5; 3]).unwrap();
        assert_eq!(p.buffers.len(), 8);
        assert!(p.buffers.iter().all(|b| b.len() == frames));
        assert_eq!(p.buffers[..4], before[..]);
        assert!(p.buffers[4..6].iter().flatten().all(|&v| v == 0.0));
        assert!(p.buffers[6].iter().all(|&v| v == 0.25));
        assert_eq!(p.buffers[7][..4], [-0.5, -0.5, -0.5, 0.0]);
        for (channel, samples, needle) in [
            (2, vec![0.1], "drives an actuator or the loopback"),
            (0, vec![0.1], "drives an actuator or the loopback"),
            (6, vec![0.1], "already has an output"),
            (5, vec![0.1, f64::NAN], "non-finite sample at 1"),
            (5, vec![0.1, 1.5], "would clip"),
        ] {
            let err = p.add_output(channel, &samples).unwrap_err();
            assert!(err.to_string().contains(needle), "{err}");
        }
        assert_eq!(p.buffers.len(), 8);
    }

    #[test]
    fn a_level_that_clips_is_refused_from_the_wiring_alone() {
        // No rig is involved: nothing can have been played.
        let err = PatternPlayback::new(&wiring(), &drives(), &[0, 1], 24e3, 1.5).unwrap_err();
        let RecipeError::Clipping { level, peak_fs, max_level } = err else { panic!("{err}") };
        assert_eq!(level, 1.5);
        assert!(peak_fs > 1.0 && (max_level * peak_fs / level - 1.0).abs() < 1e-12);
        assert!(PatternPlayback::new(&wiring(), &drives(), &[0, 1], 24e3, max_level).is_ok());
    }

    #[test]
    fn bad_inputs_are_refused_by_name() {
        let w = wiring();
        for (drives, actuators, level, needle) in [
            (drives(), vec![0, 7], 0.5, "actuator 7"),
            (drives(), vec![0], 0.5, "2 drives for 1 actuators"),
            (drives(), vec![0, 1], f64::NAN, "level"),
            (vec![vec![0.0; 3], vec![0.0; 4]], vec![0, 1], 0.5, "one length"),
            (vec![vec![0.0; 3], vec![f64::NAN; 3]], vec![0, 1], 0.5, "drive 1 holds a non-finite sample"),
        ] {
            let err = PatternPlayback::new(&w, &drives, &actuators, 24e3, level).unwrap_err();
            assert!(err.to_string().contains(needle), "{err}");
        }
        // A silent pattern plays (the marker alone) and has no clipping margin to report.
        let silent = PatternPlayback::new(&w, &[vec![0.0; 100]], &[1], 24e3, 0.5).unwrap();
        assert_eq!(silent.clip_margin_db(), None);
    }
}
