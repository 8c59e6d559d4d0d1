//! How well a scan renders experiments' stimuli, before anyone touches the plate (`metaplate experiment stimuli`).
//! Each stimulus is rendered as a session renders it ([`prepare_stimulus`]: through the calibration, at the level),
//! and the predicted peak velocity at each of its pixels is reported: at the target pixels (what the participant
//! must find), at the null pixels (actively suppressed) and at the others (a distractor's pattern), at the pixel's
//! point and within a fingertip's reach of it (a null is met at a point, and beside it the field can be large where
//! waves are long). The suppression is the weakest target's peak at its point over the strongest null's within
//! reach, in dB.
//!
//! The prediction is the scan's: `G` measured through the calibrated actuators, the drives peak-normalised to the
//! level as played. With a [`Truth`] (the mock lab's plate the scan was made on), each stimulus is also played
//! through the plate's true response, and the true figures stand beside the predicted ones.

use std::io::Write;
use std::path::PathBuf;

use metaplate_control::focus::Rendered;
use metaplate_control::pixels::{on_plate, snap_pixel};
use metaplate_control::target::Waveform;
use metaplate_figures::{PixelRole, PixelTrace, StimulusPanel};
use metaplate_recipes::recorded_wiring;
use metaplate_store::{Dataset, SceneId};
use serde::Serialize;

use crate::error::ExperimentError;
use crate::file::{Experiment, PixelWaveforms, Stimulus};
use crate::stimulus::{DriveOptions, prepare_stimulus};

/// The true velocity at a measured point when the given actuators play the given drives (full scale) at the given
/// rate, m/s: `(point, actuators, drives, sample_rate_hz)`. The binary hands in the mock lab's.
pub type TrueVelocity<'a> = &'a dyn Fn(usize, &[usize], &[Vec<f64>], f64) -> Result<Vec<f64>, String>;

/// The ground truth a stimulus is judged by.
pub struct Truth<'a> {
    /// Per experiment, per pixel, the measured points within reach (the pixel's own point first).
    pub reach: Vec<Vec<Vec<u32>>>,
    /// The plate's true response.
    pub velocity: TrueVelocity<'a>,
}

/// Per experiment, per pixel, the measured points of `dataset` within `radius_m` of the pixel's point (its own
/// first), after checking that the truth's plate `plate` (named `scene`) is the one the scan was made on.
///
/// # Errors
/// Another plate than the scan's; a pixel off the plate or in a gap.
pub fn truth_reach(
    dataset: &Dataset,
    experiments: &[Experiment],
    radius_m: f64,
    plate: &SceneId,
    scene: &str,
) -> Result<Vec<Vec<Vec<u32>>>, ExperimentError> {
    let recorded = &dataset.manifest().meta.scene;
    if plate != recorded {
        return Err(ExperimentError::Refused(format!(
            "the scan was made on the scene `{}` ({}), not on `{scene}` ({}): its truth is not this plate's",
            recorded.name, recorded.hash, plate.hash
        )));
    }
    let grid = dataset.manifest().meta.grid;
    let on_plate = on_plate(dataset);
    let mut reach = Vec::with_capacity(experiments.len());
    for e in experiments {
        let mut pixels = Vec::with_capacity(e.pixels.len());
        for p in &e.pixels {
            let own = snap_pixel(dataset, p.x_m, p.y_m, &on_plate)?;
            let (x0, y0) = grid.position_m(own as usize);
            let mut near = vec![own];
            near.extend(dataset.points().iter().copied().filter(|&q| {
                let (x, y) = grid.position_m(q as usize);
                q != own && (x - x0).hypot(y - y0) <= radius_m + 1e-9
            }));
            pixels.push(near);
        }
        reach.push(pixels);
    }
    Ok(reach)
}

/// The points a truth's lab prepares for `reach`: the scan's whole plan and `driving_points` when the plan has at
/// most `whole_plan_limit` points and covers them (so a small scan's lab reads its responses from the cache), else
/// the points within reach alone.
pub fn truth_points(
    dataset: &Dataset,
    reach: &[Vec<Vec<u32>>],
    whole_plan_limit: usize,
    driving_points: Vec<usize>,
) -> Vec<usize> {
    let mut points: Vec<usize> = reach.iter().flatten().flatten().map(|&q| q as usize).collect();
    points.sort_unstable();
    points.dedup();
    let plan: Option<Vec<usize>> = dataset
        .manifest()
        .meta
        .config
        .get("points")
        .and_then(|p| p.as_array()?.iter().map(|q| q.as_u64().map(|q| q as usize)).collect::<Option<Vec<usize>>>());
    match plan.filter(|p| p.len() <= whole_plan_limit && points.iter().all(|q| p.contains(q))) {
        Some(mut plan) => {
            plan.extend(driving_points);
            plan
        }
        None => points,
    }
}

