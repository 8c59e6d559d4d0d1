//! Drive signals that focus target waveforms on virtual pixels of a dataset's plate: what `metaplate focus` writes,
//! what `metaplate play` and the experiments play, what `metaplate demo` reports.
//!
//! Pixels are given in metres on the plate and snap to the nearest measured point ([`crate::pixels`]). The drives
//! are solved by the paper's spatiotemporal inverse filter (or time reversal) over the operating band, bin by bin.
//!
//! One-shot playback: the frequency-domain model is circular, so a drive one impulse-response long is exact only when
//! played in a loop. By default the impulse responses are zero-padded by their own length
//! ([`RenderOptions::pad_s`]), so the period is twice the response and the default focus time is half-way: the drive
//! that builds the focus fits before it and the plate's ring-down after it, and a single playback (preceded and
//! followed by silence) gives the predicted field up to the part of the responses that outlasts the padding. A
//! padding of 0 gives one period for looped playback.
//!
//! Calibration: [`render`] takes the Kirkeby inverse filters of the dataset's actuators (reading them from a
//! calibration dataset is the recipes' `play::render_through`); the drives are convolved with them (each channel
//! grows by the filter length minus one), while the predicted field is that of the uncompensated drives, since the
//! Green's functions were measured through the calibrated actuators.

use std::fmt::Write as _;
use std::str::FromStr;

use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_store::{Dataset, DatasetMeta};
use serde::Serialize;

use crate::error::ControlError;
use crate::pixels::{PointSelection, on_plate, snap_pixel};
use crate::propagation::PropagationMatrices;
use crate::render::{DriveSpectra, FocusOptions, compensate, normalise_peak, predicted_field, solve_drives};
use crate::solve::{DEFAULT_RELATIVE_ALPHA, Method, Regularisation};
use crate::target::{PixelTarget, Waveform};

/// Default operating band, Hz (the paper's).
pub const DEFAULT_FOCUS_BAND_HZ: (f64, f64) = (75.0, 400.0);

/// How drives are solved and laid out (the options of `metaplate focus`; [`Default`] is the command line's). With the
/// feature `clap`, they are command-line arguments (`--band-lo-hz` ...), flattened into a command's.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct RenderOptions {
    /// Lower edge of the operating band, Hz.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = DEFAULT_FOCUS_BAND_HZ.0))]
    pub band_lo_hz: f64,
    /// Upper edge of the operating band, Hz.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = DEFAULT_FOCUS_BAND_HZ.1))]
    pub band_hi_hz: f64,
    /// Tikhonov regularisation relative to the largest singular value at each frequency.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = DEFAULT_RELATIVE_ALPHA))]
    pub alpha_relative: f64,
    /// Time reversal instead of inverse filtering.
    #[cfg_attr(feature = "clap", arg(long))]
    pub time_reversal: bool,
    /// Zero padding of the impulse responses, s (default: their own length, for one-shot playback; 0: one period
    /// for looped playback).
    #[cfg_attr(feature = "clap", arg(long))]
    pub pad_s: Option<f64>,
    /// Focus time of plain `impulse` targets, s from the start of the drive (default: half the period).
    #[cfg_attr(feature = "clap", arg(long))]
    pub focus_s: Option<f64>,
    /// Use only the points whose every row's estimated error (the dataset's `estimated_error_db`, from the spread
    /// of repetitions) is at most this, dB; a pixel on a point left out is refused. Rows without an estimate are
    /// kept. Default: every point.
    #[cfg_attr(feature = "clap", arg(long, allow_hyphen_values = true))]
    pub max_error_db: Option<f64>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            band_lo_hz: DEFAULT_FOCUS_BAND_HZ.0,
            band_hi_hz: DEFAULT_FOCUS_BAND_HZ.1,
            alpha_relative: DEFAULT_RELATIVE_ALPHA,
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
#[derive(Debug, Clone, PartialEq)]
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
    /// The target does not parse as a [`Waveform`].
    pub fn from_text(x_m: f64, y_m: f64, target: &str) -> Result<Self, ControlError> {
        let label = target.trim().to_owned();
        let target = if label == "impulse" { TargetSpec::ImpulseAtFocus } else { TargetSpec::Waveform(label.parse()?) };
        Ok(Self { x_m, y_m, target, label })
    }
}

