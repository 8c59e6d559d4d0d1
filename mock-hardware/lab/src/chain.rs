//! The signal chain: what the audio interface plays, through actuators, plate and LDV, to the DAQ's inputs.
//!
//! A playback is turned into signals once per DAQ acquisition, the first time the DAQ samples a time it covers
//! ([`LabState::fill`]): per active actuator channel, the force spectrum (cached per drive buffer) times the
//! Green's function spectrum at the beam's point, one inverse FFT, then one band-limited resampling onto the DAQ's
//! sample times. Noise, dropouts, the LDV's range and clipping are applied per DAQ sample as the DAQ reads.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::rng::{SplitMix64, mix64, unit_open};
use metaplate_core::scene::FaultKind;
use metaplate_dsp::fft;
use metaplate_dsp::resample::Interpolator;
use metaplate_mock_audio::{FaultWindows, Playback, PlaybackObserver};
use metaplate_mock_ldv::MockDevice;
use metaplate_plate::GreensFunctions;
use metaplate_plate::actuator::VoiceCoil;
use num_complex::Complex64;

use crate::LabError;

/// Lowest signal level used to scale the noise (a level of 0 would make it infinite), fraction of full.
const MIN_NOISE_LEVEL: f64 = 0.05;
/// Length of a random (probability-drawn) dropout, s: 20 to 100 ms, as speckle dropouts while the beam rests.
const DROPOUT_MIN_S: f64 = 0.020;
const DROPOUT_SPAN_S: f64 = 0.080;
/// Relative level below which spectrum bins count as empty when sizing the loopback's interpolator.
const BAND_EDGE_LEVEL: f64 = 1e-7;
/// Stream constant of the aiming error's draws.
const AIM_STREAM: u64 = 0x0000_0A1A_0E44;
/// Drive buffers whose forces are kept (one per actuator of a scan, plus room).
const DRIVE_CACHE_LEN: usize = 16;

/// Fixed parameters of the chain, from the scene and the lab's options.
#[derive(Debug, Clone)]
pub(crate) struct ChainParams {
    pub seed: u64,
    pub actuator_channels: Vec<u32>,
    pub loopback_channel: u32,
    pub velocity_input: u8,
    pub loopback_input: u8,
    pub loopback_volts_per_full_scale: f64,
    pub daq_ppm: f64,
    pub noise_rms_m_s: f64,
    pub dropout_probability: f64,
    /// Whether the vibrometer's output clips at its range's full scale (the scene's `daq.clipping`).
    pub clipping: bool,
    /// Beam positioning error, m rms per axis (0: exact aim).
    pub aim_error_rms_m: f64,
    /// Top of the Green's functions' band, Hz.
    pub band_hi_hz: f64,
}

/// The beam's offset from its prepared point, m: zero within the controller's resolution (it holds the beam in whole
/// micrometres, so an exact aim reads back up to half a micrometre off), else as measured.
fn beam_offset_m(dx_m: f64, dy_m: f64) -> (f64, f64) {
    let within = |d: f64| d.abs() < metaplate_mock_ldv::BEAM_RESOLUTION_M;
    if within(dx_m) && within(dy_m) { (0.0, 0.0) } else { (dx_m, dy_m) }
}

/// The Green's functions and where their points are.
#[derive(Debug)]
pub(crate) struct Plate {
    pub greens: GreensFunctions,
    /// (x, y) of each prepared point, m, in the order of `greens.points`.
    pub positions_m: Vec<(f64, f64)>,
    /// Half the grid spacing, m: how far the beam may be from a prepared point.
    pub tolerance_m: f64,
    pub coils: Vec<VoiceCoil>,
    /// Per prepared point, how to take the response's slope there (grid points with prepared neighbours).
    pub slopes: Vec<Slope>,
}

/// Finite differences for the slope of the response at a prepared point, along x and along y: the prepared-point
/// indices `(minus, plus)` and their distance, m (`None`: no neighbour along that axis, no slope).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Slope {
    pub x: Option<(usize, usize, f64)>,
    pub y: Option<(usize, usize, f64)>,
}

