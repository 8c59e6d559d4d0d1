//! `metaplate focus`: drive signals that focus target waveforms on virtual pixels, from a measured (or simulated)
//! dataset, written as a multichannel WAV file; optionally the predicted field at the pixels.
//!
//! Pixels are given in metres on the plate and snap to the nearest measured point. The drives are solved by the
//! paper's spatiotemporal inverse filter (or time reversal) over the operating band, bin by bin.
//!
//! One-shot playback: the frequency-domain model is circular, so a drive one impulse-response long is exact only when
//! played in a loop. By default the impulse responses are zero-padded by their own length (`--pad-s`), so the
//! period is twice the response and the default focus time is half-way: the drive that builds the focus fits
//! before it and the plate's ring-down after it, and a single playback (preceded and followed by silence) gives the
//! predicted field up to the part of the responses that outlasts the padding. `--pad-s 0` writes one period for
//! looped playback.
//!
//! Calibration: `--calibration DIR` reads the calibration dataset a `metaplate calibrate` run writes (recipes'
//! `Calibration::load`: checksums verified, one Kirkeby inverse filter per actuator). The drives are convolved with
//! the filters of the dataset's actuators (each channel grows by the filter length minus one); the predicted field
//! is that of the uncompensated drives, since the Green's functions were measured through the calibrated actuators.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use metaplate_control::PropagationMatrices;
use metaplate_control::pixels::{PointSelection, on_plate, snap_pixel};
use metaplate_control::render::{
    DriveSpectra, FocusOptions, compensate, normalise_peak, predicted_field, solve_drives,
};
use metaplate_control::solve::{Method, Regularisation};
use metaplate_control::target::{PixelTarget, Waveform};
use metaplate_core::grid::GridSpec;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_recipes::Calibration;
use metaplate_store::Dataset;
use serde_json::json;

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

/// Default operating band, Hz (the paper's).
const BAND_HZ: (f64, f64) = (75.0, 400.0);
/// Default Tikhonov regularisation relative to the largest singular value (the control crate's).
const ALPHA_RELATIVE: f64 = metaplate_control::solve::DEFAULT_RELATIVE_ALPHA;

/// How drives are solved and laid out (the options of `metaplate focus`; `metaplate demo` uses the defaults).
#[derive(Args, Debug, Clone)]
pub struct RenderOptions {
    /// Lower edge of the operating band, Hz.
    #[arg(long, default_value_t = BAND_HZ.0)]
    pub band_lo_hz: f64,
    /// Upper edge of the operating band, Hz.
    #[arg(long, default_value_t = BAND_HZ.1)]
    pub band_hi_hz: f64,
    /// Tikhonov regularisation relative to the largest singular value at each frequency.
    #[arg(long, default_value_t = ALPHA_RELATIVE)]
    pub alpha_relative: f64,
    /// Time reversal instead of inverse filtering.
    #[arg(long)]
    pub time_reversal: bool,
    /// Zero padding of the impulse responses, s (default: their own length, for one-shot playback; 0: one period
    /// for looped playback).
    #[arg(long)]
    pub pad_s: Option<f64>,
    /// Focus time of plain `impulse` targets, s from the start of the drive (default: half the period).
    #[arg(long)]
    pub focus_s: Option<f64>,
    /// Use only the points whose every row's estimated error (the dataset's `estimated_error_db`, from the spread
    /// of repetitions) is at most this, dB; a pixel on a point left out is refused. Rows without an estimate are
    /// kept. Default: every point.
    #[arg(long, allow_hyphen_values = true)]
    pub max_error_db: Option<f64>,
}

impl Default for RenderOptions {
    /// The command line's defaults.
    fn default() -> Self {
        Self {
            band_lo_hz: BAND_HZ.0,
            band_hi_hz: BAND_HZ.1,
            alpha_relative: ALPHA_RELATIVE,
            time_reversal: false,
            pad_s: None,
            focus_s: None,
            max_error_db: None,
        }
    }
}

