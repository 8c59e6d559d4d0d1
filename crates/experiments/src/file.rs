//! The experiment file: pixels, stimuli, phases, order, responses, masking. The format is documented once, in the
//! crate docs ([`crate`]); this module parses and validates it.

use std::collections::BTreeMap;
use std::path::Path;

use metaplate_control::target::Waveform;
use metaplate_core::hash::fnv1a_64;
use metaplate_core::toml_locate::DocIndex;
use serde::{Deserialize, Serialize};

use crate::error::ExperimentError;

/// Prefix of [`Experiment::file_hash`] and the plan's hash: the hash algorithm's name.
pub const HASH_PREFIX: &str = "fnv1a64:";

/// One virtual pixel: where it is on the plate and what it is called.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pixel {
    /// Name (unique; `thumb`, `index`...).
    pub name: String,
    /// Position on the plate, m, from the plate's centre along its long axis (scene coordinates).
    pub x_m: f64,
    /// Position on the plate, m, across the plate.
    pub y_m: f64,
}

/// What one pixel does during one play of a stimulus; times from the play's start (plus `start_s`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Pattern {
    /// A train of `count` white-noise bursts of `burst_s`, each followed by `pause_s`.
    NoiseBursts {
        /// Burst length, s.
        burst_s: f64,
        /// Pause after each burst, s.
        pause_s: f64,
        /// Number of bursts (>= 1).
        count: u32,
        /// Delay of the first burst from the play's start, s.
        #[serde(default)]
        start_s: f64,
    },
    /// A train of `count` Hann-windowed sinusoidal wavelets of `wavelet_s` at `freq_hz`, each followed by `pause_s`.
    Wavelets {
        /// Carrier frequency, Hz.
        freq_hz: f64,
        /// Length of one wavelet, s (at least one cycle).
        wavelet_s: f64,
        /// Pause after each wavelet, s.
        pause_s: f64,
        /// Number of wavelets (>= 1).
        count: u32,
        /// Delay of the first wavelet from the play's start, s.
        #[serde(default)]
        start_s: f64,
    },
    /// A sinusoid of `freq_hz` for `duration_s`.
    Sine {
        /// Frequency, Hz.
        freq_hz: f64,
        /// Length, s.
        duration_s: f64,
        /// Delay from the play's start, s.
        #[serde(default)]
        start_s: f64,
    },
    /// A null target: vibration at the pixel is actively suppressed.
    Null,
}

/// A sequence over pixels: the same pattern at each named pixel in turn, `delay_s` apart (motion cues).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sequence {
    /// Pixel names in order of activation.
    pub pixels: Vec<String>,
    /// Delay between successive activations, s.
    pub delay_s: f64,
    /// What plays at each pixel (its `start_s` is added to the pixel's delay).
    pub pattern: Pattern,
}

/// One stimulus: one condition of the experiment, what plays at each pixel and which response is correct.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stimulus {
    /// Identifier (unique), journalled with every trial.
    pub id: String,
    /// The label of the correct response option.
    pub correct: String,
    /// What plays at each named pixel; pixels not named get null targets (suppressed).
    #[serde(default)]
    pub pixels: BTreeMap<String, Pattern>,
    /// A sequence over pixels, in addition to (and not overlapping) `pixels`.
    #[serde(default)]
    pub sequence: Option<Sequence>,
    /// How many times the stimulus plays per presentation (>= 1; the paper's experiment 3: 1 to 4 by speed).
    #[serde(default = "one")]
    pub plays: u32,
    /// Pause between plays, s.
    #[serde(default)]
    pub play_pause_s: f64,
}

fn one() -> u32 {
    1
}

/// A response option: what the experimenter enters and the key that enters it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResponseOption {
    /// Label (unique), as journalled.
    pub label: String,
    /// The console key (one character, unique).
    pub key: String,
}

/// The trial order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OrderMode {
    /// All conditions x repeats shuffled together (the paper's).
    Full,
    /// One block per repeat, each holding every condition once in its own random order.
    Blocked,
}