impl Slope {
    /// The grid neighbours of grid point `p`: `[x - 1, x + 1, y - 1, y + 1]`, `None` past the grid's edge.
    pub fn grid_neighbours(grid: &metaplate_core::grid::GridSpec, p: usize) -> [Option<usize>; 4] {
        let (ix, iy) = grid.indices(p);
        let at = |x: Option<usize>, y: Option<usize>| match (x, y) {
            (Some(x), Some(y)) if x < grid.nx && y < grid.ny => Some(grid.index(x, y)),
            _ => None,
        };
        [
            at(ix.checked_sub(1), Some(iy)),
            at(Some(ix + 1), Some(iy)),
            at(Some(ix), iy.checked_sub(1)),
            at(Some(ix), Some(iy + 1)),
        ]
    }

    /// The slope rule of point `p` (a flat grid index, or a driving point: none) among the prepared `points`:
    /// central differences where both neighbours are prepared, one-sided where one is.
    pub fn at(scene: &metaplate_core::scene::Scene, points: &[usize], p: usize) -> Slope {
        if p >= scene.grid.len() {
            return Slope::default();
        }
        let k = |q: Option<usize>| q.and_then(|q| points.iter().position(|&r| r == q));
        let Some(me) = k(Some(p)) else { return Slope::default() };
        let h = scene.grid.spacing_m;
        let [xm, xp, ym, yp] = Slope::grid_neighbours(&scene.grid, p).map(k);
        let axis = |minus: Option<usize>, plus: Option<usize>| match (minus, plus) {
            (Some(m), Some(p)) => Some((m, p, 2.0 * h)),
            (Some(m), None) => Some((m, me, h)),
            (None, Some(p)) => Some((me, p, h)),
            (None, None) => None,
        };
        Slope { x: axis(xm, xp), y: axis(ym, yp) }
    }
}

impl Plate {
    /// The prepared point nearest `(x_m, y_m)`, within the tolerance.
    pub fn point_at(&self, x_m: f64, y_m: f64) -> Option<usize> {
        let d2 = |&(px, py): &(f64, f64)| (px - x_m).powi(2) + (py - y_m).powi(2);
        let (k, best) = self.positions_m.iter().map(d2).enumerate().min_by(|a, b| a.1.total_cmp(&b.1))?;
        (best <= self.tolerance_m.powi(2)).then_some(k)
    }
}

/// What one drive buffer does, computed once: per active actuator its force spectrum, and the loopback.
#[derive(Debug)]
struct DriveEffect {
    /// Length of the 24 kHz-grid FFT the spectra belong to.
    fft_len: usize,
    /// (actuator, force spectrum bins 0..=k_max on the half-rate audio grid, N).
    forces: Vec<(usize, Vec<Complex64>)>,
    /// Loopback voltage on the half-rate audio grid (band-limited decimation), V; empty when silent.
    loopback_v: Vec<f64>,
    /// Interpolator suited to the loopback's bandwidth.
    loopback_interp: &'static Interpolator,
}

/// A playback with what the lab knows of it.
#[derive(Debug)]
struct Scheduled {
    playback: Playback,
    /// Cache key of its drive buffer.
    key: u64,
    /// Prepared point under the beam at playback start (None: beam off every prepared point, or laser off).
    point_k: Option<usize>,
    /// Where the beam really is relative to that point, m (the aiming error; zero when exact).
    aim_offset_m: (f64, f64),
    /// A random dropout: (start, end) virtual time, s.
    dropout_s: Option<(f64, f64)>,
    /// Time from the playback's start to the end of its last non-silent frame, s: the plate answers nothing to
    /// silence, so its response ends one ring-down after this, not after the playback's silent tail.
    sounding_s: f64,
    /// Rendered for the DAQ acquisition `run` (its id): first DAQ sample index, velocity (m/s), loopback (V).
    rendered: Option<Rendered>,
}

#[derive(Debug)]
struct Rendered {
    run: u64,
    first: u64,
    velocity_m_s: Vec<f64>,
    loopback_v: Vec<f64>,
}

/// A DAQ acquisition as the lab sees it: when its sample 0 was taken.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DaqRun {
    pub id: u64,
    pub t0_s: f64,
    /// Seeds the LDV noise of this acquisition: set from the playback it records (see [`LabState::schedule`]),
    /// so that the same measurement draws the same noise in any session (a resumed scan equals an uninterrupted
    /// one); from the run counter when nothing plays.
    pub noise_key: u64,
}

