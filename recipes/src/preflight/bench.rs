//! The checks that talk to the instruments: each turns what the rig answers or records into a [`CheckOutcome`].

use metaplate_core::daq::DaqConfig;
use metaplate_core::rig::{Recording, Rig};
use metaplate_core::vibrometer::VelocityScale;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::{DeconvConfig, deconvolve_with_reference};
use metaplate_dsp::drift::{ExcitationTemplate, fit_clock};
use metaplate_dsp::stats::median;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use serde_json::{Value, json};

use super::reciprocity::{RECIPROCITY_LIMIT_DB, Reciprocity};
use super::{
    CheckOutcome, LOOPBACK_LEVEL_TOLERANCE_DB, MAX_PEAK_FRACTION, MIN_CHIRP_SNR_DB, MIN_PEAK_FRACTION, PreflightConfig,
};
use crate::drive::{DRIVE_PEAK_FS, to_audio_rate};
use crate::engine::session::BLOCK_LEN_SAMPLES;

/// The loopback sweep: 100 Hz to 4 kHz (wide, for a sharp location), 0.25 s, -20 dBFS, repeated back to back.
const LOOPBACK_SWEEP: (f64, f64, f64, f64) = (100.0, 4000.0, 0.25, 0.1);
/// Repetitions of the loopback sweep: four give the drift with three periods of lever.
const LOOPBACK_REPETITIONS: usize = 4;
/// The actuator chirp: the scan's band, 0.3 s; quiet (-26 dBFS) for the wiring check.
const CHIRP: (f64, f64, f64) = (62.0, 625.0, 0.3);
/// Peak of the wiring check's chirps, full scale.
const QUIET_FS: f64 = 0.05;
/// Length of the impulse response estimated from each chirp, s: the part above the noise.
const IR_S: f64 = 0.1;
/// Silence before the first chirp, s: where the noise is measured.
const LEAD_S: f64 = 0.2;
/// Recording beyond the last signal, s (latency and ring-down).
const TAIL_S: f64 = 0.3;
/// SNRs are reported up to this, dB (a noiseless simulated input would otherwise give infinity).
const SNR_CAP_DB: f64 = 200.0;

/// The rig, with what the checks learn on the way (the velocity scale in force).
pub(super) struct Bench<'a> {
    rig: &'a mut Rig,
    daq_config: DaqConfig,
    scale: Option<VelocityScale>,
}

impl<'a> Bench<'a> {
    pub(super) fn new(rig: &'a mut Rig) -> Self {
        let daq_config = rig.wiring.daq_config(BLOCK_LEN_SAMPLES);
        Self { rig, daq_config, scale: None }
    }

    fn daq_rate_hz(&self) -> f64 {
        self.rig.wiring.daq_sample_rate_hz
    }

    /// The vibrometer answers its identity, switches its laser on and takes the velocity range.
    pub(super) fn vibrometer(&mut self, max_velocity_m_s: f64) -> CheckOutcome {
        let ldv = &mut self.rig.vibrometer;
        let identity = match ldv.identify() {
            Ok(id) => id,
            Err(e) => {
                return CheckOutcome::fail(
                    "vibrometer",
                    format!("the LDV does not answer its identity query: {e}. Is it on, and is the serial port right?"),
                    json!({}),
                );
            }
        };
        let details = json!({"vendor": identity.vendor, "model": identity.model, "serial": identity.serial,
                             "firmware": identity.firmware});
        let who = format!(
            "{} {} (serial {}, firmware {})",
            identity.vendor, identity.model, identity.serial, identity.firmware
        );
        if let Err(e) = ldv.set_laser(true) {
            return CheckOutcome::fail(
                "vibrometer",
                format!("{who} answers but its laser does not come on: {e}"),
                details,
            );
        }
        match ldv.set_velocity_range(max_velocity_m_s) {
            Ok(scale) => {
                self.scale = Some(scale);
                CheckOutcome::pass(
                    "vibrometer",
                    format!(
                        "{who} answers; laser on; range {} m/s full scale ({} m/s per V)",
                        scale.full_scale_m_s, scale.m_s_per_v
                    ),
                    merge(details, json!({"full_scale_m_s": scale.full_scale_m_s, "m_s_per_v": scale.m_s_per_v})),
                )
            }
            Err(e) => CheckOutcome::fail(
                "vibrometer",
                format!("{who} refuses the velocity range of {max_velocity_m_s} m/s: {e}"),
                details,
            ),
        }
    }

