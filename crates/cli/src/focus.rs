//! `metaplate focus`: drive signals that focus target waveforms on virtual pixels, from a measured (or simulated)
//! dataset, written as a multichannel WAV file; optionally the predicted field at the pixels. The rendering is
//! control's `focus` (one-shot padding, the focus time, the calibration's compensation: see there).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_control::focus::{PixelSpec, RenderOptions, parse_pixel};
use metaplate_recipes::play::render_through;
use metaplate_store::Dataset;

use crate::wav;

/// Arguments of `metaplate focus`.
#[derive(Args)]
pub struct FocusArgs {
    /// Dataset directory (a scan or `metaplate simulate greens`).
    #[arg(long)]
    data: PathBuf,
    /// Calibration dataset (what `metaplate calibrate` writes): the drives go through its Kirkeby filters.
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// A pixel: `X_M,Y_M` in metres, optionally `:TARGET` with TARGET one of `impulse[@T]`, `impulses@T1,T2,..`,
    /// `noise@START,DURATION[,SEED]`, `sine@FREQ[,START,DURATION]`, `wavelets@FREQ,CYCLES,T1,..`, `null` (times
    /// in s from the start of the drive, frequencies in Hz). Default target: an impulse at the focus time.
    /// Repeat for several pixels.
    #[arg(long = "pixel", required = true, allow_hyphen_values = true)]
    pixels: Vec<String>,
    /// Output WAV file: 32-bit float, one channel per actuator, peak-normalised to 1.
    #[arg(long)]
    out: PathBuf,
    /// Also write the predicted field v(x, t) at the pixels: CSV when the name ends in `.csv`, JSON otherwise.
    #[arg(long)]
    field: Option<PathBuf>,
    /// With --field, write the field at every measured point too (large: points x samples).
    #[arg(long)]
    field_all_points: bool,
    /// How the drives are solved and laid out.
    #[command(flatten)]
    render: RenderOptions,
}

/// Runs `metaplate focus`.
pub fn run(args: &FocusArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let specs: Vec<PixelSpec> = args.pixels.iter().map(|p| parse_pixel(p)).collect::<Result<_, _>>()?;
    let r = render_through(&dataset, &specs, args.calibration.as_deref(), &args.render)?;
    let fs = dataset.sample_rate_hz();
    let samples = r.signals.first().map_or(0, Vec::len);
    wav::write_f32(&args.out, fs, &r.signals)?;
    println!(
        "wrote {}: {} channels x {samples} samples at {fs} Hz ({:.3} s; focus time {:.4} s; {})",
        args.out.display(),
        r.signals.len(),
        samples as f64 / fs,
        r.focus_s,
        if r.pad_s > 0.0 { "for one-shot playback" } else { "one period, loop it" }
    );
    println!("peak drive {:.6e} (dataset drive units), normalisation factor {:.6e}", r.peak, r.factor);
    if r.factor == 0.0 {
        println!("every target is null: the drives are silent");
    }
    if let Some(path) = &args.field {
        let csv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        let text = r.field_text(&specs, fs, args.field_all_points, csv)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote the predicted field to {}", path.display());
    }
    Ok(())
}