/// Counters for tests and logs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LabStats {
    /// Playbacks scheduled.
    pub playbacks: u64,
    /// Drive buffers whose forces were computed (cache misses).
    pub drive_computations: u64,
    /// Playbacks rendered for a DAQ acquisition.
    pub renders: u64,
    /// Playbacks during which the beam was on no prepared point (the plate then gave no velocity).
    pub beam_off_prepared_points: u64,
    /// Random (probability-drawn) LDV dropouts.
    pub random_dropouts: u64,
}

/// The lab's shared state: playbacks, the DAQ acquisition, caches.
pub(crate) struct LabState {
    pub params: ChainParams,
    plate: Arc<Plate>,
    clock: Arc<VirtualClock>,
    ldv: Arc<Mutex<MockDevice>>,
    windows: FaultWindows,
    playbacks: Vec<Scheduled>,
    drives: HashMap<u64, Arc<DriveEffect>>,
    drive_order: Vec<u64>,
    run: Option<DaqRun>,
    next_run: u64,
    /// Plays of each drive buffer at each beam site: (site hash, buffer hash) -> count.
    occurrences: HashMap<(u64, u64), u64>,
    pub stats: LabStats,
    /// Scratch buffers reused across renders (no per-playback allocation of the big spectra).
    spectrum: Vec<Complex64>,
    time: Vec<f64>,
}

