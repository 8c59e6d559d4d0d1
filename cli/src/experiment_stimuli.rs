//! `metaplate experiment stimuli`: how well a scan renders an experiment's stimuli, before anyone touches the
//! plate. Each stimulus is rendered as `experiment run` renders it (through the calibration, at the level), and the
//! predicted peak velocity at each of its pixels is reported: at the target pixels (what the participant must
//! find), at the null pixels (actively suppressed) and at the others (a distractor's pattern), at the pixel's point
//! and within a fingertip's reach of it (`--fingertip-radius-m`, 5 mm: a null is met at a point, and beside it the
//! field can be large where waves are long). The suppression is the weakest target's peak at its point over the
//! strongest null's within reach, in dB.
//!
//! The prediction is the scan's: `G` measured through the calibrated actuators, the drives peak-normalised to the
//! level as played. On the mock lab a scan's Green's functions lie within -35 to -49 dB of the plate's truth, so the
//! figures are the truth's to a fraction of a decibel.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_control::target::Waveform;
use metaplate_experiment::file::PixelWaveforms;
use metaplate_experiment::{Experiment, Stimulus, builtin};
use metaplate_figures::{PixelRole, PixelTrace, StimulusPanel};
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_recipes::recorded_wiring;
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::experiment_run::{DriveOptions, prepare_stimulus};

/// Arguments of `metaplate experiment stimuli`.
#[derive(Args, Debug)]
pub struct StimuliArgs {
    /// Experiments: built-in names or experiment files (default: the paper's four).
    experiments: Vec<String>,
    /// The scan the stimuli are rendered from (measured through --calibration; the pixels snap to its points).
    #[arg(long)]
    data: PathBuf,
    /// The calibration the scan was measured through.
    #[arg(long)]
    calibration: PathBuf,
    /// Drive level relative to full scale, as `experiment run --level`.
    #[arg(long, default_value_t = DRIVE_PEAK_FS)]
    level: f64,
    /// A fingertip's reach, m: a null pixel's figure is the largest predicted peak at the measured points within
    /// this distance of it (the field at one point can be nulled while a finger resting there still feels the field
    /// beside it). The default, 5 mm, is a fingertip's contact radius: on the paper's 5 mm grid it takes the four
    /// neighbours; on a coarser scan only the point.
    #[arg(long, default_value_t = 0.005)]
    fingertip_radius_m: f64,
    /// Seed of the stimuli's noise (default: each experiment's plan seed).
    #[arg(long)]
    seed: Option<u64>,
    /// Print JSON: `{"level", "experiments": [{"name", "stimuli": [{"id", "pixels": [{"name", "role",
    /// "predicted_peak_mm_s", "within_fingertip_mm_s"}], "target_min_mm_s", "null_max_mm_s", "suppression_db"}]}]}`
    /// (`null_max_mm_s` within reach).
    #[arg(long)]
    json: bool,
    /// Also write, per experiment, `DIR/<experiment>-stimuli.png` and `.svg`: each stimulus's predicted velocity at
    /// its pixels over time (targets in colour, nulls grey, others a second colour), as the paper's Figs. S8 to S11.
    #[arg(long, value_name = "DIR")]
    figures: Option<PathBuf>,
}

/// What a pixel does in a stimulus.
fn role(target: bool, waveform: &Waveform) -> PixelRole {
    match (target, waveform.is_null()) {
        (true, _) => PixelRole::Target,
        (false, true) => PixelRole::Null,
        (false, false) => PixelRole::Other,
    }
}

/// A role's name in the report.
fn role_name(role: PixelRole) -> &'static str {
    match role {
        PixelRole::Target => "target",
        PixelRole::Null => "null",
        PixelRole::Other => "other",
    }
}

