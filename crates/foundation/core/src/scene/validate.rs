//! The valid ranges of a scene, checked in one place.
//!
//! Ranges are wide enough for any real plate and instrument, and narrow enough that a number in the wrong unit
//! (millimetres for metres, GPa for Pa) falls outside them.

use super::Scene;
use super::outline::Outline;
use super::resonator::ResonatorModel;
use crate::grid::GridError;

/// One thing wrong with a scene: where (a dotted key path) and what.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Problem {
    pub(crate) key_path: String,
    pub(crate) message: String,
}

type Check = Result<(), Problem>;

fn problem(key_path: impl Into<String>, message: String) -> Check {
    Err(Problem { key_path: key_path.into(), message })
}

fn finite(path: &str, v: f64, unit: &str) -> Check {
    if v.is_finite() { Ok(()) } else { problem(path, format!("must be finite, got {v} {unit}")) }
}

fn positive(path: &str, v: f64, unit: &str) -> Check {
    if v.is_finite() && v > 0.0 { Ok(()) } else { problem(path, format!("must be finite and > 0, got {v} {unit}")) }
}

fn non_negative(path: &str, v: f64, unit: &str) -> Check {
    if v.is_finite() && v >= 0.0 { Ok(()) } else { problem(path, format!("must be finite and >= 0, got {v} {unit}")) }
}

/// `lo <= v <= hi`; `why` says what a value outside means.
fn within(path: &str, v: f64, (lo, hi): (f64, f64), unit: &str, why: &str) -> Check {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        problem(path, format!("must lie in [{}, {}] {unit}, got {}{why}", num(lo), num(hi), num(v)))
    }
}

/// A number as a person reads it: plain for everyday magnitudes, scientific for the rest.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e4).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

const UNIT_MISTAKE: &str = ": no solid is outside this range; is the value in the key's unit?";

impl Scene {
    /// Every check of [`Scene::validate`], stopping at the first problem.
    pub(crate) fn check(&self) -> Check {
        if self.name.trim().is_empty() {
            return problem("name", "must not be empty".to_owned());
        }
        if i64::try_from(self.seed).is_err() {
            return problem("seed", format!("must be at most 2^63 - 1 (a TOML integer), got {}", self.seed));
        }
        self.check_plate()?;
        self.check_supports()?;
        self.check_resonators()?;
        self.check_actuators()?;
        self.check_grid()?;
        self.check_instruments()?;
        for (i, f) in self.faults.iter().enumerate() {
            non_negative(&format!("faults[{i}].at_s"), f.at_s, "s")?;
            non_negative(&format!("faults[{i}].duration_s"), f.duration_s, "s")?;
        }
        self.check_setup()
    }

    fn check_setup(&self) -> Check {
        let s = &self.setup;
        if let Some([a, b]) = s.swapped_actuators {
            let n = self.actuators.len();
            if a == b || a >= n || b >= n {
                return problem(
                    "setup.swapped_actuators",
                    format!(
                        "must name two different actuators of the {n} (0 to {}), got [{a}, {b}]",
                        n.saturating_sub(1)
                    ),
                );
            }
        }
        if let Some(rate) = s.audio_device_rate_hz {
            positive("setup.audio_device_rate_hz", rate, "Hz")?;
        }
        Ok(())
    }

    fn check_plate(&self) -> Check {
        let p = &self.plate;
        match p.outline {
            Outline::Stadium { straight_length_m, radius_m } => {
                non_negative("plate.outline.straight_length_m", straight_length_m, "m")?;
                positive("plate.outline.radius_m", radius_m, "m")?;
            }
            Outline::Rectangle { width_m, height_m } => {
                positive("plate.outline.width_m", width_m, "m")?;
                positive("plate.outline.height_m", height_m, "m")?;
            }
        }
        positive("plate.thickness_m", p.thickness_m, "m")?;
        // Kirchhoff (thin-plate) theory needs h well below the plate's size; a thicker "plate" is also the usual
        // sign of millimetres typed as metres.
        let smallest_m = 2.0 * p.outline.inradius_m();
        if p.thickness_m > smallest_m / 10.0 {
            return problem(
                "plate.thickness_m",
                format!(
                    "{} m is not thin beside the plate's smallest size ({smallest_m} m); it must be below a tenth of \
                     it. The key is in metres: 1.5 mm is 0.0015",
                    p.thickness_m
                ),
            );
        }
        within("plate.youngs_modulus_pa", p.youngs_modulus_pa, (1e5, 1e12), "Pa", UNIT_MISTAKE)?;
        if !(p.poisson_ratio > -1.0 && p.poisson_ratio < 0.5) {
            return problem("plate.poisson_ratio", format!("must lie in (-1, 0.5), got {}", p.poisson_ratio));
        }
        within("plate.density_kg_m3", p.density_kg_m3, (10.0, 1e5), "kg/m^3", UNIT_MISTAKE)?;
        within("plate.loss_factor", p.loss_factor, (0.0, 1.0), "", "")
    }