    /// The DAQ takes the velocity and loopback inputs at the wiring's rate and range.
    pub(super) fn daq(&mut self) -> CheckOutcome {
        let identity = self.rig.daq.identity().clone();
        let who = format!(
            "{} {} (serial {}, firmware {})",
            identity.vendor, identity.model, identity.serial, identity.firmware
        );
        let c = &self.daq_config;
        let details = json!({"vendor": identity.vendor, "model": identity.model, "serial": identity.serial,
                             "firmware": identity.firmware, "sample_rate_hz": c.sample_rate_hz});
        match self.rig.daq.configure(c) {
            Ok(()) => CheckOutcome::pass(
                "daq",
                format!(
                    "{who} records inputs {} (LDV) and {} (loopback) at {} Hz, +/-{} V",
                    self.rig.wiring.velocity_input,
                    self.rig.wiring.loopback_input,
                    c.sample_rate_hz,
                    self.rig.wiring.daq_range_v
                ),
                details,
            ),
            Err(e) => CheckOutcome::fail("daq", format!("{who} refuses the configuration: {e}"), details),
        }
    }

    /// The audio interface opens at exactly the wiring's rate and channel count.
    pub(super) fn audio(&mut self) -> CheckOutcome {
        let identity = self.rig.audio.identity().clone();
        let config = self.rig.wiring.audio_config();
        let who = format!("{} {} ({})", identity.vendor, identity.model, identity.serial);
        let details = json!({"vendor": identity.vendor, "model": identity.model, "serial": identity.serial,
                             "sample_rate_hz": config.sample_rate_hz, "channels": config.channels});
        match self.rig.audio.configure(&config) {
            Ok(()) => CheckOutcome::pass(
                "audio",
                format!("{who} opens at {} Hz with {} channels", config.sample_rate_hz, config.channels),
                details,
            ),
            Err(e) => CheckOutcome::fail(
                "audio",
                format!(
                    "{who} does not open at {} Hz with {} channels: {e}. Set the interface's clock to {} Hz (its \
                     control panel) or the hardware file's wiring.audio_sample_rate_hz to the rate it runs at",
                    config.sample_rate_hz, config.channels, config.sample_rate_hz
                ),
                details,
            ),
        }
    }

    /// Plays `signals` (audio channel, samples at the DAQ rate; padded to the longest) and records `record_s`.
    fn play(&mut self, signals: &[(u32, Vec<f64>)], record_s: f64) -> Result<Recording, String> {
        let len = signals.iter().map(|(_, s)| s.len()).max().unwrap_or(0);
        let padded: Vec<Vec<f64>> = signals
            .iter()
            .map(|(_, s)| {
                let mut s = s.clone();
                s.resize(len, 0.0);
                s
            })
            .collect();
        let refs: Vec<&[f64]> = padded.iter().map(Vec::as_slice).collect();
        let converted = to_audio_rate(&refs, &self.rig.wiring, self.daq_rate_hz()).map_err(|e| e.to_string())?;
        let frames = converted.first().map_or(0, Vec::len);
        let mut buffers = vec![vec![0.0; frames]; self.rig.wiring.audio_channels as usize];
        for ((channel, _), samples) in signals.iter().zip(converted) {
            if let Some(buffer) = buffers.get_mut(*channel as usize) {
                *buffer = samples;
            }
        }
        let record_samples = (record_s * self.daq_rate_hz()).ceil() as usize;
        let result = self.rig.play_and_record(&buffers, record_samples);
        if result.is_err() {
            // Leave the devices stopped for the next check (errors here add nothing to the first one).
            let _ = self.rig.audio.finish();
            let _ = self.rig.daq.stop();
        }
        let recording = result.map_err(|e| e.to_string())?;
        if recording.gap || recording.underruns > 0 {
            return Err(format!(
                "the recording has a gap ({} underruns, gap {}): USB or audio buffers too small?",
                recording.underruns, recording.gap
            ));
        }
        Ok(recording)
    }