/// Order of the trials and the seed that draws it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Order {
    /// Full randomisation or blocks.
    pub mode: OrderMode,
    /// Default seed of the plan (a session may give its own; the plan records the one used).
    pub seed: u64,
}

/// The phases of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Phases {
    /// A familiarisation phase first: every stimulus once, in random order, unscored and unmarked to the
    /// participant.
    pub familiarisation: bool,
    /// Scored repeats of every condition (>= 1).
    pub repeats: u32,
}

/// Masking noise on a separate output pair (the paper: pink noise on headphones).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Masking {
    /// The noise's colour; only `pink` is defined.
    pub noise: String,
    /// Output channels of the audio interface (0-based), two distinct.
    pub channels: [u16; 2],
    /// Level, dB re full scale, as the noise's RMS (<= 0; pink noise peaks about 12 dB above it, so above about
    /// -12 dB FS it clips and is refused when played).
    pub level_dbfs: f64,
}

/// How a trial's presentation ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Presentation {
    /// Plays once; the participant may request repeats.
    Once,
    /// Repeats (after `repeat_pause_s`) until the response is entered (the paper's experiment 2).
    UntilResponse,
}

/// A parsed, validated experiment file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Name (`pixel-identification`).
    pub name: String,
    /// One line for people.
    pub description: String,
    /// Accuracy expected by guessing (0 < chance < 1), for the report's p values.
    pub chance: f64,
    /// How a presentation ends.
    pub presentation: Presentation,
    /// Pause before a repetition of the stimulus, s (until-response repeats and requested repeats).
    pub repeat_pause_s: f64,
    /// Whether trial times are of interest (reported per condition; experiment 2).
    #[serde(default)]
    pub record_trial_times: bool,
    /// The virtual pixels.
    pub pixels: Vec<Pixel>,
    /// The response options.
    pub responses: Vec<ResponseOption>,
    /// The stimuli, one per condition.
    pub stimuli: Vec<Stimulus>,
    /// The phases.
    pub phases: Phases,
    /// The order.
    pub order: Order,
    /// Masking noise, if any.
    #[serde(default)]
    pub masking: Option<Masking>,
}

/// Longest stimulus play the drive period is sized for, s: a longer one is a typo.
const MAX_PLAY_S: f64 = 60.0;