/// What to render and how (`experiment stimuli`'s options).
#[derive(Debug, Clone, PartialEq)]
pub struct StimuliOptions {
    /// The scan's directory, as the report names it.
    pub data: PathBuf,
    /// The calibration the scan was measured through, and the level.
    pub drive: DriveOptions,
    /// A fingertip's reach, m.
    pub fingertip_radius_m: f64,
    /// Seed of the stimuli's noise (default: each experiment's plan seed).
    pub seed: Option<u64>,
    /// Where to write each experiment's figure of the stimuli, if anywhere.
    pub figures: Option<PathBuf>,
}

/// The report (keys in alphabetical order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StimuliReport {
    /// The scan.
    pub dataset: PathBuf,
    /// Per experiment.
    pub experiments: Vec<ExperimentStimuli>,
    /// The drive level, relative to full scale.
    pub level: f64,
}

/// One experiment's stimuli.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExperimentStimuli {
    /// The experiment.
    pub name: String,
    /// Its stimuli, in the file's order.
    pub stimuli: Vec<StimulusRow>,
}

/// One stimulus: its pixels and the summary (mm/s; dB). The `true_` figures are present only with a truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StimulusRow {
    /// The stimulus.
    pub id: String,
    /// The strongest null at its point.
    pub null_max_at_point_mm_s: Option<f64>,
    /// The strongest null within reach.
    pub null_max_mm_s: Option<f64>,
    /// Its pixels.
    pub pixels: Vec<PixelRow>,
    /// Weakest target over the strongest null at the points, dB.
    pub suppression_at_points_db: Option<f64>,
    /// Weakest target over the strongest null within reach, dB.
    pub suppression_db: Option<f64>,
    /// The weakest target at its point.
    pub target_min_mm_s: Option<f64>,
    /// As `null_max_at_point_mm_s`, on the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_null_max_at_point_mm_s: Option<Option<f64>>,
    /// As `null_max_mm_s`, on the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_null_max_mm_s: Option<Option<f64>>,
    /// As `suppression_at_points_db`, on the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_suppression_at_points_db: Option<Option<f64>>,
    /// As `suppression_db`, on the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_suppression_db: Option<Option<f64>>,
    /// As `target_min_mm_s`, on the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_target_min_mm_s: Option<Option<f64>>,
}

/// One pixel of a stimulus, mm/s.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PixelRow {
    /// The pixel's name.
    pub name: String,
    /// Predicted peak at its point.
    pub predicted_peak_mm_s: f64,
    /// `target`, `null` or `other`.
    pub role: &'static str,
    /// True peak at its point (with a truth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_peak_mm_s: Option<f64>,
    /// True peak within reach (with a truth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_within_fingertip_mm_s: Option<f64>,
    /// Predicted peak within reach.
    pub within_fingertip_mm_s: f64,
}

/// What a pixel does in a stimulus.
fn role(target: bool, waveform: &Waveform) -> PixelRole {
    match (target, waveform.is_null()) {
        (true, _) => PixelRole::Target,
        (false, true) => PixelRole::Null,
        (false, false) => PixelRole::Other,
    }
}

fn role_name(role: PixelRole) -> &'static str {
    match role {
        PixelRole::Target => "target",
        PixelRole::Null => "null",
        PixelRole::Other => "other",
    }
}