    /// The loopback (level and latency) and the clocks (drift), from one recording of the loopback sweep.
    pub(super) fn loopback(&mut self, max_drift_ppm: f64) -> (CheckOutcome, CheckOutcome) {
        let fs = self.daq_rate_hz();
        let w = self.rig.wiring.clone();
        let (f1_hz, f2_hz, duration_s, amplitude) = LOOPBACK_SWEEP;
        let spec = sweep(f1_hz, f2_hz, duration_s, amplitude, fs);
        let sweep = match spec.generate() {
            Ok(s) => s,
            Err(e) => return internal_pair("loopback", &e.to_string()),
        };
        let signal: Vec<f64> = sweep.iter().copied().cycle().take(LOOPBACK_REPETITIONS * sweep.len()).collect();
        let record_s = signal.len() as f64 / fs + TAIL_S;
        let recording = match self.play(&[(w.loopback_channel, signal)], record_s) {
            Ok(r) => r,
            Err(e) => {
                let fail =
                    CheckOutcome::fail("loopback", format!("the loopback sweep could not be played: {e}"), json!({}));
                return (fail, CheckOutcome::not_run("clocks", "the loopback"));
            }
        };
        let template = match ExcitationTemplate::new(&sweep, None, fs) {
            Ok(t) => t,
            Err(e) => return internal_pair("loopback", &e.to_string()),
        };
        let expected_v = amplitude * w.loopback_volts_per_full_scale;
        let peak_v = peak(&recording.loopback_v);
        let route = format!("audio channel {} to DAQ input {}", w.loopback_channel, w.loopback_input);
        let positions = match template.locate(&recording.loopback_v, LOOPBACK_REPETITIONS) {
            Ok(p) => p,
            Err(_) => {
                let message = if template.locate(&recording.velocity_v, LOOPBACK_REPETITIONS).is_ok() {
                    format!(
                        "the loopback sweep arrives on DAQ input {} (the LDV's) instead of input {}: the two DAQ \
                         inputs are swapped; exchange the cables or wiring.velocity_input and wiring.loopback_input",
                        w.velocity_input, w.loopback_input
                    )
                } else if peak_v < 1e-3 * expected_v {
                    format!(
                        "no signal on the loopback ({route}): {peak_v:.1e} V peak where {expected_v:.3} V was \
                         expected. The loopback cable is missing, or on another output or input"
                    )
                } else {
                    format!(
                        "DAQ input {} records {peak_v:.3} V peak, but not the sweep played on audio channel {}: the \
                         loopback cable is on another output",
                        w.loopback_input, w.loopback_channel
                    )
                };
                let details = json!({"peak_v": peak_v, "expected_peak_v": expected_v});
                return (
                    CheckOutcome::fail("loopback", message, details),
                    CheckOutcome::not_run("clocks", "the loopback"),
                );
            }
        };
        let level_db = 20.0 * (peak_v / expected_v).log10();
        let (clocks, latency_s) = match fit_clock(&positions, sweep.len()) {
            Ok(fit) => {
                let latency_s = fit.latency_samples / fs;
                let details = json!({"drift_ppm": fit.drift_ppm, "limit_ppm": max_drift_ppm,
                                     "residual_rms_samples": fit.residual_rms_samples});
                let clocks = if fit.drift_ppm.abs() <= max_drift_ppm {
                    CheckOutcome::pass(
                        "clocks",
                        format!(
                            "audio-to-DAQ drift {:+.1} ppm, within the {max_drift_ppm} ppm the run corrects",
                            fit.drift_ppm
                        ),
                        details,
                    )
                } else {
                    CheckOutcome::fail(
                        "clocks",
                        format!(
                            "audio-to-DAQ drift {:+.1} ppm, beyond the {max_drift_ppm} ppm the run corrects: a wrong \
                             nominal rate on one device, or a faulty clock; check both rates",
                            fit.drift_ppm
                        ),
                        details,
                    )
                };
                (clocks, Some(latency_s))
            }
            Err(e) => {
                let message = format!("the loopback's repetitions do not lie on one clock line: {e}");
                (CheckOutcome::fail("clocks", message, json!({"limit_ppm": max_drift_ppm})), None)
            }
        };
        let details = json!({"peak_v": peak_v, "expected_peak_v": expected_v, "level_db": level_db,
                             "latency_s": latency_s});
        let latency_text =
            latency_s.map_or_else(|| "latency unknown".to_string(), |l| format!("latency {:.2} ms", l * 1e3));
        let loopback = if level_db.abs() <= LOOPBACK_LEVEL_TOLERANCE_DB {
            CheckOutcome::pass(
                "loopback",
                format!(
                    "{route}: {peak_v:.3} V peak ({level_db:+.1} dB of the expected {expected_v:.3} V), {latency_text}"
                ),
                details,
            )
        } else {
            CheckOutcome::fail(
                "loopback",
                format!(
                    "{route}: {peak_v:.3} V peak, {level_db:+.1} dB from the {expected_v:.3} V that \
                     wiring.loopback_volts_per_full_scale = {} predicts: correct that value (every response's scale \
                     depends on it) or the output's level",
                    w.loopback_volts_per_full_scale
                ),
                details,
            )
        };
        (loopback, clocks)
    }