impl Experiment {
    /// Parses and validates an experiment from TOML text; `origin` (a path or a built-in's name) prefixes every
    /// error.
    ///
    /// # Errors
    /// [`ExperimentError::Syntax`] (not TOML) or [`ExperimentError::Invalid`] (unknown or missing key, wrong type,
    /// value out of range, a name that does not resolve), each with the line and key path.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self, ExperimentError> {
        let doc = DocIndex::parse(text, origin).map_err(ExperimentError::Syntax)?;
        let experiment: Experiment = toml::from_str(text).map_err(|e| ExperimentError::from(doc.schema_error(&e)))?;
        experiment.check().map_err(|(key_path, message)| ExperimentError::from(doc.invalid(key_path, message)))?;
        Ok(experiment)
    }

    /// Reads, parses and validates an experiment file.
    ///
    /// # Errors
    /// [`ExperimentError::Io`] when it cannot be read; otherwise as [`Experiment::from_toml_str`].
    pub fn load(path: &Path) -> Result<Self, ExperimentError> {
        let text = std::fs::read_to_string(path).map_err(ExperimentError::io("read", path))?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// The identity of the experiment's content: FNV-1a over its canonical JSON (fields in declaration order,
    /// maps sorted, floats in their shortest round-trip form), so comments and formatting do not change it.
    pub fn file_hash(&self) -> String {
        // Serialising plain data with string keys cannot fail; an empty string would still hash deterministically.
        let canonical = serde_json::to_string(self).unwrap_or_default();
        format!("{HASH_PREFIX}{:016x}", fnv1a_64(canonical.bytes()))
    }

    /// The stimulus with `id`.
    pub fn stimulus(&self, id: &str) -> Option<&Stimulus> {
        self.stimuli.iter().find(|s| s.id == id)
    }

    /// The index of the pixel named `name`.
    pub fn pixel_index(&self, name: &str) -> Option<usize> {
        self.pixels.iter().position(|p| p.name == name)
    }

    /// Response labels, in file order.
    pub fn labels(&self) -> Vec<&str> {
        self.responses.iter().map(|r| r.label.as_str()).collect()
    }

    /// Checks every rule of the format; the error is `(key path, reason)`.
    fn check(&self) -> Result<(), (String, String)> {
        let bad = |path: String, why: String| Err((path, why));
        if self.name.trim().is_empty() {
            return bad("name".into(), "must not be empty".into());
        }
        if !(self.chance.is_finite() && self.chance > 0.0 && self.chance < 1.0) {
            return bad(
                "chance".into(),
                format!("must be a fraction between 0 and 1 (exclusive), got {}", self.chance),
            );
        }
        non_negative("repeat_pause_s", self.repeat_pause_s)?;
        if self.pixels.is_empty() {
            return bad("pixels".into(), "at least one pixel is needed".into());
        }
        for (i, p) in self.pixels.iter().enumerate() {
            if p.name.trim().is_empty() {
                return bad(format!("pixels[{i}].name"), "must not be empty".into());
            }
            if self.pixels[..i].iter().any(|q| q.name == p.name) {
                return bad(format!("pixels[{i}].name"), format!("pixel `{}` is named twice", p.name));
            }
            for (key, v) in [("x_m", p.x_m), ("y_m", p.y_m)] {
                if !(v.is_finite() && v.abs() < 10.0) {
                    return bad(format!("pixels[{i}].{key}"), format!("must be a position in metres, got {v}"));
                }
            }
        }
        if self.responses.len() < 2 {
            return bad("responses".into(), "at least two response options are needed".into());
        }
        for (i, r) in self.responses.iter().enumerate() {
            if r.label.trim().is_empty() {
                return bad(format!("responses[{i}].label"), "must not be empty".into());
            }
            if self.responses[..i].iter().any(|q| q.label == r.label) {
                return bad(format!("responses[{i}].label"), format!("`{}` is an option twice", r.label));
            }
            if r.key.chars().count() != 1 {
                return bad(format!("responses[{i}].key"), format!("must be one character, got `{}`", r.key));
            }
            if self.responses[..i].iter().any(|q| q.key == r.key) {
                return bad(format!("responses[{i}].key"), format!("key `{}` enters two options", r.key));
            }
        }
        if self.stimuli.is_empty() {
            return bad("stimuli".into(), "at least one stimulus is needed".into());
        }
        for (i, s) in self.stimuli.iter().enumerate() {
            self.check_stimulus(i, s)?;
        }
        if self.phases.repeats == 0 {
            return bad("phases.repeats".into(), "must be at least 1".into());
        }
        if let Some(m) = &self.masking {
            if m.noise != "pink" {
                return bad("masking.noise".into(), format!("only `pink` is defined, got `{}`", m.noise));
            }
            if m.channels[0] == m.channels[1] {
                return bad("masking.channels".into(), "the two channels must differ".into());
            }
            if !(m.level_dbfs.is_finite() && m.level_dbfs <= 0.0) {
                return bad("masking.level_dbfs".into(), format!("must be <= 0 dB FS, got {}", m.level_dbfs));
            }
        }
        Ok(())
    }

    fn check_stimulus(&self, i: usize, s: &Stimulus) -> Result<(), (String, String)> {
        let at = |key: &str| format!("stimuli[{i}].{key}");
        if s.id.trim().is_empty() {
            return Err((at("id"), "must not be empty".into()));
        }
        if self.stimuli[..i].iter().any(|q| q.id == s.id) {
            return Err((at("id"), format!("stimulus `{}` is defined twice", s.id)));
        }
        if !self.responses.iter().any(|r| r.label == s.correct) {
            return Err((
                at("correct"),
                format!("`{}` is not a response option ({})", s.correct, self.labels().join(", ")),
            ));
        }
        if s.plays == 0 {
            return Err((at("plays"), "must be at least 1".into()));
        }
        non_negative(&at("play_pause_s"), s.play_pause_s)?;
        for (name, pattern) in &s.pixels {
            if self.pixel_index(name).is_none() {
                return Err((at(&format!("pixels.{name}")), format!("no pixel is named `{name}`")));
            }
            check_pattern(&at(&format!("pixels.{name}")), pattern)?;
        }
        if let Some(seq) = &s.sequence {
            if seq.pixels.len() < 2 {
                return Err((at("sequence.pixels"), "a sequence needs at least two pixels".into()));
            }
            for (j, name) in seq.pixels.iter().enumerate() {
                if self.pixel_index(name).is_none() {
                    return Err((at(&format!("sequence.pixels[{j}]")), format!("no pixel is named `{name}`")));
                }
                if seq.pixels[..j].contains(name) || s.pixels.contains_key(name) {
                    return Err((at(&format!("sequence.pixels[{j}]")), format!("pixel `{name}` is given twice")));
                }
            }
            if !(seq.delay_s.is_finite() && seq.delay_s > 0.0) {
                return Err((at("sequence.delay_s"), format!("must be positive, got {}", seq.delay_s)));
            }
            check_pattern(&at("sequence.pattern"), &seq.pattern)?;
            if seq.pattern.duration_s() > seq.delay_s + 1e-12 {
                return Err((
                    at("sequence.pattern"),
                    format!(
                        "lasts {} s, longer than the delay of {} s: the sequence's activations would overlap",
                        seq.pattern.duration_s(),
                        seq.delay_s
                    ),
                ));
            }
        }
        let sine =
            s.pixels.values().chain(s.sequence.as_ref().map(|q| &q.pattern)).any(|p| matches!(p, Pattern::Sine { .. }));
        if sine && s.plays > 1 {
            return Err((
                at("plays"),
                "a stimulus with a sine plays once (repeat it with `presentation = \"until-response\"` or on request)"
                    .into(),
            ));
        }
        if s.pixels.values().all(|p| *p == Pattern::Null) && s.sequence.is_none() {
            return Err((at("pixels"), "nothing plays: give at least one pixel a pattern other than null".into()));
        }
        let total = s.duration_s();
        if total > MAX_PLAY_S {
            return Err((at("plays"), format!("the presentation lasts {total} s, more than {MAX_PLAY_S} s")));
        }
        Ok(())
    }
}

