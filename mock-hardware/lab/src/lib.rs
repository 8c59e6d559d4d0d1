//! The mock lab: audio interface, actuators, plate, LDV and DAQ wired together on one virtual clock, from a scene.
//!
//! # Use
//! ```no_run
//! # use metaplate_lab::{MockLab, LabOptions};
//! # use metaplate_core::scene::Scene;
//! let scene = Scene::builtin("metamaterial")?;
//! let lab = MockLab::new(&scene, &LabOptions::default())?; // computes (or loads) the Green's functions
//! let rig = lab.rig()?; // the REAL drivers over mock transports, on the lab's virtual clock
//! // ... hand `rig` to a recipe; keep `lab` alive while the rig is used ...
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//! [`MockLab::rig`] gives a [`Rig`]: `PolytecDriver` (Polytec's RS-232 syntax to the mock controller
//! [`UnitSpec::lab_default`], over an in-process line, or over a pseudo-terminal through the real `serialport`
//! transport), the lab's own aimer ([`aim::LabAimer`]: the lab knows where the beam lands), `U6Driver` (the LabJack U6's USB functions to the mock U6) and `AudioDriver` (over
//! [`MockPcm`]), all on one [`VirtualClock`], and the [`Wiring`]: actuator `i` on audio channel `i`, loopback on
//! the channel after the last actuator (8 for the paper's 8 actuators), DAQ input 0 = LDV velocity, input 1 =
//! loopback, rates from the scene.
//!
//! # Signal chain (per playback)
//! 1. The audio interface ([`MockPcm`]) plays the buffer from `submit time + latency_s` at its true rate
//!    `fs_a = 48 kHz * (1 + audio ppm)`; underrun faults insert silence into what is physically played.
//! 2. Each active actuator channel (all-zero channels are skipped) goes through the amplifier (1 V at the coil per
//!    full-scale sample, folded into the coil's force factor) and the actuator's voice coil
//!    (`VoiceCoil::drive_to_force` at 48 kHz: cubic, gain spread, suspension high-pass, roll-off), giving force in N.
//! 3. Force is convolved with the plate's Green's function from that actuator to the point under the beam (m/s
//!    per N, [`metaplate_plate::greens_functions`] for the prepared points; with a cache directory they are cut
//!    from the one entry of the scene's physics and the lab's band, duration and rate, which holds every point).
//! 4. The LDV turns velocity into its output voltage: noise `noise_rms_m_s / signal level` (the speckle level at
//!    the spot, at least 0.05), dropouts (garbage across the range: random ones with the scene's
//!    `dropout_probability` per playback, and the `ldv_dropout` windows; the next signal-level query reads low),
//!    clipping at the selected range's full scale (10 V x the range), then volts = m/s / (range's m/s per V). The
//!    range of the controller's first velocity decoder is read from the mock controller, so the `VelocityScale`
//!    the driver reports converts the voltage back exactly; before the beam is first aimed the output is 0 V. (The scene's `daq.volts_per_m_s` is the sensitivity of the range a recipe is
//!    expected to pick; the lab uses the range actually selected.)
//! 5. The DAQ samples input 0 (LDV output) and input 1 (loopback channel × `loopback_volts_per_full_scale`) at its
//!    true rate `fs_d = 24 kHz * (1 + daq ppm)` from the moment it was started, digitised to 16 bits with
//!    clipping by the mock LabJack U6 (serial [`LAB_U6_SERIAL`], an ideal calibration: 20 V / 65536 per code on
//!    +/-10 V, 0 V at code 32768, so the codes are the scene's 16-bit rule), and streamed as StreamData packets to
//!    the real U6 driver. A scene with another
//!    `daq.bits` (0: ideal) or `daq.clipping = false` gets an in-process DAQ instead (`direct_daq`: the same
//!    samples, digitised as the scene says, no USB link and none of its faults), for error budgets.
//!
//! # Clocks
//! Everything runs on one [`VirtualClock`] (true time). The DAQ's sample `n` is taken at `t0 + n / fs_d`, `t0`
//! being the virtual time of its `Start` command; an audio frame `k` sounds at `start + k / fs_a`. Reading DAQ
//! samples up to time `t` advances the clock to `t` (so causality holds: a later playback cannot reach samples
//! already read); `AudioOut::finish` advances it to the end of the playback. So a 3 s sweep takes 3 s of virtual
//! time, and no wall time beyond the computation. Mapping both rates to true time and resampling band-limited
//! (dsp's Kaiser-sinc [`metaplate_dsp::resample::Interpolator`]) makes the loopback show the real latency and the
//! ppm difference (for the built-in scenes 20 - (-30) = 50 ppm, DAQ fast of the interface).
//!
//! # How a playback is computed (performance)
//! The work is done once per (playback, DAQ acquisition), when the DAQ first samples a time the playback covers:
//! - per distinct drive buffer (hash of its samples; the same compensated sweep plays at every point), cached: the
//!   force spectrum of each active actuator on a half-rate (24 kHz) grid of the audio clock, only the bins inside
//!   the Green's functions' band; and the loopback decimated by 2 (an ideal low-pass at 12 kHz);
//! - per playback: the Green's function spectrum at the beam's point (one FFT), the product with the force spectra,
//!   one inverse FFT on the half-rate grid, and one interpolation of velocity and loopback onto the DAQ's sample
//!   times;
//! - per DAQ sample: copying, noise (a cheap counter-based approximately normal draw), dropouts, range, clipping.
//!
//! # Faults (from the scene's `faults`, in virtual time, deterministic under the seed)
//! | kind | device | what the recipe sees through the drivers |
//! |---|---|---|
//! | `serial_timeout` | LDV | no reply to lines answered in the window; in process every missed read costs its timeout in virtual time; `VibrometerError::Timeout` when the retries are spent |
//! | `garbled_reply` / `partial_reply` | LDV | corrupted / truncated replies; the driver resynchronises, `Timeout` if all attempts fail |
//! | `ldv_dropout` | LDV signal | velocity output is garbage in the window; `SIG?` answered in it reads 2 % |
//! | `usb_stall` | DAQ | every read in the window times out (costing its timeout in virtual time): `DaqError::Timeout` once the driver's retries are spent |
//! | `daq_overrun` | DAQ | once per window, the window's worth of packets (at least one) is lost at the source: the next block has `integrity.overrun` and `samples_missing` |
//! | `audio_underrun` | audio | silence inserted into the physical playback (visible on the loopback), `PlaybackReport::underruns` |
//! | `disconnect` | all three (a USB hub glitch) | each device, at its first use after the window's start, fails with `Disconnected` (the DAQ power-cycles, the LDV link drops, the audio stream closes); reopening fails with `Disconnected` until the window's end, then works |
//!
//! # Setup mistakes (from the scene's `[setup]`, for `metaplate check` to catch)
//! The rig's [`Wiring`] stays the nominal one; the lab behind it is cabled as the setup says:
//! `swapped_actuators = [a, b]` makes the channel wired to actuator `a` drive actuator `b` and the reverse;
//! `loopback_disconnected` leaves the DAQ's loopback input silent; `audio_device_rate_hz` clocks the mock interface
//! at another rate than the wiring asks for, so the audio driver refuses to open it. (`disk_free_bytes` is read by
//! the binary, which owns the disk.)
//!
//! # The truth a measurement is compared with
//! - [`MockLab::true_response`]: the small-signal linear chain at a prepared point (the voice coil's linear filter
//!   times the plate's Green's function), at given frequencies; [`MockLab::response_error_db`]: a measured
//!   response against it over [`ERROR_BAND_HZ`], by `metaplate_dsp::accuracy`'s measure ([`time_zero_first`] puts a
//!   two-sided response's time 0 first); [`MockLab::true_velocity`]: what a set of drives does at a point, the truth
//!   a stimulus is judged by.
//! - [`windowed_truth`]: one row's truth on a stored window's DFT bins, from the Green's function's FFT on a grid
//!   long enough that those bins are its own (no DTFT per bin): the full truth; the windowed truth, band-limited as
//!   the deconvolution's `DeconvConfig::band` and cut to the window's `pre_samples` and `ir_len` (what a perfect
//!   measurement of the window returns); and optionally the truth folded modulo a periodic excitation's period.
//!   The truncation (windowed against full, from the truth alone) and the aliasing (folded against windowed) follow.
//! - [`budget`]: the error budget's variants ([`budget::Budget::variants`]: the floor with every imperfection off,
//!   each imperfection alone, all on), per-row errors against the full and the windowed (and folded) truth,
//!   overall and per octave band, medians and 95th percentiles, the truncation and aliasing terms, whether the
//!   terms add as powers, and whether each floor row splits into its windowed error plus the truncation
//!   ([`budget::splits`]). The truth for a nonlinear actuator is its small-signal linear part. The scans of the
//!   variants run above this crate (`metaplate-evaluation`).
//!
//! # Simplifications
//! - The beam is read once per playback (at submit): moving it during a playback does not change that playback.
//! - An aiming error (`ldv.aim_error_rms_m`) offsets the beam from each commanded point by a normal draw per point
//!   (keyed by the seed and the point, the same at every playback there); the response at the offset spot is the
//!   point's plus the offset times the response's slope, by differences with the neighbouring grid points (the lab
//!   prepares them), central where both exist: first order in the offset, fine for offsets far below the 5 mm step
//!   and the shortest wavelength.
//! - A DAQ acquisition records only the playbacks submitted during it: the ring-down of an earlier playback (the
//!   previous unit's last sweep) is not carried into the next acquisition, and a random dropout's low `SIG?`
//!   reading ends when the beam moves. Random draws (noise, dropouts) are keyed by what is measured (the spot, the
//!   drive, and how often that drive has played there: the attempt), not by the session's history. So what a
//!   measurement yields depends on (scene, seed, what is played where, its attempt) alone, never on what the
//!   session measured before: a run resumed after a crash equals an uninterrupted one.
//! - The Green's functions are sampled at the DAQ's nominal rate and applied on the audio clock's half-rate grid
//!   (a frequency scaling of the plate by the audio clock's offset, 30 ppm: far below any modal bandwidth).
//! - The loopback is ideally low-passed at 12 kHz (the real DAQ would alias content above; drive signals have none).
//! - Noise is white at the DAQ rate, approximately normal (Irwin-Hall of 4 uniforms), level-scaled per spot.
//! - The beam must rest on a prepared point (within half a grid step); elsewhere the plate gives no velocity
//!   (counted in [`LabStats::beam_off_prepared_points`]). Besides grid points, the actuators' own positions are
//!   prepared (point index `grid.len() + k`, the plate crate's driving points), for calibration on the magnets.
//! - Over a pseudo-terminal, LDV timeouts cost wall time (the real port waits) and no virtual time, and a disconnect
//!   is seen as a timeout (see `PtyServer`).