impl LabState {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        params: ChainParams,
        plate: Arc<Plate>,
        clock: Arc<VirtualClock>,
        ldv: Arc<Mutex<MockDevice>>,
        windows: FaultWindows,
    ) -> Self {
        Self {
            params,
            plate,
            clock,
            ldv,
            windows,
            playbacks: Vec::new(),
            drives: HashMap::new(),
            drive_order: Vec::new(),
            run: None,
            next_run: 0,
            occurrences: HashMap::new(),
            stats: LabStats::default(),
            spectrum: Vec::new(),
            time: Vec::new(),
        }
    }

    /// A DAQ acquisition started now.
    pub fn daq_started(&mut self) {
        let noise_key = mix64(self.params.seed ^ mix64(self.next_run.wrapping_add(0x0015_E000)));
        self.run = Some(DaqRun { id: self.next_run, t0_s: self.clock.now_s(), noise_key });
        self.next_run += 1;
    }

    /// Schedules a playback: where the beam is, whether a random dropout strikes it.
    fn schedule(&mut self, playback: &Playback, beam: Option<(f64, f64)>) {
        self.stats.playbacks += 1;
        let point_k = beam.and_then(|(x, y)| self.plate.point_at(x, y));
        if beam.is_some() && point_k.is_none() {
            self.stats.beam_off_prepared_points += 1;
        }
        // Random draws are keyed by what is measured, not by the session's history: the beam position (whole
        // micrometres), the drive buffer, and how many times this lab has played that buffer there. A scan that
        // resumes after a crash replays the same measurements in the same order per point, so it draws the same
        // noise and dropouts as an uninterrupted run.
        let key = hash_samples(&playback.samples, playback.channels);
        let site = beam.map_or(u64::MAX, |(x, y)| {
            mix64(((x * 1e6).round() as i64 as u64) ^ mix64((y * 1e6).round() as i64 as u64))
        });
        let occurrence = self.occurrences.entry((site, key)).or_insert(0);
        let measurement = mix64(self.params.seed ^ mix64(site ^ mix64(key ^ *occurrence)));
        *occurrence += 1;
        if let Some(run) = self.run.as_mut() {
            run.noise_key = mix64(measurement ^ 0x0015_E000);
        }
        // The aiming error is the scanner's at this point: keyed by the point alone, the same at every playback.
        let drawn_m = if self.params.aim_error_rms_m > 0.0 {
            let mut rng = SplitMix64::new(self.params.seed ^ site, AIM_STREAM);
            (self.params.aim_error_rms_m * rng.normal(), self.params.aim_error_rms_m * rng.normal())
        } else {
            (0.0, 0.0)
        };
        // Plus where the beam really is against the point: nothing for the lab's exact aim, the fit's error for a
        // beam steered by taught mirrors.
        let landed_m = match (beam, point_k.and_then(|k| self.plate.positions_m.get(k))) {
            (Some((x, y)), Some(&(px, py))) => beam_offset_m(x - px, y - py),
            _ => (0.0, 0.0),
        };
        let aim_offset_m = (drawn_m.0 + landed_m.0, drawn_m.1 + landed_m.1);
        let draw = mix64(measurement ^ 0xD40F_0D40);
        let dropout_s = (unit_open(draw) < self.params.dropout_probability).then(|| {
            let at = playback.start_s + unit_open(mix64(draw)) * (playback.end_s() - playback.start_s);
            (at, at + DROPOUT_MIN_S + DROPOUT_SPAN_S * unit_open(mix64(draw ^ 1)))
        });
        if dropout_s.is_some() {
            self.stats.random_dropouts += 1;
            // The controller's signal level reads low at the next query, as after a real dropout.
            if let Ok(mut ldv) = self.ldv.lock() {
                ldv.controller_mut().start_dropout(1);
            }
        }
        let channels = playback.channels.max(1) as usize;
        let sounding_frames = playback.samples.iter().rposition(|v| *v != 0.0).map_or(0, |i| i / channels + 1);
        self.playbacks.push(Scheduled {
            playback: playback.clone(),
            key,
            point_k,
            aim_offset_m,
            dropout_s,
            sounding_s: sounding_frames as f64 / playback.frame_rate_hz,
            rendered: None,
        });
    }

    /// The forces and loopback of a drive buffer, from the cache or computed.
    fn drive_effect(&mut self, scheduled_k: usize) -> Result<Arc<DriveEffect>, LabError> {
        let key = self.playbacks[scheduled_k].key;
        if let Some(hit) = self.drives.get(&key) {
            return Ok(Arc::clone(hit));
        }
        let effect = Arc::new(compute_drive(&self.params, &self.plate, &self.playbacks[scheduled_k].playback)?);
        self.stats.drive_computations += 1;
        if self.drive_order.len() >= DRIVE_CACHE_LEN {
            let old = self.drive_order.remove(0);
            self.drives.remove(&old);
        }
        self.drive_order.push(key);
        self.drives.insert(key, Arc::clone(&effect));
        Ok(effect)
    }

    /// Renders playback `k` onto the DAQ samples of `run`.
    fn render(&mut self, k: usize, run: DaqRun, fd_hz: f64) -> Result<(), LabError> {
        let (start_s, sounding_s, fa_hz, point_k, aim_offset_m) = {
            let s = &self.playbacks[k];
            (s.playback.start_s, s.sounding_s, s.playback.frame_rate_hz, s.point_k, s.aim_offset_m)
        };
        // The DAQ samples the playback reaches: from just before it (the interpolator's reach) to the end of the
        // plate's ring-down after its last sound. Rendering no further keeps the rounding noise of the FFT
        // convolution (some -110 dB) out of the next acquisition, which would otherwise see it or not depending on
        // whether this playback happened in the same session.
        let ring_s = self.plate.greens.ir_len as f64 / self.plate.greens.sample_rate_hz;
        // The playback's start relative to the acquisition, rounded to 10 ns. Both instants are sums of many clock
        // steps whose rounding (about 1e-14 s after minutes, 1e-10 s after days) depends on how long the session
        // has run; through the DAQ's 16-bit quantiser that would flip a few bits of a measurement depending on its
        // history. Rounded, a measurement renders the same bits whether it is the first of a session or the
        // thousandth, so a resumed scan equals an uninterrupted one. The shift is common to velocity and loopback,
        // so the reference deconvolution does not see it.
        let offset_s = ((start_s - run.t0_s) * 1e8).round() / 1e8;
        let first_f = (offset_s * fd_hz - 32.0).ceil().max(0.0);
        let last_f = ((offset_s + sounding_s + ring_s) * fd_hz).floor();
        if last_f < first_f {
            // Over before this acquisition started: nothing to compute.
            self.playbacks[k].rendered =
                Some(Rendered { run: run.id, first: 0, velocity_m_s: vec![], loopback_v: vec![] });
            return Ok(());
        }
        let effect = self.drive_effect(k)?;
        // Half-rate audio grid: sample j at start_s + 2 j / fa.
        let grid_hz = fa_hz / 2.0;
        let first = first_f as u64;
        let len = (last_f - first_f) as usize + 1;
        let pos0 = (first_f / fd_hz - offset_s) * grid_hz;
        let step = grid_hz / fd_hz;
        let mut velocity_m_s = vec![0.0; len];
        if let Some(point_k) = point_k
            && !effect.forces.is_empty()
        {
            self.velocity_on_grid(&effect, point_k, aim_offset_m)?;
            let interp = Interpolator::for_band(self.params.band_hi_hz, grid_hz);
            interp.resample_into(&self.time, pos0, step, &mut velocity_m_s)?;
        }
        let mut loopback_v = vec![0.0; len];
        if !effect.loopback_v.is_empty() {
            effect.loopback_interp.resample_into(&effect.loopback_v, pos0, step, &mut loopback_v)?;
        }
        self.stats.renders += 1;
        self.playbacks[k].rendered = Some(Rendered { run: run.id, first, velocity_m_s, loopback_v });
        Ok(())
    }

    /// Plate velocity on the half-rate audio grid into `self.time` (length `effect.fft_len`), m/s.
    /// `aim_offset_m`: where the beam is relative to the point, m (first order, through the point's [`Slope`]).
    fn velocity_on_grid(
        &mut self,
        effect: &DriveEffect,
        point_k: usize,
        aim_offset_m: (f64, f64),
    ) -> Result<(), LabError> {
        let n = effect.fft_len;
        self.spectrum.clear();
        self.spectrum.resize(fft::bin_count(n), Complex64::new(0.0, 0.0));
        for (actuator, force) in &effect.forces {
            let greens = if aim_offset_m == (0.0, 0.0) {
                greens_spectrum(&self.plate.greens, point_k, *actuator, n, force.len())?
            } else {
                let ir = aimed_response(&self.plate, point_k, *actuator, aim_offset_m)?;
                let mut spectrum = fft::forward(&ir, n)?;
                spectrum.truncate(force.len());
                spectrum
            };
            for ((v, f), g) in self.spectrum.iter_mut().zip(force).zip(&greens) {
                *v += f * g;
            }
        }
        self.time.resize(n, 0.0);
        fft::inverse_into(&self.spectrum, n, &mut self.time)?;
        Ok(())
    }

    /// The DAQ's `fill`: voltage at `input` for samples `first ..` of the current acquisition.
    pub fn fill(&mut self, input: u8, first: u64, nominal_hz: f64, out: &mut [f64]) -> Result<(), LabError> {
        out.fill(0.0);
        let Some(run) = self.run else { return Ok(()) };
        let fd_hz = nominal_hz * (1.0 + self.params.daq_ppm * 1e-6);
        let t_first = run.t0_s + first as f64 / fd_hz;
        let t_end = run.t0_s + (first + out.len() as u64) as f64 / fd_hz;
        // Reading samples up to t_end means t_end has come.
        self.clock.advance(t_end - self.clock.now_s());
        // Playbacks that ended (response tail included) well before this block are done with.
        let tail_s = self.plate.greens.ir_len as f64 / self.plate.greens.sample_rate_hz + 1.0;
        self.playbacks.retain(|s| s.playback.end_s() + tail_s >= t_first);
        for k in 0..self.playbacks.len() {
            let fresh = self.playbacks[k].rendered.as_ref().is_some_and(|r| r.run == run.id);
            // Only the playbacks that start during this acquisition: the ring-down of an earlier one (the previous
            // unit's last sweep, still up to 1e-4 of peak when the next acquisition starts) is not carried over, so
            // that a measurement is the same whether or not the session measured something just before it (a
            // resumed run starts on a plate at rest). Recipes record each playback whole, ring-down included.
            let own = self.playbacks[k].playback.start_s >= run.t0_s;
            if !fresh && own && self.playbacks[k].playback.start_s - 0.01 <= t_end {
                self.render(k, run, fd_hz)?;
            }
        }
        let is_velocity = input == self.params.velocity_input;
        if !is_velocity && input != self.params.loopback_input {
            return Ok(());
        }
        for s in &self.playbacks {
            let Some(r) = s.rendered.as_ref().filter(|r| r.run == run.id) else { continue };
            let src = if is_velocity { &r.velocity_m_s } else { &r.loopback_v };
            add_overlap(out, first, src, r.first);
        }
        if is_velocity { self.ldv_output(run, first, fd_hz, out) } else { Ok(()) }
    }

    /// Turns plate velocity (m/s) into the LDV's output voltage: dropouts, noise, range, clipping.
    fn ldv_output(&mut self, run: DaqRun, first: u64, fd_hz: f64, out: &mut [f64]) -> Result<(), LabError> {
        let (range, level) = {
            let ldv = self.ldv.lock().map_err(|_| LabError::Poisoned("the LDV mock"))?;
            let c = ldv.controller();
            (c.output_range(), c.beam_m().map(|_| c.speckle_level()))
        };
        let (Some(range), Some(level)) = (range, level) else {
            // No beam on the plate yet (or no decoder): no Doppler signal, the velocity output rests at 0 V.
            out.fill(0.0);
            return Ok(());
        };
        let full_scale = range.m_s_per_v() * metaplate_ldv::OUTPUT_FULL_SCALE_V;
        let noise = self.params.noise_rms_m_s / level.max(MIN_NOISE_LEVEL);
        let key = run.noise_key;
        for (i, v) in out.iter_mut().enumerate() {
            *v += noise * approx_normal(mix64(key ^ (first + i as u64)));
        }
        // Dropouts: scheduled (ldv_dropout windows) and random (per playback): the decoder loses lock and its
        // output is garbage across the range.
        let time_of = |i: usize| run.t0_s + (first + i as u64) as f64 / fd_hz;
        let mut dropouts: Vec<(f64, f64)> = self
            .windows
            .of_kind(FaultKind::LdvDropout)
            .map(|f| (f.at_s, f.at_s + f.duration_s.max(1.0 / fd_hz)))
            .collect();
        dropouts.extend(self.playbacks.iter().filter(|s| s.playback.start_s >= run.t0_s).filter_map(|s| s.dropout_s));
        let (t_lo, t_hi) = (time_of(0), time_of(out.len()));
        for (a, b) in dropouts.into_iter().filter(|&(a, b)| b >= t_lo && a <= t_hi) {
            let i0 = (((a - t_lo) * fd_hz).ceil().max(0.0) as usize).min(out.len());
            let i1 = (((b - t_lo) * fd_hz).floor().max(0.0) as usize + 1).min(out.len());
            for (i, v) in out.iter_mut().enumerate().take(i1).skip(i0) {
                *v = full_scale * (2.0 * unit_open(mix64(key ^ 0xBAD ^ (first + i as u64))) - 1.0);
            }
        }
        let volts_per_m_s = 1.0 / range.m_s_per_v();
        let clip = if self.params.clipping { full_scale } else { f64::INFINITY };
        for v in out.iter_mut() {
            *v = v.clamp(-clip, clip) * volts_per_m_s;
        }
        Ok(())
    }
}