fn non_negative(path: &str, v: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v >= 0.0 { Ok(()) } else { Err((path.to_owned(), format!("must be >= 0 s, got {v}"))) }
}

fn check_pattern(path: &str, p: &Pattern) -> Result<(), (String, String)> {
    let positive = |key: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err((format!("{path}.{key}"), format!("must be positive, got {v}")))
        }
    };
    let count_ok = |c: u32| if c >= 1 { Ok(()) } else { Err((format!("{path}.count"), "must be at least 1".into())) };
    match p {
        Pattern::NoiseBursts { burst_s, pause_s, count, start_s } => {
            positive("burst_s", *burst_s)?;
            non_negative(&format!("{path}.pause_s"), *pause_s)?;
            non_negative(&format!("{path}.start_s"), *start_s)?;
            count_ok(*count)
        }
        Pattern::Wavelets { freq_hz, wavelet_s, pause_s, count, start_s } => {
            positive("freq_hz", *freq_hz)?;
            positive("wavelet_s", *wavelet_s)?;
            non_negative(&format!("{path}.pause_s"), *pause_s)?;
            non_negative(&format!("{path}.start_s"), *start_s)?;
            if wavelet_s * freq_hz < 1.0 {
                return Err((
                    format!("{path}.wavelet_s"),
                    format!("a wavelet holds at least one cycle: {wavelet_s} s at {freq_hz} Hz is less"),
                ));
            }
            count_ok(*count)
        }
        Pattern::Sine { freq_hz, duration_s, start_s } => {
            positive("freq_hz", *freq_hz)?;
            positive("duration_s", *duration_s)?;
            non_negative(&format!("{path}.start_s"), *start_s)
        }
        Pattern::Null => Ok(()),
    }
}