    /// Each actuator's chirp in turn, at `amplitude` full scale, one recording each, after a silent lead: the
    /// velocity's peak and mean square over the chirp and its ring-down, the lead's mean square, whether the DAQ
    /// clipped, and with `responses` the impulse response from the loopback to the velocity ([`IR_S`] long; the
    /// chirp plays on the loopback channel too, so the start latency and the clocks' drift cancel, as in a scan).
    fn chirps(&mut self, amplitude: f64, responses: bool) -> Result<Slots, String> {
        let fs = self.daq_rate_hz();
        let (f1_hz, f2_hz, duration_s) = CHIRP;
        let mut played = vec![0.0; (LEAD_S * fs).round() as usize];
        let lead = played.len();
        played.extend(sweep(f1_hz, f2_hz, duration_s, amplitude, fs).generate().map_err(|e| e.to_string())?);
        let cfg = DeconvConfig {
            sample_rate_hz: fs,
            ir_len: (IR_S * fs).round() as usize,
            band: Some(BandLimit { lo_hz: f1_hz, hi_hz: f2_hz, lo_transition_hz: 20.0, hi_transition_hz: 50.0 }),
            regularisation: 1e-3,
            pre_samples: 0,
        };
        let loopback_channel = self.rig.wiring.loopback_channel;
        let mut slots = Slots { per_slot: Vec::new(), noise_ms: 0.0, clipped: false };
        let mut noise = Vec::new();
        for channel in self.rig.wiring.actuator_channels.clone() {
            let mut signals = vec![(channel, played.clone())];
            if responses {
                signals.push((loopback_channel, played.clone()));
            }
            let recording = self.play(&signals, LEAD_S + duration_s + TAIL_S)?;
            let v = &recording.velocity_v;
            let (quiet, chirp) = v.split_at(lead.min(v.len()));
            noise.push(mean_square(quiet));
            let response = if responses {
                deconvolve_with_reference(v, &recording.loopback_v, &cfg).map_err(|e| e.to_string())?
            } else {
                Vec::new()
            };
            slots.clipped |= recording.clipped;
            slots.per_slot.push(Slot { peak_v: peak(chirp), mean_square_v2: mean_square(chirp), response });
        }
        slots.noise_ms = median(&mut noise).unwrap_or(0.0);
        Ok(slots)
    }

    /// With the beam on each magnet, a chirp on every channel: the responses, beam on magnet `i` and channel `j`,
    /// must be reciprocal (`i, j` equal to `j, i` up to the coils' gains) as a passive plate's are, which a swap of
    /// two cables breaks in a recognisable way; and every magnet must move.
    pub(super) fn actuator_wiring(&mut self, sites_m: &[(f64, f64)]) -> CheckOutcome {
        let channels = self.rig.wiring.actuator_channels.clone();
        let mut responses: Vec<Vec<Vec<f64>>> = Vec::with_capacity(sites_m.len());
        let mut moving = Vec::with_capacity(sites_m.len());
        for (a, &(x, y)) in sites_m.iter().enumerate() {
            if let Err(e) = self.rig.vibrometer.move_to(x, y) {
                return CheckOutcome::fail(
                    "actuator_wiring",
                    format!("the beam cannot go to actuator {a}'s magnet at ({x:.4}, {y:.4}) m: {e}"),
                    json!({}),
                );
            }
            match self.chirps(QUIET_FS, true) {
                Ok(slots) => {
                    let loudest = slots.per_slot.iter().map(|s| s.mean_square_v2).fold(0.0, f64::max);
                    moving.push(loudest > 10.0 * slots.noise_ms && loudest > 0.0);
                    responses.push(slots.per_slot.into_iter().map(|s| s.response).collect());
                }
                Err(e) => {
                    return CheckOutcome::fail(
                        "actuator_wiring",
                        format!("the chirps with the beam on actuator {a}'s magnet failed: {e}"),
                        json!({}),
                    );
                }
            }
        }
        let wiring = Reciprocity::of(&responses);
        let details = json!({
            "moving": moving,
            "reciprocity_error_db": wiring.as_wired_db,
            "swapped_error_db": wiring.if_swapped_db,
        });
        let mut problems: Vec<String> = moving
            .iter()
            .enumerate()
            .filter(|&(_, &m)| !m)
            .map(|(a, _)| {
                format!(
                    "the beam on actuator {a}'s magnet sees no motion from any channel (amplifier off, cables out, or \
                     the beam off the magnet)"
                )
            })
            .collect();
        if problems.is_empty() {
            let swaps = wiring.swapped_pairs();
            for &(a, b) in &swaps {
                problems.push(format!(
                    "actuators {a} and {b} are swapped: channel {} (wired to actuator {a}) drives actuator {b} and \
                     channel {} drives actuator {a}; swap the two cables back at the amplifier, or exchange the two \
                     entries of wiring.actuator_channels",
                    channels[a], channels[b]
                ));
            }
            let in_swaps = |i: usize| swaps.iter().any(|&(a, b)| a == i || b == i);
            for (a, b, error_db) in wiring.unexplained() {
                if !in_swaps(a) && !in_swaps(b) {
                    problems.push(format!(
                        "the responses between actuators {a} and {b} are not reciprocal ({error_db:.1} dB, at most \
                         {RECIPROCITY_LIMIT_DB} dB expected): a cable is on the wrong channel, or the beam is off a \
                         magnet"
                    ));
                }
            }
        }
        if problems.is_empty() {
            CheckOutcome::pass(
                "actuator_wiring",
                format!(
                    "each actuator is on its wired channel: the {} magnets' responses are reciprocal within {:.1} dB",
                    sites_m.len(),
                    wiring.worst_as_wired_db()
                ),
                details,
            )
        } else {
            CheckOutcome::fail("actuator_wiring", problems.join("; "), details)
        }
    }