/// Adds `src` (starting at sample `src_first`) into `out` (starting at `out_first`) where they overlap.
fn add_overlap(out: &mut [f64], out_first: u64, src: &[f64], src_first: u64) {
    let lo = out_first.max(src_first);
    let hi = (out_first + out.len() as u64).min(src_first + src.len() as u64);
    if hi <= lo {
        return;
    }
    let (o, s, n) = ((lo - out_first) as usize, (lo - src_first) as usize, (hi - lo) as usize);
    out[o..o + n].iter_mut().zip(&src[s..s + n]).for_each(|(a, b)| *a += b);
}

/// A standard-normal-like draw from 64 random bits: the sum of four 16-bit uniforms, centred and scaled to unit
/// variance (Irwin-Hall; tails end at 3.46 sigma). Far cheaper than Box-Muller, which would cost more than the
/// whole rest of a recording.
fn approx_normal(bits: u64) -> f64 {
    let sum: u64 = (0..4).map(|k| (bits >> (16 * k)) & 0xFFFF).sum();
    // Each uniform on 0..65536 has mean 32767.5 and variance (65536^2 - 1) / 12.
    (sum as f64 - 4.0 * 32767.5) / (4.0 * (65536.0f64 * 65536.0 - 1.0) / 12.0).sqrt()
}

