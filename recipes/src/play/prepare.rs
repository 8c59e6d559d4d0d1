//! A pattern rendered from a scan through its calibration, checked and ready to play: what `metaplate play` plays
//! and what an experiment's stimuli are (prepared, hence checked, before the first trial, and played one by one).
//!
//! Refusals (nothing played): a pixel off the plate or in a gap of the scan (control's `pixels`), a drive that would
//! clip at the level ([`RecipeError::Clipping`]), a dataset that is not a scan in m/s per full-scale drive (the
//! predicted velocity would have no physical unit), a scan measured through another calibration, a rig of another
//! plate ([`check_playable`]).

use std::fmt::Write as _;
use std::path::Path;

use metaplate_control::focus::{PixelSpec, RenderOptions, Rendered, render};
use metaplate_core::rig::{Rig, Wiring};
use metaplate_core::scene::SceneId;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_store::Dataset;
use serde::Serialize;

use super::{PatternPlayback, Played};
use crate::error::RecipeError;
use crate::plans::calibrate::Calibration;

/// The unit of a scan's impulse responses: what makes a predicted field a velocity at a level of full scale.
pub const SCAN_IR_UNIT: &str = "m/s per full-scale drive, through the calibration's inverse filters";

/// One pixel of a pattern and its predicted peak velocity at the pattern's level.
#[derive(Debug, Clone)]
pub struct PixelPrediction {
    /// The pixel as asked.
    pub spec: PixelSpec,
    /// The measured point it snapped to (grid flat index).
    pub point_index: u32,
    /// Peak of the predicted velocity over the playback, mm/s.
    pub predicted_peak_mm_s: f64,
}

/// A pattern rendered, checked (on the plate, no clipping) and ready to play on a rig of the given wiring.
#[derive(Debug, Clone)]
pub struct PreparedPattern {
    /// What control rendered.
    pub rendered: Rendered,
    /// The buffers at the level, and the loopback marker.
    pub playback: PatternPlayback,
    /// Each pixel's predicted peak velocity at the level.
    pub pixels: Vec<PixelPrediction>,
}

/// What `metaplate play --json` prints: the pattern and how it played (keys in alphabetical order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlayReport {
    /// Headroom of the buffers, dB (`None` for a silent pattern).
    pub clip_margin_db: Option<f64>,
    /// The pattern's length, s.
    pub duration_s: f64,
    /// Focus time of plain `impulse` targets, s after the onset.
    pub focus_s: f64,
    /// The recording has a gap.
    pub gap: bool,
    /// Measured minus scheduled onset, s.
    pub latency_s: f64,
    /// The level, relative to full scale.
    pub level: f64,
    /// Onset located on the loopback, s.
    pub measured_onset_s: f64,
    /// Each pixel's prediction.
    pub pixels: Vec<PixelReport>,
    /// Onset in the buffers, s.
    pub scheduled_onset_s: f64,
    /// Audio underruns.
    pub underruns: u32,
}

/// One pixel of a [`PlayReport`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PixelReport {
    /// The measured point it snapped to.
    pub point_index: u32,
    /// Peak predicted velocity at the level, mm/s.
    pub predicted_peak_mm_s: f64,
    /// The target as given.
    pub target: String,
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
}

/// Reads the calibration dataset in `dir` and returns the filters of `actuators` (the dataset's actuator numbers,
/// in its column order), checking their sample rate against `sample_rate_hz`.
///
/// # Errors
/// An unreadable calibration ([`RecipeError::PlayRefused`] naming it, with the reason); a filter at another rate.
pub fn calibration_filters(
    dir: &Path,
    actuators: &[u16],
    sample_rate_hz: f64,
) -> Result<Vec<KirkebyFilter>, RecipeError> {
    // Calibrations hold actuators 0..n: load as many as the highest the dataset uses.
    let wired = actuators.iter().map(|&a| usize::from(a) + 1).max().unwrap_or(0);
    let calibration = load(dir, wired)?;
    actuators
        .iter()
        .map(|&a| {
            let filter = calibration
                .filters
                .get(usize::from(a))
                .ok_or_else(|| RecipeError::Internal("calibration filter missing".into()))?;
            if (filter.sample_rate_hz - sample_rate_hz).abs() > 1e-9 * sample_rate_hz {
                return Err(refused(format!(
                    "the calibration {} is at {} Hz, the dataset at {sample_rate_hz} Hz",
                    dir.display(),
                    filter.sample_rate_hz
                )));
            }
            Ok(filter.clone())
        })
        .collect()
}

