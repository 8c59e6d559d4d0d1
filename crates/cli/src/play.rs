//! `metaplate play`: renders targets at pixels as `metaplate focus` does (same `--pixel` syntax and rendering
//! options), through the calibration's Kirkeby filters, and plays them on the rig's audio interface (the mock lab
//! of `--scene`, or the instruments of `--hardware FILE`), with a timing marker on the loopback: it prints the
//! onset scheduled and measured on the loopback, the latency, the headroom, and the predicted peak velocity at
//! each pixel.
//!
//! Refusals (exit 1, nothing played): a pixel off the plate or in a gap of the scan (control's `pixels`), a drive
//! that would clip at `--level` (recipes' `RecipeError::Clipping`), a dataset that is not a scan in m/s per
//! full-scale drive (the predicted velocity would have no physical unit), or a rig of another plate.
//!
//! [`prepare`] and [`Pattern::play`] are the reusable core (an experiment's stimuli are prepared, hence checked,
//! before the first trial, and played one by one).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use metaplate_core::rig::{Rig, Wiring};
use metaplate_keypad::{HidInput, Keypad};
use metaplate_lab::MockLab;
use metaplate_recipes::Calibration;
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_recipes::play::{PatternPlayback, Played};
use metaplate_store::Dataset;
use serde_json::json;

use crate::focus::{PixelSpec, RenderOptions, Rendered, parse_pixel, render};
use crate::rig::{self, Plate};
use crate::run::Source;

/// The unit of a scan's impulse responses: what makes a predicted field a velocity at a level of full scale.
const SCAN_IR_UNIT: &str = "m/s per full-scale drive, through the calibration's inverse filters";

/// Arguments of `metaplate play`.
#[derive(Args)]
pub struct PlayArgs {
    /// Scan dataset directory (impulse responses in m/s per full-scale drive, measured through the calibration).
    #[arg(long)]
    data: PathBuf,
    /// Calibration dataset (what `metaplate calibrate` writes): the drives go through its Kirkeby filters.
    #[arg(long)]
    calibration: PathBuf,
    /// A pixel: `X_M,Y_M[:TARGET]`, as `metaplate focus --pixel` takes it. Repeat for several pixels.
    #[arg(long = "pixel", required = true, allow_hyphen_values = true)]
    pixels: Vec<String>,
    /// Where to play: --scene (mock lab) or --hardware FILE.
    #[command(flatten)]
    source: Source,
    /// Playback level relative to full scale: the drives (peak-normalised to 1) are multiplied by it, and the
    /// predicted velocities scale with it. The default is the recipes' drive peak, 1 dB below full scale: the
    /// headroom the conversion to the audio rate may need between samples.
    #[arg(long, default_value_t = DRIVE_PEAK_FS)]
    level: f64,
    /// Mock lab only: the seed of its noise. Default: the scene's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Mock lab only: where the plate's Green's functions are cached.
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
    /// Print one JSON object (pixels with predicted peak mm/s, onsets, latency, clip margin) instead of text.
    #[arg(long)]
    json: bool,
    /// How the drives are solved and laid out (as `metaplate focus`).
    #[command(flatten)]
    render: RenderOptions,
}

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
pub struct Pattern {
    /// What focus rendered.
    pub rendered: Rendered,
    /// The buffers at the level, and the loopback marker.
    pub playback: PatternPlayback,
    /// Each pixel's predicted peak velocity at the level.
    pub pixels: Vec<PixelPrediction>,
}

/// Renders `specs` on `dataset` through the calibration in `calibration` with `options`, and prepares them at
/// `level` (relative to full scale) for a rig wired as `wiring` says.
///
/// # Errors
/// A dataset that is not a scan through this calibration (its unit, its calibration hash), a pixel off the plate or in a gap (control's typed error), rendering
/// errors, and a drive that would clip at `level` (`RecipeError::Clipping`, found by downcasting).
pub fn prepare(
    dataset: &Dataset,
    specs: &[PixelSpec],
    calibration: &Path,
    options: &RenderOptions,
    wiring: &Wiring,
    level: f64,
) -> anyhow::Result<Pattern> {
    let unit = dataset.manifest().meta.description.as_ref().map_or("unstated", |d| d.ir_unit.as_str());
    if unit != SCAN_IR_UNIT {
        bail!(
            "the dataset's impulse responses are in `{unit}`, not `{SCAN_IR_UNIT}`: play needs a scan measured \
             through a calibration, so that a level of full scale has a velocity"
        );
    }
    // The responses hold the filters they were measured through: compensating with others would play a pattern
    // the prediction does not describe.
    let scanned_through = dataset.manifest().meta.config.get("calibration").and_then(|v| v.as_str());
    let wired = dataset.actuators().iter().map(|&a| usize::from(a) + 1).max().unwrap_or(0);
    let given = Calibration::load(calibration, wired)
        .with_context(|| format!("reading the calibration {}", calibration.display()))?;
    if scanned_through != Some(given.content_hash.as_str()) {
        bail!(
            "the dataset was scanned through the calibration {}, not {} ({})",
            scanned_through.unwrap_or("(none recorded)"),
            calibration.display(),
            given.content_hash
        );
    }
    let rendered = render(dataset, specs, Some(calibration), options)?;
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
    Ok(Pattern { rendered, playback, pixels })
}