    /// At a few grid points: the signal level, and each actuator's chirp at the scan's drive level against the
    /// velocity range and the noise.
    pub(super) fn ldv_signal(&mut self, config: &PreflightConfig) -> CheckOutcome {
        let Some(scale) = self.scale else {
            return CheckOutcome::not_run("ldv_signal", "the vibrometer's velocity range");
        };
        let (mut levels, mut snrs_db, mut peak_m_s, mut clipped_at) = (Vec::new(), Vec::new(), 0.0_f64, Vec::new());
        let mut rows = Vec::new();
        for &(x, y) in &config.ldv_points_m {
            let level = match self.rig.vibrometer.move_to(x, y).and_then(|()| self.rig.vibrometer.signal_level()) {
                Ok(level) => level,
                Err(e) => {
                    let message = format!("the LDV at ({x:.4}, {y:.4}) m: {e}");
                    return CheckOutcome::fail("ldv_signal", message, json!({}));
                }
            };
            let slots = match self.chirps(DRIVE_PEAK_FS, false) {
                Ok(s) => s,
                Err(e) => {
                    let message = format!("the chirps at ({x:.4}, {y:.4}) m failed: {e}");
                    return CheckOutcome::fail("ldv_signal", message, json!({}));
                }
            };
            let point_peak = slots.per_slot.iter().map(|s| s.peak_v * scale.m_s_per_v).fold(0.0, f64::max);
            let point_snrs: Vec<f64> =
                slots.per_slot.iter().map(|s| db_ratio(s.mean_square_v2, slots.noise_ms)).collect();
            if slots.clipped || point_peak >= 0.99 * scale.full_scale_m_s {
                clipped_at.push(format!("({x:.3}, {y:.3}) m"));
            }
            peak_m_s = peak_m_s.max(point_peak);
            rows.push(json!({"x_m": x, "y_m": y, "level": level, "peak_m_s": point_peak, "snr_db": point_snrs,
                             "clipped": slots.clipped}));
            levels.push(level);
            snrs_db.extend(point_snrs);
        }
        let median_level = median(&mut levels.clone()).unwrap_or(0.0);
        let median_snr_db = median(&mut snrs_db).unwrap_or(0.0);
        let fraction = peak_m_s / scale.full_scale_m_s;
        let details = json!({"points": rows, "median_level": median_level, "median_snr_db": median_snr_db,
                             "peak_m_s": peak_m_s, "full_scale_m_s": scale.full_scale_m_s});
        let mut problems = Vec::new();
        if median_level < config.min_signal_level {
            problems.push(format!(
                "the LDV's signal level is {median_level:.2} (median of {} points), below the {:.2} the scan aims \
                 for: the plate returns too little light. Apply retroreflective tape, refocus the beam, or clean the \
                 optics",
                levels.len(),
                config.min_signal_level
            ));
        }
        // The scan widens the range where a response clips (and measures the point again), so a clip costs time,
        // not data: a note, not a failure. A response lost in the range's resolution is not corrected.
        let mut notes = Vec::new();
        if !clipped_at.is_empty() {
            notes.push(format!(
                "the velocity clips the {} m/s range at {}: the scan will widen the range there and measure again; a \
                 larger range from the start saves that time",
                scale.full_scale_m_s,
                clipped_at.join(", ")
            ));
        } else if fraction > MAX_PEAK_FRACTION {
            notes.push(format!(
                "a short chirp already reaches {:.0} % of the {} m/s range: the scan's longer sweeps may clip (the \
                 scan then widens the range and measures again)",
                100.0 * fraction,
                scale.full_scale_m_s
            ));
        } else if fraction < MIN_PEAK_FRACTION {
            problems.push(format!(
                "the response peaks at {peak_m_s:.2e} m/s, {:.3} % of the {} m/s range: choose a smaller range, or \
                 check the amplifier's gain",
                100.0 * fraction,
                scale.full_scale_m_s
            ));
        }
        if median_snr_db < MIN_CHIRP_SNR_DB {
            problems.push(format!(
                "a chirp at the scan's drive level stands only {median_snr_db:.1} dB above the noise (median; at \
                 least {MIN_CHIRP_SNR_DB} dB expected)"
            ));
        }
        let notes = if notes.is_empty() { String::new() } else { format!(". Note: {}", notes.join("; ")) };
        if problems.is_empty() {
            CheckOutcome::pass(
                "ldv_signal",
                format!(
                    "signal level {median_level:.2} (median of {} points); peak {:.2} mm/s, {:.0} % of the {} m/s \
                     range; chirp SNR {median_snr_db:.0} dB (median){notes}",
                    levels.len(),
                    peak_m_s * 1e3,
                    100.0 * fraction,
                    scale.full_scale_m_s
                ),
                details,
            )
        } else {
            CheckOutcome::fail("ldv_signal", format!("{}{notes}", problems.join("; ")), details)
        }
    }
}