/// A 64-bit hash of a buffer's samples and shape: four independent multiply lanes over pairs of samples (the
/// lanes run in parallel on the CPU: about 1 ms for 15 s of 9 channels).
fn hash_samples(samples: &[f32], channels: u32) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let pair = |p: &[f32]| u64::from(p[0].to_bits()) | (u64::from(p[1].to_bits()) << 32);
    let mut lanes = [1u64, 2, 3, 4];
    let mut chunks = samples.chunks_exact(8);
    for c in &mut chunks {
        for (l, lane) in lanes.iter_mut().enumerate() {
            *lane = (*lane ^ pair(&c[2 * l..2 * l + 2])).wrapping_mul(K).rotate_left(29);
        }
    }
    let mut h = mix64(u64::from(channels) ^ (samples.len() as u64).rotate_left(32));
    for (i, &x) in chunks.remainder().iter().enumerate() {
        h ^= mix64(u64::from(x.to_bits()) ^ (i as u64) << 40);
    }
    lanes.iter().fold(h, |h, &l| mix64(h ^ l))
}

/// The Green's function spectrum from actuator `actuator` to prepared point `point_k`: bins `0..bins` of its
/// `fft_len`-point FFT. (A full FFT: the response is not band-limited, its band-limited precursor being cut at
/// t = 0, so an FFT of a decimated response would alias into the band.)
fn greens_spectrum(
    greens: &GreensFunctions,
    point_k: usize,
    actuator: usize,
    fft_len: usize,
    bins: usize,
) -> Result<Vec<Complex64>, LabError> {
    let actuator_k = greens
        .actuators
        .iter()
        .position(|&a| a == actuator)
        .ok_or(LabError::NotPrepared { what: format!("actuator {actuator}") })?;
    let ir = greens.ir(point_k, actuator_k).ok_or(LabError::NotPrepared { what: format!("point #{point_k}") })?;
    let mut spectrum = fft::forward(ir, fft_len)?;
    spectrum.truncate(bins);
    Ok(spectrum)
}

