//! What the page draws (`/api/view`: the snapshot, the maps, the last point's spectra, the log's tail) and one
//! point's rows (`/api/point/N`). As in [`crate::state`], fields are declared in alphabetical order: the JSON is
//! what the monitor served when these were `serde_json::Value` objects.

use metaplate_recipes::cells::{SNR_SCALE_DB, grid_cells, planned_points, worst_status};
use metaplate_store::IrRecord;
use serde::{Serialize, Serializer};

use crate::follow::RunFiles;
use crate::state::RunState;

/// What the page draws.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct View {
    /// The last lines of the run's log.
    pub log_tail: String,
    /// The SNR map's colour scale, dB.
    pub snr_scale_db: [f64; 2],
    /// The SNR map (a scan), inline SVG.
    pub snr_svg: Option<String>,
    /// The last committed point's spectra.
    pub spectrum: Option<Spectrum>,
    /// The `/api/state` snapshot.
    pub state: RunState,
    /// The status map (a scan), inline SVG.
    pub status_svg: Option<String>,
}

impl View {
    /// The view of `files` with the snapshot `state`, the maps `width_px` wide.
    pub fn new(files: &RunFiles, state: RunState, width_px: usize) -> Self {
        let maps = maps_svg(files, width_px, SNR_SCALE_DB);
        let (status_svg, snr_svg) = maps.map_or((None, None), |(status, snr)| (Some(status), Some(snr)));
        View {
            log_tail: files.log_tail.clone(),
            snr_scale_db: [SNR_SCALE_DB.0, SNR_SCALE_DB.1],
            snr_svg,
            spectrum: files.last_commit.as_ref().and_then(|(_, records)| spectra(records)),
            state,
            status_svg,
        }
    }
}

/// The status and SNR maps of a scan as inline SVG (`None` for a calibration, which has no grid to show).
pub fn maps_svg(files: &RunFiles, width_px: usize, snr_scale_db: (f64, f64)) -> Option<(String, String)> {
    let meta = &files.manifest.as_ref()?.meta;
    if meta.config.contains_key("actuator_sites_m") {
        return None;
    }
    let (states, snr) = grid_cells(&meta.grid, &planned_points(&meta.config), files.all_rows());
    let (nx, ny) = (meta.grid.nx, meta.grid.ny);
    Some((
        metaplate_figures::status_map_svg(nx, ny, &states, width_px),
        metaplate_figures::snr_map_svg(nx, ny, &snr, snr_scale_db, width_px),
    ))
}

/// Log-spaced frequencies of the spectrum plot, Hz.
const SPECTRUM_BAND_HZ: (f64, f64) = (20.0, 2000.0);
/// Points per actuator of the spectrum plot.
const SPECTRUM_POINTS: usize = 240;

/// Magnitude spectra of one committed point (or a calibration's actuator), one line per row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spectrum {
    /// One line per row.
    pub actuators: Vec<SpectrumLine>,
    /// The frequencies, Hz: the geometric centres of log-spaced intervals.
    pub freq_hz: Vec<f64>,
    /// The rows' grid point.
    pub point: u32,
}

/// One row's magnitude spectrum.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumLine {
    /// The row's actuator.
    pub actuator: u16,
    /// The largest bin's magnitude in each interval, dB re 1 (`null` where it is zero).
    pub db: Vec<Option<f64>>,
    /// A calibration row's kind (filter, response, verification), `null` for a scan's.
    pub kind: Option<&'static str>,
}

