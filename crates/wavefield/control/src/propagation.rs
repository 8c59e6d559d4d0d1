//! Propagation matrices `G(omega)`: the plate's transfer functions from each actuator to each point, per FFT bin of
//! the operating band.

use std::ops::Range;

use faer::MatRef;
use num_complex::Complex64;

use metaplate_dsp::fft;
use metaplate_store::Dataset;

use crate::error::{ControlError, check_finite};

/// Default operating band of the paper's focusing experiments, Hz.
pub const DEFAULT_BAND_HZ: (f64, f64) = (75.0, 400.0);

/// `G(omega)` at the bins of one band: for each bin `k` an `M x N` complex matrix (M points, N actuators) whose entry
/// `(m, n)` is the unnormalised DFT, at bin frequency `freqs_hz()[k]`, of the impulse response from actuator `n` to
/// point `m` (units of the response, e.g. (m/s) per unit drive).
///
/// The DFT has the impulse responses' own length (`fft_len()`), so the model is circular with period
/// `fft_len / sample_rate_hz` seconds: a drive signal of that length, played in a loop, gives exactly the field that
/// [`crate::render`] predicts. Matrices are stored column-major, one after the other.
#[derive(Debug, Clone)]
pub struct PropagationMatrices {
    freqs_hz: Vec<f64>,
    bins: Range<usize>,
    points: Vec<u32>,
    actuators: Vec<u16>,
    fft_len: usize,
    sample_rate_hz: f64,
    data: Vec<Complex64>,
}

impl PropagationMatrices {
    /// Builds `G(omega)` from a dataset over the FFT bins whose frequency lies in `band_hz = (lo, hi)` (inclusive),
    /// for `points` (grid flat indices, in that order, duplicates allowed) or, when `None`, for every point of the
    /// dataset in ascending order. Actuators are the dataset's, ascending.
    ///
    /// Valid range: `0 <= lo < hi`, finite; at least one bin in the band (`lo <= hi` spans at least one multiple of
    /// `sample_rate_hz / ir_len` below Nyquist). Cost: one real FFT of `ir_len` per impulse response, spread over the
    /// machine's cores; memory `16 * M * N * bins` bytes.
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for a bad band, [`ControlError::EmptyBand`] when no bin falls in it,
    /// [`ControlError::Empty`] for an empty `points`, [`ControlError::UnknownPoint`] or
    /// [`ControlError::MissingResponse`] when the dataset lacks a point or a (point, actuator) pair,
    /// [`ControlError::NonFinite`] for a non-finite stored sample.
    pub fn from_dataset(dataset: &Dataset, band_hz: (f64, f64), points: Option<&[u32]>) -> Result<Self, ControlError> {
        Self::from_dataset_padded(dataset, band_hz, points, dataset.ir_len())
    }

    /// As [`Self::from_dataset`], with each impulse response zero-padded to `fft_len` samples before its DFT: the
    /// model's period becomes `fft_len / sample_rate_hz`, which is what a drive played once (not looped) needs (see
    /// [`crate::render`]). Valid range: `fft_len >= ir_len`; the rest as [`Self::from_dataset`].
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for `fft_len < ir_len`; otherwise as [`Self::from_dataset`].
    pub fn from_dataset_padded(
        dataset: &Dataset,
        band_hz: (f64, f64),
        points: Option<&[u32]>,
        fft_len: usize,
    ) -> Result<Self, ControlError> {
        if fft_len < dataset.ir_len() {
            return Err(ControlError::InvalidParameter {
                name: "fft_len",
                reason: format!("{fft_len} is shorter than the impulse responses ({} samples)", dataset.ir_len()),
            });
        }
        let sample_rate_hz = dataset.sample_rate_hz();
        let bins = band_bins(band_hz, fft_len, sample_rate_hz)?;
        let points: Vec<u32> = points.map_or_else(|| dataset.points().to_vec(), <[u32]>::to_vec);
        if points.is_empty() {
            return Err(ControlError::Empty { input: "points" });
        }
        let actuators = dataset.actuators().to_vec();
        // Column c = (actuator n, point m) in column-major order of one bin's matrix: c = n * M + m.
        let mut columns: Vec<&[f32]> = Vec::with_capacity(points.len() * actuators.len());
        for &actuator in &actuators {
            for &point_index in &points {
                if dataset.points().binary_search(&point_index).is_err() {
                    return Err(ControlError::UnknownPoint { point_index });
                }
                columns.push(
                    dataset.ir(point_index, actuator).ok_or(ControlError::MissingResponse { point_index, actuator })?,
                );
            }
        }
        Self::assemble(&columns, bins, points, actuators, fft_len, sample_rate_hz)
    }