/// The response from actuator `actuator` at the spot `offset_m` (m) from prepared point `point_k`: the point's
/// response plus the offset times its slope along each axis that has one (see [`Slope`]).
fn aimed_response(plate: &Plate, point_k: usize, actuator: usize, offset_m: (f64, f64)) -> Result<Vec<f64>, LabError> {
    let greens = &plate.greens;
    let actuator_k = greens
        .actuators
        .iter()
        .position(|&a| a == actuator)
        .ok_or(LabError::NotPrepared { what: format!("actuator {actuator}") })?;
    let ir = |k: usize| greens.ir(k, actuator_k).ok_or(LabError::NotPrepared { what: format!("point #{k}") });
    let mut out = ir(point_k)?.to_vec();
    let slope = plate.slopes.get(point_k).copied().unwrap_or_default();
    for (axis, d) in [(slope.x, offset_m.0), (slope.y, offset_m.1)] {
        if let Some((minus, plus, span_m)) = axis {
            let (m, p) = (ir(minus)?, ir(plus)?);
            for ((o, a), b) in out.iter_mut().zip(p).zip(m) {
                *o += d * (a - b) / span_m;
            }
        }
    }
    Ok(out)
}

/// The force spectra and loopback of one drive buffer.
fn compute_drive(params: &ChainParams, plate: &Plate, playback: &Playback) -> Result<DriveEffect, LabError> {
    let channels = playback.channels as usize;
    let frames = playback.frames();
    // Half-rate grid length: the frames, the response's ring-down, and a guard against wrap-around.
    let fft_len = fft::fast_len(frames.div_ceil(2) + plate.greens.ir_len + 64)?;
    let channel =
        |c: usize| -> Vec<f64> { playback.samples.iter().skip(c).step_by(channels).map(|&x| f64::from(x)).collect() };
    // Bins of the half-rate grid that the Green's functions can pass (their band), with one to spare.
    let k_max = ((params.band_hi_hz / (playback.frame_rate_hz / 2.0) * fft_len as f64).ceil() as usize + 1)
        .min(fft::bin_count(fft_len));
    let mut forces = Vec::new();
    for (actuator, &c) in params.actuator_channels.iter().enumerate() {
        let c = c as usize;
        if c >= channels || !playback.samples.iter().skip(c).step_by(channels).any(|&x| x != 0.0) {
            continue;
        }
        let Some(coil) = plate.coils.get(actuator) else { continue };
        let force = coil.drive_to_force(&channel(c))?;
        // Decimation by 2 in the frequency domain: the half-rate spectrum is half the full-rate one's low bins.
        let full = fft::forward(&force, 2 * fft_len)?;
        forces.push((actuator, full.iter().take(k_max).map(|f| f * 0.5).collect()));
    }
    let lc = params.loopback_channel as usize;
    let (loopback_v, loopback_interp) =
        if lc < channels && playback.samples.iter().skip(lc).step_by(channels).any(|&x| x != 0.0) {
            let volts: Vec<f64> = channel(lc).iter().map(|x| x * params.loopback_volts_per_full_scale).collect();
            let full = fft::forward(&volts, 2 * fft_len)?;
            // Ideal anti-alias filter at the half rate, then the bandwidth actually used sizes the interpolator.
            let half: Vec<Complex64> = full.iter().take(fft::bin_count(fft_len)).map(|v| v * 0.5).collect();
            let peak = half.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let top = half.iter().rposition(|v| v.norm() > BAND_EDGE_LEVEL * peak).unwrap_or(0);
            let top_hz = top as f64 * (playback.frame_rate_hz / 2.0) / fft_len as f64;
            (fft::inverse(&half, fft_len)?, Interpolator::for_band(top_hz, playback.frame_rate_hz / 2.0))
        } else {
            (Vec::new(), Interpolator::for_band(0.0, 1.0))
        };
    Ok(DriveEffect { fft_len, forces, loopback_v, loopback_interp })
}