/// What one actuator's chirp gave at the beam.
struct Slot {
    /// Peak |V| in its slot.
    peak_v: f64,
    /// Mean square in its slot, V^2.
    mean_square_v2: f64,
    /// Its impulse response, V per full scale, from the start of the playback.
    response: Vec<f64>,
}

/// Every actuator's chirp at the beam, the noise before them, and whether the DAQ clipped.
struct Slots {
    per_slot: Vec<Slot>,
    noise_ms: f64,
    clipped: bool,
}

fn sweep(f1_hz: f64, f2_hz: f64, duration_s: f64, amplitude: f64, sample_rate_hz: f64) -> SweepSpec {
    SweepSpec {
        kind: SweepKind::Linear,
        f1_hz,
        f2_hz,
        duration_s,
        sample_rate_hz,
        amplitude,
        fade_in_s: 0.005,
        fade_out_s: 0.005,
    }
}

fn internal_pair(name: &'static str, detail: &str) -> (CheckOutcome, CheckOutcome) {
    let fail = CheckOutcome::fail(name, format!("internal error building the test signal: {detail}"), json!({}));
    (fail, CheckOutcome::not_run("clocks", "the loopback"))
}

fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

fn mean_square(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64 }
}

/// `10 log10(a / b)` for energies, capped at [`SNR_CAP_DB`] (and at its negative) so it stays finite.
pub(super) fn db_ratio(a: f64, b: f64) -> f64 {
    if b <= 0.0 {
        return if a > 0.0 { SNR_CAP_DB } else { 0.0 };
    }
    if a <= 0.0 {
        return -SNR_CAP_DB;
    }
    (10.0 * (a / b).log10()).clamp(-SNR_CAP_DB, SNR_CAP_DB)
}

fn merge(mut a: Value, b: Value) -> Value {
    if let (Some(a), Value::Object(b)) = (a.as_object_mut(), b) {
        a.extend(b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_ratios_stay_finite_at_the_extremes() {
        assert_eq!(db_ratio(1.0, 0.0), SNR_CAP_DB);
        assert_eq!(db_ratio(0.0, 0.0), 0.0);
        assert_eq!(db_ratio(0.0, 1.0), -SNR_CAP_DB);
        assert!((db_ratio(100.0, 1.0) - 20.0).abs() < 1e-12);
        assert_eq!(db_ratio(f64::MAX, f64::MIN_POSITIVE), SNR_CAP_DB);
    }
}