/// The summary over `pixels` of `figures` (at the point, within reach): weakest target at its point, strongest
/// null at its point and within reach, and the two suppressions.
fn summary(pixels: &[(&'static str, Option<(f64, f64)>)]) -> [Option<f64>; 5] {
    let of = |role: &'static str| pixels.iter().filter(move |p| p.0 == role).filter_map(|p| p.1);
    let target_min = of("target").map(|f| f.0).reduce(f64::min);
    let null_at_point = of("null").map(|f| f.0).reduce(f64::max);
    let null_max = of("null").map(|f| f.1).reduce(f64::max);
    let ratio_db = |t: Option<f64>, n: Option<f64>| match (t, n) {
        (Some(t), Some(n)) if t > 0.0 && n > 0.0 => Some(20.0 * (t / n).log10()),
        _ => None,
    };
    [target_min, null_at_point, null_max, ratio_db(target_min, null_at_point), ratio_db(target_min, null_max)]
}

/// Each pixel's true peak velocity, mm/s, at its point and within reach, when `rendered` plays at `level`.
fn true_peaks_mm_s(
    truth: &Truth<'_>,
    e: usize,
    rendered: &Rendered,
    level: f64,
    fs: f64,
) -> Result<Vec<(f64, f64)>, ExperimentError> {
    let drives: Vec<Vec<f64>> = rendered.signals.iter().map(|s| s.iter().map(|v| v * level).collect()).collect();
    let actuators: Vec<usize> = rendered.g.actuators().iter().map(|&a| usize::from(a)).collect();
    let peak = |q: u32| -> Result<f64, ExperimentError> {
        let v = (truth.velocity)(q as usize, &actuators, &drives, fs).map_err(ExperimentError::Playback)?;
        Ok(1e3 * v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
    };
    truth.reach[e]
        .iter()
        .map(|near| {
            let at_point = peak(near[0])?;
            let mut within = at_point;
            for &q in &near[1..] {
                within = within.max(peak(q)?);
            }
            Ok((at_point, within))
        })
        .collect()
}

/// Renders every stimulus of `experiments` from `dataset` and reports them (writing the figures `options` asks
/// for, naming each file on `log`).
///
/// # Errors
/// The rig the scan was measured on not recorded; a stimulus refused (naming the experiment and stimulus); the
/// truth's errors; the figures'.
pub fn stimuli_report(
    dataset: &Dataset,
    experiments: &[Experiment],
    options: &StimuliOptions,
    truth: Option<&Truth<'_>>,
    log: &mut dyn Write,
) -> Result<StimuliReport, ExperimentError> {
    let wiring = recorded_wiring(&dataset.manifest().meta.config)
        .map_err(|e| ExperimentError::Playback(format!("the rig {} was measured on: {e}", options.data.display())))?;
    let level = options.drive.level;
    let mut rows = Vec::new();
    for (e, experiment) in experiments.iter().enumerate() {
        let seed = options.seed.unwrap_or(experiment.order.seed);
        let mut stimuli = Vec::new();
        let mut panels = Vec::new();
        for stimulus in &experiment.stimuli {
            let prepared = prepare_stimulus(dataset, &options.drive, experiment, stimulus, seed, &wiring, false)
                .map_err(|err| {
                    ExperimentError::Playback(format!(
                        "`{}`: rendering the stimulus `{}`: {err}",
                        experiment.name, stimulus.id
                    ))
                })?;
            let waveforms = stimulus.waveforms(experiment, seed)?;
            // The field within a fingertip's reach of each pixel, as a multiple of the field at its point.
            let rendered = &prepared.pattern.rendered;
            let at_point = rendered.field_at_pixels()?;
            if options.figures.is_some() {
                panels.push(stimulus_panel(dataset, experiment, stimulus, &waveforms, &at_point, level));
            }
            let within = rendered.peaks_within(&dataset.manifest().meta, options.fingertip_radius_m)?;
            let true_peaks = match truth {
                Some(t) => Some(true_peaks_mm_s(t, e, rendered, level, dataset.sample_rate_hz())?),
                None => None,
            };
            let pixels: Vec<PixelRow> = waveforms
                .iter()
                .zip(&prepared.pattern.pixels)
                .zip(at_point.iter().zip(&within))
                .map(|((pw, p), (v, near))| {
                    let point_peak = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                    let reach = if point_peak > 0.0 { near / point_peak } else { 1.0 };
                    let truth = true_peaks.as_ref().map(|t| t[pw.pixel]);
                    PixelRow {
                        name: experiment.pixels[pw.pixel].name.clone(),
                        predicted_peak_mm_s: p.predicted_peak_mm_s,
                        role: role_name(role(pw.target, &pw.waveform)),
                        true_peak_mm_s: truth.map(|t| t.0),
                        true_within_fingertip_mm_s: truth.map(|t| t.1),
                        within_fingertip_mm_s: p.predicted_peak_mm_s * reach,
                    }
                })
                .collect();
            let predicted: Vec<_> =
                pixels.iter().map(|p| (p.role, Some((p.predicted_peak_mm_s, p.within_fingertip_mm_s)))).collect();
            let [target_min, null_at_point, null_max, supp_at_points, supp] = summary(&predicted);
            let on_truth = truth.map(|_| {
                let t: Vec<_> =
                    pixels.iter().map(|p| (p.role, p.true_peak_mm_s.zip(p.true_within_fingertip_mm_s))).collect();
                summary(&t)
            });
            let pick = |i: usize| on_truth.map(|s| s[i]);
            stimuli.push(StimulusRow {
                id: stimulus.id.clone(),
                null_max_at_point_mm_s: null_at_point,
                null_max_mm_s: null_max,
                pixels,
                suppression_at_points_db: supp_at_points,
                suppression_db: supp,
                target_min_mm_s: target_min,
                true_null_max_at_point_mm_s: pick(1),
                true_null_max_mm_s: pick(2),
                true_suppression_at_points_db: pick(3),
                true_suppression_db: pick(4),
                true_target_min_mm_s: pick(0),
            });
        }
        if let Some(dir) = &options.figures {
            let title = format!("{}: predicted velocity at the pixels, level {level}", experiment.name);
            let written = metaplate_figures::stimuli(dir, &format!("{}-stimuli", experiment.name), &title, &panels)
                .map_err(|e| ExperimentError::Output(e.to_string()))?;
            writeln!(log, "wrote {}", written.png.display())?;
        }
        rows.push(ExperimentStimuli { name: experiment.name.clone(), stimuli });
    }
    Ok(StimuliReport { dataset: options.data.clone(), experiments: rows, level })
}

/// A stimulus's panel of the stimuli figure: each pixel's predicted velocity at `level` in mm/s (the rows of
/// `at_point`, in the waveforms' order), from 20 ms before the onset to 50 ms after the stimulus ends.
fn stimulus_panel(
    dataset: &Dataset,
    experiment: &Experiment,
    stimulus: &Stimulus,
    waveforms: &[PixelWaveforms],
    at_point: &[Vec<f64>],
    level: f64,
) -> StimulusPanel {
    let fs = dataset.sample_rate_hz();
    // A session delays every stimulus by the scan's impulse-response length (see `prepare_stimulus`).
    let onset = dataset.ir_len();
    let from = onset.saturating_sub((0.020 * fs).round() as usize);
    let to = onset + ((stimulus.duration_s() + 0.050) * fs).round() as usize;
    let traces = waveforms
        .iter()
        .zip(at_point)
        .map(|(pw, v)| PixelTrace {
            label: experiment.pixels[pw.pixel].name.clone(),
            role: role(pw.target, &pw.waveform),
            velocity_mm_s: v[from.min(v.len())..to.min(v.len())].iter().map(|x| 1e3 * level * x).collect(),
        })
        .collect();
    StimulusPanel { title: stimulus.id.clone(), sample_rate_hz: fs, start_s: (from as f64 - onset as f64) / fs, traces }
}

impl StimuliReport {
    /// Writes the report as one table: per stimulus the weakest target, the strongest null and other pixel within
    /// reach, the suppression (and the true figures, with a truth).
    ///
    /// # Errors
    /// Writing to `out`.
    pub fn write_table(&self, out: &mut dyn Write) -> Result<(), ExperimentError> {
        let stimuli = || self.experiments.iter().flat_map(|e| e.stimuli.iter().map(move |s| (e, s)));
        let with_truth = stimuli().any(|(_, s)| s.true_target_min_mm_s.is_some());
        writeln!(
            out,
            "peak velocity at level {:?} of full scale, mm/s (targets at their point; nulls and others within a \
             fingertip's reach); predicted from the scan{}",
            self.level,
            if with_truth { ", and true (the scene's plate playing the same drives)" } else { "" }
        )?;
        write!(
            out,
            "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
            "experiment", "stimulus", "target min", "null max", "other max", "suppression dB"
        )?;
        if with_truth {
            write!(out, " {:>12} {:>12} {:>15}", "true target", "true null", "true supp. dB")?;
        }
        writeln!(out)?;
        let cell = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.2}"));
        let db = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.1}"));
        for (e, s) in stimuli() {
            let other_max =
                s.pixels.iter().filter(|p| p.role == "other").map(|p| p.within_fingertip_mm_s).reduce(f64::max);
            write!(
                out,
                "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
                e.name,
                s.id,
                cell(s.target_min_mm_s),
                cell(s.null_max_mm_s),
                cell(other_max),
                db(s.suppression_db),
            )?;
            if with_truth {
                write!(
                    out,
                    " {:>12} {:>12} {:>15}",
                    cell(s.true_target_min_mm_s.flatten()),
                    cell(s.true_null_max_mm_s.flatten()),
                    db(s.true_suppression_db.flatten())
                )?;
            }
            writeln!(out)?;
        }
        Ok(())
    }
}

/// The default experiments of `experiment stimuli`: the built-ins' names.
pub fn default_experiments() -> Vec<String> {
    crate::builtin::names().iter().map(|n| (*n).to_owned()).collect()
}