/// What a pixel should do: an impulse at the focus time (decided when rendering), or a given waveform.
#[derive(Debug, Clone, PartialEq)]
pub enum TargetSpec {
    /// A band-limited impulse at the focus time ([`RenderOptions::focus_s`], default half the period).
    ImpulseAtFocus,
    /// This waveform (times from the start of the drive).
    Waveform(Waveform),
}

/// A pixel to render: position in metres, what it should do, and how to name it in reports.
#[derive(Debug, Clone)]
pub struct PixelSpec {
    /// x on the plate, m.
    pub x_m: f64,
    /// y on the plate, m.
    pub y_m: f64,
    /// The target.
    pub target: TargetSpec,
    /// The target as reports print it: `--pixel`'s text after the colon (`impulse` by default), or the name of an
    /// experiment's pattern.
    pub label: String,
}

impl PixelSpec {
    /// A pixel at (`x_m`, `y_m`) with a target in `--pixel`'s syntax (`impulse` for an impulse at the focus time).
    ///
    /// # Errors
    /// A target control's `Waveform` does not parse.
    pub fn from_text(x_m: f64, y_m: f64, target: &str) -> anyhow::Result<Self> {
        let label = target.trim().to_owned();
        let target = if label == "impulse" {
            TargetSpec::ImpulseAtFocus
        } else {
            TargetSpec::Waveform(label.parse::<Waveform>()?)
        };
        Ok(Self { x_m, y_m, target, label })
    }
}

pub(crate) fn parse_pixel(text: &str) -> anyhow::Result<PixelSpec> {
    let (position, target) = text.split_once(':').unwrap_or((text, "impulse"));
    let Some((x, y)) = position.split_once(',') else { bail!("--pixel `{text}`: expected X_M,Y_M[:TARGET]") };
    let number = |s: &str| s.trim().parse::<f64>().with_context(|| format!("--pixel `{text}`: `{s}` is not a number"));
    let (x_m, y_m) = (number(x)?, number(y)?);
    if !(x_m.is_finite() && y_m.is_finite()) {
        bail!("--pixel `{text}`: coordinates must be finite");
    }
    PixelSpec::from_text(x_m, y_m, target)
}

/// Reads the calibration dataset in `dir` and returns the filters of `actuators` (the dataset's actuator numbers,
/// in its column order), checking their sample rate against the dataset's.
fn read_calibration(dir: &Path, actuators: &[u16], sample_rate_hz: f64) -> anyhow::Result<Vec<KirkebyFilter>> {
    // Calibrations hold actuators 0..n: load as many as the highest the dataset uses.
    let wired = actuators.iter().map(|&a| usize::from(a) + 1).max().unwrap_or(0);
    let calibration =
        Calibration::load(dir, wired).with_context(|| format!("reading the calibration {}", dir.display()))?;
    actuators
        .iter()
        .map(|&a| {
            let filter = calibration.filters.get(usize::from(a)).context("internal: calibration filter missing")?;
            if (filter.sample_rate_hz - sample_rate_hz).abs() > 1e-9 * sample_rate_hz {
                bail!(
                    "the calibration {} is at {} Hz, the dataset at {sample_rate_hz} Hz",
                    dir.display(),
                    filter.sample_rate_hz
                );
            }
            Ok(filter.clone())
        })
        .collect()
}

/// Drives rendered for a set of pixels: what `metaplate focus` writes, and what `metaplate demo` reports.
pub struct Rendered {
    /// The propagation matrices the drives were solved on (padded as [`RenderOptions::pad_s`] says).
    pub g: PropagationMatrices,
    /// The drive spectra (before compensation).
    pub drives: DriveSpectra,
    /// Each pixel's measured point (grid flat index).
    pub points: Vec<u32>,
    /// The signals to play, one per actuator: compensated when a calibration was given, peak-normalised to 1.
    pub signals: Vec<Vec<f64>>,
    /// Peak of the signals before normalisation (dataset drive units).
    pub peak: f64,
    /// The normalisation factor applied (0 when every target is null).
    pub factor: f64,
    /// Focus time of plain `impulse` targets, s.
    pub focus_s: f64,
    /// Zero padding used, s.
    pub pad_s: f64,
}