    /// Builds `G(omega)` from impulse responses in hand (simulated Green's functions, tests): `ir(m, n)` is the
    /// response from the `n`-th of `actuators` to the `m`-th of `points`, each `ir_len` samples at `sample_rate_hz`.
    /// Same band rule and valid range as [`Self::from_dataset`].
    ///
    /// # Errors
    /// As [`Self::from_dataset`]; [`ControlError::MissingResponse`] when `ir` gives `None` or a response of another
    /// length, [`ControlError::InvalidParameter`] for the sample rate.
    pub fn from_impulse_responses<'a>(
        points: Vec<u32>,
        actuators: Vec<u16>,
        sample_rate_hz: f64,
        band_hz: (f64, f64),
        ir: impl Fn(usize, usize) -> Option<&'a [f64]>,
    ) -> Result<Self, ControlError> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "sample_rate_hz",
                reason: format!("must be finite and positive, got {sample_rate_hz}"),
            });
        }
        if points.is_empty() || actuators.is_empty() {
            return Err(ControlError::Empty { input: if points.is_empty() { "points" } else { "actuators" } });
        }
        let mut columns: Vec<&[f64]> = Vec::with_capacity(points.len() * actuators.len());
        for (n, &actuator) in actuators.iter().enumerate() {
            for (m, &point_index) in points.iter().enumerate() {
                columns.push(ir(m, n).ok_or(ControlError::MissingResponse { point_index, actuator })?);
            }
        }
        let fft_len = columns[0].len();
        if let Some(pos) = columns.iter().position(|c| c.len() != fft_len) {
            let (n, m) = (pos / points.len(), pos % points.len());
            return Err(ControlError::MissingResponse { point_index: points[m], actuator: actuators[n] });
        }
        let bins = band_bins(band_hz, fft_len, sample_rate_hz)?;
        Self::assemble(&columns, bins, points, actuators, fft_len, sample_rate_hz)
    }

    /// FFTs the columns (actuator-major, then point) and lays each bin's matrix contiguously.
    fn assemble<T: Copy + Into<f64> + Sync>(
        columns: &[&[T]],
        bins: Range<usize>,
        points: Vec<u32>,
        actuators: Vec<u16>,
        fft_len: usize,
        sample_rate_hz: f64,
    ) -> Result<Self, ControlError> {
        let spectra = band_spectra(columns, fft_len, bins.clone())?;
        // Transpose from (column, bin) to (bin, column): each bin's matrix contiguous.
        let n_bins = bins.len();
        let n_cols = columns.len();
        let mut data = vec![Complex64::new(0.0, 0.0); n_bins * n_cols];
        for (c, spectrum) in spectra.chunks_exact(n_bins).enumerate() {
            for (k, &value) in spectrum.iter().enumerate() {
                data[k * n_cols + c] = value;
            }
        }
        let freqs_hz = bins.clone().map(|k| fft::bin_freq_hz(k, fft_len, sample_rate_hz)).collect();
        Ok(Self { freqs_hz, bins, points, actuators, fft_len, sample_rate_hz, data })
    }

    /// Builds `G(omega)` from matrices already in hand (synthetic tests, other sources): `bins` are FFT bin numbers
    /// of a length-`fft_len` DFT at `sample_rate_hz` (consecutive, ascending), `data` holds one column-major
    /// `points.len() x actuators.len()` matrix per bin, back to back.
    ///
    /// Valid range: `fft_len >= 1`, `bins` non-empty with `bins.end <= fft_len / 2 + 1`, finite positive sample rate,
    /// non-empty points and actuators, `data.len() == bins.len() * points.len() * actuators.len()`, all finite.
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`], [`ControlError::Empty`], [`ControlError::LengthMismatch`] or
    /// [`ControlError::NonFinite`] naming what broke the range.
    pub fn from_parts(
        bins: Range<usize>,
        fft_len: usize,
        sample_rate_hz: f64,
        points: Vec<u32>,
        actuators: Vec<u16>,
        data: Vec<Complex64>,
    ) -> Result<Self, ControlError> {
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "sample_rate_hz",
                reason: format!("must be finite and positive, got {sample_rate_hz}"),
            });
        }
        if bins.is_empty() || fft_len == 0 || bins.end > fft::bin_count(fft_len) {
            return Err(ControlError::InvalidParameter {
                name: "bins",
                reason: format!(
                    "{bins:?} is not a non-empty range of the {} bins of a {fft_len}-point FFT",
                    fft_len / 2 + 1
                ),
            });
        }
        if points.is_empty() {
            return Err(ControlError::Empty { input: "points" });
        }
        if actuators.is_empty() {
            return Err(ControlError::Empty { input: "actuators" });
        }
        let expected = bins.len() * points.len() * actuators.len();
        if data.len() != expected {
            return Err(ControlError::LengthMismatch {
                what: "propagation data against bins x points x actuators",
                a: data.len(),
                b: expected,
            });
        }
        check_finite("propagation data", data.iter().flat_map(|c| [c.re, c.im]))?;
        let freqs_hz = bins.clone().map(|k| fft::bin_freq_hz(k, fft_len, sample_rate_hz)).collect();
        Ok(Self { freqs_hz, bins, points, actuators, fft_len, sample_rate_hz, data })
    }

    /// Frequencies of the bins, Hz, ascending.
    pub fn freqs_hz(&self) -> &[f64] {
        &self.freqs_hz
    }

    /// FFT bin numbers of the band (bin `k` is at `k * sample_rate_hz / fft_len` Hz).
    pub fn bins(&self) -> Range<usize> {
        self.bins.clone()
    }

    /// Number of bins in the band.
    pub fn n_bins(&self) -> usize {
        self.bins.len()
    }

    /// Grid points (flat indices), in row order of every matrix.
    pub fn points(&self) -> &[u32] {
        &self.points
    }

    /// Number of points, `M`.
    pub fn n_points(&self) -> usize {
        self.points.len()
    }

    /// Actuator numbers, in column order of every matrix.
    pub fn actuators(&self) -> &[u16] {
        &self.actuators
    }

    /// Number of actuators, `N`.
    pub fn n_actuators(&self) -> usize {
        self.actuators.len()
    }

    /// DFT length (the impulse responses' length), samples.
    pub fn fft_len(&self) -> usize {
        self.fft_len
    }

    /// Sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// `G` at band bin `k` (`0 <= k < n_bins()`, i.e. frequency `freqs_hz()[k]`): an `M x N` complex matrix view, or
    /// `None` past the last bin.
    pub fn at_bin(&self, k: usize) -> Option<MatRef<'_, Complex64>> {
        let size = self.points.len() * self.actuators.len();
        let slice = self.data.get(k.checked_mul(size)?..k.checked_add(1)?.checked_mul(size)?)?;
        Some(MatRef::from_column_major_slice(slice, self.points.len(), self.actuators.len()))
    }

    /// Row position of grid point `point_index` in every matrix (its first occurrence), or `None`.
    pub fn row_of(&self, point_index: u32) -> Option<usize> {
        self.points.iter().position(|&p| p == point_index)
    }

    /// The same matrices with their rows relabelled as the grid points `points` (for another grid, e.g. a coarser
    /// lattice through the same points).
    ///
    /// # Errors
    /// [`ControlError::LengthMismatch`] unless `points` has one label per row.
    pub fn with_points(&self, points: Vec<u32>) -> Result<Self, ControlError> {
        if points.len() != self.points.len() {
            return Err(ControlError::LengthMismatch {
                what: "new point labels against rows",
                a: points.len(),
                b: self.points.len(),
            });
        }
        Ok(Self { points, ..self.clone() })
    }

    /// The same matrices restricted to the bins whose frequency lies in `band_hz = (lo, hi)` (inclusive): what a
    /// narrower operating band sees of a dataset loaded over a wider one.
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] unless `0 <= lo < hi` (finite); [`ControlError::EmptyBand`] when none of
    /// the bins falls in the band.
    pub fn select_band(&self, band_hz: (f64, f64)) -> Result<Self, ControlError> {
        let wanted = band_bins(band_hz, self.fft_len, self.sample_rate_hz)?;
        let bins = wanted.start.max(self.bins.start)..wanted.end.min(self.bins.end);
        if bins.is_empty() {
            return Err(ControlError::EmptyBand {
                lo_hz: band_hz.0,
                hi_hz: band_hz.1,
                spacing_hz: self.sample_rate_hz / self.fft_len as f64,
                nyquist_hz: self.sample_rate_hz / 2.0,
            });
        }
        let (first, count) = (bins.start - self.bins.start, bins.len());
        let size = self.points.len() * self.actuators.len();
        Ok(Self {
            freqs_hz: self.freqs_hz[first..first + count].to_vec(),
            bins,
            points: self.points.clone(),
            actuators: self.actuators.clone(),
            fft_len: self.fft_len,
            sample_rate_hz: self.sample_rate_hz,
            data: self.data[first * size..(first + count) * size].to_vec(),
        })
    }

    /// The sub-matrices for the rows `rows` (positions into [`Self::points`], any order, duplicates allowed).
    ///
    /// # Errors
    /// [`ControlError::Empty`] for no rows, [`ControlError::InvalidParameter`] for a row past the last point.
    pub fn select_rows(&self, rows: &[usize]) -> Result<Self, ControlError> {
        if rows.is_empty() {
            return Err(ControlError::Empty { input: "rows" });
        }
        let m = self.points.len();
        if let Some(&bad) = rows.iter().find(|&&r| r >= m) {
            return Err(ControlError::InvalidParameter { name: "rows", reason: format!("row {bad} >= {m} points") });
        }
        let n = self.actuators.len();
        let mut data = Vec::with_capacity(self.bins.len() * rows.len() * n);
        for matrix in self.data.chunks_exact(m * n) {
            for col in matrix.chunks_exact(m) {
                data.extend(rows.iter().map(|&r| col[r]));
            }
        }
        let points = rows.iter().map(|&r| self.points[r]).collect();
        Ok(Self {
            freqs_hz: self.freqs_hz.clone(),
            bins: self.bins.clone(),
            points,
            actuators: self.actuators.clone(),
            fft_len: self.fft_len,
            sample_rate_hz: self.sample_rate_hz,
            data,
        })
    }
}

/// The FFT bins of a length-`fft_len` DFT at `sample_rate_hz` whose frequency lies in `band_hz` (inclusive).
///
/// # Errors
/// [`ControlError::InvalidParameter`] unless `0 <= lo < hi` (finite); [`ControlError::EmptyBand`] when no bin falls
/// in the band below or at Nyquist.
pub fn band_bins(band_hz: (f64, f64), fft_len: usize, sample_rate_hz: f64) -> Result<Range<usize>, ControlError> {
    let (lo_hz, hi_hz) = band_hz;
    if !(lo_hz.is_finite() && hi_hz.is_finite() && lo_hz >= 0.0 && lo_hz < hi_hz) {
        return Err(ControlError::InvalidParameter {
            name: "band_hz",
            reason: format!("need finite 0 <= lo < hi, got ({lo_hz}, {hi_hz}) Hz"),
        });
    }
    let spacing_hz = sample_rate_hz / fft_len as f64;
    let first = (lo_hz / spacing_hz).ceil() as usize;
    let last = ((hi_hz / spacing_hz).floor() as usize).min(fft_len / 2);
    if fft_len == 0 || first > last {
        return Err(ControlError::EmptyBand { lo_hz, hi_hz, spacing_hz, nyquist_hz: sample_rate_hz / 2.0 });
    }
    Ok(first..last + 1)
}

/// The `bins` of the real FFT (length `fft_len`) of every column, back to back (`columns.len() * bins.len()`),
/// spread over the available cores: the FFTs dominate loading a dataset.
fn band_spectra<T: Copy + Into<f64> + Sync>(
    columns: &[&[T]],
    fft_len: usize,
    bins: Range<usize>,
) -> Result<Vec<Complex64>, ControlError> {
    let n_bins = bins.len();
    let mut out = vec![Complex64::new(0.0, 0.0); columns.len() * n_bins];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).max(1);
    let per_thread = columns.len().div_ceil(threads).max(1);
    let results: Vec<Result<(), ControlError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = columns
            .chunks(per_thread)
            .zip(out.chunks_mut(per_thread * n_bins))
            .map(|(cols, outs)| {
                let bins = bins.clone();
                scope.spawn(move || -> Result<(), ControlError> {
                    let mut samples = vec![0.0; fft_len];
                    let mut spectrum = vec![Complex64::new(0.0, 0.0); fft::bin_count(fft_len)];
                    for (col, dst) in cols.iter().zip(outs.chunks_exact_mut(n_bins)) {
                        // Zero-padding past the response (the buffer is reused, and the FFT overwrites it).
                        samples.fill(0.0);
                        for (s, &v) in samples.iter_mut().zip(col.iter()) {
                            *s = v.into();
                        }
                        fft::forward_destructive(&mut samples, &mut spectrum)?;
                        dst.copy_from_slice(&spectrum[bins.clone()]);
                    }
                    Ok(())
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or(Err(ControlError::NonFiniteResult { what: "FFT worker" })))
            .collect()
    });
    results.into_iter().collect::<Result<(), _>>()?;
    Ok(out)
}