impl FromStr for PixelSpec {
    type Err = ControlError;

    /// Parses `--pixel`'s syntax, `X_M,Y_M[:TARGET]` (see [`parse_pixel`]).
    fn from_str(text: &str) -> Result<Self, ControlError> {
        parse_pixel(text)
    }
}

/// Parses `X_M,Y_M[:TARGET]` (metres; TARGET in [`Waveform`]'s syntax or `impulse`, the default).
///
/// # Errors
/// [`ControlError::Pixel`] for a malformed position or non-finite coordinates; a target that does not parse.
pub fn parse_pixel(text: &str) -> Result<PixelSpec, ControlError> {
    let refuse = |reason: String| ControlError::Pixel { text: text.to_owned(), reason };
    let (position, target) = text.split_once(':').unwrap_or((text, "impulse"));
    let Some((x, y)) = position.split_once(',') else { return Err(refuse("expected X_M,Y_M[:TARGET]".into())) };
    let number = |s: &str| s.trim().parse::<f64>().map_err(|_| refuse(format!("`{s}` is not a number")));
    let (x_m, y_m) = (number(x)?, number(y)?);
    if !(x_m.is_finite() && y_m.is_finite()) {
        return Err(refuse("coordinates must be finite".into()));
    }
    PixelSpec::from_text(x_m, y_m, target)
}

/// Drives rendered for a set of pixels.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The propagation matrices the drives were solved on (padded as [`RenderOptions::pad_s`] says).
    pub g: PropagationMatrices,
    /// The drive spectra (before compensation).
    pub drives: DriveSpectra,
    /// Each pixel's measured point (grid flat index).
    pub points: Vec<u32>,
    /// The signals to play, one per actuator: compensated when filters were given, peak-normalised to 1.
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

fn during(context: &'static str) -> impl FnOnce(ControlError) -> ControlError {
    move |e| ControlError::During { context, cause: Box::new(e) }
}

/// Solves, compensates (with `filters`, one per actuator of the dataset in its column order, if given) and
/// peak-normalises the drives that focus `specs` on the dataset's plate.
///
/// # Errors
/// A pixel off the plate, in a gap of the scan or on a point left out by [`RenderOptions::max_error_db`]; a
/// negative or non-finite padding; filters in another number than the actuators; the solver's errors.
pub fn render(
    dataset: &Dataset,
    specs: &[PixelSpec],
    filters: Option<&[KirkebyFilter]>,
    options: &RenderOptions,
) -> Result<Rendered, ControlError> {
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
        return Err(ControlError::InvalidParameter {
            name: "--pad-s",
            reason: format!("must be finite and >= 0, got {pad_s}"),
        });
    }
    let fft_len = ir_len + (pad_s * fs).round() as usize;
    let band = (options.band_lo_hz, options.band_hi_hz);
    let kept = selection.as_ref().map(|s| s.kept.as_slice());
    let g =
        PropagationMatrices::from_dataset_padded(dataset, band, kept, fft_len).map_err(during("building G(omega)"))?;
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
    let drives = solve_drives(&g, &targets, &focus).map_err(during("solving the drives"))?;
    let mut signals = drives.signals(&g)?;
    if let Some(filters) = filters {
        signals = compensate(&signals, filters)?;
    }
    let (peak, factor) = normalise_peak(&mut signals, 1.0)?;
    Ok(Rendered { g, drives, points, signals, peak, factor, focus_s, pad_s })
}

impl Rendered {
    /// The predicted field at each pixel over one period, in the dataset's units per drive unit times the
    /// normalisation (so per full scale of the signals).
    ///
    /// # Errors
    /// As [`predicted_field`].
    pub fn field_at_pixels(&self) -> Result<Vec<Vec<f64>>, ControlError> {
        let rows: Vec<usize> = self
            .points
            .iter()
            .map(|&p| self.g.row_of(p).ok_or(ControlError::UnknownPoint { point_index: p }))
            .collect::<Result<_, _>>()?;
        predicted_field(&self.g, &self.drives, Some(&rows), self.factor)
    }