/// Solves, compensates (with the calibration dataset in `calibration`, if any) and peak-normalises the drives that
/// focus `specs` on the dataset's plate.
///
/// # Errors
/// A pixel off the plate or in a gap of the scan, a bad target, options outside their range, an unreadable
/// calibration, and the solver's errors.
pub fn render(
    dataset: &Dataset,
    specs: &[PixelSpec],
    calibration: Option<&Path>,
    options: &RenderOptions,
) -> anyhow::Result<Rendered> {
    let on_plate = on_plate(dataset);
    let points: Vec<u32> =
        specs.iter().map(|s| snap_pixel(dataset, s.x_m, s.y_m, &on_plate)).collect::<Result<_, _>>()?;
    let selection = options.max_error_db.map(|db| PointSelection::by_estimated_error(dataset, db)).transpose()?;
    if let Some(selection) = &selection {
        for (spec, &point) in specs.iter().zip(&points) {
            selection.check_pixel(spec.x_m, spec.y_m, point)?;
        }
    }
    let fs = dataset.sample_rate_hz();
    let ir_len = dataset.ir_len();
    let pad_s = options.pad_s.unwrap_or(ir_len as f64 / fs);
    if !(pad_s.is_finite() && pad_s >= 0.0) {
        bail!("--pad-s must be finite and >= 0, got {pad_s}");
    }
    let fft_len = ir_len + (pad_s * fs).round() as usize;
    let band = (options.band_lo_hz, options.band_hi_hz);
    let kept = selection.as_ref().map(|s| s.kept.as_slice());
    let g = PropagationMatrices::from_dataset_padded(dataset, band, kept, fft_len).context("building G(omega)")?;
    let focus_s = options.focus_s.unwrap_or(fft_len as f64 / fs / 2.0);
    let targets: Vec<PixelTarget> = specs
        .iter()
        .zip(&points)
        .map(|(spec, &point_index)| {
            let waveform = match &spec.target {
                TargetSpec::ImpulseAtFocus => Waveform::Impulse { time_s: focus_s },
                TargetSpec::Waveform(w) => w.clone(),
            };
            PixelTarget { point_index, waveform, amplitude: 1.0 }
        })
        .collect();
    let method = if options.time_reversal { Method::TimeReversal } else { Method::InverseFilter };
    let focus = FocusOptions {
        regularisation: Regularisation::Relative(options.alpha_relative),
        method,
        ..FocusOptions::default()
    };
    let drives = solve_drives(&g, &targets, &focus).context("solving the drives")?;
    let mut signals = drives.signals(&g)?;
    if let Some(dir) = calibration {
        let filters = read_calibration(dir, g.actuators(), fs)?;
        signals = compensate(&signals, &filters)?;
    }
    let (peak, factor) = normalise_peak(&mut signals, 1.0)?;
    Ok(Rendered { g, drives, points, signals, peak, factor, focus_s, pad_s })
}

/// Runs `metaplate focus`.
pub fn run(args: &FocusArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let specs: Vec<PixelSpec> = args.pixels.iter().map(|p| parse_pixel(p)).collect::<anyhow::Result<_>>()?;
    let r = render(&dataset, &specs, args.calibration.as_deref(), &args.render)?;
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
        let at_pixels = r.field_at_pixels()?;
        let everywhere =
            if args.field_all_points { Some(predicted_field(&r.g, &r.drives, None, r.factor)?) } else { None };
        write_field(path, fs, &specs, &r.points, &at_pixels, r.g.points(), everywhere.as_deref())?;
        println!("wrote the predicted field to {}", path.display());
    }
    Ok(())
}

impl Rendered {
    /// The predicted field at each pixel over one period, in the dataset's units per drive unit times the
    /// normalisation (so per full scale of the written signals).
    ///
    /// # Errors
    /// As [`predicted_field`].
    pub fn field_at_pixels(&self) -> anyhow::Result<Vec<Vec<f64>>> {
        let rows: Vec<usize> = self
            .points
            .iter()
            .map(|&p| self.g.row_of(p).context("internal: pixel not among the rows"))
            .collect::<Result<_, _>>()?;
        Ok(predicted_field(&self.g, &self.drives, Some(&rows), self.factor)?)
    }