/// The lab's handle on its state, shared by the DAQ source, the audio observer and the DAQ link.
#[derive(Clone)]
pub(crate) struct Shared(pub Arc<Mutex<LabState>>);

impl Shared {
    pub fn lock(&self) -> Result<std::sync::MutexGuard<'_, LabState>, LabError> {
        self.0.lock().map_err(|_| LabError::Poisoned("the lab state"))
    }
}

impl PlaybackObserver for Shared {
    fn on_playback(&self, playback: &Playback) {
        // The beam position at playback start: the beam is assumed not to move while it plays.
        let beam = self.ldv_beam();
        if let Ok(mut state) = self.0.lock() {
            state.schedule(playback, beam);
        }
    }
}

impl Shared {
    fn ldv_beam(&self) -> Option<(f64, f64)> {
        let ldv = self.0.lock().ok().map(|s| Arc::clone(&s.ldv))?;
        let device = ldv.lock().ok()?;
        device.controller().beam_m()
    }
}

/// The DAQ's inputs, read from the lab's state. A failure inside the chain (a bug, or a poisoned lock) becomes a
/// non-finite voltage, which the mock DAQ reports as a hardware fault: the recipe sees a `DaqError::Device`.
pub(crate) struct LabSource(pub Shared);

impl metaplate_mock_daq::SignalSource for LabSource {
    fn fill(&mut self, input: u8, first_sample_index: u64, sample_rate_hz: f64, out: &mut [f64]) {
        let result = self.0.lock().and_then(|mut s| s.fill(input, first_sample_index, sample_rate_hz, out));
        if result.is_err() {
            out.fill(f64::NAN);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::beam_offset_m;

    /// An exact aim reads back within the controller's whole micrometre: no offset, so the response is the point's
    /// own, bit for bit; a beam really off the point keeps its offset, sign and all.
    #[test]
    fn the_beam_offset_is_zero_within_the_controllers_micrometre_and_kept_beyond() {
        assert_eq!(beam_offset_m(0.49e-6, -0.49e-6), (0.0, 0.0));
        assert_eq!(beam_offset_m(-1e-18, 0.0), (0.0, 0.0));
        assert_eq!(beam_offset_m(0.2e-3, 0.0), (0.2e-3, 0.0));
        assert_eq!(beam_offset_m(0.0, -1.5e-6), (0.0, -1.5e-6));
    }
}