/// Runs `metaplate experiment stimuli`.
pub fn run(args: &StimuliArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let wiring = recorded_wiring(&dataset.manifest().meta.config)
        .with_context(|| format!("the rig {} was measured on", args.data.display()))?;
    let drive = DriveOptions { calibration: args.calibration.clone(), level: args.level };
    let names: Vec<String> = if args.experiments.is_empty() {
        builtin::names().iter().map(|n| (*n).to_owned()).collect()
    } else {
        args.experiments.clone()
    };
    let mut experiments = Vec::new();
    for name in &names {
        let experiment = builtin::resolve(name)?;
        let seed = args.seed.unwrap_or(experiment.order.seed);
        let mut stimuli = Vec::new();
        let mut panels = Vec::new();
        for stimulus in &experiment.stimuli {
            let prepared = prepare_stimulus(&dataset, &drive, &experiment, stimulus, seed, &wiring, false)
                .with_context(|| format!("`{}`: rendering the stimulus `{}`", experiment.name, stimulus.id))?;
            let waveforms = stimulus.waveforms(&experiment, seed)?;
            // The field within a fingertip's reach of each pixel, as a multiple of the field at its point.
            let rendered = &prepared.pattern.rendered;
            let at_point = rendered.field_at_pixels()?;
            if args.figures.is_some() {
                panels.push(stimulus_panel(&dataset, &experiment, stimulus, &waveforms, &at_point, args.level));
            }
            let within = rendered.peaks_within(&dataset.manifest().meta.grid, args.fingertip_radius_m)?;
            let pixels: Vec<(String, &'static str, f64, f64)> = waveforms
                .iter()
                .zip(&prepared.pattern.pixels)
                .zip(at_point.iter().zip(&within))
                .map(|((pw, p), (v, near))| {
                    let point_peak = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                    let reach = if point_peak > 0.0 { near / point_peak } else { 1.0 };
                    let name = experiment.pixels[pw.pixel].name.clone();
                    (
                        name,
                        role_name(role(pw.target, &pw.waveform)),
                        p.predicted_peak_mm_s,
                        p.predicted_peak_mm_s * reach,
                    )
                })
                .collect();
            // Targets at their point (the focus); nulls over the fingertip (what the finger beside the focus feels).
            let target_min = pixels.iter().filter(|p| p.1 == "target").map(|p| p.2).reduce(f64::min);
            let null_max = pixels.iter().filter(|p| p.1 == "null").map(|p| p.3).reduce(f64::max);
            let suppression_db = match (target_min, null_max) {
                (Some(t), Some(n)) if t > 0.0 && n > 0.0 => Some(20.0 * (t / n).log10()),
                _ => None,
            };
            stimuli.push(json!({
                "id": stimulus.id,
                "pixels": pixels.iter().map(|(name, role, peak, near)| {
                    json!({"name": name, "role": role, "predicted_peak_mm_s": peak, "within_fingertip_mm_s": near})
                }).collect::<Vec<_>>(),
                "target_min_mm_s": target_min,
                "null_max_mm_s": null_max,
                "suppression_db": suppression_db,
            }));
        }
        if let Some(dir) = &args.figures {
            let title = format!("{}: predicted velocity at the pixels, level {}", experiment.name, args.level);
            let written = metaplate_figures::stimuli(dir, &format!("{}-stimuli", experiment.name), &title, &panels)?;
            eprintln!("wrote {}", written.png.display());
        }
        experiments.push(json!({"name": experiment.name, "stimuli": stimuli}));
    }
    let document = json!({"dataset": args.data, "level": args.level, "experiments": experiments});
    if args.json {
        println!("{document}");
    } else {
        print_table(&document);
    }
    Ok(())
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
    // `experiment run` delays every stimulus by the scan's impulse-response length (see `prepare_stimulus`).
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

fn print_table(document: &Value) {
    println!(
        "predicted peak velocity at level {} of full scale, mm/s (targets at their point; nulls and others within a \
         fingertip's reach)",
        document["level"]
    );
    println!(
        "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
        "experiment", "stimulus", "target min", "null max", "other max", "suppression dB"
    );
    for e in document["experiments"].as_array().into_iter().flatten() {
        for s in e["stimuli"].as_array().into_iter().flatten() {
            let max_of = |role: &str| {
                s["pixels"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter(|p| p["role"] == role)
                    .filter_map(|p| p["within_fingertip_mm_s"].as_f64())
                    .reduce(f64::max)
            };
            let cell = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.2}"));
            println!(
                "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
                e["name"].as_str().unwrap_or(""),
                s["id"].as_str().unwrap_or(""),
                cell(s["target_min_mm_s"].as_f64()),
                cell(s["null_max_mm_s"].as_f64()),
                cell(max_of("other")),
                s["suppression_db"].as_f64().map_or_else(|| "-".to_owned(), |v| format!("{v:.1}")),
            );
        }
    }
}