    /// Per pixel, the largest |v| over one period at any measured point within `radius_m` of its point on `grid`
    /// (the point itself included), in the units of [`Rendered::field_at_pixels`]: what a fingertip resting there
    /// feels rather than the field at one point (a null is a point; beside it the field can be large).
    ///
    /// # Errors
    /// A pixel's point off `grid`, a negative or non-finite radius, and [`predicted_field`]'s errors.
    pub fn peaks_within(&self, grid: &GridSpec, radius_m: f64) -> anyhow::Result<Vec<f64>> {
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            bail!("a radius of {radius_m} m (must be finite and >= 0)");
        }
        let position = |p: u32| -> anyhow::Result<(f64, f64)> {
            anyhow::ensure!((p as usize) < grid.len(), "point {p} is off the {} x {} grid", grid.nx, grid.ny);
            Ok(grid.position_m(p as usize))
        };
        let mut near: Vec<Vec<usize>> = Vec::with_capacity(self.points.len());
        let mut rows: Vec<usize> = Vec::new();
        for &pixel in &self.points {
            let (x0, y0) = position(pixel)?;
            let mut mine = Vec::new();
            for (row, &p) in self.g.points().iter().enumerate() {
                let (x, y) = position(p)?;
                if (x - x0).hypot(y - y0) <= radius_m + 1e-9 {
                    let at = rows.iter().position(|&r| r == row).unwrap_or_else(|| {
                        rows.push(row);
                        rows.len() - 1
                    });
                    mine.push(at);
                }
            }
            near.push(mine);
        }
        let field = predicted_field(&self.g, &self.drives, Some(&rows), self.factor)?;
        let peak = |v: &Vec<f64>| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        Ok(near.iter().map(|mine| mine.iter().map(|&i| peak(&field[i])).fold(0.0, f64::max)).collect())
    }
}

/// Writes the predicted field: CSV (`t_s` then one column per pixel, then per point with --field-all-points) when
/// `path` ends in `.csv`, else JSON `{"sample_rate_hz", "pixels": [{"x_m", "y_m", "point_index", "target", "v"}],
/// "points": [{"point_index", "v"}]}`; velocities in the dataset's units per unit drive, times the normalisation.
fn write_field(
    path: &Path,
    fs: f64,
    specs: &[PixelSpec],
    points: &[u32],
    at_pixels: &[Vec<f64>],
    all_points: &[u32],
    everywhere: Option<&[Vec<f64>]>,
) -> anyhow::Result<()> {
    let is_csv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let text = if is_csv {
        let mut columns: Vec<(String, &[f64])> = specs
            .iter()
            .zip(points)
            .zip(at_pixels)
            .map(|((s, p), v)| (format!("pixel_{p}_{}_{}", s.x_m, s.y_m), v.as_slice()))
            .collect();
        if let Some(all) = everywhere {
            columns.extend(all_points.iter().zip(all).map(|(p, v)| (format!("point_{p}"), v.as_slice())));
        }
        let mut out = String::from("t_s");
        for (name, _) in &columns {
            let _ = write!(out, ",{name}");
        }
        out.push('\n');
        let len = columns.first().map_or(0, |c| c.1.len());
        for i in 0..len {
            let _ = write!(out, "{}", i as f64 / fs);
            for (_, v) in &columns {
                let _ = write!(out, ",{:e}", v[i]);
            }
            out.push('\n');
        }
        out
    } else {
        let pixels: Vec<_> = specs
            .iter()
            .zip(points)
            .zip(at_pixels)
            .map(|((s, p), v)| json!({"x_m": s.x_m, "y_m": s.y_m, "point_index": p, "target": s.label, "v": v}))
            .collect();
        let mut doc = json!({"sample_rate_hz": fs, "pixels": pixels});
        if let Some(all) = everywhere {
            doc["points"] = all_points.iter().zip(all).map(|(p, v)| json!({"point_index": p, "v": v})).collect();
        }
        serde_json::to_string(&doc)?
    };
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}
