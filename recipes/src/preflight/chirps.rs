//! The pre-flight's chirp checks: each actuator's chirp at the beam, for the actuators' wiring (reciprocity) and
//! the LDV's signal at a few grid points.

use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::{DeconvConfig, deconvolve_with_reference};
use metaplate_dsp::stats::median;
use serde_json::json;

use super::bench::Bench;
use super::reciprocity::{RECIPROCITY_LIMIT_DB, Reciprocity};
use super::signals::{TAIL_S, db_ratio, mean_square, peak, sweep};
use super::{CheckOutcome, MAX_PEAK_FRACTION, MIN_CHIRP_SNR_DB, MIN_PEAK_FRACTION, PreflightConfig};
use crate::drive::DRIVE_PEAK_FS;

/// The actuator chirp: the scan's band, 0.3 s; quiet (-26 dBFS) for the wiring check.
const CHIRP: (f64, f64, f64) = (62.0, 625.0, 0.3);
/// Peak of the wiring check's chirps, full scale.
const QUIET_FS: f64 = 0.05;
/// Length of the impulse response estimated from each chirp, s: the part above the noise.
const IR_S: f64 = 0.1;
/// Silence before the first chirp, s: where the noise is measured.
const LEAD_S: f64 = 0.2;

impl Bench<'_> {
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
            if let Err(e) = self.rig.aim.aim_at(x, y) {
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
            let level = match self
                .rig
                .aim
                .aim_at(x, y)
                .map_err(|e| e.to_string())
                .and_then(|()| self.rig.vibrometer.signal_level().map_err(|e| e.to_string()))
            {
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