    fn check_supports(&self) -> Check {
        for (i, s) in self.supports.iter().enumerate() {
            let path = |key: &str| format!("supports[{i}].{key}");
            finite(&path("x_m"), s.x_m, "m")?;
            finite(&path("y_m"), s.y_m, "m")?;
            positive(&path("size_m"), s.size_m, "m")?;
            positive(&path("stiffness_n_per_m"), s.stiffness_n_per_m, "N/m")?;
            non_negative(&path("loss_factor"), s.loss_factor, "")?;
            if !self.plate.outline.contains_square(s.x_m, s.y_m, s.size_m) {
                return problem(
                    format!("supports[{i}]"),
                    format!(
                        "the {} m pad at ({}, {}) m is not wholly under the plate (coordinates are from the plate's \
                         centre)",
                        s.size_m, s.x_m, s.y_m
                    ),
                );
            }
        }
        Ok(())
    }

    fn check_resonators(&self) -> Check {
        let r = &self.resonators;
        if r.model == ResonatorModel::None {
            return Ok(());
        }
        if let Some(design) = &r.design {
            let (cell, plate) = (&design.plate, &self.plate);
            // The cell's band structure is the scene's plate's only if the plate is the cell's, bit for bit.
            for (key, scene_value, design_value) in [
                ("thickness_m", plate.thickness_m, cell.thickness_m),
                ("youngs_modulus_pa", plate.youngs_modulus_pa, cell.youngs_modulus_pa),
                ("poisson_ratio", plate.poisson_ratio, cell.poisson_ratio),
                ("density_kg_m3", plate.density_kg_m3, cell.density_kg_m3),
            ] {
                if scene_value != design_value {
                    return problem(
                        format!("plate.{key}"),
                        format!("is {scene_value}, but design `{}`'s plate has {design_value}", design.name),
                    );
                }
            }
        }
        positive("resonators.pitch_m", r.pitch_m, "m")?;
        positive("resonators.rod_height_m", r.rod_height_m, "m")?;
        positive("resonators.rod_diameter_m", r.rod_diameter_m, "m")?;
        if r.rod_diameter_m >= r.pitch_m {
            return problem(
                "resonators.rod_diameter_m",
                format!("{} m rods do not fit a {} m lattice", r.rod_diameter_m, r.pitch_m),
            );
        }
        within("resonators.rod_youngs_modulus_pa", r.rod_youngs_modulus_pa, (1e5, 1e12), "Pa", UNIT_MISTAKE)?;
        within("resonators.rod_density_kg_m3", r.rod_density_kg_m3, (10.0, 1e5), "kg/m^3", UNIT_MISTAKE)?;
        non_negative("resonators.loss_factor", r.loss_factor, "")?;
        non_negative("resonators.region_inset_m", r.region_inset_m, "m")?;
        if !(0.0..0.5).contains(&r.height_spread) {
            return problem("resonators.height_spread", format!("must lie in [0, 0.5), got {}", r.height_spread));
        }
        if let Some(m) = r.mass_ratio {
            positive("resonators.mass_ratio", m, "")?;
        }
        if let Some(f) = r.resonance_hz {
            positive("resonators.resonance_hz", f, "Hz")?;
        }
        if let Some(g) = r.gyration_radius_m {
            positive("resonators.gyration_radius_m", g, "m")?;
            // All of the rod's mass at its tip is the largest radius a rod of this height can have.
            if g > r.rod_height_m {
                return problem(
                    "resonators.gyration_radius_m",
                    format!("{g} m exceeds the rod height {} m (no rod can have it)", r.rod_height_m),
                );
            }
        }
        match r.lattice_sites_m(&self.plate.outline) {
            Ok(sites) if sites.is_empty() => problem(
                "resonators.region_inset_m",
                format!("an inset of {} m leaves no lattice site on the plate", r.region_inset_m),
            ),
            Ok(_) => Ok(()),
            Err(e) => problem("resonators.pitch_m", e.to_string()),
        }
    }

