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

use anyhow::{Context, bail};
use clap::Args;
use metaplate_control::pixels::{on_plate, snap_pixel};
use metaplate_control::target::Waveform;
use metaplate_experiment::file::PixelWaveforms;
use metaplate_experiment::{Experiment, Stimulus, builtin};
use metaplate_figures::{PixelRole, PixelTrace, StimulusPanel};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_recipes::recorded_wiring;
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::experiment_run::{DriveOptions, prepare_stimulus};
use crate::focus::Rendered;
use crate::rig::{PREPARE_WHOLE_PLAN_POINTS, Plate};

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
    /// The mock lab's scene the scan was made on (a built-in's name or a scene file): each stimulus is then also
    /// played, as rendered from the scan, through that plate's true response (the ground truth: what the
    /// fingertips would feel), and the report gives the true figures beside the predicted ones.
    #[arg(long, value_name = "SCENE")]
    truth: Option<String>,
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
}

/// The ground truth a stimulus is judged by: the scan's lab, with the points within reach of the pixels prepared.
struct Truth {
    lab: MockLab,
    /// Per experiment, per pixel, the measured points within reach (the pixel's own point first).
    reach: Vec<Vec<Vec<u32>>>,
}

impl Truth {
    /// The lab of `scene` (which must be the one `dataset` was made on), preparing the points within `radius_m`
    /// of every pixel of `experiments`.
    fn new(
        scene: &str,
        dataset: &Dataset,
        experiments: &[Experiment],
        radius_m: f64,
        cache: Option<PathBuf>,
    ) -> anyhow::Result<Self> {
        let plate = Plate::resolve(scene)?;
        let recorded = &dataset.manifest().meta.scene;
        if plate.id != *recorded {
            bail!(
                "the scan was made on the scene `{}` ({}), not on `{scene}` ({}): its truth is not this plate's",
                recorded.name,
                recorded.hash,
                plate.id.hash
            );
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
        let mut points: Vec<usize> = reach.iter().flatten().flatten().map(|&q| q as usize).collect();
        points.sort_unstable();
        points.dedup();
        // A small scan's lab prepared its whole plan and the magnets (`Plate::small_plan_points`): the same request
        // here reads the plate's responses from the cache instead of computing them.
        let plan: Option<Vec<usize>> =
            dataset.manifest().meta.config.get("points").and_then(|p| {
                p.as_array()?.iter().map(|q| q.as_u64().map(|q| q as usize)).collect::<Option<Vec<usize>>>()
            });
        let prepared =
            match plan.filter(|p| p.len() <= PREPARE_WHOLE_PLAN_POINTS && points.iter().all(|q| p.contains(q))) {
                Some(mut plan) => {
                    plan.extend(plate.driving_points());
                    plan
                }
                None => points,
            };
        eprintln!("the ground truth: the plate of `{scene}` at {} points (cached once computed)", prepared.len());
        let lab = MockLab::new(
            &plate.scene,
            &LabOptions {
                // The scan's seed: it draws the coils' unit-to-unit spread, part of the truth.
                seed: Some(dataset.manifest().meta.seed),
                points: Some(prepared),
                cache_dir: cache,
                ..LabOptions::default()
            },
        )?;
        Ok(Self { lab, reach })
    }

    /// Each pixel's true peak velocity, mm/s, at its point and within reach, when `rendered` plays at `level`;
    /// pixels in `experiment`'s order (`e` its index among the experiments).
    fn peaks_mm_s(&self, e: usize, rendered: &Rendered, level: f64, fs: f64) -> anyhow::Result<Vec<(f64, f64)>> {
        let drives: Vec<Vec<f64>> = rendered.signals.iter().map(|s| s.iter().map(|v| v * level).collect()).collect();
        let actuators: Vec<usize> = rendered.g.actuators().iter().map(|&a| usize::from(a)).collect();
        let peak = |q: u32| -> anyhow::Result<f64> {
            let v = self.lab.true_velocity(q as usize, &actuators, &drives, fs)?;
            Ok(1e3 * v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
        };
        self.reach[e]
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
    let resolved: Vec<Experiment> = names.iter().map(|n| builtin::resolve(n)).collect::<Result<_, _>>()?;
    let truth = match &args.truth {
        Some(scene) => Some(Truth::new(scene, &dataset, &resolved, args.fingertip_radius_m, args.cache.dir())?),
        None => None,
    };
    let mut experiments = Vec::new();
    for (e, experiment) in resolved.iter().enumerate() {
        let seed = args.seed.unwrap_or(experiment.order.seed);
        let mut stimuli = Vec::new();
        let mut panels = Vec::new();
        for stimulus in &experiment.stimuli {
            let prepared = prepare_stimulus(&dataset, &drive, experiment, stimulus, seed, &wiring, false)
                .with_context(|| format!("`{}`: rendering the stimulus `{}`", experiment.name, stimulus.id))?;
            let waveforms = stimulus.waveforms(experiment, seed)?;
            // The field within a fingertip's reach of each pixel, as a multiple of the field at its point.
            let rendered = &prepared.pattern.rendered;
            let at_point = rendered.field_at_pixels()?;
            if args.figures.is_some() {
                panels.push(stimulus_panel(&dataset, experiment, stimulus, &waveforms, &at_point, args.level));
            }
            let within = rendered.peaks_within(&dataset.manifest().meta.grid, args.fingertip_radius_m)?;
            let true_peaks = match &truth {
                Some(t) => Some(t.peaks_mm_s(e, rendered, args.level, dataset.sample_rate_hz())?),
                None => None,
            };
            let pixels: Vec<PixelFigures> = waveforms
                .iter()
                .zip(&prepared.pattern.pixels)
                .zip(at_point.iter().zip(&within))
                .map(|((pw, p), (v, near))| {
                    let point_peak = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
                    let reach = if point_peak > 0.0 { near / point_peak } else { 1.0 };
                    PixelFigures {
                        name: experiment.pixels[pw.pixel].name.clone(),
                        role: role_name(role(pw.target, &pw.waveform)),
                        at_point_mm_s: p.predicted_peak_mm_s,
                        within_mm_s: p.predicted_peak_mm_s * reach,
                        truth_mm_s: true_peaks.as_ref().map(|t| t[pw.pixel]),
                    }
                })
                .collect();
            let mut row = json!({
                "id": stimulus.id,
                "pixels": pixels.iter().map(|p| {
                    let mut j = json!({"name": p.name, "role": p.role, "predicted_peak_mm_s": p.at_point_mm_s,
                        "within_fingertip_mm_s": p.within_mm_s});
                    if let Some((at, near)) = p.truth_mm_s {
                        j["true_peak_mm_s"] = json!(at);
                        j["true_within_fingertip_mm_s"] = json!(near);
                    }
                    j
                }).collect::<Vec<_>>(),
            });
            merge_summary(&mut row, "", &summary(&pixels, |p| Some((p.at_point_mm_s, p.within_mm_s))));
            if truth.is_some() {
                merge_summary(&mut row, "true_", &summary(&pixels, |p| p.truth_mm_s));
            }
            stimuli.push(row);
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

/// One pixel's figures in one stimulus, mm/s.
struct PixelFigures {
    name: String,
    role: &'static str,
    /// Predicted from the scan: at the pixel's point, and the largest within reach.
    at_point_mm_s: f64,
    within_mm_s: f64,
    /// On the ground truth (with `--truth`): at the point, and the largest within reach.
    truth_mm_s: Option<(f64, f64)>,
}

/// A stimulus's summary over its pixels, from `figures` (at the point, within reach) of each: the weakest target
/// at its point, the strongest null at its point and within reach, and the suppressions (the weakest target over
/// each, dB).
struct Summary {
    target_min_mm_s: Option<f64>,
    null_max_at_point_mm_s: Option<f64>,
    null_max_mm_s: Option<f64>,
}

fn summary(pixels: &[PixelFigures], figures: impl Fn(&PixelFigures) -> Option<(f64, f64)>) -> Summary {
    let of = |role: &'static str| pixels.iter().filter(move |p| p.role == role).filter_map(&figures);
    Summary {
        target_min_mm_s: of("target").map(|f| f.0).reduce(f64::min),
        null_max_at_point_mm_s: of("null").map(|f| f.0).reduce(f64::max),
        null_max_mm_s: of("null").map(|f| f.1).reduce(f64::max),
    }
}

/// Writes `summary` into a stimulus's row, each key prefixed by `prefix` (`""` predicted, `"true_"` truth).
fn merge_summary(row: &mut Value, prefix: &str, summary: &Summary) {
    let ratio_db = |t: Option<f64>, n: Option<f64>| match (t, n) {
        (Some(t), Some(n)) if t > 0.0 && n > 0.0 => Some(20.0 * (t / n).log10()),
        _ => None,
    };
    let s = summary;
    row[format!("{prefix}target_min_mm_s")] = json!(s.target_min_mm_s);
    row[format!("{prefix}null_max_at_point_mm_s")] = json!(s.null_max_at_point_mm_s);
    row[format!("{prefix}null_max_mm_s")] = json!(s.null_max_mm_s);
    row[format!("{prefix}suppression_at_points_db")] = json!(ratio_db(s.target_min_mm_s, s.null_max_at_point_mm_s));
    row[format!("{prefix}suppression_db")] = json!(ratio_db(s.target_min_mm_s, s.null_max_mm_s));
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
    let stimuli = || document["experiments"].as_array().into_iter().flatten();
    let with_truth = stimuli()
        .flat_map(|e| e["stimuli"].as_array().into_iter().flatten())
        .any(|s| s.get("true_target_min_mm_s").is_some());
    println!(
        "peak velocity at level {} of full scale, mm/s (targets at their point; nulls and others within a fingertip's \
         reach); predicted from the scan{}",
        document["level"],
        if with_truth { ", and true (the scene's plate playing the same drives)" } else { "" }
    );
    print!(
        "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
        "experiment", "stimulus", "target min", "null max", "other max", "suppression dB"
    );
    if with_truth {
        print!(" {:>12} {:>12} {:>15}", "true target", "true null", "true supp. dB");
    }
    println!();
    let cell = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.2}"));
    let db = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.1}"));
    for e in stimuli() {
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
            print!(
                "{:<26} {:<22} {:>12} {:>12} {:>12} {:>15}",
                e["name"].as_str().unwrap_or(""),
                s["id"].as_str().unwrap_or(""),
                cell(s["target_min_mm_s"].as_f64()),
                cell(s["null_max_mm_s"].as_f64()),
                cell(max_of("other")),
                db(s["suppression_db"].as_f64()),
            );
            if with_truth {
                print!(
                    " {:>12} {:>12} {:>15}",
                    cell(s["true_target_min_mm_s"].as_f64()),
                    cell(s["true_null_max_mm_s"].as_f64()),
                    db(s["true_suppression_db"].as_f64())
                );
            }
            println!();
        }
    }
}