    /// Per pixel, the largest |v| over one period at any measured point within `radius_m` of its point (the point
    /// itself included), the points where `meta` places them (on its grid, or scattered), in the units of
    /// [`Rendered::field_at_pixels`]: what a fingertip resting there feels rather than the field at one point (a null
    /// is a point; beside it the field can be large).
    ///
    /// # Errors
    /// A point `meta` does not place, a negative or non-finite radius, and [`predicted_field`]'s errors.
    pub fn peaks_within(&self, meta: &DatasetMeta, radius_m: f64) -> Result<Vec<f64>, ControlError> {
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "radius_m",
                reason: format!("a radius of {radius_m} m (must be finite and >= 0)"),
            });
        }
        let position = |p: u32| meta.position_m(p as usize).ok_or(ControlError::UnknownPoint { point_index: p });
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

    /// The predicted field as a file's text: CSV (`t_s` then one column per pixel, then per point with
    /// `all_points`) when `csv`, else JSON `{"pixels": [{"point_index", "target", "v", "x_m", "y_m"}], "points":
    /// [{"point_index", "v"}], "sample_rate_hz"}`; velocities in the dataset's units per unit drive, times the
    /// normalisation. `specs` are the pixels rendered, `sample_rate_hz` the dataset's rate.
    ///
    /// # Errors
    /// As [`predicted_field`].
    pub fn field_text(
        &self,
        specs: &[PixelSpec],
        sample_rate_hz: f64,
        all_points: bool,
        csv: bool,
    ) -> Result<String, ControlError> {
        let at_pixels = self.field_at_pixels()?;
        let everywhere =
            if all_points { Some(predicted_field(&self.g, &self.drives, None, self.factor)?) } else { None };
        let pixel_columns = specs.iter().zip(&self.points).zip(&at_pixels);
        if !csv {
            let pixels = pixel_columns
                .map(|((s, &point_index), v)| FieldPixel { point_index, target: &s.label, v, x_m: s.x_m, y_m: s.y_m })
                .collect();
            let points = everywhere.as_ref().map(|all| {
                self.g.points().iter().zip(all).map(|(&point_index, v)| FieldPoint { point_index, v }).collect()
            });
            let doc = FieldFile { pixels, points, sample_rate_hz };
            return serde_json::to_string(&doc)
                .map_err(|e| ControlError::InvalidParameter { name: "field", reason: e.to_string() });
        }
        let mut columns: Vec<(String, &[f64])> =
            pixel_columns.map(|((s, p), v)| (format!("pixel_{p}_{}_{}", s.x_m, s.y_m), v.as_slice())).collect();
        if let Some(all) = &everywhere {
            columns.extend(self.g.points().iter().zip(all).map(|(p, v)| (format!("point_{p}"), v.as_slice())));
        }
        let mut out = String::from("t_s");
        for (name, _) in &columns {
            let _ = write!(out, ",{name}");
        }
        out.push('\n');
        let len = columns.first().map_or(0, |c| c.1.len());
        for i in 0..len {
            let _ = write!(out, "{}", i as f64 / sample_rate_hz);
            for (_, v) in &columns {
                let _ = write!(out, ",{:e}", v[i]);
            }
            out.push('\n');
        }
        Ok(out)
    }
}

/// The JSON field file (keys in alphabetical order, as it has always been written).
#[derive(Serialize)]
struct FieldFile<'a> {
    pixels: Vec<FieldPixel<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    points: Option<Vec<FieldPoint<'a>>>,
    sample_rate_hz: f64,
}

#[derive(Serialize)]
struct FieldPixel<'a> {
    point_index: u32,
    target: &'a str,
    v: &'a [f64],
    x_m: f64,
    y_m: f64,
}

#[derive(Serialize)]
struct FieldPoint<'a> {
    point_index: u32,
    v: &'a [f64],
}
