//! `metaplate play`: targets at pixels rendered as `focus` renders them, through the calibration, played on the rig
//! with a marker on the loopback (the recipes' `play::prepare`: its refusals, onsets, latency, predicted peaks).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_control::focus::{PixelSpec, RenderOptions, parse_pixel};
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_recipes::play::{check_playable, prepare};
use metaplate_store::Dataset;

use metaplate_lab::LabOptions;

use crate::rig::{self, Plate};
use crate::run::Source;

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

/// Runs `metaplate play`.
pub fn run(args: &PlayArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let specs: Vec<PixelSpec> = args.pixels.iter().map(|p| parse_pixel(p)).collect::<Result<_, _>>()?;
    let (plate, mut rig, _lab) = match (&args.source.scene, &args.source.hardware) {
        (_, Some(file)) => {
            let (plate, opened) = rig::hardware_rig_and_keypad(file, metaplate_drivers::OpenPurpose::Play)?;
            check_playable(&dataset, &plate.id)?;
            (plate, opened.rig, None)
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            check_playable(&dataset, &plate.id)?;
            // Only the magnets are prepared: nothing is measured at the pixels (the beam rests where it is).
            let points = Some(plate.scene.driving_points());
            let options = LabOptions { seed: args.seed, cache_dir: args.cache.dir(), points, ..LabOptions::default() };
            let (lab, rig) = rig::mock_rig_with(&plate, &options)?;
            (plate, rig, Some(lab))
        }
        (None, None) => bail!("give --scene or --hardware"),
    };
    let pattern = prepare(&dataset, &specs, &args.calibration, &args.render, &rig.wiring, args.level)?;
    let played = pattern.play(&mut rig)?;
    if args.json {
        println!("{}", serde_json::to_string(&pattern.report(&played))?);
        return Ok(());
    }
    print!("{}", pattern.describe(&played, &plate.id.name));
    Ok(())
}