impl Pattern {
    /// Time from the play's start to the pattern's end, s (0 for a null target). A train ends with its last
    /// element, not its last pause.
    pub fn duration_s(&self) -> f64 {
        match self {
            Self::NoiseBursts { burst_s, pause_s, count, start_s } => {
                start_s + f64::from(count.saturating_sub(1)) * (burst_s + pause_s) + burst_s
            }
            Self::Wavelets { wavelet_s, pause_s, count, start_s, .. } => {
                start_s + f64::from(count.saturating_sub(1)) * (wavelet_s + pause_s) + wavelet_s
            }
            Self::Sine { duration_s, start_s, .. } => start_s + duration_s,
            Self::Null => 0.0,
        }
    }

    /// The pattern's element start times over `plays` plays, `play_period_s` apart, delayed by `offset_s`.
    fn element_starts(&self, offset_s: f64, plays: u32, play_period_s: f64) -> Vec<f64> {
        let (count, step_s, start_s) = match self {
            Self::NoiseBursts { burst_s, pause_s, count, start_s } => (*count, burst_s + pause_s, *start_s),
            Self::Wavelets { wavelet_s, pause_s, count, start_s, .. } => (*count, wavelet_s + pause_s, *start_s),
            Self::Sine { start_s, .. } => (1, 0.0, *start_s),
            Self::Null => (0, 0.0, 0.0),
        };
        (0..plays)
            .flat_map(|p| {
                (0..count).map(move |k| offset_s + f64::from(p) * play_period_s + start_s + f64::from(k) * step_s)
            })
            .collect()
    }

    /// Control's waveform for this pattern over `plays` plays `play_period_s` apart, delayed by `offset_s`; noise
    /// drawn from `seed`. A sine plays once (validation refuses a sine in a stimulus of several plays: control's
    /// sine is one span).
    fn waveform(&self, offset_s: f64, plays: u32, play_period_s: f64, seed: u64) -> Waveform {
        let starts = self.element_starts(offset_s, plays, play_period_s);
        match self {
            Self::NoiseBursts { burst_s, .. } => Waveform::NoiseBursts { starts_s: starts, duration_s: *burst_s, seed },
            Self::Wavelets { freq_hz, wavelet_s, .. } => Waveform::WaveletTrain {
                freq_hz: *freq_hz,
                cycles: wavelet_s * freq_hz,
                times_s: starts.iter().map(|t| t + wavelet_s / 2.0).collect(),
            },
            Self::Sine { freq_hz, duration_s, start_s } => {
                Waveform::Sine { freq_hz: *freq_hz, start_s: offset_s + start_s, duration_s: *duration_s }
            }
            Self::Null => Waveform::Null,
        }
    }
}

/// What one pixel does over a whole presentation, as control's waveform.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelWaveforms {
    /// Index into [`Experiment::pixels`].
    pub pixel: usize,
    /// The pixel's target waveform; [`Waveform::Null`] for suppression.
    pub waveform: Waveform,
    /// True when this pixel carries what the participant must find (see [`Stimulus::target_pixels`]).
    pub target: bool,
}

impl Stimulus {
    /// Length of one play, s: the longest pattern, the sequence included.
    pub fn play_s(&self) -> f64 {
        let own = self.pixels.values().map(Pattern::duration_s).fold(0.0, f64::max);
        let seq = self
            .sequence
            .as_ref()
            .map_or(0.0, |s| (s.pixels.len().saturating_sub(1)) as f64 * s.delay_s + s.pattern.duration_s());
        own.max(seq)
    }

    /// Length of one presentation, s: every play and the pauses between them.
    pub fn duration_s(&self) -> f64 {
        let plays = f64::from(self.plays);
        plays * self.play_s() + (plays - 1.0).max(0.0) * self.play_pause_s
    }

    /// What the participant must find: the non-null pixels whose pattern occurs once among the stimulus's pixels
    /// (the active pixel among nulls; the odd one out among four alike); for a sequence, or when no pattern is
    /// unique, every non-null pixel. Pixel names, sorted.
    pub fn target_pixels(&self) -> Vec<&str> {
        if let Some(seq) = &self.sequence {
            let mut all: Vec<&str> = seq.pixels.iter().map(String::as_str).collect();
            all.extend(self.pixels.iter().filter(|(_, p)| **p != Pattern::Null).map(|(n, _)| n.as_str()));
            all.sort_unstable();
            return all;
        }
        let active: Vec<(&str, &Pattern)> =
            self.pixels.iter().filter(|(_, p)| **p != Pattern::Null).map(|(n, p)| (n.as_str(), p)).collect();
        let unique: Vec<&str> = active
            .iter()
            .filter(|(_, p)| self.pixels.values().filter(|q| *q == *p).count() == 1)
            .map(|(n, _)| *n)
            .collect();
        if unique.is_empty() { active.into_iter().map(|(n, _)| n).collect() } else { unique }
    }