    fn check_actuators(&self) -> Check {
        if self.actuators.is_empty() {
            return problem("actuators", "a scene needs at least one actuator".to_owned());
        }
        for (i, a) in self.actuators.iter().enumerate() {
            let path = |key: &str| format!("actuators[{i}].{key}");
            finite(&path("x_m"), a.x_m, "m")?;
            finite(&path("y_m"), a.y_m, "m")?;
            if !self.plate.outline.contains(a.x_m, a.y_m) {
                return problem(
                    format!("actuators[{i}]"),
                    format!("({}, {}) m is off the plate (coordinates are from the plate's centre)", a.x_m, a.y_m),
                );
            }
            if let Some(j) = self.supports.iter().position(|s| s.covers(a.x_m, a.y_m)) {
                return problem(
                    format!("actuators[{i}]"),
                    format!("({}, {}) m is on support pad supports[{j}]", a.x_m, a.y_m),
                );
            }
            let c = &a.voice_coil;
            positive(&path("voice_coil.force_factor_n_per_v"), c.force_factor_n_per_v, "N/V")?;
            positive(&path("voice_coil.suspension_resonance_hz"), c.suspension_resonance_hz, "Hz")?;
            positive(&path("voice_coil.suspension_q"), c.suspension_q, "")?;
            positive(&path("voice_coil.rolloff_hz"), c.rolloff_hz, "Hz")?;
            non_negative(&path("voice_coil.spread_db"), c.spread_db, "dB")?;
            within(&path("voice_coil.nonlinearity"), c.nonlinearity, (-1.0, 1.0), "", ": the model is for weak ones")?;
        }
        Ok(())
    }

    fn check_grid(&self) -> Check {
        self.grid.validate().or_else(|e| match e {
            GridError::InvalidParameter { name, reason } => problem(format!("grid.{name}"), reason),
            other => problem("grid", other.to_string()),
        })?;
        if self.measured_points().is_empty() {
            let g = &self.grid;
            let (x0, y0) = g.position_m(0);
            let (x1, y1) = g.position_m(g.len() - 1);
            return problem(
                "grid",
                format!(
                    "no grid point is on the plate and off the supports (grid spans x {x0}..{x1} m, y {y0}..{y1} m)"
                ),
            );
        }
        Ok(())
    }

    fn check_instruments(&self) -> Check {
        let l = &self.ldv;
        non_negative("ldv.noise_rms_m_s", l.noise_rms_m_s, "m/s")?;
        if !(l.speckle_mean_level > 0.0 && l.speckle_mean_level <= 1.0) {
            return problem("ldv.speckle_mean_level", format!("must lie in (0, 1], got {}", l.speckle_mean_level));
        }
        non_negative("ldv.speckle_spread", l.speckle_spread, "")?;
        within("ldv.dropout_probability", l.dropout_probability, (0.0, 1.0), "", "")?;
        positive("ldv.max_velocity_m_s", l.max_velocity_m_s, "m/s")?;
        within("ldv.aim_error_rms_m", l.aim_error_rms_m, (0.0, 0.002), "m", "")?;

        let d = &self.daq;
        if d.bits > 32 {
            return problem("daq.bits", format!("must be 0 (ideal) or lie in 1..=32, got {}", d.bits));
        }
        positive("daq.range_v", d.range_v, "V")?;
        positive("daq.sample_rate_hz", d.sample_rate_hz, "Hz")?;
        within(
            "daq.clock_offset_ppm",
            d.clock_offset_ppm,
            (-1000.0, 1000.0),
            "ppm",
            ": no working clock is so far off",
        )?;
        positive("daq.volts_per_m_s", d.volts_per_m_s, "V per m/s")?;

        let a = &self.audio;
        positive("audio.sample_rate_hz", a.sample_rate_hz, "Hz")?;
        let needed = self.actuators.len() + 1;
        if (a.channels as usize) < needed {
            return problem(
                "audio.channels",
                format!("{} channels cannot drive {} actuators plus the loopback reference", a.channels, needed - 1),
            );
        }
        non_negative("audio.latency_s", a.latency_s, "s")?;
        within(
            "audio.clock_offset_ppm",
            a.clock_offset_ppm,
            (-1000.0, 1000.0),
            "ppm",
            ": no working clock is so far off",
        )
    }
}