mod accuracy;
pub mod aim;
pub mod budget;
mod chain;
mod direct_daq;
mod links;
pub mod mirrors;
#[cfg(unix)]
pub mod serve;
pub mod session;
pub mod teacher;
mod truth;
pub mod windowed_truth;

pub use accuracy::{ERROR_BAND_HZ, time_zero_first};

use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use metaplate_audio::AudioDriver;
use metaplate_core::clock::VirtualClock;
use metaplate_core::rig::{Rig, Wiring};
use metaplate_core::scene::Scene;
use metaplate_daq::{DriverSettings, U6Driver};
use metaplate_ldv::{PolytecConfig, PolytecDriver, RetryPolicy};
use metaplate_mock_audio::{FaultWindows, MockPcm};
use metaplate_mock_daq::{MockTransport, MockU6, u6_info};
use metaplate_mock_ldv::{FaultSchedule, MockController, MockDevice, MockLine, PtyServer, UnitSpec};
use metaplate_plate::actuator::VoiceCoil;
use metaplate_plate::{GreensFunctions, GreensRequest, ModelOptions, greens_functions};
use num_complex::Complex64;

pub use chain::LabStats;

/// Resolution of the U6's stream codes, bits: a scene's DAQ of this resolution, clipping, records through the
/// mock U6; any other is served in process (see the `daq` docs of the scene).
const PROTOCOL_BITS: u32 = 16;