    /// Control's waveform at every pixel of `experiment` for one presentation (all `plays`), with noise drawn
    /// from `seed`. Pixels the stimulus does not name are null targets.
    ///
    /// # Errors
    /// [`ExperimentError::Stimulus`] when the stimulus names a pixel `experiment` does not have (a stimulus of
    /// another file).
    pub fn waveforms(&self, experiment: &Experiment, seed: u64) -> Result<Vec<PixelWaveforms>, ExperimentError> {
        let period_s = self.play_s() + self.play_pause_s;
        let targets = self.target_pixels();
        let mut out: Vec<PixelWaveforms> = (0..experiment.pixels.len())
            .map(|pixel| PixelWaveforms { pixel, waveform: Waveform::Null, target: false })
            .collect();
        let mut place = |name: &str, waveform: Waveform| -> Result<(), ExperimentError> {
            let pixel = experiment.pixel_index(name).ok_or_else(|| ExperimentError::Stimulus {
                stimulus: self.id.clone(),
                reason: format!("no pixel `{name}` in experiment `{}`", experiment.name),
            })?;
            out[pixel] = PixelWaveforms { pixel, waveform, target: targets.contains(&name) };
            Ok(())
        };
        for (k, (name, pattern)) in self.pixels.iter().enumerate() {
            // Each pixel its own noise: bursts at different pixels are independent draws.
            place(name, pattern.waveform(0.0, self.plays, period_s, seed.wrapping_add(k as u64)))?;
        }
        if let Some(seq) = &self.sequence {
            for (j, name) in seq.pixels.iter().enumerate() {
                let offset_s = j as f64 * seq.delay_s;
                let seed = seed.wrapping_add((self.pixels.len() + j) as u64);
                place(name, seq.pattern.waveform(offset_s, self.plays, period_s, seed))?;
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
name = "tiny"
description = "two pixels"
chance = 0.5
presentation = "once"
repeat_pause_s = 0.5

[[pixels]]
name = "left"
x_m = -0.016
y_m = 0.0

[[pixels]]
name = "right"
x_m = 0.016
y_m = 0.0

[[responses]]
label = "left"
key = "1"

[[responses]]
label = "right"
key = "2"

[[stimuli]]
id = "at-left"
correct = "left"
pixels.left = { kind = "noise-bursts", burst_s = 0.025, pause_s = 0.075, count = 5 }

[[stimuli]]
id = "at-right"
correct = "right"
pixels.right = { kind = "noise-bursts", burst_s = 0.025, pause_s = 0.075, count = 5 }

[phases]
familiarisation = true
repeats = 3

[order]
mode = "full"
seed = 1
"#;

    fn parse(text: &str) -> Result<Experiment, ExperimentError> {
        Experiment::from_toml_str(text, "test.toml")
    }

    fn invalid(text: &str) -> (String, String, String) {
        match parse(text) {
            Err(ExperimentError::Invalid(l)) => (l.location, l.key_path, l.message),
            other => panic!("expected an invalid-file error, got {other:?}"),
        }
    }

    #[test]
    fn a_minimal_file_parses_and_its_hash_ignores_formatting() {
        let e = parse(MINIMAL).unwrap();
        assert_eq!(e.stimuli.len(), 2);
        assert_eq!(e.stimuli[0].target_pixels(), ["left"]);
        let reformatted = format!("# a comment\n{}", MINIMAL.replace("chance = 0.5", "chance    = 0.50"));
        assert_eq!(parse(&reformatted).unwrap().file_hash(), e.file_hash());
        let changed = MINIMAL.replace("count = 5 }\n\n[[stimuli]]", "count = 4 }\n\n[[stimuli]]");
        assert_ne!(parse(&changed).unwrap().file_hash(), e.file_hash());
        assert!(e.file_hash().starts_with(HASH_PREFIX));
    }

    #[test]
    fn errors_name_file_line_key_and_reason() {
        let (location, key, message) = invalid(&MINIMAL.replace("correct = \"right\"", "correct = \"up\""));
        assert_eq!(location, "test.toml:33:1");
        assert_eq!(key, "stimuli[1].correct");
        assert!(message.contains("`up` is not a response option"), "{message}");

        let (location, key, message) = invalid(&MINIMAL.replace(
            "burst_s = 0.025, pause_s = 0.075, count = 5 }\n\n[[stimuli]]",
            "burst_ms = 25, pause_s = 0.075, count = 5 }\n\n[[stimuli]]",
        ));
        assert!(location.starts_with("test.toml:29:"), "{location}");
        assert_eq!(key, "stimuli[0].pixels.left");
        assert!(message.contains("burst_ms"), "{message}");

        let (_, key, _) = invalid(&MINIMAL.replace("chance = 0.5", "chance = 1.5"));
        assert_eq!(key, "chance");
        let (_, key, message) = invalid(&MINIMAL.replace("pixels.right =", "pixels.middle ="));
        assert_eq!(key, "stimuli[1].pixels.middle");
        assert!(message.contains("no pixel is named `middle`"), "{message}");
        let (_, key, _) = invalid(&MINIMAL.replace("key = \"2\"", "key = \"1\""));
        assert_eq!(key, "responses[1].key");
        let (_, key, _) = invalid(&MINIMAL.replace("repeats = 3", "repeats = 0"));
        assert_eq!(key, "phases.repeats");
        let (_, key, _) = invalid(&MINIMAL.replace("burst_s = 0.025", "burst_s = -0.025"));
        assert_eq!(key, "stimuli[0].pixels.left.burst_s");
        assert!(matches!(parse("name = "), Err(ExperimentError::Syntax(_))));
        // A missing top-level key: no key path, and the message says which key.
        let missing = parse(&MINIMAL.replace("chance = 0.5\n", "")).unwrap_err().to_string();
        assert!(missing.starts_with("test.toml:") && missing.contains("missing key `chance`"), "{missing}");
    }

    #[test]
    fn sequences_must_not_overlap_and_map_to_delayed_bursts() {
        let seq = MINIMAL.replace(
            "pixels.right = { kind = \"noise-bursts\", burst_s = 0.025, pause_s = 0.075, count = 5 }",
            "sequence = { pixels = [\"left\", \"right\"], delay_s = 0.08, pattern = { kind = \"noise-bursts\", \
             burst_s = 0.05, pause_s = 0.0, count = 1 } }\nplays = 2\nplay_pause_s = 0.5",
        );
        let e = parse(&seq).unwrap();
        let s = &e.stimuli[1];
        assert!((s.play_s() - 0.13).abs() < 1e-12);
        assert!((s.duration_s() - (2.0 * 0.13 + 0.5)).abs() < 1e-12);
        let w = s.waveforms(&e, 9).unwrap();
        match &w[1].waveform {
            Waveform::NoiseBursts { starts_s, duration_s, .. } => {
                assert_eq!(*duration_s, 0.05);
                assert!((starts_s[0] - 0.08).abs() < 1e-12 && (starts_s[1] - (0.08 + 0.63)).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        let (_, key, message) = invalid(&seq.replace(
            "pattern = { kind = \"noise-bursts\", burst_s = 0.05, pause_s = 0.0, count = 1 }",
            "pattern = { kind = \"sine\", freq_hz = 90.0, duration_s = 0.05 }",
        ));
        assert_eq!(key, "stimuli[1].plays");
        assert!(message.contains("plays once"), "{message}");
        let (_, key, message) = invalid(&seq.replace("burst_s = 0.05", "burst_s = 0.1"));
        assert_eq!(key, "stimuli[1].sequence.pattern");
        assert!(message.contains("overlap"), "{message}");
    }
}