fn refused(reason: String) -> RecipeError {
    RecipeError::PlayRefused { reason }
}

fn load(dir: &Path, actuators: usize) -> Result<Calibration, RecipeError> {
    Calibration::load(dir, actuators).map_err(|e| refused(format!("reading the calibration {}: {e}", dir.display())))
}

/// Renders `specs` on `dataset` as control's [`render`] does, through the filters of the calibration dataset in
/// `calibration` when one is given: what `metaplate focus` writes.
///
/// # Errors
/// As [`calibration_filters`] and [`render`].
pub fn render_through(
    dataset: &Dataset,
    specs: &[PixelSpec],
    calibration: Option<&Path>,
    options: &RenderOptions,
) -> Result<Rendered, RecipeError> {
    let filters = match calibration {
        Some(dir) => Some(calibration_filters(dir, dataset.actuators(), dataset.sample_rate_hz())?),
        None => None,
    };
    Ok(render(dataset, specs, filters.as_deref(), options)?)
}

/// Renders `specs` on `dataset` through the calibration in `calibration` with `options`, and prepares them at
/// `level` (relative to full scale) for a rig wired as `wiring` says.
///
/// # Errors
/// A dataset that is not a scan through this calibration (its unit, its calibration hash), a pixel off the plate or
/// in a gap ([`RecipeError::Control`]), rendering errors, and a drive that would clip at `level`
/// ([`RecipeError::Clipping`]).
pub fn prepare(
    dataset: &Dataset,
    specs: &[PixelSpec],
    calibration: &Path,
    options: &RenderOptions,
    wiring: &Wiring,
    level: f64,
) -> Result<PreparedPattern, RecipeError> {
    check_scan_unit(dataset)?;
    // The responses hold the filters they were measured through: compensating with others would play a pattern
    // the prediction does not describe.
    let scanned_through = dataset.manifest().meta.config.get("calibration").and_then(|v| v.as_str());
    let wired = dataset.actuators().iter().map(|&a| usize::from(a) + 1).max().unwrap_or(0);
    let given = load(calibration, wired)?;
    if scanned_through != Some(given.content_hash.as_str()) {
        return Err(refused(format!(
            "the dataset was scanned through the calibration {}, not {} ({})",
            scanned_through.unwrap_or("(none recorded)"),
            calibration.display(),
            given.content_hash
        )));
    }
    let rendered = render_through(dataset, specs, Some(calibration), options)?;
    let playback =
        PatternPlayback::new(wiring, &rendered.signals, rendered.g.actuators(), dataset.sample_rate_hz(), level)?;
    let fields = rendered.field_at_pixels()?;
    let pixels = specs
        .iter()
        .zip(&rendered.points)
        .zip(&fields)
        .map(|((spec, &point_index), v)| PixelPrediction {
            spec: spec.clone(),
            point_index,
            predicted_peak_mm_s: 1e3 * level * v.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        })
        .collect();
    Ok(PreparedPattern { rendered, playback, pixels })
}

