//! The pre-flight's bench: the rig with what the checks learn on the way, and the checks of the instruments
//! themselves (vibrometer, DAQ, audio) and of the loopback and the clocks. The chirp checks are in `chirps`.

use metaplate_core::daq::DaqConfig;
use metaplate_core::rig::{Recording, Rig};
use metaplate_core::vibrometer::VelocityScale;
use metaplate_dsp::drift::{ExcitationTemplate, fit_clock};
use serde_json::json;

use super::signals::{TAIL_S, merge, peak, sweep};
use super::{CheckOutcome, LOOPBACK_LEVEL_TOLERANCE_DB};
use crate::drive::to_audio_rate;
use crate::engine::session::BLOCK_LEN_SAMPLES;

/// The loopback sweep: 100 Hz to 4 kHz (wide, for a sharp location), 0.25 s, -20 dBFS, repeated back to back.
const LOOPBACK_SWEEP: (f64, f64, f64, f64) = (100.0, 4000.0, 0.25, 0.1);
/// Repetitions of the loopback sweep: four give the drift with three periods of lever.
const LOOPBACK_REPETITIONS: usize = 4;

/// The rig, with what the checks learn on the way (the velocity scale in force).
pub(super) struct Bench<'a> {
    pub(super) rig: &'a mut Rig,
    daq_config: DaqConfig,
    /// The velocity scale in force, once the vibrometer check set it.
    pub(super) scale: Option<VelocityScale>,
}

impl<'a> Bench<'a> {
    pub(super) fn new(rig: &'a mut Rig) -> Self {
        let daq_config = rig.wiring.daq_config(BLOCK_LEN_SAMPLES);
        Self { rig, daq_config, scale: None }
    }

    pub(super) fn daq_rate_hz(&self) -> f64 {
        self.rig.wiring.daq_sample_rate_hz
    }

    /// The vibrometer answers its identity and takes the velocity range.
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
        match ldv.set_velocity_range(max_velocity_m_s) {
            Ok(scale) => {
                self.scale = Some(scale);
                CheckOutcome::pass(
                    "vibrometer",
                    format!(
                        "{who} answers; range {} m/s full scale ({} m/s per V)",
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
    pub(super) fn play(&mut self, signals: &[(u32, Vec<f64>)], record_s: f64) -> Result<Recording, String> {
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
        if recording.daq_overrun {
            let daq = self.rig.daq.identity();
            return Err(format!(
                "the DAQ's stream overflowed: its buffer filled before the host read it and samples were lost at \
                 the source (the {} {} reports it). Close what else uses the computer or the USB bus, or plug the \
                 DAQ into a port of its own",
                daq.vendor, daq.model
            ));
        }
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
}

fn internal_pair(name: &'static str, detail: &str) -> (CheckOutcome, CheckOutcome) {
    let fail = CheckOutcome::fail(name, format!("internal error building the test signal: {detail}"), json!({}));
    (fail, CheckOutcome::not_run("clocks", "the loopback"))
}
