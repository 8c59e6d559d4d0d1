//! Behavioural experiments on the display: the paper's four (Results, "Multi-Pixel Wave Focusing"; Materials and
//! Methods and Supplementary Methods, "Haptic Perception") and any other written as a file.
//!
//! - [`file`](mod@file): the experiment file (format below), parsed and validated through
//!   `metaplate_core::toml_locate` with file, line, key and reason, as scene files are; [`Experiment::file_hash`],
//!   FNV-1a over its canonical JSON (comments and formatting do not change it);
//! - [`builtin`]: the paper's four, `pixel-identification`, `odd-one-out-exploration`, `motion-direction`,
//!   `multi-touch-odd-one-out` (files in `crates/experiments/builtin/`; their pixels below);
//! - [`plan`]: the full trial plan from a file and a seed (familiarisation, then conditions x repeats, fully
//!   shuffled or blocked, drawn with `metaplate_core::rng::SplitMix64`), and its hash ([`Plan::hash`]);
//! - [`journal`]: a session's directory: `plan.json` stored durably (the store's `write_bytes`) before the first
//!   trial, and `journal.jsonl`, appended and fsync'd per entry; a correction, an undo or a void is a new line, a
//!   torn last line is tolerated and cut, voided trials are re-queued at the end; a resume with a different plan or
//!   file is refused unless forced;
//! - [`participant`]: the simulated participant, a documented psychometric model of the predicted field (logistic
//!   functions of the level above a vibrotactile threshold and of the target-to-others contrast, a lapse rate;
//!   options as `sim:seed=3,lapse=0.05`);
//! - [`masking`]: the masking noise, two independent pink noises (`metaplate_dsp::noise`), faded, at the file's
//!   level;
//! - [`stats`]: Wilson 95 % intervals, exact one-sided binomial p values against chance (with their log10),
//!   confusion matrices;
//! - [`lock`]: one writer per session; [`duplicates`]: trials a journal answers more than once; [`settle`]: a
//!   correction that settles one;
//! - [`stimulus`]: a stimulus rendered once through the calibration and checked, ready to play (recipes'
//!   `play::prepare`, with the experiment's control `Waveform`s as focus targets delayed by one impulse-response
//!   length);
//! - [`runner`]: one participant's session on a rig (`experiment run`): the plan stored before the first trial,
//!   each trial played, answered and journalled as it ends, answered by the simulated participant or the
//!   experimenter's console (a trait; [`console`] reads the terminal and the keypad, through
//!   `metaplate_keypad::Key::character`, on threads: a response key, `r` repeat, `u` undo, `v` void, `p` pause);
//! - [`report`]: the report of session directories (`experiment report`: accuracy, Wilson 95 %, exact p,
//!   confusion, trial times; its Parquet, [`trials_parquet`]); [`listing`]: the built-ins as `experiment list`
//!   prints them;
//! - [`stimuli`]: how well a scan renders experiments' stimuli (`experiment stimuli`: each pixel's predicted peak
//!   at its point and within a fingertip's reach, and the suppression; the rig's wiring read back from the dataset
//!   with `metaplate_recipes::recorded_wiring`).
//!
//! The rig itself is the caller's: the runner plays on the `Rig` it is handed. Nothing here links tokio or a real
//! device backend (`.ci/run` checks both with `cargo tree`).
//!
//! # The experiment file
//! TOML; SI units, the unit in each key's name (times in seconds, frequencies in hertz, positions in metres in the
//! scene's coordinates: from the plate's centre, x along its long axis). Every key is checked: an unknown key, a
//! missing key, a value of the wrong type or out of range, a name that does not resolve is an error naming the file,
//! line, key path and reason.
//!
//! | key | meaning |
//! |---|---|
//! | `name`, `description` | the experiment's name and one line for people |
//! | `chance` | accuracy by guessing, strictly between 0 and 1 (the report's p values are against it) |
//! | `presentation` | `"once"` (the participant may request repeats) or `"until-response"` (the stimulus repeats until the response is entered; the paper's experiment 2) |
//! | `repeat_pause_s` | pause before each repeat of the stimulus, s |
//! | `record_trial_times` | report trial times per condition (default false; experiment 2) |
//! | `[[pixels]]` `name`, `x_m`, `y_m` | the virtual pixels: unique names, positions |
//! | `[[responses]]` `label`, `key` | the response options: unique labels, one unique console key each |
//! | `[[stimuli]]` | one per condition: `id` (unique), `correct` (a response label), `pixels.NAME = PATTERN` for any pixels (pixels not named are **null targets**, actively suppressed), optionally `sequence = { pixels = [NAMES], delay_s, pattern = PATTERN }` (the same pattern at each pixel in turn, `delay_s` apart; must not overlap), `plays` (times the stimulus plays per presentation, default 1) and `play_pause_s` (between plays, default 0) |
//! | `[phases]` `familiarisation`, `repeats` | a familiarisation phase (every stimulus once, random order, unscored and unmarked to the participant), then `repeats` scored trials of every condition |
//! | `[order]` `mode`, `seed` | `"full"` (every trial shuffled together, the paper's) or `"blocked"` (one block per repeat, each condition once per block); the default seed of the plan |
//! | `[masking]` `noise`, `channels`, `level_dbfs` | optional masking noise on a separate output pair: `"pink"`, two distinct 0-based audio channels, level <= 0 dB FS |
//!
//! A `PATTERN` is an inline table with a `kind`:
//! - `{ kind = "noise-bursts", burst_s, pause_s, count, start_s = 0 }`: white-noise bursts, each followed by a pause;
//! - `{ kind = "wavelets", freq_hz, wavelet_s, pause_s, count, start_s = 0 }`: Hann-windowed sinusoidal wavelets of
//!   `wavelet_s` (at least one cycle), each followed by a pause;
//! - `{ kind = "sine", freq_hz, duration_s, start_s = 0 }`;
//! - `{ kind = "null" }`: suppression.
//!
//! These map onto `metaplate_control::target::Waveform` (`NoiseBursts`, `WaveletTrain` with `cycles = wavelet_s *
//! freq_hz` centred on each wavelet, `Sine`, `Null`), one per pixel; synthesis is control's. A stimulus with a sine
//! plays once (`plays = 1`): control's sine is one span.
//!
//! # The built-ins: where the pixels are, and two choices the paper leaves open
//! The five pixels are the fingertips of a right hand, palm down, 3.2 cm apart (the paper's interdigit spacing) in
//! a row along the plate's long axis through its centre: thumb, index, middle, ring and little finger at x = -6.4,
//! -3.2, 0, 3.2 and 6.4 cm, y = 0. That row lies inside the built-in metamaterial plate's resonator region (the
//! display: the 25 x 15 cm stadium inset by 1 cm) and at the same coordinates on the homogeneous plate; the
//! positions are not on the 5 mm grid, so a runner snaps each to its nearest measured point (at most 2.5 mm away).
//! Experiment 3 (`motion-direction`): the bursts are 50 ms long (the paper: "non-overlapping" at delays down to
//! 80 ms; 50 ms leaves a 30 ms gap at the fastest speed), and the sequence plays once at 640 ms, twice at 320 ms,
//! three times at 160 ms and four times at 80 ms (the paper: "replayed 1, 2, 3, or 4 times, depending on speed ...
//! to approximately compensate for the shorter stimulus duration at higher speeds"), 500 ms apart. The pause before
//! a repeat is 0.5 s in all four (the paper: "a brief pause"); masking is pink noise on channels 22 and 23 at
//! -20 dB FS RMS (the paper gives no level), played as [`masking`] says.

pub mod builtin;
pub mod console;
pub mod duplicates;
pub mod error;
pub mod file;
pub mod journal;
pub mod listing;
pub mod lock;
pub mod masking;
pub mod participant;
pub mod plan;
pub mod report;
pub mod runner;
pub mod settle;
pub mod stats;
pub mod stimuli;
pub mod stimulus;
mod trial;
pub mod trials_parquet;

pub use error::ExperimentError;
pub use file::{Experiment, Pattern, Pixel, Stimulus};
pub use journal::{Entry, Session, SessionRecord, TrialRecord};
pub use participant::{FieldAtPixels, SimParticipant};
pub use plan::{Phase, Plan, PlannedTrial};