/// Refuses a dataset whose impulse responses are not in [`SCAN_IR_UNIT`]: without the calibration's filters in
/// them, a level of full scale has no velocity. An import of another tool's measurement (in m/s/N, say) is one.
fn check_scan_unit(dataset: &Dataset) -> Result<(), RecipeError> {
    let unit = dataset.manifest().meta.description.as_ref().map_or("unstated", |d| d.ir_unit.as_str());
    if unit == SCAN_IR_UNIT {
        return Ok(());
    }
    Err(refused(format!(
        "the dataset's impulse responses are in `{unit}`, not `{SCAN_IR_UNIT}`: play needs a scan measured through a \
         calibration, so that a level of full scale has a velocity (`metaplate focus` renders drive signals from any \
         dataset, for another player)"
    )))
}

/// Refuses, before a rig is touched, a dataset that cannot be played on a rig of the plate `rig_plate`: one that is
/// not a scan through a calibration (its unit), or one measured on another plate (the drives would focus nowhere).
///
/// # Errors
/// [`RecipeError::PlayRefused`] naming the dataset's unit and the one needed, or both plates.
pub fn check_playable(dataset: &Dataset, rig_plate: &SceneId) -> Result<(), RecipeError> {
    check_scan_unit(dataset)?;
    let measured_on = &dataset.manifest().meta.scene;
    if measured_on == rig_plate {
        return Ok(());
    }
    Err(refused(format!(
        "the dataset was measured on the plate `{}`, the rig is the plate `{}`: the drives would focus nowhere",
        measured_on.name, rig_plate.name
    )))
}

impl PreparedPattern {
    /// Plays the pattern on `rig` and measures its onset on the loopback.
    ///
    /// # Errors
    /// As [`PatternPlayback::play`]: device errors, a marker not found in the loopback.
    pub fn play(&self, rig: &mut Rig) -> Result<Played, RecipeError> {
        self.playback.play(rig)
    }

    /// What `metaplate play` prints for this pattern played on the plate `plate` as `played` says: the level, the
    /// headroom, the focus time, the onsets and latency, a warning for underruns or a gap, and each pixel's
    /// predicted peak (one line each).
    #[must_use]
    pub fn describe(&self, played: &Played, plate: &str) -> String {
        let mut out = String::new();
        let margin = self.playback.clip_margin_db().map_or("silent".into(), |db| format!("clip margin {db:.2} dB"));
        let _ = writeln!(
            out,
            "played {:.3} s on `{plate}` at level {} ({margin}); impulses focus {:.4} s after the onset",
            self.playback.duration_s, self.playback.level, self.rendered.focus_s
        );
        let _ = writeln!(
            out,
            "onset: scheduled {:.6} s, measured {:.6} s on the loopback, latency {:.3} ms",
            played.scheduled_onset_s,
            played.measured_onset_s,
            played.latency_s * 1e3
        );
        if played.underruns > 0 || played.gap {
            let _ = writeln!(out, "warning: {} audio underrun(s), recording gap: {}", played.underruns, played.gap);
        }
        for p in &self.pixels {
            let _ = writeln!(
                out,
                "pixel ({}, {}) {}: point {}, predicted peak {:.3} mm/s",
                p.spec.x_m, p.spec.y_m, p.spec.label, p.point_index, p.predicted_peak_mm_s
            );
        }
        out
    }

    /// The report `metaplate play --json` prints for this pattern played as `played` says.
    #[must_use]
    pub fn report(&self, played: &Played) -> PlayReport {
        let pixels = self
            .pixels
            .iter()
            .map(|p| PixelReport {
                point_index: p.point_index,
                predicted_peak_mm_s: p.predicted_peak_mm_s,
                target: p.spec.label.clone(),
                x_m: p.spec.x_m,
                y_m: p.spec.y_m,
            })
            .collect();
        PlayReport {
            clip_margin_db: self.playback.clip_margin_db(),
            duration_s: self.playback.duration_s,
            focus_s: self.rendered.focus_s,
            gap: played.gap,
            latency_s: played.latency_s,
            level: self.playback.level,
            measured_onset_s: played.measured_onset_s,
            pixels,
            scheduled_onset_s: played.scheduled_onset_s,
            underruns: played.underruns,
        }
    }
}