impl Pattern {
    /// Plays the pattern on `rig` and measures its onset on the loopback.
    ///
    /// # Errors
    /// As `PatternPlayback::play`: device errors, a marker not found in the loopback.
    pub fn play(&self, rig: &mut Rig) -> anyhow::Result<Played> {
        Ok(self.playback.play(rig)?)
    }

    /// The report `metaplate play --json` prints for this pattern played as `played` says.
    pub fn report(&self, played: &Played) -> serde_json::Value {
        let pixels: Vec<_> = self
            .pixels
            .iter()
            .map(|p| {
                json!({"x_m": p.spec.x_m, "y_m": p.spec.y_m, "target": p.spec.label, "point_index": p.point_index,
                    "predicted_peak_mm_s": p.predicted_peak_mm_s})
            })
            .collect();
        json!({
            "level": self.playback.level,
            "duration_s": self.playback.duration_s,
            "focus_s": self.rendered.focus_s,
            "clip_margin_db": self.playback.clip_margin_db(),
            "scheduled_onset_s": played.scheduled_onset_s,
            "measured_onset_s": played.measured_onset_s,
            "latency_s": played.latency_s,
            "underruns": played.underruns,
            "gap": played.gap,
            "pixels": pixels,
        })
    }
}

/// What [`rig_for`] opens.
pub struct OpenedSource {
    /// The plate.
    pub plate: Plate,
    /// The rig.
    pub rig: Rig,
    /// The mock lab behind the rig, if it is one: keep it alive while the rig is used.
    pub lab: Option<MockLab>,
    /// The response keypad the hardware file names, if any.
    pub keypad: Option<Keypad<Box<dyn HidInput>>>,
}

/// The rig `source` names (the mock lab of `--scene`, seeded with `seed`, its Green's functions cached in
/// `cache_dir`; or the instruments of `--hardware`, with its keypad), checked to be the plate `dataset` was measured
/// on.
///
/// # Errors
/// Neither source given; the rig's errors; a rig of another plate (the drives would focus nowhere).
pub fn rig_for(
    dataset: &Dataset,
    source: &Source,
    seed: Option<u64>,
    cache_dir: Option<PathBuf>,
) -> anyhow::Result<OpenedSource> {
    let measured_on = dataset.manifest().meta.scene.clone();
    let same_plate = |plate: &Plate| {
        if measured_on == plate.id {
            return Ok(());
        }
        Err(anyhow::anyhow!(
            "the dataset was measured on the plate `{}`, the rig is the plate `{}`: the drives would focus nowhere",
            measured_on.name,
            plate.id.name
        ))
    };
    match (&source.scene, &source.hardware) {
        (_, Some(file)) => {
            let (plate, opened) = rig::hardware_rig_and_keypad(file)?;
            same_plate(&plate)?;
            Ok(OpenedSource { plate, rig: opened.rig, lab: None, keypad: opened.keypad })
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            same_plate(&plate)?;
            // Only the magnets are prepared: nothing is measured at the pixels (the beam rests where it is).
            let (lab, rig) = rig::mock_rig(&plate, plate.driving_points(), seed, cache_dir)?;
            Ok(OpenedSource { plate, rig, lab: Some(lab), keypad: None })
        }
        (None, None) => bail!("give --scene or --hardware"),
    }
}

/// Runs `metaplate play`.
pub fn run(args: &PlayArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let specs: Vec<PixelSpec> = args.pixels.iter().map(|p| parse_pixel(p)).collect::<anyhow::Result<_>>()?;
    let OpenedSource { plate, mut rig, lab: _lab, keypad: _ } =
        rig_for(&dataset, &args.source, args.seed, args.cache.dir())?;
    let pattern = prepare(&dataset, &specs, &args.calibration, &args.render, &rig.wiring, args.level)?;
    let played = pattern.play(&mut rig)?;
    if args.json {
        println!("{}", pattern.report(&played));
        return Ok(());
    }
    let margin = pattern.playback.clip_margin_db().map_or("silent".into(), |db| format!("clip margin {db:.2} dB"));
    println!(
        "played {:.3} s on `{}` at level {} ({margin}); impulses focus {:.4} s after the onset",
        pattern.playback.duration_s, plate.id.name, pattern.playback.level, pattern.rendered.focus_s
    );
    println!(
        "onset: scheduled {:.6} s, measured {:.6} s on the loopback, latency {:.3} ms",
        played.scheduled_onset_s,
        played.measured_onset_s,
        played.latency_s * 1e3
    );
    if played.underruns > 0 || played.gap {
        println!("warning: {} audio underrun(s), recording gap: {}", played.underruns, played.gap);
    }
    for p in &pattern.pixels {
        println!(
            "pixel ({}, {}) {}: point {}, predicted peak {:.3} mm/s",
            p.spec.x_m, p.spec.y_m, p.spec.label, p.point_index, p.predicted_peak_mm_s
        );
    }
    Ok(())
}