/// The magnitude spectra, dB (re 1), of `records` (one per actuator; a calibration's rows carry their `kind`) on
/// log-spaced frequencies: the largest bin in each frequency's interval, so that narrow resonances are not lost;
/// `None` for no records. A response that cannot be transformed (non-finite samples) is left out.
pub fn spectra(records: &[IrRecord]) -> Option<Spectrum> {
    let first = records.first()?;
    let fs = first.meta.sample_rate_hz;
    let hi = SPECTRUM_BAND_HZ.1.min(fs / 2.0);
    let ratio = (hi / SPECTRUM_BAND_HZ.0).max(1.0);
    let freq_hz: Vec<f64> =
        (0..=SPECTRUM_POINTS).map(|i| SPECTRUM_BAND_HZ.0 * ratio.powf(i as f64 / SPECTRUM_POINTS as f64)).collect();
    let mut actuators = Vec::new();
    for record in records {
        let x: Vec<f64> = record.ir.iter().map(|v| f64::from(*v)).collect();
        let n = x.len().max(2);
        let Ok(spectrum) = metaplate_dsp::fft::forward(&x, n) else { continue };
        let bin = |f: f64| ((f * n as f64 / fs).round() as usize).min(spectrum.len() - 1);
        let db: Vec<Option<f64>> = freq_hz
            .windows(2)
            .map(|w| {
                let (a, b) = (bin(w[0]), bin(w[1]).max(bin(w[0])));
                let peak = spectrum[a..=b].iter().map(|c| c.norm()).fold(0.0, f64::max);
                (peak > 0.0).then(|| 20.0 * peak.log10())
            })
            .collect();
        actuators.push(SpectrumLine { actuator: record.meta.actuator, db, kind: record.meta.kind.map(|k| k.as_str()) });
    }
    let centres: Vec<f64> = freq_hz.windows(2).map(|w| (w[0] * w[1]).sqrt()).collect();
    Some(Spectrum { actuators, freq_hz: centres, point: first.meta.point_index })
}

/// `/api/point/N`: one committed point's rows and its worst status.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointView {
    /// Column of the point (of its first row).
    pub ix: Option<u32>,
    /// Row of the point.
    pub iy: Option<u32>,
    /// The grid index asked for.
    pub point: u32,
    /// Its rows, one per actuator.
    pub rows: Vec<PointRow>,
    /// Its worst status over the rows.
    pub status: Option<&'static str>,
    /// Position, m.
    pub x_m: Option<f64>,
    /// Position, m.
    pub y_m: Option<f64>,
}

/// One row of a point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointRow {
    /// The actuator.
    pub actuator: u16,
    /// The impulse response (written as the f64 of each f32 sample, as before).
    #[serde(serialize_with = "f32_as_f64")]
    pub ir: Vec<f32>,
    /// A calibration row's kind.
    pub kind: Option<&'static str>,
    /// Measurement time, µs since the Unix epoch.
    pub measured_at_unix_us: Option<i64>,
    /// Retries.
    pub retries: Option<u32>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// SNR, dB.
    pub snr_db: Option<f64>,
    /// The row's status.
    pub status: Option<&'static str>,
}

impl PointView {
    /// The view of grid point `point` from its committed `records`.
    pub fn new(point: u32, records: Vec<IrRecord>) -> Self {
        let first = records.first().map(|r| r.meta);
        let status = worst_status(records.iter().map(|r| &r.meta)).map(|s| s.label());
        let rows = records
            .into_iter()
            .map(|r| {
                let m = r.meta;
                PointRow {
                    actuator: m.actuator,
                    ir: r.ir,
                    kind: m.kind.map(|k| k.as_str()),
                    measured_at_unix_us: m.measured_at_unix_us,
                    retries: m.retries,
                    sample_rate_hz: m.sample_rate_hz,
                    snr_db: m.snr_db,
                    status: m.status.map(|s| s.as_str()),
                }
            })
            .collect();
        PointView {
            ix: first.map(|m| m.ix),
            iy: first.map(|m| m.iy),
            point,
            rows,
            status,
            x_m: first.map(|m| m.x_m),
            y_m: first.map(|m| m.y_m),
        }
    }
}

/// Serializes f32 samples as f64 numbers: `0.1f32` as `0.10000000149011612`, as the JSON value of an f32 was
/// written.
fn f32_as_f64<S: Serializer>(samples: &[f32], serializer: S) -> Result<S::Ok, S::Error> {
    serializer.collect_seq(samples.iter().map(|&v| f64::from(v)))
}