/// The serial number of the mock lab's U6 (what a dataset records as the DAQ's serial).
pub const LAB_U6_SERIAL: u32 = 360_000_001;

/// Why the lab could not be built or used.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// An option is out of its valid range.
    #[error("invalid lab option {name}: {reason}")]
    InvalidOption {
        /// Which option.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] metaplate_core::scene::SceneError),
    /// The plate model failed (Green's functions, voice coils).
    #[error(transparent)]
    Plate(#[from] metaplate_plate::PlateError),
    /// Signal processing failed inside the chain.
    #[error(transparent)]
    Dsp(#[from] metaplate_dsp::error::DspError),
    /// A point or actuator that was not prepared.
    #[error("not prepared in this lab: {what}")]
    NotPrepared {
        /// What was asked for.
        what: String,
    },
    /// The pseudo-terminal for the LDV could not be set up.
    #[error(transparent)]
    Pty(#[from] metaplate_mock_ldv::PtyError),
    /// A driver failed to open on its mock device.
    #[error("cannot open the {device} driver: {detail}")]
    Driver {
        /// Which device.
        device: &'static str,
        /// The driver's error.
        detail: String,
    },
    /// [`MockLab::rig`] was called twice (the devices have one driver each).
    #[error("the rig of this lab has already been taken")]
    RigTaken,
    /// A lock was poisoned by a panic elsewhere.
    #[error("{0} lock was poisoned")]
    Poisoned(&'static str),
    /// The stand-in rig cannot serve: its folder, FIFO, socket, library copy or hardware file.
    #[error("the stand-in rig: {what}")]
    Serve {
        /// What failed, and the system's reason.
        what: String,
    },
}

/// How the LDV controller is served.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LdvLink {
    /// An in-process `SerialLine` (no I/O; timeouts cost virtual time only). The default.
    #[default]
    InProcess,
    /// A pseudo-terminal served by a thread, opened with the real `serialport` transport (feature `pty`, Unix only).
    Pty,
}

/// What the lab prepares and how it serves the devices.
///
/// Valid range: `band_hz` with `0 < lo < hi <= daq.sample_rate_hz / 2`; `ir_duration_s > 0` (see
/// [`GreensRequest`]); `loopback_volts_per_full_scale` finite and > 0; points on the plate.
#[derive(Debug, Clone, PartialEq)]
pub struct LabOptions {
    /// Replaces the scene's seed (noise, dropouts, speckle, coil spread, garbled bytes).
    pub seed: Option<u64>,
    /// Where Green's functions are cached (one entry per scene physics, model options, band, duration and rate,
    /// holding every point: labs preparing other points share it); `None`: computed every time, for the prepared
    /// points only.
    pub cache_dir: Option<PathBuf>,
    /// Flat grid indices to prepare (`grid.len() + k`: actuator k's driving point); `None`: the scene's measured
    /// points and every driving point.
    pub points: Option<Vec<usize>>,
    /// Plate discretisation.
    pub model: ModelOptions,
    /// Band of the Green's functions, Hz (the plate passes nothing outside it).
    pub band_hz: (f64, f64),
    /// Length of the Green's functions, s.
    pub ir_duration_s: f64,
    /// How the LDV is served.
    pub ldv_link: LdvLink,
    /// Loopback voltage at the DAQ for a full-scale audio sample, V.
    pub loopback_volts_per_full_scale: f64,
    /// How the rig aims the beam: `None`, the lab's exact in-process aimer ([`aim::LabAimer`]); a taught fit (from
    /// teaching [`MockLab::mirrors`], as `metaplate aim teach --scene` does), the real galvo aimer
    /// ([`metaplate_aim::galvo::GalvoAimer`]) over the lab's mirrors, so the beam lands where the fit and the
    /// mirrors' unknown geometry put it, off by the fit's error. The responses at grid points carry that error
    /// (their neighbours are prepared for the slope); those on the magnets, where a calibration aims, do not.
    pub galvo_fit: Option<metaplate_aim::galvo::GalvoFit>,
}

impl Default for LabOptions {
    /// Scene seed, no cache, every measured point, default plate model, 40 to 800 Hz (the paper's sweeps and their
    /// low harmonics), 0.5 s responses, in-process LDV, 1 V loopback per full scale, exact in-process aim.
    fn default() -> Self {
        Self {
            seed: None,
            cache_dir: None,
            points: None,
            model: ModelOptions::default(),
            band_hz: (40.0, 800.0),
            ir_duration_s: 0.5,
            ldv_link: LdvLink::InProcess,
            loopback_volts_per_full_scale: 1.0,
            galvo_fit: None,
        }
    }
}

/// Constants a test needs to compare a measurement with the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabConstants {
    /// The audio interface's true frame rate, Hz.
    pub audio_rate_true_hz: f64,
    /// The DAQ's true sample rate, Hz.
    pub daq_rate_true_hz: f64,
    /// Output latency of the audio interface, s.
    pub audio_latency_s: f64,
    /// DAQ clock relative to the audio clock, ppm: `(fs_d / 24 kHz) / (fs_a / 48 kHz) - 1` (about 50 for the
    /// built-in scenes).
    pub drift_ppm: f64,
    /// Loopback voltage per full-scale sample, V: multiply a velocity-per-loopback-volt response by it to get
    /// velocity per full scale.
    pub loopback_volts_per_full_scale: f64,
    /// The Green's functions' band, Hz: outside it the plate passes nothing.
    pub band_hz: (f64, f64),
}

/// The mock lab of one scene. Keep it alive while its [`Rig`] is in use (it owns the pseudo-terminal server).
pub struct MockLab {
    scene: Scene,
    options: LabOptions,
    clock: Arc<VirtualClock>,
    ldv: Arc<Mutex<MockDevice>>,
    shared: chain::Shared,
    plate: Arc<chain::Plate>,
    windows: FaultWindows,
    wiring: Wiring,
    /// The mirrors' geometry, from the scene's own seed: hardware, not one of the draws `LabOptions::seed`
    /// replaces, so a fit taught on the scene's mirrors (`metaplate aim teach --scene`) fits them at every seed.
    mirror_geometry: mirrors::MirrorGeometry,
    rig_taken: Mutex<bool>,
    #[cfg_attr(not(feature = "pty"), allow(dead_code))] // Only the pseudo-terminal link fills it.
    pty: Mutex<Option<PtyServer>>,
}

impl std::fmt::Debug for MockLab {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MockLab")
            .field("scene", &self.scene.name)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl MockLab {
    /// Builds the lab of `scene`: validates, computes (or loads from `options.cache_dir`) the Green's functions
    /// of the prepared points from every actuator, and sets up the mock devices (nothing is served until
    /// [`MockLab::rig`]).
    ///
    /// # Errors
    /// [`LabError::Scene`], [`LabError::InvalidOption`], [`LabError::Plate`] (a point off the plate, a band the
    /// model refuses, a cache that cannot be written).
    pub fn new(scene: &Scene, options: &LabOptions) -> Result<MockLab, LabError> {
        scene.validate()?;
        let mirror_geometry = mirrors::MirrorGeometry::seeded(scene.seed);
        let mut scene = scene.clone();
        if let Some(seed) = options.seed {
            scene.seed = seed;
        }
        let lv = options.loopback_volts_per_full_scale;
        if !(lv.is_finite() && lv > 0.0) {
            return Err(LabError::InvalidOption { name: "loopback_volts_per_full_scale", reason: format!("{lv}") });
        }
        let (_, hi) = options.band_hz;
        let fs_g = scene.daq.sample_rate_hz;
        if !(hi.is_finite() && hi > 0.0 && hi <= fs_g / 2.0) {
            return Err(LabError::InvalidOption { name: "band_hz", reason: format!("top {hi} Hz at {fs_g} Hz") });
        }
        // By default the measured points and the actuators' driving points (index `grid.len() + k`, where the
        // calibration recipe aims the beam, on the magnet).
        let points =
            options.points.clone().unwrap_or_else(|| [scene.measured_points(), scene.driving_points()].concat());
        // An aiming error (the scene's drawn one, or a taught galvo fit's) needs the response's slope at each grid
        // point: its measurable grid neighbours too.
        let aim_errs = scene.ldv.aim_error_rms_m > 0.0 || options.galvo_fit.is_some();
        let points = if aim_errs { with_grid_neighbours(&scene, points) } else { points };
        let request = GreensRequest {
            points: points.clone(),
            actuators: (0..scene.actuators.len()).collect(),
            band_hz: options.band_hz,
            duration_s: options.ir_duration_s,
            sample_rate_hz: fs_g,
        };
        let greens = greens_functions(&scene, &options.model, &request, options.cache_dir.as_deref())?;
        let coils = VoiceCoil::for_scene(&scene, scene.audio.sample_rate_hz)?;
        let plate = Arc::new(chain::Plate {
            slopes: points.iter().map(|&p| chain::Slope::at(&scene, &points, p)).collect(),
            positions_m: points.iter().map(|&p| point_position_m(&scene, p)).collect(),
            tolerance_m: scene.grid.spacing_m / 2.0,
            greens,
            coils,
        });
        let clock = Arc::new(VirtualClock::new());
        let windows = FaultWindows::new(&scene.faults);
        let controller = MockController::new(UnitSpec::lab_default(), &scene.ldv, scene.seed);
        let ldv = Arc::new(Mutex::new(
            MockDevice::new(controller, FaultSchedule::scripted(scene.seed, []))
                .with_clock(Arc::clone(&clock))
                .charging_read_timeouts()
                .with_timed_faults(Box::new(links::LdvFaults::new(&windows))),
        ));
        let n_act = scene.actuators.len() as u32;
        let wiring = Wiring {
            actuator_channels: (0..n_act).collect(),
            loopback_channel: n_act,
            audio_channels: n_act + 1,
            audio_sample_rate_hz: scene.audio.sample_rate_hz,
            velocity_input: 0,
            loopback_input: 1,
            daq_range_v: scene.daq.range_v,
            daq_sample_rate_hz: scene.daq.sample_rate_hz,
            loopback_volts_per_full_scale: lv,
        };
        let params = chain::ChainParams {
            seed: scene.seed,
            // The physical cabling: the scene's setup may swap two actuators' cables behind the wiring's back.
            actuator_channels: scene.setup.physical_channels(&wiring.actuator_channels),
            loopback_channel: wiring.loopback_channel,
            velocity_input: wiring.velocity_input,
            loopback_input: wiring.loopback_input,
            loopback_volts_per_full_scale: if scene.setup.loopback_disconnected { 0.0 } else { lv },
            daq_ppm: scene.daq.clock_offset_ppm,
            noise_rms_m_s: scene.ldv.noise_rms_m_s,
            dropout_probability: scene.ldv.dropout_probability,
            clipping: scene.daq.clipping,
            aim_error_rms_m: scene.ldv.aim_error_rms_m,
            band_hi_hz: hi,
        };
        let state =
            chain::LabState::new(params, Arc::clone(&plate), Arc::clone(&clock), Arc::clone(&ldv), windows.clone());
        let shared = chain::Shared(Arc::new(Mutex::new(state)));
        Ok(MockLab {
            scene,
            options: options.clone(),
            clock,
            ldv,
            shared,
            plate,
            windows,
            wiring,
            mirror_geometry,
            rig_taken: Mutex::new(false),
            pty: Mutex::new(None),
        })
    }

    /// The real drivers over the mock devices, on the lab's clock, with the wiring. Once per lab.
    ///
    /// # Errors
    /// [`LabError::RigTaken`] on a second call; [`LabError::Pty`] or [`LabError::Driver`] when a link cannot be
    /// opened (for example the DAQ driver's handshake, if a fault window covers time 0).
    pub fn rig(&self) -> Result<Rig, LabError> {
        {
            let mut taken = self.rig_taken.lock().map_err(|_| LabError::Poisoned("the rig flag"))?;
            if *taken {
                return Err(LabError::RigTaken);
            }
            *taken = true;
        }
        let clock: Arc<dyn metaplate_core::clock::Clock> = self.clock.clone();
        let ldv_error =
            |e: metaplate_core::vibrometer::VibrometerError| LabError::Driver { device: "LDV", detail: e.to_string() };
        let vibrometer: Box<dyn metaplate_core::vibrometer::Vibrometer + Send> = match self.options.ldv_link {
            LdvLink::InProcess => Box::new(
                PolytecDriver::new(
                    MockLine::new(Arc::clone(&self.ldv)),
                    RetryPolicy::default(),
                    PolytecConfig::default(),
                )
                .map_err(ldv_error)?,
            ),
            #[cfg(feature = "pty")]
            LdvLink::Pty => {
                let server = PtyServer::spawn(Arc::clone(&self.ldv))?;
                let selector = metaplate_ldv::PortSelector::Path(server.path().to_path_buf());
                let line = metaplate_ldv::SerialPortLine::open(selector)
                    .map_err(|e| LabError::Driver { device: "LDV", detail: e.to_string() })?;
                *self.pty.lock().map_err(|_| LabError::Poisoned("the pty slot"))? = Some(server);
                Box::new(PolytecDriver::new(line, RetryPolicy::default(), PolytecConfig::default()).map_err(ldv_error)?)
            }
            // The real serial transport is a backend (`metaplate-ldv`'s feature `serial`), not built here.
            #[cfg(not(feature = "pty"))]
            LdvLink::Pty => {
                return Err(LabError::Driver {
                    device: "LDV",
                    detail: "this build of the mock lab has no pseudo-terminal link (feature `pty`)".into(),
                });
            }
        };
        let daq: Box<dyn metaplate_core::daq::Daq + Send> = if self.scene.daq.bits == PROTOCOL_BITS
            && self.scene.daq.clipping
        {
            let source = Box::new(chain::LabSource(self.shared.clone()));
            let calibration = metaplate_u6_protocol::Calibration::ideal();
            let device = MockU6::new(u6_info(LAB_U6_SERIAL), calibration, source);
            let transport = MockTransport::new(device, metaplate_mock_daq::FaultSchedule::none());
            let link = links::LabDaqLink::new(transport, Arc::clone(&self.clock), &self.windows, self.shared.clone());
            Box::new(
                U6Driver::open(link, DriverSettings::default())
                    .map_err(|e| LabError::Driver { device: "DAQ", detail: e.to_string() })?,
            )
        } else {
            Box::new(direct_daq::DirectDaq::new(self.shared.clone(), self.scene.daq.bits, self.scene.daq.clipping))
        };
        // The interface runs at its own clock setting, which the setup may have left at another rate than the rig
        // asks for.
        let mut audio = self.scene.audio;
        if let Some(rate_hz) = self.scene.setup.audio_device_rate_hz {
            audio.sample_rate_hz = rate_hz;
        }
        let pcm = MockPcm::new(&audio, Arc::clone(&self.clock), &self.scene.faults)
            .with_observer(Arc::new(self.shared.clone()));
        let aim: Box<dyn metaplate_core::aim::Aim + Send> = match &self.options.galvo_fit {
            None => Box::new(aim::LabAimer::new(Arc::clone(&self.ldv), Arc::clone(&self.clock))),
            Some(fit) => Box::new(
                metaplate_aim::galvo::GalvoAimer::new(
                    fit.clone(),
                    Box::new(self.mirrors()),
                    clock.clone(),
                    metaplate_aim::galvo::GalvoSettings { settle_s: aim::SETTLE_S },
                )
                .map_err(|e| LabError::Driver { device: "galvo mirrors", detail: e.to_string() })?,
            ),
        };
        Ok(Rig { vibrometer, aim, daq, audio: Box::new(AudioDriver::new(pcm)), clock, wiring: self.wiring.clone() })
    }

    /// The scene in force (with the seed override applied).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The lab's virtual clock (the rig's clock).
    pub fn clock(&self) -> &Arc<VirtualClock> {
        &self.clock
    }

    /// The wiring the rig reports.
    pub fn wiring(&self) -> &Wiring {
        &self.wiring
    }

    /// The lab's galvanometer mirrors ([`mirrors::MockMirrors`], geometry drawn from the scene's own seed, whatever
    /// [`LabOptions::seed`] says): the beam
    /// of the lab's vibrometer lands where they point, so a galvo aimer over them replaces the rig's in-process
    /// aimer. Take them once: a second pair would steer the same beam (the rig takes a pair when
    /// [`LabOptions::galvo_fit`] is set).
    pub fn mirrors(&self) -> mirrors::MockMirrors {
        mirrors::MockMirrors::on_ldv(self.mirror_geometry, Arc::clone(&self.ldv))
    }

    /// The mock LDV device (to inspect the controller, or latch a fault by hand in a test).
    pub fn ldv_device(&self) -> &Arc<Mutex<MockDevice>> {
        &self.ldv
    }

    /// The Green's functions the lab uses (prepared points × every actuator, m/s per N at the DAQ's nominal rate).
    pub fn greens(&self) -> &GreensFunctions {
        &self.plate.greens
    }

    /// Counters of the signal chain.
    ///
    /// # Errors
    /// [`LabError::Poisoned`] if a panic poisoned the lab's state.
    pub fn stats(&self) -> Result<LabStats, LabError> {
        Ok(self.shared.lock()?.stats)
    }

    /// Constants for comparing measurements with [`MockLab::true_response`].
    pub fn constants(&self) -> LabConstants {
        let a = 1.0 + self.scene.audio.clock_offset_ppm * 1e-6;
        let d = 1.0 + self.scene.daq.clock_offset_ppm * 1e-6;
        LabConstants {
            audio_rate_true_hz: self.scene.audio.sample_rate_hz * a,
            daq_rate_true_hz: self.scene.daq.sample_rate_hz * d,
            audio_latency_s: self.scene.audio.latency_s,
            drift_ppm: (d / a - 1.0) * 1e6,
            loopback_volts_per_full_scale: self.options.loopback_volts_per_full_scale,
            band_hz: self.options.band_hz,
        }
    }

    /// The linear part of the chain from a full-scale sample on `actuator`'s audio channel to plate velocity at
    /// grid point `point` (flat grid index, one of the prepared points), at each of `freqs_hz`: voice coil's linear
    /// response (N per full scale) times the Green's function (m/s per N) as the lab applies it. m/s per full
    /// scale. The cubic nonlinearity, noise and the LDV's range are not included.
    ///
    /// Valid range: `0 <= f <= daq.sample_rate_hz / 2` (zero outside the band by construction).
    ///
    /// # Errors
    /// [`LabError::NotPrepared`] for a point or actuator the lab did not prepare; [`LabError::InvalidOption`] for a
    /// frequency out of range.
    pub fn true_response(&self, point: usize, actuator: usize, freqs_hz: &[f64]) -> Result<Vec<Complex64>, LabError> {
        let greens = &self.plate.greens;
        let point_k = self.prepared_point(point)?;
        let ir = greens.ir(point_k, actuator).ok_or(LabError::NotPrepared { what: format!("actuator {actuator}") })?;
        let coil = self.plate.coils.get(actuator).ok_or(LabError::NotPrepared { what: format!("coil {actuator}") })?;
        let nyquist = greens.sample_rate_hz / 2.0;
        freqs_hz
            .iter()
            .map(|&f| {
                if !(0.0..=nyquist).contains(&f) {
                    return Err(LabError::InvalidOption {
                        name: "freqs_hz",
                        reason: format!("{f} Hz outside 0..={nyquist}"),
                    });
                }
                // The response's DTFT, by a rotating phasor (re-normalised now and then against rounding drift).
                let step = Complex64::from_polar(1.0, -2.0 * PI * f / greens.sample_rate_hz);
                let mut phasor = Complex64::new(1.0, 0.0);
                let mut sum = Complex64::new(0.0, 0.0);
                for (n, &h) in ir.iter().enumerate() {
                    sum += phasor * h;
                    phasor *= step;
                    if n % 1024 == 1023 {
                        phasor /= phasor.norm();
                    }
                }
                Ok(sum * coil.frequency_response(f))
            })
            .collect()
    }
}

impl MockLab {
    /// Where grid point `point` is among the prepared points (its index in the Green's functions).
    ///
    /// # Errors
    /// [`LabError::NotPrepared`] for a point the lab did not prepare.
    fn prepared_point(&self, point: usize) -> Result<usize, LabError> {
        self.plate
            .greens
            .points
            .iter()
            .position(|&p| p == point)
            .ok_or(LabError::NotPrepared { what: format!("grid point {point}") })
    }
}

/// `points` and, after them, the measurable grid neighbours (one step along x or y) of its grid points that it
/// lacks, in ascending order.
fn with_grid_neighbours(scene: &Scene, mut points: Vec<usize>) -> Vec<usize> {
    let mask = scene.grid_mask();
    let mut extra: Vec<usize> = points
        .iter()
        .filter(|&&p| p < scene.grid.len())
        .flat_map(|&p| chain::Slope::grid_neighbours(&scene.grid, p).into_iter().flatten())
        .filter(|&q| mask[q] && !points.contains(&q))
        .collect();
    extra.sort_unstable();
    extra.dedup();
    points.extend(extra);
    points
}

/// Where point `point` is, m: a grid point, or (from `grid.len()` on) an actuator's driving point.
fn point_position_m(scene: &Scene, point: usize) -> (f64, f64) {
    match point.checked_sub(scene.grid.len()).and_then(|k| scene.actuators.get(k)) {
        Some(actuator) => (actuator.x_m, actuator.y_m),
        None => scene.grid.position_m(point),
    }
}
